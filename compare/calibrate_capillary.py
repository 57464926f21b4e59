r"""Tabulate the elastocapillary equilibrium law of the spheroid from static FE runs with a surface tension.

A Fung ball (``C`` Pa, ``alpha``) of radius ``a0`` with a surface tension ``gamma`` (N/m, non-wetting plates:
contact angle 180 deg) between frictionless plates has, by dimensional analysis,

    F_eq / (C a0^2) = f(x; alpha, Gamma),    x = delta / (2 a0),    Gamma = gamma / (C a0)

(the elastocapillary number). Default grid: Gamma = 0, 0.1, 0.2, 0.4, 0.6, 1, 2 (the fitted FE edge does not start
beyond ~2 yet), alpha = 0, 0.5, 1, x = 0 .. 0.3 on mesh level 1. The table stores the coupling ratio

    R(x; alpha, Gamma) = f / (f_plate(x; alpha) + Gamma d(x)),

``f_plate`` the tension-free plate law at the same mesh level and ``d(x) = F_drop / (gamma a0)`` the exact liquid
drop between the plates (``reduced.drop``). R = 1 at Gamma = 0 (the plate table) and R -> 1 as Gamma -> inf
(the drop: C -> 0); a purely additive law (elastic force + drop force) would have R = 1 everywhere. Taking the
ratio at ONE mesh level cancels most of the mesh's error: the reduced law
(``reduced.capillary.Capillary``) multiplies R by the shipped, finer plate table plus Gamma d(x).

One static FE run per (alpha, Gamma) to ``x_max`` plus one to ``x_small`` (``fem.spheroid.compress(static=True,
surface_tension=...)`` on a contact-edge-fitted level), and the same pair without tension per alpha; their states
are the table grid (``compare.calibrate.table_grid``: no interpolation; x = 0, 0.02 .. 0.3 by default, ``n_small`` > 0
adds a run to ``x_small`` whose states refine the start: at strong tension its first tiny step does not start yet). Written to
``reduced/data/capillary_master.npz``: arrays ``x`` (n_x,), ``alpha`` (n_a,), ``gamma`` (n_g: Gamma = gamma /
(C a0) nodes, from 0), ``ratio`` R (n_g, n_a, n_x), ``drop`` d(x) at ``drop_x`` (121 points uniform in sqrt(x): the reduced law's spline; at
the table's x: ``drop_nodes``), ``f`` (n_g, n_a, n_x: the FE's f),
``metadata`` (JSON: mesh, command, timing, ``check``: the relative change of f = R (f_plate + Gamma d) at the
check points when the ratio is taken on the finer level ``error_mesh``, the table's discretisation error).

``python -m tissuemech.compare.calibrate_capillary [--out PATH] [--store DIR] [--mesh M] [--error-mesh M]
[--gammas g,..] [--alphas a,..] [--x-max X] [--n-x N] [--check a:G,..]`` regenerates it (resumable with ``--store``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from tissuemech.compare.calibrate import table_grid

__all__ = [
    "capillary_curve",
    "tabulate",
    "drop_curve",
    "write",
    "main",
    "DEFAULT_GAMMAS",
    "DEFAULT_ALPHAS",
    "DEFAULT_OUT",
    "RADIUS",
    "C_REF",
    "KAPPA",
]

# Gamma = gamma / (C a0) nodes (the fitted FE edge starts up to ~2)
DEFAULT_GAMMAS = (0.0, 0.1, 0.2, 0.4, 0.6, 1.0, 2.0)
DEFAULT_ALPHAS = (0.0, 0.5, 1.0)
DEFAULT_OUT = Path(__file__).resolve().parent.parent / "reduced" / "data" / "capillary_master.npz"
RADIUS, C_REF, KAPPA = 500e-6, 200.0, 2.2e9  # the plate table's ball (compare.calibrate)


def capillary_curve(
    *, alpha: float, Gamma: float, x_max: float, n: int, mesh: Any = 1, radius: float = RADIUS, C: float = C_REF
) -> dict:
    """One static FE run (module level, picklable): x = delta/(2 a0) and f = F/(C a0^2) at its ``n`` equal states
    up to ``x_max``, the ball with tension gamma = Gamma C a0, and the run's wall time (s)."""
    from tissuemech.fem import spheroid as fem_spheroid

    t0 = time.perf_counter()
    r = fem_spheroid.compress(
        radius=radius,
        C=C,
        alpha=alpha,
        displacement=2 * radius * x_max,
        ramp_time=1.0,
        end_time=1.0,
        kappa=KAPPA,
        mesh=mesh,
        static=True,
        n_static=n,
        surface_tension=Gamma * C * radius,
    )
    return {
        "x": np.asarray(r.approach) / (2 * radius),
        "f": np.asarray(r.force) / (C * radius**2),
        "seconds": time.perf_counter() - t0,
    }


