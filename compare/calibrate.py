r"""Tabulate the spheroid's dimensionless equilibrium master curves from static FE runs.

For an incompressible Fung ball of radius ``a0`` between frictionless plates, dimensional analysis
gives the equilibrium plate force and equator radius as

    F_eq / (C a0^2) = f(x; alpha),    r_mid / a0 = g(x; alpha),    x = delta / (2 a0),

(``delta`` the total approach, m; ``C`` in Pa). One static FE run per ``alpha``
(``fem.spheroid.compress(..., static=True)`` on a contact-edge-fitted level: the force is smooth in x,
no node-to-node jitter), run as two pieces (x up to ``x_small`` in fine steps, then to ``x_max``) whose
states ARE the table grid ``x`` (default 0, 0.0025 .. 0.01, 0.02 .. 0.36: no interpolation). The table is
written to ``reduced/data/spheroid_master.npz`` with arrays ``x`` (n_x,), ``alpha`` (n_a,), ``f`` and
``g`` (n_a, n_x), ``f_over_hertz`` h = f / ((32/3) x^1.5) (-> 1 as x -> 0; its leading correction grows
like sqrt(x): interpolate h in s = sqrt(x), not f in x), and ``metadata`` (JSON: mesh, command, kappa/C,
the discretisation error = max relative difference of f against an independent finer-level run at
``check_alphas``, and the residual of the small-x basis fit h = 1 + sum_k c_k s^k).

``python -m tissuemech.compare.calibrate [--out PATH] [--store DIR] [--n-x N] [--x-max X] [--alphas a,b,..]
[--mesh M] [--error-mesh M] [--check-alphas a,b,..] [--reference JSON]`` regenerates it through ``compare.batch``
(resumable with ``--store``). With ``--reference`` (converged Richardson forces, e.g. tests/data/plate_reference_levels1-3.json)
the metadata also gets ``model_error_rel`` = half the table's largest error against that reference (the relative
1-sigma error of F_eq that ``compare.fit`` adds with ``model_error="auto"``; the finer-level check alone does not
set it).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from tissuemech.reduced.material import hertz_plate_f

__all__ = [
    "MasterCurves",
    "tabulate",
    "table_grid",
    "smooth",
    "sqrt_basis",
    "write",
    "load",
    "reference_error",
    "DEFAULT_ALPHAS",
    "CHECK_ALPHAS",
    "DEFAULT_OUT",
]

DEFAULT_ALPHAS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.25, 1.5)
CHECK_ALPHAS = (0.0, 0.5, 1.0)
DEFAULT_OUT = Path(__file__).resolve().parent.parent / "reduced" / "data" / "spheroid_master.npz"
RADIUS, C_REF, KAPPA = 500e-6, 200.0, 2.2e9  # the seed's ball; kappa/C = 1.1e7 (nearly incompressible)


class MasterCurves(NamedTuple):
    """x = delta/(2 a0) (n_x,), alpha (n_a,), f = F_eq/(C a0^2) and g = r_mid/a0 (n_a, n_x)."""

    x: np.ndarray
    alpha: np.ndarray
    f: np.ndarray
    g: np.ndarray


def hertz_f(x: np.ndarray) -> np.ndarray:
    """Small-strain Hertz law in master-curve form: F/(C a0^2) = (32/3) x^1.5 (E* = 8 C)."""
    return hertz_plate_f(np.asarray(x, dtype=float))


def static_curve(
    *,
    alpha: float,
    x_max: float,
    mesh: Any = "default",
    radius: float = RADIUS,
    C: float = C_REF,
    kappa: float = KAPPA,
    n: int | None = None,
) -> dict:
    """One static FE run (module level, picklable): approach (m), force (N), midplane radius (m);
    ``n`` equal steps in the approach up to x_max (None: the default of ``compress``)."""
    from tissuemech.fem import spheroid as fem_spheroid

    r = fem_spheroid.compress(
        radius=radius,
        C=C,
        alpha=alpha,
        branches=(),
        displacement=2 * radius * x_max,
        ramp_time=1.0,
        end_time=1.0,
        kappa=kappa,
        mesh=mesh,
        static=True,
        n_static=n,
    )
    return {
        "approach": np.asarray(r.approach),
        "force": np.asarray(r.force),
        "midplane_radius": np.asarray(r.midplane_radius),
        "radius": radius,
        "C": C,
    }


def _to_master(run: Any, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a0, C = float(run["radius"]), float(run["C"])
    xs = np.asarray(run["approach"]) / (2 * a0)
    order = np.argsort(xs)
    xs = xs[order]
    if xs[-1] < x[-1] * (1 - 1e-9):
        raise RuntimeError(
            f"the static FE run stopped at x = delta/(2 a0) = {xs[-1]:.4g} before the "
            f"table end {x[-1]:.4g}. Hint: reduce x_max or refine the load stepping."
        )
    f = np.interp(x, np.r_[0.0, xs], np.r_[0.0, np.asarray(run["force"])[order] / (C * a0**2)])
    g = np.interp(x, np.r_[0.0, xs], np.r_[1.0, np.asarray(run["midplane_radius"])[order] / a0])
    return f, g


def table_grid(n_x: int = 37, x_max: float = 0.36, x_small: float = 0.01, n_small: int = 4) -> np.ndarray:
    """0, then n_small steps to x_small, then equal steps x_small apart... to x_max (n_x points from x_small
    on when x_max / x_small = n_x - 1): the states of the two static runs, i.e. the table grid."""
    main = np.linspace(0.0, x_max, n_x)[1:]
    small = np.linspace(0.0, x_small, n_small + 1)[1:] if 0 < x_small < main[0] * (1 + 1e-12) else np.array([])
    return np.unique(np.r_[0.0, small[small < main[0] * (1 - 1e-9)], main])


def tabulate(
    *,
    alphas: Sequence[float] = DEFAULT_ALPHAS,
    n_x: int = 37,
    x_max: float = 0.36,
    x_small: float = 0.01,
    n_small: int = 4,
    mesh: Any = 2,
    executor: Any = None,
    store: str | None = None,
    curve: Callable[..., Any] = static_curve,
) -> MasterCurves:
    """Static FE curves per alpha (through ``compare.batch``): one run to x_max in n_x - 1 equal steps and
    one to x_small in n_small steps (skipped if n_small = 0); f, g on ``table_grid`` (the run states)."""
    from tissuemech.compare import batch

    if not 0 < x_max < 0.5:
        raise ValueError(f"x_max = delta/(2 a0) must be in (0, 0.5); got {x_max}")
    if any(a < 0 for a in alphas):
        raise ValueError("alpha must be >= 0 (0 is neo-Hookean)")
    x = table_grid(n_x, x_max, x_small if n_small else 0.0, n_small)
    jobs = [dict(alpha=float(a), x_max=float(x_max), mesh=mesh, n=n_x - 1) for a in alphas]
    if n_small and x[1] < x_max / (n_x - 1) * (1 - 1e-9):
        jobs += [dict(alpha=float(a), x_max=float(x_small), mesh=mesh, n=n_small) for a in alphas]
    if curve is not static_curve:  # a user/fake curve may not take n
        jobs = [{k: v for k, v in j.items() if k != "n"} for j in jobs]
    runs = batch.run(curve, jobs, executor=executor, store=store)
    failed = [j for j, r in zip(jobs, runs, strict=True) if r is None]
    if failed:
        raise RuntimeError(
            f"calibration: {len(failed)} FE curve(s) failed, first {failed[0]}; rerun with the same store to retry"
        )
    done = [r for r in runs if r is not None]
    na = len(alphas)
    fg = []
    for i in range(na):
        parts = [done[i]] + ([done[na + i]] if len(done) > na else [])
        merged = {
            "approach": np.concatenate([p["approach"] for p in parts]),
            "force": np.concatenate([p["force"] for p in parts]),
            "midplane_radius": np.concatenate([p["midplane_radius"] for p in parts]),
            "radius": parts[0]["radius"],
            "C": parts[0]["C"],
        }
        fg.append(_to_master(merged, x))
    return MasterCurves(x, np.asarray(alphas, dtype=float), np.array([a for a, _ in fg]), np.array([b for _, b in fg]))


def sqrt_basis(x: np.ndarray, degree: int) -> np.ndarray:
    """Columns s^k, k = 1..degree, s = sqrt(x): the small-x basis of h = f / f_Hertz - 1."""
    s = np.sqrt(np.maximum(np.asarray(x, float), 0.0))
    return np.stack([s**k for k in range(1, degree + 1)], axis=1)


def smooth(curves: MasterCurves, degree: int = 8) -> tuple[MasterCurves, float]:
    """Least-squares fits in s = sqrt(x) (per alpha) that keep the exact small-strain limits:

        f / f_Hertz = 1 + sum_{k=1..degree} c_k s^k,   g = 1 + sum_{k=1..degree/2+1} d_k x^k.

    The basis contains the true small-x behaviour of a finite ball between plates (f / f_Hertz - 1 grows
    like sqrt(x), physics: the finite-size correction to the half-space Hertz law). With the fitted-edge
    FE the data are smooth already; the returned max relative change of f is the fit residual (a check that
    the basis represents the curves, not a noise filter). Returns (smoothed curves, max relative change of f)."""
    x = curves.x
    pos = x > 0
    xp = x[pos]
    Vf, Vf_all = sqrt_basis(xp, degree), sqrt_basis(x, degree)
    Vg = np.stack([x**k for k in range(1, degree // 2 + 2)], axis=1)
    f_s, g_s = np.empty_like(curves.f), np.empty_like(curves.g)
    for i in range(len(curves.alpha)):
        ratio = curves.f[i, pos] / hertz_f(xp)
        c = np.linalg.lstsq(Vf, ratio - 1.0, rcond=None)[0]
        f_s[i] = hertz_f(x) * (1.0 + Vf_all @ c)
        d = np.linalg.lstsq(Vg, curves.g[i] - 1.0, rcond=None)[0]
        g_s[i] = 1.0 + Vg @ d
    change = float(np.max(np.abs(f_s[:, pos] / curves.f[:, pos] - 1.0)))
    return MasterCurves(x, curves.alpha, f_s, g_s), change


def write(path: str | Path, curves: MasterCurves, metadata: dict, raw: MasterCurves | None = None) -> None:
    """Write the table (and ``f_over_hertz``) with JSON metadata to an npz file."""
    x = curves.x
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(x > 0, curves.f / hertz_f(x), np.nan)
    if x[0] == 0:  # the Hertz limit of a ball between plates (h - 1 ~ sqrt(x) -> 0)
        ratio[:, 0] = 1.0
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    extra = {} if raw is None else dict(f_raw=raw.f, g_raw=raw.g)
    np.savez(
        path,
        x=x,
        alpha=curves.alpha,
        f=curves.f,
        g=curves.g,
        f_over_hertz=ratio,
        metadata=np.asarray(json.dumps(metadata)),
        **extra,  # type: ignore[arg-type]  # numpy stubs: savez **kwds typed as the allow_pickle bool
    )


def load(path: str | Path = DEFAULT_OUT) -> tuple[MasterCurves, dict]:
    """Read a master-curve table: (MasterCurves, metadata dict)."""
    with np.load(path, allow_pickle=False) as z:
        return MasterCurves(z["x"], z["alpha"], z["f"], z["g"]), json.loads(str(z["metadata"]))


def reference_error(table: str | Path, reference: dict) -> tuple[float, str]:
    """Largest |f_table / f_ref - 1| of a written table over converged reference points: (error, point name).

    ``reference``: {"alpha A x X": {"reference": f_ref, ...}, ...} (f = F_eq/(C a0^2); the format of
    ``compare.bench.fem_spheroid.reference``; other keys are ignored), e.g. tests/data/plate_reference_levels1-3.json.
    Points outside the table's x or alpha range are skipped. Raises ValueError when none is inside.
    """
    from tissuemech.reduced import spheroid

    mc = spheroid.master_curve(str(table))
    curves, _ = load(table)
    worst, at = -1.0, ""
    for name, v in reference.items():
        parts = name.split()
        if len(parts) != 4 or parts[0] != "alpha" or parts[2] != "x" or not isinstance(v, dict):
            continue
        a, x = float(parts[1]), float(parts[3])
        if not (curves.alpha.min() <= a <= curves.alpha.max() and 0 < x <= curves.x.max()):
            continue
        e = abs(float(mc.f(x, a)) / float(v["reference"]) - 1.0)
        if e > worst:
            worst, at = e, name
    if worst < 0:
        raise ValueError("the reference has no point 'alpha A x X' inside the table's x and alpha range")
    return worst, at


if __name__ == "__main__":  # kept: python -m tissuemech.compare.calibrate is tissuemech calibrate
    from tissuemech.compare.cli.calibrate import main

    raise SystemExit(main())
