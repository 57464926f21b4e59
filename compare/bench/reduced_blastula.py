"""Benchmark of the reduced blastula paths (``reduced.blastula``, ``reduced.viscoshell``).

    python -m tissuemech.compare.bench.reduced_blastula [--n 1000000] [--baseline 2000]

Each row: the path, points per call, compile time, throughput after compile (points/s, best of a
few calls with ``block_until_ready``), the max relative error against a high-accuracy reference,
and the plain-SciPy baseline (a ``scipy.integrate.quad`` loop; ``brentq`` on it for the inverse)
with the speed-up. Timings on a shared 2-core CPU are pessimistic.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable, Sequence

import jax.numpy as jnp
import numpy as np
from scipy.optimize import brentq

from tissuemech.compare.bench.common import jit_timed as _timed
from tissuemech.compare.bench.common import print_rows
from tissuemech.compare.cases import BLASTULA_C, BLASTULA_INNER_RADIUS, FIG4_OUTER_RADIUS
from tissuemech.compare.reference import shell_pressure

A, B, C = BLASTULA_INNER_RADIUS, FIG4_OUTER_RADIUS, BLASTULA_C


def _quad_pressure(la: float, A: float, B: float, C: float, alpha: float) -> float:
    return shell_pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=alpha)


def _scipy_rate(fn: Callable, items) -> float:
    t0 = time.perf_counter()
    for it in items:
        fn(*it)
    return len(items) / (time.perf_counter() - t0)


def rows(n: int = 1_000_000, n_baseline: int = 2000, seed: int = 0) -> list[dict]:
    from tissuemech.reduced import blastula as bl
    from tissuemech.reduced import viscoshell as vs

    rng = np.random.default_rng(seed)
    out: list[dict] = []
    alpha = 0.2
    geo = dict(inner_radius=A, outer_radius=B)

    # -- forward, quadrature path: random stretch in [1, 4] and alpha in [0, 0.3]
    la = jnp.asarray(rng.uniform(1.0, 4.0, n))
    al = jnp.asarray(rng.uniform(0.0, 0.3, n))
    tc, dt, p = _timed(lambda x, a: bl.pressure(x, **geo, C=C, alpha=a), la, al)
    idx = rng.choice(n, n_baseline, replace=False)
    items = [(float(la[i]), A, B, C, float(al[i])) for i in idx]
    ref = np.array([_quad_pressure(*it) for it in items])
    err = float(np.max(np.abs(np.asarray(p)[idx] / ref - 1)))
    base = _scipy_rate(_quad_pressure, items)
    out.append(
        dict(
            path="blastula.pressure quadrature",
            points=n,
            compile_s=tc,
            points_per_s=n / dt,
            max_rel_err=err,
            baseline="scipy quad loop",
            baseline_points_per_s=base,
            speedup=n / dt / base,
        )
    )

    # -- inverse (rising branch): Fung alpha = 0.2 over lambda_a in [0.5, 4]; neo-Hookean below the limit
    for a_inv, hi in ((alpha, 4.0), (0.0, float(bl.limit_point(**geo, C=C, alpha=0.0).inner_stretch) - 1e-3)):
        la = jnp.asarray(rng.uniform(0.5, hi, n))
        pt = bl.pressure(la, **geo, C=C, alpha=a_inv)
        tc, dt, la_inv = _timed(lambda q: bl.inner_stretch(q, **geo, C=C, alpha=a_inv), pt, repeats=2)
        err = float(np.nanmax(np.abs(np.asarray(la_inv) / np.asarray(la) - 1)))
        nb = max(n_baseline // 10, 20)
        sub = [(float(pt[i]), float(la[i])) for i in idx[:nb]]

        def brent(pv: float, _la: float, a_=a_inv, hi_=hi) -> float:
            f = lambda x: _quad_pressure(x, A, B, C, a_) - pv
            return brentq(f, 0.5, hi_ + 1e-3, xtol=1e-14, rtol=1e-14)

        base = _scipy_rate(brent, sub)
        out.append(
            dict(
                path=f"blastula.inner_stretch (alpha={a_inv:g})",
                points=n,
                compile_s=tc,
                points_per_s=n / dt,
                max_rel_err=err,
                baseline="brentq on quad",
                baseline_points_per_s=base,
                speedup=n / dt / base,
            )
        )

    # -- diffrax radial-ODE path (vmapped), error against the quadrature
    m = max(n // 50, 1000)
    la = jnp.asarray(rng.uniform(1.0, 4.0, m))
    tc, dt, p_ode = _timed(lambda x: bl.pressure(x, **geo, C=C, alpha=alpha, method="ode"), la, repeats=2)
    p_q = bl.pressure(la, **geo, C=C, alpha=alpha)
    err = float(np.max(np.abs(np.asarray(p_ode) / np.asarray(p_q) - 1)))
    out.append(
        dict(
            path="blastula.pressure ode (Dopri8, vmap)",
            points=m,
            compile_s=tc,
            points_per_s=m / dt,
            max_rel_err=err,
            baseline="scipy quad loop",
            baseline_points_per_s=base_fwd(out),
            speedup=m / dt / base_fwd(out),
        )
    )

    # -- limit point (scan + bisection), vmapped over alpha x B
    nl = 10_000
    al = jnp.asarray(rng.uniform(0.0, 0.05, nl))
    Bs = jnp.asarray(rng.uniform(52e-6, 100e-6, nl))
    tc, dt, lim = _timed(lambda a, b: bl.limit_point(inner_radius=A, outer_radius=b, C=C, alpha=a), al, Bs)
    out.append(
        dict(
            path="blastula.limit_point",
            points=nl,
            compile_s=tc,
            points_per_s=nl / dt,
            max_rel_err="",
            baseline="",
            baseline_points_per_s="",
            speedup="",
        )
    )

    # -- 1e6-point parameter grid (stretch x alpha x B) in one call, by broadcasting
    g = round(n ** (1 / 3))
    la_g = jnp.linspace(1.0, 4.0, g)[:, None, None]
    al_g = jnp.linspace(0.0, 0.3, g)[None, :, None]
    B_g = jnp.linspace(52e-6, 150e-6, g)[None, None, :]
    tc, dt, grid = _timed(lambda x, a, b: bl.pressure(x, inner_radius=A, outer_radius=b, C=C, alpha=a), la_g, al_g, B_g)
    ok = bool(np.all(np.isfinite(np.asarray(grid))))
    out.append(
        dict(
            path=f"pressure grid {g}x{g}x{g} (la x alpha x B)",
            points=g**3,
            compile_s=tc,
            points_per_s=g**3 / dt,
            max_rel_err="" if ok else "non-finite",
            baseline="",
            baseline_points_per_s="",
            speedup="",
        )
    )

    # -- viscoelastic shell: one creep history (step, held 60 tau), after compile
    t = jnp.linspace(0.0, 12_000.0, 61)
    kw = dict(pressure=150.0, **geo, C=C, alpha=alpha, branches=[(1.2, 200.0)])
    t0 = time.perf_counter()
    run = vs.inflate(t, **kw)
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    run = vs.inflate(t, **kw)
    t_run = time.perf_counter() - t0
    relaxed = float(bl.inner_stretch(150.0, **geo, C=C, alpha=alpha))
    out.append(
        dict(
            path="viscoshell.inflate (1 branch, 61 outputs)",
            points=1,
            compile_s=t_first - t_run,
            points_per_s=1 / t_run,
            max_rel_err=abs(float(run.inner_stretch[-1]) / relaxed - 1),
            baseline="vs relaxed elastic limit",
            baseline_points_per_s="",
            speedup="",
        )
    )
    return out


def base_fwd(rows_so_far: list[dict]) -> float:
    return rows_so_far[0]["baseline_points_per_s"]


def main(argv: Sequence[str] | None = None) -> list[dict]:
    import tissuemech.reduced  # noqa: F401  (x64)

    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench.reduced_blastula")
    ap.add_argument("--n", type=int, default=1_000_000, help="points per vectorised call")
    ap.add_argument("--baseline", type=int, default=2000, help="points in the scipy quad loop")
    args = ap.parse_args(list(argv) if argv is not None else None)
    r = rows(args.n, args.baseline)
    print_rows(r)
    return r


if __name__ == "__main__":
    main()
