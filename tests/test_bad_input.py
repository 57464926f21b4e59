"""No silent wrong number: bad or extreme inputs at every public entry point and the CLI.

Every case asserts the exception type and that the message names the quantity (its keyword, or the
word the message uses for it). ``CASES`` is also what ``notes/issue13_sweep.py`` runs to count the
outcomes (clear error / other error / unclear error / silent result) before and after issue 13.
"""

from __future__ import annotations

import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tissuemech.reduced  # noqa: F401  (float64)
from tissuemech.compare import batch, fit, scan
from tissuemech.compare.cli import main as cli_main
from tissuemech.reduced import blastula as bl
from tissuemech.reduced import spheroid as sp
from tissuemech.reduced import viscoshell as vs

SHELL = dict(inner_radius=50e-6, outer_radius=75e-6, C=200.0, alpha=0.2)
GEO = dict(inner_radius=50e-6, outer_radius=75e-6)
BALL = dict(radius=500e-6, C=150.0, alpha=0.2, branches=[(0.4, 200.0)], displacement=50e-6, ramp_time=0.2)
T = np.array([0.0, 0.1, 0.2, 10.0])
VS = dict(pressure=100.0, **GEO, C=200.0, alpha=0.0, branches=[(1.0, 10.0)])


def kw(base, **over):
    out = dict(base)
    out.update(over)
    return out


def _p(**over):
    a = kw(SHELL, **over)
    x = a.pop("x", 1.5)
    return lambda: bl.pressure(x, **a)


def _force(t=T, fn=sp.force, **over):
    return lambda: fn(t, **kw(BALL, **over))


def _vs(t=(0.0, 1.0), **over):
    return lambda: vs.inflate(np.asarray(t) if not isinstance(t, str) else t, **kw(VS, **over))


def _scan_sph(**over):
    a = dict(n=2, times=np.array([0.0, 0.1, 0.2, 10.0]))
    a.update(over)
    return lambda: scan.spheroid(**a)


def _scan_bl(**over):
    a = dict(n=2)
    a.update(over)
    return lambda: scan.blastula(**a)


def _fem_inflate(**over):
    from tissuemech.fem.blastula import inflate

    a = kw(dict(**SHELL, pressures=[100.0], mesh="coarse"), **over)
    return lambda: inflate(**a)


def _fem_creep(**over):
    from tissuemech.fem.blastula import creep

    a = kw(dict(**SHELL, branches=[(0.5, 100.0)], pressure=50.0, ramp_time=1.0, end_time=10.0, mesh="coarse"), **over)
    a.pop("x", None)
    return lambda: creep(**a)


def _fem_compress(**over):
    from tissuemech.fem.spheroid import compress

    a = kw(dict(**BALL, end_time=10.0, mesh="coarse"), **over)
    return lambda: compress(**a)


ramp50 = lambda t: 50e-6 * jnp.minimum(t / 0.2, 1.0)

