"""No plausible wrong number under jax.jit: the numeric bad inputs of tests/test_bad_input.py (reduced cases), traced.

Every public reduced function, called with traced inputs, either raises at run time (``equinox.error_if``: a
``JaxRuntimeError`` whose text carries the eager message, naming the quantity) or returns the documented NaN flag,
for every input it refuses eagerly. Each function is jitted once with ALL its numeric inputs traced (one compiled
program per function), then run with the good values with one entry replaced by a bad one.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tissuemech.reduced  # noqa: F401  (float64)
from tissuemech.reduced import blastula as bl
from tissuemech.reduced import spheroid as sp
from tissuemech.reduced import viscoshell as vs

SHELL = dict(inner_radius=50e-6, outer_radius=75e-6, C=200.0, alpha=0.2)
BALL = dict(radius=500e-6, C=150.0, alpha=0.2, beta=0.4, tau=200.0, displacement=50e-6, ramp_time=0.2)
T = np.array([0.0, 0.1, 0.2, 10.0])
NAN = "nan"  # the documented NaN flag


def _shell_fn(fn):
    @jax.jit
    def run(x, inner_radius, outer_radius, C, alpha):
        return fn(x, inner_radius=inner_radius, outer_radius=outer_radius, C=C, alpha=alpha)

    return run


@functools.cache
def _jitted(name):
    if name == "pressure":
        return _shell_fn(bl.pressure)
    if name == "pressure ode":
        return _shell_fn(functools.partial(bl.pressure, method="ode"))
    if name == "pressure_derivative":
        return _shell_fn(bl.pressure_derivative)
    if name == "inner_stretch":
        return _shell_fn(bl.inner_stretch)
    if name == "profiles":
        return _shell_fn(lambda x, **kw: bl.profiles(x, **kw).sigma_theta)
    if name == "limit_point":
        return _shell_fn(lambda x, **kw: bl.limit_point(**kw).pressure)
    if name == "outer_stretch":
        return jax.jit(
            lambda x, inner_radius, outer_radius: bl.outer_stretch(
                x, inner_radius=inner_radius, outer_radius=outer_radius
            )
        )
    if name in ("force", "nominal_stress"):
        fn = getattr(sp, name)

        @jax.jit
        def run(t, radius, C, alpha, beta, tau, displacement, ramp_time):
            return fn(
                t,
                radius=radius,
                C=C,
                alpha=alpha,
                branches=[(beta, tau)],
                displacement=displacement,
                ramp_time=ramp_time,
            )

        return run
    if name == "history":  # delta(t) = d * h(t / 0.2): the scale d traced, the shape h a parameter of the case

        @functools.partial(jax.jit, static_argnums=(1, 2))
        def run(d, shape, equilibrium):
            return sp.force(
                jnp.asarray(np.linspace(0.0, 2.0, 21)),
                radius=BALL["radius"],
                C=150.0,
                alpha=0.2,
                branches=[(0.4, 200.0)],
                displacement=lambda t: d * shape(t / 0.2),
                equilibrium=equilibrium,
            )

        return run
    if name == "equilibrium_force":
        return jax.jit(lambda d, radius, C, alpha: sp.equilibrium_force(d, radius=radius, C=C, alpha=alpha))
    if name == "midplane_radius":
        return jax.jit(lambda d, radius, alpha: sp.midplane_radius(d, radius=radius, alpha=alpha))
    if name == "hertz_force":
        return jax.jit(lambda d, radius, C: sp.hertz_force(d, radius=radius, C=C))
    if name == "approach":
        return jax.jit(
            lambda t, force, tau: sp.approach(
                t, radius=500e-6, C=150.0, alpha=0.2, branches=[(0.4, tau)], force=force, ramp_time=0.2
            )
        )
    if name == "inflate":

        @jax.jit
        def run(t, pressure, inner_radius, outer_radius, C, alpha, beta, tau, ramp_time):
            return vs.inflate(
                t,
                pressure=pressure,
                inner_radius=inner_radius,
                outer_radius=outer_radius,
                C=C,
                alpha=alpha,
                branches=[(beta, tau)],
                ramp_time=ramp_time,
            ).inner_stretch

        return run
    if name == "inflate history":

        @jax.jit
        def run(p0):
            return vs.inflate(
                jnp.array([0.0, 1.0]),
                pressure=lambda t: p0 * jnp.minimum(t, 1.0) / (t - 0.5),
                **SHELL,
                branches=[(1.0, 10.0)],
            ).inner_stretch

        return run
    raise KeyError(name)


def _args(name, over):
    shell = {"x": 1.5, **SHELL}
    if name in ("pressure", "pressure ode", "pressure_derivative", "profiles", "limit_point"):
        a = {**shell, **({"alpha": 0.0} if name == "limit_point" else {}), **over}  # alpha 0: a limit point exists
        return (a["x"], a["inner_radius"], a["outer_radius"], a["C"], a["alpha"])
    if name == "inner_stretch":
        a = {**shell, "x": 50.0, **over}
        return (a["x"], a["inner_radius"], a["outer_radius"], a["C"], a["alpha"])
    if name == "outer_stretch":
        a = {**shell, **over}
        return (a["x"], a["inner_radius"], a["outer_radius"])
    if name in ("force", "nominal_stress"):
        a = {"t": T, **BALL, **over}
        return tuple(a[k] for k in ("t", "radius", "C", "alpha", "beta", "tau", "displacement", "ramp_time"))
    if name == "history":
        return (over["d"], over["shape"], over.get("equilibrium", "hertz"))
    if name == "equilibrium_force":
        a = {"d": 50e-6, "radius": 500e-6, "C": 150.0, "alpha": 0.2, **over}
        return (a["d"], a["radius"], a["C"], a["alpha"])
    if name == "midplane_radius":
        a = {"d": 50e-6, "radius": 500e-6, "alpha": 0.2, **over}
        return (a["d"], a["radius"], a["alpha"])
    if name == "hertz_force":
        a = {"d": 50e-6, "radius": 500e-6, "C": 150.0, **over}
        return (a["d"], a["radius"], a["C"])
    if name == "inflate":
        a = dict(t=np.array([0.0, 1.0]), pressure=100.0, inner_radius=50e-6, outer_radius=75e-6, C=200.0, alpha=0.0)
        a.update(beta=1.0, tau=10.0, ramp_time=0.5)
        a.update(over)
        keys = ("t", "pressure", "inner_radius", "outer_radius", "C", "alpha", "beta", "tau", "ramp_time")
        return tuple(a[k] for k in keys)
    if name == "inflate history":
        return (over.get("p0", 50.0),)
    if name == "approach":
        a = {"t": T, "force": 1e-5, "tau": 200.0, **over}
        return (a["t"], a["force"], a["tau"])
    raise KeyError(name)


ramp = lambda s: jnp.minimum(s, 1.0)
start = lambda s: 1.0 + 0.0 * s
unload = lambda s: jnp.minimum(s, 1.0) * jnp.exp(-jnp.maximum(s - 1.0, 0.0) * 4.0)
nan_shape = lambda s: s * jnp.nan

# (case, function, bad values, expected: a regex the run-time error must hold, or NAN)
CASES = [
    # ---- blastula.pressure
    ("pressure nan", "pressure", dict(x=np.nan), r"inner_stretch must be positive"),
    ("pressure inf", "pressure", dict(x=np.inf), r"inner_stretch must be positive"),
    ("pressure negative", "pressure", dict(x=-1.0), r"inner_stretch must be positive"),
    ("pressure zero", "pressure", dict(x=0.0), r"inner_stretch must be positive"),
    ("pressure past domain", "pressure", dict(x=1e80), r"inner_stretch .*1e-30\.\.1e\+30"),
    ("pressure C negative", "pressure", dict(C=-1.0), r"C \(the Fung stiffness, shear modulus / 2\) must be positive"),
    ("pressure C nan", "pressure", dict(C=np.nan), r"C \(the Fung stiffness"),
    ("pressure C zero", "pressure", dict(C=0.0), r"C \(the Fung stiffness"),
    ("pressure alpha negative", "pressure", dict(alpha=-1.0), r"alpha \(the Fung stiffening exponent\) must be >= 0"),
    ("pressure alpha inf", "pressure", dict(alpha=np.inf), r"alpha \(the Fung stiffening exponent\)"),
    ("pressure inner_radius negative", "pressure", dict(inner_radius=-1.0), r"inner_radius must be positive \(in m\)"),
    ("pressure outer_radius nan", "pressure", dict(outer_radius=np.nan), r"outer_radius must be positive \(in m\)"),
    ("pressure radii swapped", "pressure", dict(inner_radius=80e-6), r"inner_radius must be smaller than outer_radius"),
    ("pressure overflow", "pressure", dict(x=100.0), NAN),
    ("pressure overflow alpha", "pressure", dict(x=10.0, alpha=20.0), NAN),
    ("pressure ode C negative", "pressure ode", dict(C=-1.0), r"C \(the Fung stiffness"),
    ("pressure ode stretch zero", "pressure ode", dict(x=0.0), r"inner_stretch must be positive"),
    # ---- pressure_derivative, outer_stretch, limit_point, inner_stretch, profiles
    ("dp nan", "pressure_derivative", dict(x=np.nan), r"inner_stretch must be positive"),
    ("dp collapse", "pressure_derivative", dict(x=1e-100, alpha=0.0), r"inner_stretch .*1e-30\.\.1e\+30"),
    ("dp overflow", "pressure_derivative", dict(x=45.0), NAN),
    ("dp overflow nan", "pressure_derivative", dict(x=2.0, alpha=1000.0), NAN),
    ("dp C negative", "pressure_derivative", dict(C=-1.0), r"C \(the Fung stiffness"),
    ("outer_stretch past domain", "outer_stretch", dict(x=1e103), r"inner_stretch .*1e-30\.\.1e\+30"),
    ("outer_stretch negative", "outer_stretch", dict(x=-1.0), r"inner_stretch must be positive"),
    ("outer_stretch radius negative", "outer_stretch", dict(inner_radius=-1.0), r"inner_radius must be positive"),
    ("limit_point radii", "limit_point", dict(inner_radius=1e-3), r"inner_radius must be smaller than outer_radius"),
    ("limit_point alpha negative", "limit_point", dict(alpha=-1.0), r"alpha \(the Fung stiffening exponent\)"),
    ("limit_point C negative", "limit_point", dict(C=-1.0), r"C \(the Fung stiffness"),
    ("inner_stretch nan", "inner_stretch", dict(x=np.nan), r"pressure must be a finite number \(in Pa\)"),
    ("inner_stretch inf", "inner_stretch", dict(x=np.inf), r"pressure must be a finite number \(in Pa\)"),
    ("inner_stretch burst", "inner_stretch", dict(x=1000.0, alpha=0.0), NAN),
    ("inner_stretch too deflated", "inner_stretch", dict(x=-1e7), NAN),
    ("inner_stretch C negative", "inner_stretch", dict(C=-1.0), r"C \(the Fung stiffness"),
    ("inner_stretch radii", "inner_stretch", dict(outer_radius=40e-6), r"inner_radius must be smaller"),
    ("profiles stretch nan", "profiles", dict(x=np.nan), r"inner_stretch must be positive"),
    ("profiles alpha negative", "profiles", dict(alpha=-0.1), r"alpha \(the Fung stiffening exponent\)"),
    # ---- viscoshell.inflate
    ("vs t negative", "inflate", dict(t=np.array([-1.0, 0.0])), NAN),
    ("vs t nan", "inflate", dict(t=np.array([0.0, np.nan])), NAN),
    ("vs t descending", "inflate", dict(t=np.array([1.0, 0.0])), NAN),
    ("vs pressure nan", "inflate", dict(pressure=np.nan), r"pressure must be a finite number \(in Pa\)"),
    ("vs tau negative", "inflate", dict(tau=-1.0), r"tau \(relaxation time of branch 0\) must be positive \(in s\)"),
    ("vs beta negative", "inflate", dict(beta=-0.5), r"beta \(energy factor of branch 0\) must not be negative"),
    ("vs C negative", "inflate", dict(C=-1.0), r"C \(the Fung stiffness"),
    ("vs radii", "inflate", dict(inner_radius=80e-6), r"inner_radius must be smaller"),
    ("vs ramp_time negative", "inflate", dict(ramp_time=-1.0), r"ramp_time must be positive \(in s\)"),
    ("vs instantaneous burst", "inflate", dict(pressure=1000.0), NAN),
    ("vs pressure history inf", "inflate history", dict(p0=50.0), r"pressure history p\(t\) must be finite"),
    # ---- spheroid.force / nominal_stress
    (
        "force t negative",
        "force",
        dict(t=np.array([-1.0, 0.0, 0.1, 0.2])),
        r"t \(output times.*must be finite and >= 0",
    ),
    ("force t nan", "force", dict(t=np.array([0.0, np.nan, 0.1, 0.2])), r"t \(output times.*must be finite and >= 0"),
    ("force radius negative", "force", dict(radius=-1.0), r"radius \(of the ball\) must be positive \(in m\)"),
    ("force C negative", "force", dict(C=-1.0), r"C \(the Fung stiffness"),
    ("force alpha negative", "force", dict(alpha=-1.0), r"alpha \(the Fung stiffening exponent\)"),
    (
        "force alpha past table",
        "force",
        dict(alpha=5.0),
        r"alpha is outside the calibrated table \(alpha in \[0, 1\.5\]\)",
    ),
    ("force beta negative", "force", dict(beta=-0.4), r"beta \(energy factor of branch 0\)"),
    ("force tau zero", "force", dict(tau=0.0), r"tau \(relaxation time of branch 0\) must be positive"),
    ("force displacement negative", "force", dict(displacement=-1e-5), r"displacement \(the total approach.*positive"),
    ("force displacement zero", "force", dict(displacement=0.0), r"displacement \(the total approach.*positive"),
    ("force displacement nan", "force", dict(displacement=np.nan), r"displacement \(the total approach.*finite"),
    (
        "force displacement past diameter",
        "force",
        dict(displacement=1.2e-3),
        r"displacement .*smaller than the ball's diameter",
    ),
    ("force displacement past table", "force", dict(displacement=4e-4), r"beyond the calibrated table \(up to 0\.36"),
    (
        "force ramp_time negative",
        "force",
        dict(ramp_time=-1.0),
        r"ramp_time \(duration of the loading ramp\) must be positive",
    ),
    (
        "stress displacement past diameter",
        "nominal_stress",
        dict(displacement=2e-3),
        r"smaller than the ball's diameter",
    ),
    ("stress alpha past table", "nominal_stress", dict(alpha=1.6), r"alpha is outside the calibrated table"),
    ("history starts at 50 um", "history", dict(d=50e-6, shape=start), r"delta\(0\) must be 0 m"),
    ("history unloads fast", "history", dict(d=50e-6, shape=unload), r"lose contact"),
    ("history past diameter", "history", dict(d=1.2e-3, shape=ramp), r"displacement history .*diameter"),
    ("history past table", "history", dict(d=4e-4, shape=ramp, equilibrium="fem"), r"beyond the calibrated table"),
    ("history nan", "history", dict(d=50e-6, shape=nan_shape), r"displacement history .*must be finite"),
    ("history negative", "history", dict(d=-1e-6, shape=ramp), r"displacement history .*must not be negative"),
    ("approach force negative", "approach", dict(force=-1e-5), r"force \(the held plate force\) must be positive"),
    ("approach past table", "approach", dict(force=1.0), r"relaxed approach out of the equilibrium law"),
    ("approach tau zero", "approach", dict(tau=0.0), r"tau \(relaxation time of branch 0\) must be positive"),
    ("approach t negative", "approach", dict(t=np.array([-1.0, 0.0, 0.1, 0.2])), r"t \(output times"),
    # ---- equilibrium_force / midplane_radius / hertz_force
    ("F_eq nan", "equilibrium_force", dict(d=np.nan), r"displacement \(the total approach.*finite"),
    ("F_eq negative", "equilibrium_force", dict(d=-5e-5), r"displacement \(the total approach.*must not be negative"),
    ("F_eq past table", "equilibrium_force", dict(d=4e-4), r"beyond the calibrated table"),
    ("F_eq alpha past table", "equilibrium_force", dict(alpha=5.0), r"alpha is outside the calibrated table"),
    ("F_eq radius negative", "equilibrium_force", dict(radius=-5e-4), r"radius \(of the ball\) must be positive"),
    ("F_eq C negative", "equilibrium_force", dict(C=-1.0), r"C \(the Fung stiffness"),
    ("r_mid radius negative", "midplane_radius", dict(radius=-5e-4), r"radius \(of the ball\) must be positive"),
    ("r_mid displacement nan", "midplane_radius", dict(d=np.nan), r"displacement \(the total approach.*finite"),
    ("r_mid displacement negative", "midplane_radius", dict(d=-1e-5), r"must not be negative"),
    ("r_mid past incompressible range", "midplane_radius", dict(d=0.9999e-3), r"beyond the incompressible midplane"),
    ("r_mid past diameter", "midplane_radius", dict(d=2e-3), r"smaller than the ball's diameter"),
    ("r_mid alpha negative", "midplane_radius", dict(alpha=-1.0), r"alpha \(the Fung stiffening exponent\)"),
    (
        "hertz negative",
        "hertz_force",
        dict(d=-1e-6),
        r"approach \(the total approach of the plates, in m\) must not be",
    ),
    ("hertz past diameter", "hertz_force", dict(d=2e-3), r"approach .*smaller than the ball's diameter"),
    ("hertz C zero", "hertz_force", dict(C=0.0), r"C \(the Fung stiffness"),
]


@pytest.mark.parametrize("fn, over, expected", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_traced_bad_input_raises_or_is_nan(fn, over, expected):
    run = _jitted(fn)
    args = _args(fn, over)
    if expected == NAN:
        out = np.asarray(run(*args))
        assert np.all(np.isnan(out)), f"{fn} under jit: expected the NaN flag, got {out}"
    else:
        with pytest.raises(Exception, match=expected):
            jax.block_until_ready(run(*args))


@pytest.mark.parametrize("fn", sorted({c[1] for c in CASES} - {"history", "inflate history"}))
def test_traced_good_input_gives_the_eager_number(fn):
    """The run-time checks stay silent for good values: the jitted result is the eager one."""
    args = _args(fn, {})
    run = _jitted(fn)
    out = np.asarray(run(*args))
    assert np.all(np.isfinite(out))
    assert np.allclose(out, np.asarray(run.__wrapped__(*args)), rtol=1e-8)  # the same function, eager


def test_the_brief_examples_no_longer_return_numbers():
    """issue 41: blastula.pressure gave -1.664 Pa for C = -1 and 15.39 Pa for alpha = -1, limit_point 122.5 Pa for
    alpha = -1, spheroid.force numbers past the diameter and the table and zeros for a negative approach."""
    p = _jitted("pressure")
    with pytest.raises(Exception, match=r"C \(the Fung stiffness"):
        jax.block_until_ready(p(*_args("pressure", dict(C=-1.0))))
    with pytest.raises(Exception, match=r"alpha \(the Fung"):
        jax.block_until_ready(p(*_args("pressure", dict(alpha=-1.0))))
    with pytest.raises(Exception, match=r"alpha \(the Fung"):
        jax.block_until_ready(_jitted("limit_point")(*_args("limit_point", dict(alpha=-1.0))))


def test_checks_keep_vmap_and_grad():
    good = jax.vmap(lambda c: bl.pressure(1.5, **{**SHELL, "C": c}))(jnp.array([100.0, 200.0]))
    assert np.allclose(np.asarray(good), [float(bl.pressure(1.5, **{**SHELL, "C": c})) for c in (100.0, 200.0)])
    with pytest.raises(Exception, match=r"C \(the Fung stiffness"):
        jax.block_until_ready(jax.vmap(lambda c: bl.pressure(1.5, **{**SHELL, "C": c}))(jnp.array([100.0, -1.0])))
    # grad through the checks: dp/dC = p/C (p is linear in C)
    g = float(jax.grad(lambda c: bl.pressure(1.5, **{**SHELL, "C": c}))(200.0))
    assert g == pytest.approx(float(bl.pressure(1.5, **SHELL)) / 200.0, rel=1e-12)
    kw = dict(radius=500e-6, alpha=0.2, branches=[(0.4, 200.0)], displacement=50e-6, ramp_time=0.2, equilibrium="hertz")
    gF = float(jax.grad(lambda c: sp.force(T, C=c, **kw)[-1])(150.0))
    assert gF == pytest.approx(float(sp.force(T, C=150.0, **kw)[-1]) / 150.0, rel=1e-10)  # F is linear in C
    with pytest.raises(Exception, match=r"alpha is outside the calibrated table"):
        jax.block_until_ready(
            jax.vmap(lambda a: sp.force(T, C=150.0, **{**kw, "alpha": a, "equilibrium": "fem"}))(jnp.array([0.2, 5.0]))
        )
