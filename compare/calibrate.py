r"""Tabulate the spheroid's dimensionless equilibrium master curves from static FE runs.

For an incompressible Fung ball of radius ``a0`` between frictionless plates, dimensional analysis
gives the equilibrium plate force and equator radius as

    F_eq / (C a0^2) = f(x; alpha),    r_mid / a0 = g(x; alpha),    x = delta / (2 a0),

(``delta`` the total approach, m; ``C`` in Pa). One static FE run per ``alpha``
(``fem.spheroid.compress(..., static=True)``, the whole curve from 0 to ``delta``) is interpolated
onto a grid ``x`` in ``[0, x_max]`` (default 0.3). The table is written to
``reduced/data/spheroid_master.npz`` with arrays ``x`` (n_x,), ``alpha`` (n_a,), ``f`` and ``g``
(n_a, n_x), ``f_over_hertz`` = f / ((32/3) x^1.5) (smooth, -> 1 as x -> 0; interpolate this, not
``f``, whose x-derivative is singular at 0), and ``metadata`` (JSON: mesh, command, kappa/C, the
estimated discretisation error = max relative difference of f between the mesh and a coarser one).

``python -m tissuemech.compare.calibrate [--out PATH] [--store DIR] [--n-x N] [--alphas a,b,..] [--mesh M]
[--error-mesh M]`` regenerates it through ``compare.batch`` (resumable with ``--store``).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

__all__ = ["MasterCurves", "tabulate", "smooth", "write", "load", "main", "DEFAULT_ALPHAS", "DEFAULT_OUT"]

DEFAULT_ALPHAS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0)
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
    return (32.0 / 3.0) * np.asarray(x, dtype=float) ** 1.5


def static_curve(
    *, alpha: float, x_max: float, mesh: Any = "default", radius: float = RADIUS, C: float = C_REF, kappa: float = KAPPA
) -> dict:
    """One static FE run (module level, picklable): approach (m), force (N), midplane radius (m)."""
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


def tabulate(
    *,
    alphas: Sequence[float] = DEFAULT_ALPHAS,
    n_x: int = 31,
    x_max: float = 0.3,
    mesh: Any = "default",
    executor: Any = None,
    store: str | None = None,
    curve: Callable[..., Any] = static_curve,
) -> MasterCurves:
    """Run one static FE curve per alpha (through ``compare.batch``) and tabulate f, g on x in [0, x_max]."""
    from tissuemech.compare import batch

    if not 0 < x_max < 0.5:
        raise ValueError(f"x_max = delta/(2 a0) must be in (0, 0.5); got {x_max}")
    if any(a < 0 for a in alphas):
        raise ValueError("alpha must be >= 0 (0 is neo-Hookean)")
    x = np.linspace(0.0, x_max, n_x)
    runs = batch.run(
        curve, [dict(alpha=float(a), x_max=float(x_max), mesh=mesh) for a in alphas], executor=executor, store=store
    )
    fg = [_to_master(r, x) for r in runs]
    return MasterCurves(x, np.asarray(alphas, dtype=float), np.array([a for a, _ in fg]), np.array([b for _, b in fg]))


def _xlogx(x: np.ndarray) -> np.ndarray:
    return np.where(x > 0, x * np.log(np.where(x > 0, x, 1.0)), 0.0)


def smooth(curves: MasterCurves, degree: int = 3) -> tuple[MasterCurves, float]:
    """Least-squares fits in x (per alpha) that keep the exact small-strain limits:

        f / f_Hertz = 1 + c_0 x ln x + sum_{k=1..degree} c_k x^k,   g = 1 + sum_{k=1..degree+1} d_k x^k.

    (The x ln x term is the finite-ball correction to the half-space Hertz law; with it the fit
    residual is at the FE's own contact-discretisation noise, ~0.3 %, from nodes entering contact one
    at a time.) The noise is removed, so dF_eq/ddelta, which drives the Maxwell branches, is smooth.
    Returns (smoothed curves, max relative change of f)."""
    x = curves.x
    pos = x > 0
    xp = x[pos]
    Vf = np.stack([_xlogx(xp)] + [xp**k for k in range(1, degree + 1)], axis=1)
    Vf_all = np.stack([_xlogx(x)] + [x**k for k in range(1, degree + 1)], axis=1)
    Vg = np.stack([x**k for k in range(1, degree + 2)], axis=1)
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
    if x[0] == 0 and len(x) > 2:  # x -> 0 limit: extrapolate linearly from the first two positive nodes
        ratio[:, 0] = 2 * ratio[:, 1] - ratio[:, 2]
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
        **extra,
    )


def load(path: str | Path = DEFAULT_OUT) -> tuple[MasterCurves, dict]:
    """Read a master-curve table: (MasterCurves, metadata dict)."""
    with np.load(path, allow_pickle=False) as z:
        return MasterCurves(z["x"], z["alpha"], z["f"], z["g"]), json.loads(str(z["metadata"]))


def _count(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if v < 2:
        raise argparse.ArgumentTypeError(f"must be at least 2, got {v}")
    return v


def _fraction(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0 < v < 0.8:
        raise argparse.ArgumentTypeError(f"must be in (0, 0.8), got {v}")
    return v


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tissuemech.compare.calibrate``: tabulate F_eq and r_mid from static FE runs (see --help)."""
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.calibrate", description=__doc__.split("\n")[0])
    ap.add_argument(
        "--out",
        default="spheroid_master.npz",
        help="table to write (default: %(default)s in the current folder; the shipped table "
        f"{DEFAULT_OUT} is replaced only with --install)",
    )
    ap.add_argument("--install", action="store_true", help="write the shipped table reduced/data/spheroid_master.npz")
    ap.add_argument("--store", default=None, help="folder for per-run results (resume)")
    ap.add_argument(
        "--n-x", type=_count, default=31, help="points in x = delta/(2 a0) per alpha (default: %(default)s)"
    )
    ap.add_argument(
        "--x-max",
        type=_fraction,
        default=0.3,
        help="largest x = delta/(2 a0) of the table, in (0, 0.8) (default: %(default)s)",
    )
    ap.add_argument(
        "--alphas",
        default=",".join(str(a) for a in DEFAULT_ALPHAS),
        help="comma list of Fung exponents alpha >= 0 to tabulate (default: %(default)s)",
    )
    ap.add_argument(
        "--mesh", default="3", help="FE mesh of the table: a fem.spheroid level or name (default: %(default)s)"
    )
    ap.add_argument(
        "--error-mesh", default="fine", help="coarser mesh for the error estimate ('' to skip; default: %(default)s)"
    )
    ap.add_argument("--degree", type=int, default=3, help="degree of the smoothing polynomials in x (0: none)")
    a = ap.parse_args(list(sys.argv[1:] if argv is None else argv))
    try:
        alphas = [float(v) for v in a.alphas.split(",")]
    except ValueError:
        ap.error(f"--alphas must be a comma list of numbers, got {a.alphas!r}")
    if any(not (v >= 0) for v in alphas):
        ap.error(f"--alphas must be >= 0, got {a.alphas!r}")
    if a.install:
        a.out = str(DEFAULT_OUT)
    a.mesh = int(a.mesh) if str(a.mesh).isdigit() else a.mesh  # "fine" or a level number of fem.spheroid
    a.error_mesh = int(a.error_mesh) if str(a.error_mesh).isdigit() else a.error_mesh
    kw = dict(alphas=alphas, n_x=a.n_x, x_max=a.x_max)
    raw = tabulate(mesh=a.mesh, store=a.store, **kw)
    curves, change = smooth(raw, a.degree) if a.degree > 0 else (raw, 0.0)
    err = None
    if a.error_mesh:
        coarse = tabulate(mesh=a.error_mesh, store=a.store, **kw)
        err = float(np.max(np.abs(coarse.f[:, 1:] / raw.f[:, 1:] - 1.0)))
    meta = dict(
        mesh=a.mesh,
        error_mesh=a.error_mesh or None,
        discretisation_error_f=err,
        smoothing_degree=a.degree,
        smoothing_max_change_f=change,
        command="python -m tissuemech.compare.calibrate " + " ".join(sys.argv[1:] if argv is None else argv),
        radius_m=RADIUS,
        C_Pa=C_REF,
        kappa_Pa=KAPPA,
        definition="f = F_eq/(C a0^2), g = r_mid/a0, x = delta/(2 a0) (total approach delta)",
    )
    write(a.out, curves, meta, raw=raw)
    print(
        f"wrote {a.out}: {len(curves.alpha)} alphas x {len(curves.x)} points; "
        f"estimated discretisation error of f: {err if err is not None else 'not estimated'}; "
        f"smoothing changed f by at most {change:.2e}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