def drop_curve(x: np.ndarray) -> np.ndarray:
    """d(x) = F_drop / (gamma a0) of the exact liquid drop (``reduced.drop``, contact angle 180 deg) at x."""
    from tissuemech.reduced import drop

    x = np.asarray(x, float)
    out = np.zeros_like(x)
    pos = x > 0
    out[pos] = drop.force(2.0 * x[pos], radius=1.0, surface_tension=1.0)
    return out


def _columns(runs: list[dict], x: np.ndarray) -> np.ndarray:
    xs = np.concatenate([r["x"] for r in runs])
    fs = np.concatenate([r["f"] for r in runs])
    out = np.empty_like(x)
    for i, xi in enumerate(x):
        if xi == 0:
            out[i] = 0.0
            continue
        k = int(np.argmin(np.abs(xs - xi)))
        if abs(xs[k] - xi) > 1e-9 * max(xi, 1e-3):
            raise RuntimeError(f"the static FE runs have no state at x = delta/(2 a0) = {xi:.4g} (stopped early?)")
        out[i] = fs[k]
    return out


def tabulate(
    *,
    gammas: Sequence[float] = DEFAULT_GAMMAS,
    alphas: Sequence[float] = DEFAULT_ALPHAS,
    x_max: float = 0.3,
    n_x: int = 16,
    x_small: float = 0.01,
    n_small: int = 0,
    mesh: Any = 1,
    executor: Any = None,
    store: str | None = None,
    n_drop: int = 121,
) -> dict:
    """FE columns f(x) per (Gamma, alpha) on ``table_grid`` (through ``compare.batch``); returns the arrays of the
    table (``x``, ``alpha``, ``gamma``, ``f``, ``f_plate`` of the same level, ``drop``, ``ratio``) and ``seconds``
    (the summed wall time of the FE runs)."""
    from tissuemech.compare import batch

    g = np.asarray(sorted({0.0, *map(float, gammas)}))
    if g[0] < 0:
        raise ValueError(f"Gamma = gamma/(C a0) must be >= 0; got {g[0]}")
    if not 0 < x_max < 0.5:
        raise ValueError(f"x_max = delta/(2 a0) must be in (0, 0.5); got {x_max}")
    x = table_grid(n_x, x_max, x_small if n_small else 0.0, n_small)
    pieces = ((float(x_max), n_x - 1),) + (((float(x_small), n_small),) if n_small else ())
    jobs = [
        dict(alpha=float(a), Gamma=float(G), x_max=xm, n=n, mesh=mesh) for G in g for a in alphas for xm, n in pieces
    ]
    runs = batch.run(capillary_curve, jobs, executor=executor, store=store)
    if any(r is None for r in runs):
        raise RuntimeError("capillary calibration: an FE curve failed; rerun with the same store to retry")
    done = [dict(r) for r in runs if r is not None]
    na = len(alphas)
    k = len(pieces)
    f = np.array(
        [[_columns(done[k * (i * na + j) : k * (i * na + j) + k], x) for j in range(na)] for i in range(g.size)]
    )
    d = drop_curve(x)
    dx = np.linspace(0.0, np.sqrt(x_max), n_drop) ** 2  # d on a fine grid uniform in sqrt(x), for the reduced spline
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = f / (f[0][None] + g[:, None, None] * d[None, None, :])
    ratio[:, :, 0] = _extrapolate_zero(x, ratio)
    ratio[0] = 1.0
    return dict(
        x=x,
        alpha=np.asarray(alphas, float),
        gamma=g,
        f=f,
        f_plate=f[0],
        drop=drop_curve(dx),
        drop_x=dx,
        drop_nodes=d,
        ratio=ratio,
        seconds=float(sum(float(r["seconds"]) for r in done)),
    )


def _extrapolate_zero(x: np.ndarray, ratio: np.ndarray) -> np.ndarray:
    """R at x = 0 from a quadratic in s = sqrt(x) through the next three knots."""
    s = np.sqrt(x[1:4])
    V = np.stack([np.ones(3), s, s**2], axis=1)
    w = np.linalg.solve(V.T, np.array([1.0, 0.0, 0.0]))  # p(0) = e_0 . V^-1 r
    return np.einsum("k,gak->ga", w, ratio[:, :, 1:4])


