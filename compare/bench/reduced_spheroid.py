"""Benchmark of the reduced spheroid (``reduced.spheroid``): one relaxation curve and a scan of
many, against a convolution-quadrature reference and a SciPy ``solve_ivp`` baseline.

    python -m tissuemech.compare.bench.reduced_spheroid [--n 10000]

Rows: compile time, curves per second after compile (best of a few calls, ``block_until_ready``),
the max error relative to the curve's peak force (Hertz law: the convolution quadrature is exact for
it; the calibrated law: against its own rtol 1e-12 solution), the baseline (``scipy.integrate.solve_ivp``,
LSODA at rtol 1e-10, one curve at a time, the same lumped ODE) and the speed-up.

Then the public API as a user calls it (issue 14), each figure a ratio of medians of interleaved calls
in the same run: ``force`` / ``nominal_stress`` under ``jax.jit`` with a traced time array against the
eager call (``jit/eager``, target <= 1), and eager ``equilibrium_force`` / ``midplane_radius`` against
the same call under ``jax.jit`` at 1e6 points (``eager/jit``, target <= 1.5), with the eager per-call
cost at N = 1 (target <= 100 us). NumPy inputs in both, the calibrated FE law (the default).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Sequence

import jax.numpy as jnp
import numpy as np
from scipy.integrate import quad, solve_ivp

from tissuemech.compare.bench.common import jit_timed as _timed
from tissuemech.compare.bench.common import print_rows
from tissuemech.compare.reference import hertz_force

A0, D, TR, END = 500e-6, 50e-6, 0.2, 1500.0
TIMES = np.concatenate([np.linspace(0.0, TR, 21), np.geomspace(TR, END, 180)[1:]])  # 200 output times


def _hertz(delta, C):
    return hertz_force(delta, radius=A0, C=C)


def reference(t: float, C: float, beta: float, tau: float) -> float:
    """F(t) by adaptive quadrature of q = beta int_0^min(t,tr) e^{-(t-s)/tau} dF_eq/ds ds."""
    s = min(t, TR)
    rate = D / TR
    q = quad(
        lambda u: beta * 1.5 * _hertz(rate * u, C) / u * np.exp(-(s - u) / tau) if u > 0 else 0.0,
        0.0,
        s,
        epsabs=0,
        epsrel=1e-13,
        limit=200,
    )[0]
    return _hertz(rate * s, C) + q * np.exp(-max(t - TR, 0.0) / tau)


def _scipy_curve(C: float, beta: float, tau: float) -> np.ndarray:
    """The same lumped ODE with solve_ivp (LSODA), two segments (ramp, hold)."""
    rate = D / TR

    def rhs(t, q):
        d = rate * min(t, TR)
        dfe = 1.5 * _hertz(d, C) / d * rate if (0 < t < TR) else 0.0
        return [-q[0] / tau + beta * dfe]

    ramp = TIMES[TIMES <= TR]
    hold = TIMES[TIMES > TR]
    s1 = solve_ivp(rhs, (0.0, TR), [0.0], t_eval=ramp, method="LSODA", rtol=1e-10, atol=1e-16)
    s2 = solve_ivp(rhs, (TR, END), [s1.y[0, -1]], t_eval=hold, method="LSODA", rtol=1e-10, atol=1e-16)
    q = np.concatenate([s1.y[0], s2.y[0]])
    return _hertz(D * np.minimum(TIMES / TR, 1.0), C) + q


def rows(n: int = 10_000, n_ref: int = 20, seed: int = 0) -> list[dict]:
    import diffrax

    from tissuemech.reduced import spheroid as sp

    rng = np.random.default_rng(seed)
    out = []
    kw = dict(radius=A0, alpha=0.2, displacement=D, ramp_time=TR)
    T = jnp.asarray(TIMES)

    def one(C, beta, tau, method="quadrature", solver=None, equilibrium="hertz"):  # Hertz: the reference is exact
        return sp.force(T, C=C, branches=[(beta, tau)], method=method, solver=solver, equilibrium=equilibrium, **kw)

    # one curve, the Fig. 10 case
    ref = np.array([reference(t, 150.0, 0.4, 200.0) for t in TIMES])
    t0 = time.perf_counter()
    base = _scipy_curve(150.0, 0.4, 200.0)
    t_base = time.perf_counter() - t0
    for label, m, solver in (
        ("quadrature", "quadrature", None),
        ("ode Kvaerno5", "ode", diffrax.Kvaerno5()),
        ("ode Tsit5", "ode", diffrax.Tsit5()),
    ):
        tc, dt, F = _timed(lambda c, b, t_: one(c, b, t_, m, solver), 150.0, 0.4, 200.0, repeats=5)
        out.append(
            dict(
                path=f"spheroid.force one curve, {label}",
                points=1,
                compile_s=tc,
                points_per_s=1 / dt,
                max_rel_err=float(np.max(np.abs(np.asarray(F) - ref)) / ref.max()),
                baseline="scipy solve_ivp LSODA",
                baseline_points_per_s=1 / t_base,
                speedup=t_base / dt,
                baseline_err=float(np.max(np.abs(base - ref)) / ref.max()),
            )
        )

    # scans: n curves over (C, beta, tau) in one vmapped call; tau from 0.1 s (stiff-ish) to 1000 s
    Cs = jnp.asarray(rng.uniform(100.0, 300.0, n))
    bs = jnp.asarray(rng.uniform(0.0, 1.5, n))
    ts = jnp.asarray(10 ** rng.uniform(-1.0, 3.0, n))
    idx = rng.choice(n, n_ref, replace=False)
    refs = {int(i): np.array([reference(t, float(Cs[i]), float(bs[i]), float(ts[i])) for t in TIMES]) for i in idx}
    t0 = time.perf_counter()
    for i in idx[:5]:
        _scipy_curve(float(Cs[i]), float(bs[i]), float(ts[i]))
    base_rate = 5 / (time.perf_counter() - t0)
    for label, m, solver in (
        ("quadrature", "quadrature", None),
        ("ode Kvaerno5", "ode", diffrax.Kvaerno5()),
        ("ode Tsit5", "ode", diffrax.Tsit5()),
    ):
        tc, dt, G = _timed(lambda c, b, t_: one(c, b, t_, m, solver), Cs, bs, ts, repeats=2)
        err = max(np.max(np.abs(np.asarray(G[i]) - r)) / r.max() for i, r in refs.items())
        out.append(
            dict(
                path=f"spheroid.force scan {n} curves x {TIMES.size} times, {label}",
                points=n,
                compile_s=tc,
                points_per_s=n / dt,
                max_rel_err=float(err),
                baseline="scipy solve_ivp LSODA loop",
                baseline_points_per_s=base_rate,
                speedup=n / dt / base_rate,
            )
        )
    # the calibrated FE law (the default): quadrature vs its own tight ODE solution
    tc, dt, G3 = _timed(lambda c, b, t_: one(c, b, t_, "quadrature", None, "fem"), Cs, bs, ts, repeats=2)
    sub = np.asarray(idx[:5])
    ref3 = np.asarray(
        sp.force(
            T, C=Cs[sub], branches=[(bs[sub], ts[sub])], equilibrium="fem", method="ode", rtol=1e-12, atol=1e-12, **kw
        )
    )
    out.append(
        dict(
            path="  same scan, calibrated FE law, quadrature",
            points=n,
            compile_s=tc,
            points_per_s=n / dt,
            max_rel_err=float(np.max(np.abs(np.asarray(G3)[sub] - ref3) / ref3.max(axis=1)[:, None])),
            baseline="scipy solve_ivp LSODA loop",
            baseline_points_per_s=base_rate,
            speedup=n / dt / base_rate,
        )
    )
    return out + api_rows()


def _interleaved(fns: Sequence, repeats: int) -> list[float]:
    """Median seconds per call of each function, called in turn (warm-up first), block_until_ready."""
    import jax

    for fn in fns:
        jax.block_until_ready(fn())
    times: list[list[float]] = [[] for _ in fns]
    for _ in range(repeats):
        for i, fn in enumerate(fns):
            t0 = time.perf_counter()
            jax.block_until_ready(fn())
            times[i].append(time.perf_counter() - t0)
    return [float(np.median(t)) for t in times]


def api_rows(n_curves: int = 2000, n_points: int = 1_000_000, repeats: int = 7, seed: int = 0) -> list[dict]:
    """Eager vs jit of the public functions (issue 14 targets), ratios from interleaved medians."""
    import jax

    from tissuemech.reduced import spheroid as sp

    rng = np.random.default_rng(seed)
    out = []
    kw = dict(radius=A0, alpha=0.2, displacement=D, ramp_time=TR, branches=[(0.4, 200.0)])
    for fn in (sp.force, sp.nominal_stress):
        for label, C in (("1 curve", 150.0), (f"{n_curves} curves", rng.uniform(100.0, 300.0, n_curves))):
            jitted = jax.jit(lambda t, c, fn=fn: fn(t, C=c, **kw))
            te, tj = _interleaved(
                [lambda fn=fn, C=C: fn(TIMES, C=C, **kw), lambda jitted=jitted, C=C: jitted(TIMES, C)],
                repeats,  # 2000 curves (issue 40): ~0.4 s a call; fewer repeats left +-20 % noise in the ratio
            )
            out.append(
                dict(
                    path=f"spheroid.{fn.__name__} jit(traced t) vs eager, {label} x {TIMES.size} times",
                    eager_s=te,
                    jit_s=tj,
                    ratio=tj / te,
                    target="jit/eager <= 1",
                )
            )
    d = rng.uniform(0.0, 150e-6, n_points)
    one = 100e-6
    cases = (
        ("equilibrium_force", lambda v: sp.equilibrium_force(v, radius=A0, C=150.0, alpha=0.2), "fem"),
        (
            "equilibrium_force",
            lambda v: sp.equilibrium_force(v, radius=A0, C=150.0, alpha=0.2, equilibrium="hertz"),
            "hertz",
        ),
        ("midplane_radius", lambda v: sp.midplane_radius(v, radius=A0, alpha=0.2, midplane="fem"), "fem"),
        ("midplane_radius", lambda v: sp.midplane_radius(v, radius=A0, alpha=0.2), "incompressible"),
    )
    for name, fn, law in cases:
        jitted = jax.jit(fn)
        jax.block_until_ready(jitted(d))
        t0 = time.perf_counter()
        jax.block_until_ready(jitted(d))
        # enough interleaved calls for ~0.3 s per function: a median of 7 calls of ~1 ms moved the ratio by +-0.3
        n_rep = int(np.clip(0.3 / max(time.perf_counter() - t0, 1e-6), repeats, 300))
        te, tj = _interleaved([lambda fn=fn: fn(d), lambda jitted=jitted: jitted(d)], n_rep)
        te1, tj1 = _interleaved([lambda fn=fn: fn(one), lambda jitted=jitted: jitted(one)], 200)
        out.append(
            dict(
                path=f"spheroid.{name} ({law}) eager vs jit",
                points=n_points,
                eager_s=te,
                jit_s=tj,
                ratio=te / tj,
                target="eager/jit <= 1.5; N=1 <= 100 us",
                eager_us_at_1=te1 * 1e6,
                jit_us_at_1=tj1 * 1e6,
            )
        )
    return out


def main(argv: Sequence[str] | None = None) -> list[dict]:
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench.reduced_spheroid", description=__doc__)
    ap.add_argument("--n", type=int, default=10_000, help="curves in the scan (default %(default)s)")
    a = ap.parse_args(argv)
    r = rows(a.n)
    print_rows(r)
    return r


if __name__ == "__main__":
    main()
