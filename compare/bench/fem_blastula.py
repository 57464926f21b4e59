"""Benchmark of the FE blastula: accuracy vs the exact solution, convergence table, seed sets, speed.

``python -m tissuemech.compare.bench fem-blastula [--quick] [--figure PATH.png]`` prints the tables. The exact reference is the
incompressible thick-shell integral of docs/physics.md (scipy quad + brentq); for the creep table
(``fem.blastula.creep``, issue 5's ramp-and-hold) it is the reduced viscoelastic shell ``reduced.viscoshell``. Timings exclude imports and
the first (warm-up) call; the machine is shared, so they are pessimistic.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.optimize import minimize_scalar

from tissuemech.compare.cases import BLASTULA_C, BLASTULA_INNER_RADIUS
from tissuemech.compare.reference import shell_inner_stretch, shell_pressure
from tissuemech.fem.blastula import LimitPointError, creep, inflate

A, C = BLASTULA_INNER_RADIUS, BLASTULA_C


def p_exact(la: float, B: float, alpha: float) -> float:
    """Exact pressure (Pa) at inner stretch la, outer radius B (m): ``compare.reference.shell_pressure``."""
    return shell_pressure(la, outer_radius=B, alpha=alpha)


def la_exact(p: float, B: float, alpha: float) -> float:
    """Exact inner stretch at pressure p (Pa): ``compare.reference.shell_inner_stretch``."""
    return shell_inner_stretch(p, outer_radius=B, alpha=alpha)


def _err(r, B, alpha):
    """Relative inner-stretch error (load control) or pressure error p_exact(la_FE)/p_FE - 1 (arc-length)."""
    if r.method == "arclength":
        k = r.pressure > 0
        return np.abs(np.array([p_exact(l, B, alpha) for l in r.inner_stretch[k]]) / r.pressure[k] - 1)
    ex = np.array([la_exact(p, B, alpha) if p > 0 else 1.0 for p in r.pressure])
    return np.abs(r.inner_stretch / ex - 1)


def speed(repeats: int = 5) -> None:
    ps = np.linspace(20.0, 1000.0, 50)
    kw = dict(inner_radius=A, outer_radius=75e-6, C=C, alpha=0.2, pressures=ps)
    inflate(**kw)  # warm-up
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        r = inflate(**kw)
        times.append(time.perf_counter() - t)
    e = _err(r, 75e-6, 0.2)
    print("\n## Speed: alpha = 0.2, B = 75 um, 0 -> 1 kPa in 50 equal steps, default mesh (4 x 8 Q2/P1disc)")
    print(f"wall time  min {min(times):.3f} s  median {np.median(times):.3f} s  ({repeats} runs)")
    print(
        f"Newton iterations {r.newton_iterations.sum()} in total; max |inner stretch error| {e.max():.2e}"
        f" (at 200/500/1000 Pa: {_err(inflate(**{**kw, 'pressures': [200.0, 500.0, 1000.0]}), 75e-6, 0.2)})"
    )


def convergence(quick: bool) -> None:
    meshes = [(2, 4), (3, 6), (4, 8), (8, 16)] if not quick else [(2, 4), (4, 8), (8, 16)]
    kappas = [2.2e5, 2.2e7, 2.2e9]
    ps = [200.0, 500.0, 1000.0]
    ex = np.array([la_exact(p, 75e-6, 0.2) for p in ps])
    lam = {}
    for k in kappas:
        for m in meshes:
            lam[k, m] = inflate(
                inner_radius=A, outer_radius=75e-6, C=C, alpha=0.2, pressures=ps, mesh=m, kappa=k
            ).inner_stretch
    print("\n## Convergence (alpha = 0.2, B = 75 um): max over p in {200, 500, 1000} Pa of relative error")
    print(
        "total = |FE/exact - 1|; mesh = |FE(mesh)/FE(finest) - 1| at the same kappa; "
        "kappa = |FE(finest)/exact - 1| (the compressibility error)"
    )
    print(f"{'kappa/C':>8} {'mesh':>8} {'total':>10} {'mesh err':>10} {'kappa err':>10}")
    for k in kappas:
        fine = lam[k, meshes[-1]]
        for m in meshes:
            tot = np.abs(lam[k, m] / ex - 1).max()
            me = np.abs(lam[k, m] / fine - 1).max()
            ke = np.abs(fine / ex - 1).max()
            print(f"{k / C:8.0e} {str(m):>8} {tot:10.2e} {me:10.2e} {ke:10.2e}")


def seed_sets() -> None:
    print("\n## Seed parameter sets (load control 0 -> 1 kPa in 20 steps, default mesh)")
    print(
        f"{'B (um)':>6} {'alpha':>6} {'final p (Pa)':>12} {'inner stretch':>13} {'outer':>8} {'max rel err*':>12} {'time (s)':>8}  note"
    )
    for B, alpha in [(75e-6, 1e-5), (75e-6, 0.1), (75e-6, 0.2), (75e-6, 0.3), (52e-6, 0.2), (60e-6, 0.2)]:
        t = time.perf_counter()
        note = ""
        try:
            r = inflate(inner_radius=A, outer_radius=B, C=C, alpha=alpha, pressures=np.linspace(50, 1000, 20))
        except LimitPointError as e:
            note = f"limit point: load control stopped at {e.last_converged:.4g} Pa"
            r = inflate(
                inner_radius=A,
                outer_radius=B,
                C=C,
                alpha=alpha,
                pressures=None,
                method="arclength",
                max_inner_stretch=3.0,
            )
            note += "; arc-length from 0 to inner stretch 3 (err* = pressure error on the traced curve)"
        dt = time.perf_counter() - t
        print(
            f"{B * 1e6:6.0f} {alpha:6.0e} {r.pressure[-1]:12.2f} {r.inner_stretch[-1]:13.6f} "
            f"{r.outer_stretch[-1]:8.5f} {_err(r, B, alpha).max():12.2e} {dt:8.2f}  {note}"
        )


def limit_point() -> None:
    print("\n## Neo-Hookean (alpha = 1e-5) limit point by arc-length, default mesh")
    print(
        f"{'B (um)':>6} {'exact p_max':>11} {'FE p_max':>10} {'rel err':>9} {'exact la*':>9} {'traced to':>9} {'steps':>5} {'time':>6}"
    )
    for B in [52e-6, 60e-6, 75e-6]:
        o = minimize_scalar(
            lambda l: -p_exact(l, B, 1e-5), bounds=(1.01, 4.0), method="bounded", options={"xatol": 1e-10}
        )
        t = time.perf_counter()
        r = inflate(
            inner_radius=A,
            outer_radius=B,
            C=C,
            alpha=1e-5,
            pressures=None,
            method="arclength",
            max_inner_stretch=1.25 * o.x,
        )
        dt = time.perf_counter() - t
        print(
            f"{B * 1e6:6.0f} {-o.fun:11.4f} {r.pressure.max():10.4f} {r.pressure.max() / -o.fun - 1:9.1e} "
            f"{o.x:9.4f} {r.inner_stretch[-1]:9.4f} {len(r.pressure):5d} {dt:6.2f}"
        )
    try:
        inflate(inner_radius=A, outer_radius=75e-6, C=C, alpha=1e-5, pressures=np.linspace(10, 200, 20))
    except LimitPointError as e:
        print("load control message:", str(e).split(" (load level")[0])


def creep_table(quick: bool) -> None:
    """Issue 5 creep (alpha = 0.2, beta = 0.5, tau = 100 s, 300 Pa in 1 s, held 600 s), B = 75 um:
    max |lambda_FE / lambda_reduced - 1| over the history vs mesh and number of hold steps, FE wall time."""
    from tissuemech.reduced import viscoshell as vs

    kw = dict(
        inner_radius=A,
        outer_radius=75e-6,
        C=C,
        alpha=0.2,
        branches=[(0.5, 100.0)],
        pressure=300.0,
        ramp_time=1.0,
        end_time=601.0,
    )
    meshes = ["coarse", "default"] if quick else ["coarse", "default", "fine"]
    holds = [30, 60] if quick else [15, 30, 60, 120]
    creep(**kw, mesh="coarse", n_hold=5)  # warm-up
    runs = {}
    for m in meshes:
        for n in holds:
            t = time.perf_counter()
            r = creep(**kw, mesh=m, n_hold=n)
            runs[m, n] = (r, time.perf_counter() - t)
    ts = np.unique(np.concatenate([r.time for r, _ in runs.values()]))
    red = vs.inflate(
        ts,
        pressure=300.0,
        ramp_time=1.0,
        **{k: kw[k] for k in ("inner_radius", "outer_radius", "C", "alpha", "branches")},
    )
    la_red = np.asarray(red.inner_stretch)
    print(
        "\n## Creep (fem.blastula.creep vs reduced.viscoshell): alpha = 0.2, beta = 0.5, tau = 100 s, "
        "300 Pa in 1 s (8 ramp steps), held 600 s"
    )
    print(
        f"{'mesh':>8} {'n_hold':>6} {'steps':>5} {'Newton':>6} {'max dev':>9} {'ramp':>9} {'hold':>9} "
        f"{'la(601 s)':>9} {'wall (s)':>8}"
    )
    for (m, n), (r, w) in runs.items():
        d = np.abs(r.inner_stretch / la_red[np.searchsorted(ts, r.time)] - 1)
        ramp = r.time <= 1.0
        print(
            f"{m:>8} {n:6d} {r.time.size:5d} {r.newton_iterations.sum():6d} {d.max():9.2e} {d[ramp].max():9.2e} "
            f"{d[~ramp].max():9.2e} {r.inner_stretch[-1]:9.5f} {w:8.2f}"
        )


def figure(path: str) -> None:
    """Seed Fig. 3: von Mises on the deformed section, alpha = 0.2, B = 75 um, p = 1 kPa (+ VTU)."""
    import matplotlib

    matplotlib.use("Agg")
    r = inflate(inner_radius=A, outer_radius=75e-6, C=C, alpha=0.2, pressures=np.linspace(100, 1000, 10), mesh="fine")
    ax = r.plot()
    ax.set_title("von Mises stress, alpha = 0.2, p = 1 kPa")
    ax.figure.savefig(path, dpi=120, bbox_inches="tight")
    r.to_vtu(path.rsplit(".", 1)[0] + ".vtu")
    print(f"\nwrote {path} and the VTU; von Mises range {r.von_mises.min():.0f} .. {r.von_mises.max():.0f} Pa")


def main(argv: list[str] | None = None) -> int:
    """Options: --quick (fewer meshes/repeats), --figure PATH.png (seed Fig. 3 + VTU)."""
    import argparse

    ap = argparse.ArgumentParser(
        prog="python -m tissuemech.compare.bench fem-blastula", description=__doc__.split("\n")[0]
    )
    ap.add_argument("--quick", action="store_true", help="fewer meshes and repeats")
    ap.add_argument("--figure", metavar="PATH.png", help="also write the seed's Fig. 3 (and a VTU next to it)")
    a = ap.parse_args(list(argv or []))
    quick = a.quick
    print("# FE blastula benchmark (fem.blastula.inflate; A = 50 um, C = 200 Pa, kappa = 2.2 GPa unless stated)")
    speed(3 if quick else 5)
    convergence(quick)
    seed_sets()
    limit_point()
    creep_table(quick)
    if a.figure:
        figure(a.figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