def write(path: str | Path, table: dict, metadata: dict) -> None:
    """Write the table arrays and the JSON metadata to an npz file."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    keys = ("x", "alpha", "gamma", "ratio", "drop_x", "drop", "drop_nodes", "f", "f_plate")
    np.savez(path, **{k: np.asarray(table[k]) for k in keys}, metadata=np.asarray(json.dumps(metadata)))  # type: ignore[arg-type]


def _check(table: dict, fine: dict) -> tuple[float, str]:
    """Largest relative change of f = R (f_plate_shipped + Gamma d) when R is taken on the finer level, over the
    finer table's (Gamma, alpha) columns and x > 0: (change, where)."""
    worst, at = 0.0, ""
    for i, G in enumerate(fine["gamma"]):
        for j, a in enumerate(fine["alpha"]):
            gi = int(np.argmin(np.abs(table["gamma"] - G)))
            aj = int(np.argmin(np.abs(table["alpha"] - a)))
            e = np.abs(fine["ratio"][i, j, 1:] / table["ratio"][gi, aj, 1:] - 1.0)
            k = int(np.argmax(e))
            if e[k] > worst:
                worst, at = float(e[k]), f"Gamma {G:g} alpha {a:g} x {table['x'][1:][k]:g}"
    return worst, at


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m tissuemech.compare.calibrate_capillary", description=__doc__.split("\n")[0]
    )
    p.add_argument("--out", default=str(DEFAULT_OUT))
    p.add_argument("--store", default=None)
    p.add_argument("--mesh", type=int, default=1)
    p.add_argument("--error-mesh", type=int, default=2)
    p.add_argument("--gammas", default=",".join(map(str, DEFAULT_GAMMAS)))
    p.add_argument("--alphas", default=",".join(map(str, DEFAULT_ALPHAS)))
    p.add_argument("--x-max", type=float, default=0.3)
    p.add_argument("--n-x", type=int, default=16)
    p.add_argument("--check", default="0.5:0.1", help="alpha:Gamma columns rerun on --error-mesh (none: skip)")
    p.add_argument("--executor", default=None, help="'serial' or None (2 processes)")
    a = p.parse_args(argv)
    gammas = [float(v) for v in a.gammas.split(",")]
    alphas = [float(v) for v in a.alphas.split(",")]
    t0 = time.perf_counter()
    tab = tabulate(gammas=gammas, alphas=alphas, x_max=a.x_max, n_x=a.n_x, mesh=a.mesh, executor=a.executor,
                   store=a.store)  # fmt: skip
    meta: dict[str, Any] = {
        "definition": "f = F_eq/(C a0^2) = ratio * (f_plate(x; alpha) + Gamma d(x)), x = delta/(2 a0), "
        "Gamma = gamma/(C a0), d = F_drop/(gamma a0) (contact angle 180 deg)",
        "mesh": a.mesh,
        "radius_m": RADIUS,
        "C_Pa": C_REF,
        "kappa_Pa": KAPPA,
        "fe_seconds": tab["seconds"],
        "command": "python -m tissuemech.compare.calibrate_capillary "
        + " ".join(sys.argv[1:] if argv is None else argv),
    }
    if a.check != "none":
        pairs = [tuple(float(v) for v in c.split(":")) for c in a.check.split(",")]
        checks = []
        failed = []
        for al, G in pairs:
            try:
                fine = tabulate(gammas=[G], alphas=[al], x_max=a.x_max, n_x=a.n_x, mesh=a.error_mesh,
                                executor=a.executor, store=a.store, n_drop=3)  # fmt: skip
            except Exception as exc:  # the finer level's fitted edge may not start at strong tension
                failed.append(f"alpha {al:g} Gamma {G:g}: {type(exc).__name__}")
                continue
            fine["gamma"], fine["ratio"] = fine["gamma"][1:], fine["ratio"][1:]
            checks.append(_check(tab, fine))
        meta.update(error_mesh=a.error_mesh, check_columns=a.check, check_failed=failed)
        if checks:
            err, at = max(checks)
            meta.update(discretisation_error_f=err, discretisation_error_at=at)
    meta["wall_seconds"] = time.perf_counter() - t0
    write(a.out, tab, meta)
    print(json.dumps(meta, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