E = ValueError
CASES = [
    # ---- reduced.blastula.pressure
    ("pressure text", _p(x="abc"), E, "inner_stretch"),
    ("pressure None", _p(x=None), E, "inner_stretch"),
    ("pressure nan", _p(x=np.nan), E, "inner_stretch"),
    ("pressure inf", _p(x=np.inf), E, "inner_stretch"),
    ("pressure negative", _p(x=-1.0), E, "inner_stretch"),
    ("pressure zero", _p(x=0.0), E, "inner_stretch"),
    ("pressure list with text", _p(x=[1.0, "a"]), E, "inner_stretch"),
    ("pressure bool", _p(x=True), E, "inner_stretch"),
    ("pressure complex", _p(x=1.5 + 1j), E, "inner_stretch"),
    ("pressure dict", _p(x={"a": 1}), E, "inner_stretch"),
    ("pressure C None", _p(C=None), E, "C"),
    ("pressure C text", _p(C="x"), E, "C"),
    ("pressure C negative", _p(C=-1.0), E, "C"),
    ("pressure C nan", _p(C=np.nan), E, "C"),
    ("pressure C zero", _p(C=0.0), E, "C"),
    ("pressure alpha negative", _p(alpha=-0.1), E, "alpha"),
    ("pressure alpha text", _p(alpha="a"), E, "alpha"),
    ("pressure alpha None", _p(alpha=None), E, "alpha"),
    ("pressure alpha inf", _p(alpha=np.inf), E, "alpha"),
    ("pressure inner_radius negative", _p(inner_radius=-1.0), E, "inner_radius"),
    ("pressure inner_radius text", _p(inner_radius="x"), E, "inner_radius"),
    ("pressure inner_radius None", _p(inner_radius=None), E, "inner_radius"),
    ("pressure outer_radius nan", _p(outer_radius=np.nan), E, "outer_radius"),
    ("pressure radii swapped", _p(inner_radius=80e-6), E, "inner_radius must be smaller"),
    ("pressure method", _p(method="riks"), E, "method"),
    ("pressure method number", _p(method=5), E, "method"),
    ("pressure overflow", _p(x=100.0), E, "float64"),
    ("pressure overflow alpha", _p(x=10.0, alpha=20.0), E, "float64"),
    # ---- pressure_derivative, outer_stretch, limit_point, inner_stretch, profiles
    ("dp text", lambda: bl.pressure_derivative("abc", **SHELL), E, "inner_stretch"),
    ("dp nan", lambda: bl.pressure_derivative(np.nan, **SHELL), E, "inner_stretch"),
    ("dp C text", lambda: bl.pressure_derivative(1.2, **kw(SHELL, C="x")), E, "C"),
    ("outer_stretch text", lambda: bl.outer_stretch("abc", **GEO), E, "inner_stretch"),
    ("outer_stretch negative", lambda: bl.outer_stretch(-1.0, **GEO), E, "inner_stretch"),
    (
        "outer_stretch radius text",
        lambda: bl.outer_stretch(1.2, inner_radius="x", outer_radius=75e-6),
        E,
        "inner_radius",
    ),
    ("limit_point C None", lambda: bl.limit_point(**kw(SHELL, C=None)), E, "C"),
    ("limit_point alpha text", lambda: bl.limit_point(**kw(SHELL, alpha="a")), E, "alpha"),
    ("limit_point radii", lambda: bl.limit_point(**kw(SHELL, inner_radius=1e-3)), E, "inner_radius"),
    ("inner_stretch text", lambda: bl.inner_stretch("abc", **SHELL), E, "pressure"),
    ("inner_stretch None", lambda: bl.inner_stretch(None, **SHELL), E, "pressure"),
    ("inner_stretch nan", lambda: bl.inner_stretch(np.nan, **SHELL), E, "pressure"),
    ("inner_stretch inf", lambda: bl.inner_stretch(np.inf, **SHELL), E, "pressure"),
    ("inner_stretch burst", lambda: bl.inner_stretch(1000.0, **kw(SHELL, alpha=0.0)), E, "limit pressure"),
    ("inner_stretch too deflated", lambda: bl.inner_stretch(-1e7, **SHELL), E, "smallest inner stretch"),
    ("inner_stretch C text", lambda: bl.inner_stretch(50.0, **kw(SHELL, C="x")), E, "C"),
    ("profiles n text", lambda: bl.profiles(1.2, **SHELL, n="a"), E, "n"),
    ("profiles n fraction", lambda: bl.profiles(1.2, **SHELL, n=2.5), E, "whole number"),
    ("profiles n one", lambda: bl.profiles(1.2, **SHELL, n=1), E, "at least 2"),
    ("profiles n None", lambda: bl.profiles(1.2, **SHELL, n=None), E, "n"),
    ("profiles stretch nan", lambda: bl.profiles(np.nan, **SHELL), E, "inner_stretch"),
    # ---- reduced.viscoshell.inflate
    ("vs t text", _vs(t="a"), E, "t"),
    ("vs t descending", _vs(t=[1.0, 0.0]), E, "ascending"),
    ("vs t negative", _vs(t=[-1.0, 0.0]), E, "t "),
    ("vs t 2-D", _vs(t=[[0.0, 1.0]]), E, "1-D"),
    ("vs t nan", _vs(t=[0.0, np.nan]), E, "t "),
    ("vs t empty", _vs(t=[]), E, "empty"),
    ("vs pressure text", _vs(pressure="x"), E, "pressure"),
    ("vs pressure nan", _vs(pressure=np.nan), E, "pressure"),
    ("vs pressure None", _vs(pressure=None), E, "pressure"),
    ("vs pressure array", _vs(pressure=[1.0, 2.0]), E, "pressure"),
    ("vs pressure history nan", _vs(pressure=lambda t: t * jnp.nan), E, "pressure history"),
    ("vs pressure history inf", _vs(pressure=lambda t: 1.0 / (t - 0.5)), E, "pressure history"),
    ("vs branches int", _vs(branches=5), E, "branches"),
    ("vs branches text beta", _vs(branches=[("a", 200.0)]), E, "beta"),
    ("vs branches single", _vs(branches=[(0.4,)]), E, "pair"),
    ("vs branches tau negative", _vs(branches=[(0.4, -1.0)]), E, "tau"),
    ("vs branches text", _vs(branches="ab"), E, "branches"),
    ("vs C text", _vs(C="x"), E, "C"),
    ("vs rtol negative", _vs(rtol=-1.0), E, "rtol"),
    ("vs max_steps fraction", _vs(max_steps=2.5), E, "max_steps"),
    ("vs ramp_time negative", _vs(ramp_time=-1.0), E, "ramp_time"),
    ("vs ramp_time text", _vs(ramp_time="x"), E, "ramp_time"),
    ("vs instantaneous burst", _vs(pressure=1000.0), E, "instantaneous"),
    # ---- reduced.spheroid.force / nominal_stress
    ("force t text", _force(t="a"), E, "t "),
    ("force t negative", _force(t=[-1.0, 0.0]), E, "t "),
    ("force t nan", _force(t=[0.0, np.nan]), E, "t "),
    ("force t empty", _force(t=[]), E, "t "),
    ("force radius text", _force(radius="x"), E, "radius"),
    ("force radius negative", _force(radius=-1.0), E, "radius"),
    ("force C None", _force(C=None), E, "C"),
    ("force alpha text", _force(alpha="a"), E, "alpha"),
    ("force alpha past table", _force(alpha=5.0), E, "alpha"),
    ("force branches int", _force(branches=5), E, "branches"),
    ("force branches text beta", _force(branches=[("a", 200.0)]), E, "beta"),
    ("force branches tau zero", _force(branches=[(0.4, 0.0)]), E, "tau"),
    ("force displacement text", _force(displacement="x"), E, "displacement"),
    ("force displacement negative", _force(displacement=-1e-5), E, "displacement"),
    ("force displacement nan", _force(displacement=np.nan), E, "displacement"),
    ("force displacement past diameter", _force(displacement=1.2e-3), E, "diameter"),
    ("force displacement past table", _force(displacement=4e-4), E, "calibrated table"),
    ("force ramp_time None", _force(ramp_time=None), E, "ramp_time"),
    ("force ramp_time negative", _force(ramp_time=-1.0), E, "ramp_time"),
    ("force equilibrium name", _force(equilibrium="foo"), E, "equilibrium"),
    ("force method", _force(method="x"), E, "method"),
    ("force rtol negative", _force(rtol=-1.0), E, "rtol"),
    ("force max_steps text", _force(max_steps="a"), E, "max_steps"),
    ("force jump_times nan", _force(displacement=ramp50, jump_times=[np.nan]), E, "jump_times"),
    ("history starts at 50 um", _force(displacement=lambda t: 50e-6 * jnp.exp(-t)), E, r"delta\(0\)"),
    (
        "history unloads fast",
        _force(
            t=np.linspace(0.0, 2.0, 21),
            displacement=lambda t: ramp50(t) * jnp.exp(-jnp.maximum(t - 0.2, 0.0) / 0.05),
            equilibrium="hertz",
        ),
        E,
        "lose contact",
    ),
    ("history past diameter", _force(displacement=lambda t: 1.2e-3 * t / 10.0, equilibrium="hertz"), E, "diameter"),
    ("history past table", _force(displacement=lambda t: 4e-4 * t / 10.0), E, "calibrated table"),
    ("history nan", _force(displacement=lambda t: t * jnp.nan), E, "displacement history"),
    ("history negative", _force(displacement=lambda t: -1e-6 * t, equilibrium="hertz"), E, "negative"),
    ("stress midplane name", _force(fn=sp.nominal_stress, midplane="foo", equilibrium="hertz"), E, "midplane"),
    ("stress C text", _force(fn=sp.nominal_stress, C="x"), E, "C"),
    ("stress displacement past diameter", _force(fn=sp.nominal_stress, displacement=2e-3), E, "diameter"),
    # ---- equilibrium_force / midplane_radius
    ("F_eq nan", lambda: sp.equilibrium_force(np.nan, radius=500e-6, C=150.0, alpha=0.2), E, "displacement"),
    ("F_eq negative", lambda: sp.equilibrium_force(-5e-5, radius=500e-6, C=150.0, alpha=0.2), E, "displacement"),
    ("F_eq text", lambda: sp.equilibrium_force("x", radius=500e-6, C=150.0, alpha=0.2), E, "displacement"),
    (
        "F_eq past diameter",
        lambda: sp.equilibrium_force(2e-3, radius=500e-6, C=150.0, alpha=0.2, equilibrium="hertz"),
        E,
        "diameter",
    ),
    ("F_eq radius negative", lambda: sp.equilibrium_force(5e-5, radius=-5e-4, C=150.0, alpha=0.2), E, "radius"),
    ("F_eq C text", lambda: sp.equilibrium_force(5e-5, radius=5e-4, C="x", alpha=0.2), E, "C"),
    (
        "F_eq equilibrium name",
        lambda: sp.equilibrium_force(5e-5, radius=5e-4, C=150.0, alpha=0.2, equilibrium="x"),
        E,
        "equilibrium",
    ),
    ("r_mid radius negative", lambda: sp.midplane_radius(50e-6, radius=-5e-4), E, "radius"),
    ("r_mid displacement nan", lambda: sp.midplane_radius(np.nan, radius=5e-4), E, "displacement"),
    ("r_mid displacement negative", lambda: sp.midplane_radius(-1e-5, radius=5e-4), E, "displacement"),
    ("r_mid past diameter", lambda: sp.midplane_radius(2e-3, radius=5e-4), E, "diameter"),
    ("r_mid alpha negative", lambda: sp.midplane_radius(5e-5, radius=5e-4, alpha=-1.0), E, "alpha"),
    ("r_mid midplane name", lambda: sp.midplane_radius(5e-5, radius=5e-4, midplane="foo"), E, "midplane"),
    # ---- compare.scan
    ("scan approach past diameter", _scan_sph(displacement=(1e-4, 1.2e-3), equilibrium="hertz"), E, "diameter"),
    ("scan approach past table", _scan_sph(displacement=(1e-4, 4e-4)), E, "calibrated table"),
    ("scan alpha past table", _scan_sph(alpha=(0.0, 5.0)), E, "alpha"),
    ("scan times descending", _scan_sph(times=np.array([0.0, 2.0, 1.0])), E, "times"),
    ("scan times nan", _scan_sph(times=np.array([0.0, np.nan, 1.0])), E, "times"),
    ("scan times repeated", _scan_sph(times=np.array([0.0, 1.0, 1.0])), E, "times"),
    ("scan times one", _scan_sph(times=np.array([1.0])), E, "times"),
    ("scan n text", _scan_sph(n="a"), E, "n "),
    ("scan n zero", _scan_sph(n=0), E, "n "),
    ("scan n fraction", _scan_bl(n=2.5), E, "n "),
    ("scan batch_size zero", _scan_sph(batch_size=0), E, "batch_size"),
    ("scan design method", _scan_sph(design_method="foo"), E, "design method"),
    ("scan C range text", _scan_sph(C=("a", 2.0)), E, "C"),
    ("scan C text", _scan_sph(C="x"), E, "C"),
    ("scan end_time negative", _scan_sph(times=None, end_time=-1.0), E, "end_time"),
    ("scan end_time in ramp", _scan_sph(times=None, end_time=0.1), E, "end_time"),
    ("scan huge design", _scan_sph(C=(100.0, 200.0), tau=(10.0, 100.0), n=10_000), E, "GiB"),
    ("scan beta negative", _scan_sph(beta=-1.0), E, "beta"),
    ("scan tau zero", _scan_sph(tau=0.0), E, "tau"),
    ("scan fe_checks negative", _scan_sph(fe_checks=-1), E, "fe_checks"),
    ("scan equilibrium name", _scan_sph(equilibrium="foo"), E, "equilibrium"),
    ("scan points nan", _scan_sph(points={"C": [100.0, np.nan]}), E, "C"),
    ("scan bl pressure text", _scan_bl(pressure=("a", 1.0)), E, "pressure"),
    ("scan bl pressure nan", _scan_bl(pressure=np.nan), E, "pressure"),
    ("scan bl radii", _scan_bl(inner_radius=(80e-6, 90e-6)), E, "inner_radius must be smaller"),
    ("scan bl alpha negative", _scan_bl(alpha=-1.0), E, "alpha"),
    ("scan bl huge design", _scan_bl(C=(100.0, 200.0), pressure=(0.0, 10.0), n=20_000), E, "GiB"),
    ("design n zero", lambda: scan.design({"C": (1.0, 2.0)}, n=0), E, "n "),
    ("design method", lambda: scan.design({"C": (1.0, 2.0)}, n=2, method="x"), E, "design method"),
    ("design range reversed", lambda: scan.design({"C": (5.0, 1.0)}, n=2), E, "range of C"),
    ("design log negative", lambda: scan.design({"C": (-1.0, 1.0)}, n=2, log=["C"]), E, "log scale"),
    # ---- fem (each fails before any FE work)
    ("fem pressures text", _fem_inflate(pressures=["a"]), E, "pressures"),
    ("fem pressures nan", _fem_inflate(pressures=[np.nan]), E, "pressures"),
    ("fem pressures None", _fem_inflate(pressures=None), E, "pressures"),
    ("fem pressures decreasing", _fem_inflate(pressures=[100.0, 50.0]), E, "sorted"),
    ("fem method", _fem_inflate(method="riks"), E, "method"),
    ("fem C text", _fem_inflate(C="x"), E, "C"),
    ("fem kappa negative", _fem_inflate(kappa=-1.0), E, "kappa"),
    ("fem mesh", _fem_inflate(mesh="huge"), E, "mesh"),
    ("fem formulation", _fem_inflate(formulation="x"), E, "formulation"),
    ("fem max_inner_stretch text", _fem_inflate(method="arclength", max_inner_stretch="x"), E, "max_inner_stretch"),
    ("fem creep pressure nan", _fem_creep(pressure=np.nan), E, "pressure"),
    ("fem creep ramp negative", _fem_creep(ramp_time=-1.0), E, "ramp_time"),
    ("fem creep end before ramp", _fem_creep(end_time=0.5), E, "end_time"),
    ("fem creep n_ramp fraction", _fem_creep(n_ramp=2.5), E, "n_ramp"),
    ("fem creep branches int", _fem_creep(branches=5), E, "branches"),
    ("fem compress C text", _fem_compress(C="x"), E, "C"),
    ("fem compress branches int", _fem_compress(branches=5), E, "branches"),
    ("fem compress radius negative", _fem_compress(radius=-1.0), E, "radius"),
    # ---- compare.fit.read_csv, compare.batch
    ("read_csv displacement", lambda: fit.read_csv("x.csv", displacement=-1.0), E, "displacement"),
    ("batch executor", lambda: batch.run(abs, [dict(x=1)], executor="cloud", progress=False), E, "executor"),
    ("batch points", lambda: batch.run(abs, 5, executor="serial", progress=False), E, "points"),
    ("batch function", lambda: batch.run(3, [dict(x=1)], executor="serial", progress=False), E, "function"),
]


@pytest.mark.parametrize("call, exc, words", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_names_the_quantity(call, exc, words):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(exc, match=words):
            call()


def test_enough_cases():
    assert len(CASES) + len(CLI_CASES) >= 120


# ---------------------------------------------------------------- CLI: exit code 2 and a one-line message

CLI_CASES = [
    (["blastula", "--step", "1e-9"], "--step"),
    (["blastula", "--C", "abc"], "--C"),
    (["blastula", "--C", "-1"], "--C"),
    (["blastula", "--max-pressure", "nan"], "--max-pressure"),
    (["blastula", "--inner-radius-um", "0"], "--inner-radius-um"),
    (["spheroid", "--alpha", "-1"], "--alpha"),
    (["spheroid", "--tau", "0"], "--tau"),
    (["spheroid", "--displacement-um", "2000"], "diameter"),
    (["spheroid", "--displacement-um", "400"], "--equilibrium hertz"),
    (["spheroid", "--equilibrium", "foo"], "--equilibrium"),
    (["spheroid", "--radius-um", "x"], "--radius-um"),
    (["spheroid", "--end-time", "0"], "--end-time"),
]


@pytest.mark.parametrize("argv, words", CLI_CASES, ids=[" ".join(a) for a, _ in CLI_CASES])
def test_cli_bad_arguments_exit_2(argv, words, capsys, tmp_path):
    argv = argv + ["--out", str(tmp_path / "x.png")]
    try:
        code = cli_main(argv)
    except SystemExit as e:  # argparse
        code = e.code
    err = capsys.readouterr().err
    assert code == 2
    assert words in err
    assert "Traceback" not in err


# ---------------------------------------------------------------- the documented flags inside jit, and warnings


def test_jit_nan_flag_where_one_panel_cannot_resolve():
    f = jax.jit(lambda x, a: bl.pressure(x, **GEO, C=200.0, alpha=a))
    assert np.isnan(float(f(2.0, 50.0)))  # eager: 4.894e109 Pa, see test_properties
    assert np.isclose(float(f(2.0, 50.0 * 0 + 0.2)), float(bl.pressure(2.0, **GEO, C=200.0, alpha=0.2)), rtol=1e-13)
    la, ok = bl.inner_stretch_solve(float(bl.pressure(3.0, **GEO, C=200.0, alpha=5.0)), **GEO, C=200.0, alpha=5.0)
    assert not bool(ok) and np.isnan(float(la))
    # the eager inverse solves it to full accuracy
    assert float(bl.inner_stretch(float(bl.pressure(3.0, **GEO, C=200.0, alpha=5.0)), **GEO, C=200.0, alpha=5.0)) == (
        pytest.approx(3.0, rel=1e-12)
    )


def test_viscoshell_jit_bad_times_give_nan_not_a_callback_error():
    f = jax.jit(lambda t: vs.inflate(t, **VS).inner_stretch)
    assert np.all(np.isnan(np.asarray(f(jnp.array([0.0, 2.0, 1.0])))))
    good = np.asarray(f(jnp.array([0.0, 1.0, 2.0])))
    assert np.all(np.isfinite(good)) and np.all(good > 1.0)


def test_displacement_formulation_warns_about_locking():
    from tissuemech.fem.blastula import LockingWarning

    with pytest.warns(LockingWarning, match="kappa/C"):
        with pytest.raises(ValueError, match="mesh"):  # the warning comes before any FE work
            _fem_inflate(formulation="displacement", mesh="huge")()


def test_good_callable_history_still_works():
    f = sp.force(T, **kw(BALL, displacement=ramp50, equilibrium="hertz"))
    g = sp.force(T, **kw(BALL, equilibrium="hertz"))
    assert np.allclose(np.asarray(f), np.asarray(g), rtol=1e-6)


def test_read_csv_space_separated_without_header_keeps_first_row(tmp_path):
    t = np.linspace(0.0, 10.0, 11)
    y = 100.0 * np.exp(-t / 3.0)
    f = tmp_path / "r.txt"
    np.savetxt(f, np.c_[t, y])
    rec = fit.read_csv(str(f), displacement=50e-6)
    assert rec.time.size == 11 and rec.time[0] == 0.0 and rec.nominal_stress[0] == pytest.approx(100.0)
