r"""Tabulate the elastocapillary equilibrium law of the spheroid from static FE runs with a surface tension.

A Fung ball (``C`` Pa, ``alpha``) of radius ``a0`` with a surface tension ``gamma`` (N/m, non-wetting plates:
contact angle 180 deg) between frictionless plates has, by dimensional analysis,

    F_eq / (C a0^2) = f(x; alpha, Gamma),    x = delta / (2 a0),    Gamma = gamma / (C a0)

(the elastocapillary number). Default grid: Gamma = 0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1, 1.5, 2, 3, 5, 10,
alpha = 0, 0.5, 1, x = 0, 0.01 .. 0.3 on mesh level 1 (beyond Gamma ~ 2 the first states start by continuation in the
tension, ``fem.contact.EdgeSearch``). The table stores the coupling ratio

    R(x; alpha, Gamma) = f / (f_plate(x; alpha) + Gamma d(x)),

``f_plate`` the shipped (converged) tension-free plate table (``reduced.spheroid``) and ``d(x) = F_drop / (gamma
a0)`` the exact liquid drop between the plates (``reduced.drop``). R = 1 at Gamma = 0 (the plate table) and R -> 1
as Gamma -> inf (the drop: C -> 0); a purely additive law (elastic force + drop force) would have R = 1 everywhere.
The reduced law (``reduced.capillary.Capillary``) multiplies R by the same plate table plus Gamma d(x), so it
reproduces the level-1 FE with tension at the nodes. Measured against a converged reference (FE levels 1-3,
Richardson, ``tests/data/capillary_reference.json``, (alpha, Gamma) = (0.25, 0.15), (0.75, 0.25), x = 0.025 ..
0.25): the level-1 f with tension is within 5.1e-5 of it and the table within 3.2e-5; the earlier table (the ratio taken to the tension-free
FE of the same level, x step 0.02, Gamma nodes 0, 0.1, 0.2, 0.4, 0.6, 1, 2) was +1.7e-4 .. +5.7e-4 off (largest at
x = 0.025): with a tension the fitted edge's condition is dz/dr = 0, not the tension-free N_edge = 0, and the
two level-1 errors differ (by 1e-4 - 2e-4 of f), so the same-level ratio did not cancel the mesh error but added it.

One static FE run per (alpha, Gamma) to ``x_max`` plus one to ``x_small`` (``fem.spheroid.compress(static=True,
surface_tension=...)`` on a contact-edge-fitted level), and the same pair without tension per alpha; their states
are the table grid (``compare.calibrate.table_grid``: no interpolation; x = 0, 0.02 .. 0.3 by default, ``n_small`` > 0
adds a run to ``x_small`` whose states refine the start: at strong tension its first tiny step does not start yet). Written to
``reduced/data/capillary_master.npz``: arrays ``x`` (n_x,), ``alpha`` (n_a,), ``gamma`` (n_g: Gamma = gamma /
(C a0) nodes, from 0), ``ratio`` R (n_g, n_a, n_x), ``drop`` d(x) at ``drop_x`` (121 points uniform in sqrt(x): the reduced law's spline; at
the table's x: ``drop_nodes``), ``f`` (n_g, n_a, n_x: the FE's f),
``metadata`` (JSON: mesh, command, timing, ``check``: the relative change of f = R (f_plate + Gamma d) at the
check points when the ratio is taken on the finer level ``error_mesh``, the table's discretisation error).

``tissuemech calibrate-capillary [--out PATH] [--store DIR] [--mesh M] [--error-mesh M]
[--gammas g,..] [--alphas a,..] [--x-max X] [--n-x N] [--check a:G,..] [--against REF.json]`` regenerates it
(resumable with ``--store``; ``--against``: the table's largest error against a converged reference goes into the
metadata as ``reference_error_f``). ``--reference REF.json [--reference-columns a:G,..] [--reference-levels 1,2,3]``
writes such a reference instead (:func:`reference`: FE levels 1-3 at off-node (alpha, Gamma) columns and x =
0.025 .. 0.25, Richardson with the observed order; ``tests/data/capillary_reference.json``).
"""

from __future__ import annotations

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
    "reference",
    "reference_error",
    "run",
    "main",
    "DEFAULT_GAMMAS",
    "DEFAULT_ALPHAS",
    "DEFAULT_OUT",
    "RADIUS",
    "C_REF",
    "KAPPA",
]

# Gamma = gamma / (C a0) nodes (the fitted FE edge starts on level 1 up to 10 with the continuation in the tension)
DEFAULT_GAMMAS = (0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0)
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
    n_x: int = 31,
    x_small: float = 0.01,
    n_small: int = 0,
    mesh: Any = 1,
    executor: Any = None,
    store: str | None = None,
    n_drop: int = 121,
    plate: str = "shipped",
) -> dict:
    """FE columns f(x) per (Gamma, alpha) on ``table_grid`` (through ``compare.batch``); returns the arrays of the
    table (``x``, ``alpha``, ``gamma``, ``f``, ``f_plate`` of the same level, ``drop``, ``ratio``) and ``seconds``
    (the summed wall time of the FE runs). ``plate``: the ratio's elastic part, "shipped" (default: the shipped,
    converged plate table, so that f = R (f_plate + Gamma d) reproduces the FE of ``mesh`` at the nodes) or "same"
    (the tension-free FE of the same level; measured worse: the edge condition with a tension, dz/dr = 0, is not the
    tension-free one, N_edge = 0, and their level-1 errors differ by 1e-4 - 2e-4 of f, which the same-level ratio
    carried into every Gamma > 0: +1.7e-4 - 5.7e-4 against the converged reference at alpha 0.25, Gamma 0.15, while
    the level-1 f with tension is within 5.1e-5 of it)."""
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
    if plate == "shipped":
        from tissuemech.reduced import spheroid as sph

        mc = sph.master_curve()
        fp = np.array([np.asarray(mc.f(x, float(a))) for a in alphas])
    elif plate == "same":
        fp = f[0]
    else:
        raise ValueError(f"plate must be 'shipped' or 'same', got {plate!r}")
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = f / (fp[None] + g[:, None, None] * d[None, None, :])
    ratio[:, :, 0] = _extrapolate_zero(x, ratio)
    ratio[0] = 1.0
    return dict(
        x=x,
        alpha=np.asarray(alphas, float),
        gamma=g,
        f=f,
        f_plate=fp,
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


def reference(
    columns: Sequence[tuple[float, float]],
    *,
    levels: Sequence[int] = (1, 2, 3),
    x_max: float = 0.25,
    n: int = 10,
    curves: Sequence[dict] | None = None,
) -> dict:
    """A converged reference of f = F_eq / (C a0^2) at the (alpha, Gamma) ``columns`` and the ``n`` equal states
    x = delta/(2 a0) up to ``x_max`` (choose them off the table's nodes): one static FE run per column and level
    (:func:`capillary_curve`; or the given ``curves``, dicts with alpha, Gamma, level, x, f), Richardson from the three
    finest levels with the observed order (``compare.bench.fem_spheroid.richardson``, h ~ 1 / n_core). Returns a
    JSON-able dict: ``levels``, ``h``, ``points`` (alpha, Gamma, x, f per level, observed order p, f_ref)."""
    from tissuemech.compare.bench.fem_spheroid import richardson
    from tissuemech.fem.spheroid import LEVELS

    levels = [int(v) for v in levels]
    if len(levels) < 3:
        raise ValueError(f"a Richardson reference needs three mesh levels; got {levels}")
    if curves is None:
        curves = [
            dict(alpha=a, Gamma=G, level=lev, **capillary_curve(alpha=a, Gamma=G, x_max=x_max, n=n, mesh=lev))
            for a, G in columns
            for lev in levels
        ]
    h = [1.0 / LEVELS[lev][0] for lev in levels]
    points = []
    for a, G in columns:
        per = {c["level"]: c for c in curves if c["alpha"] == a and c["Gamma"] == G}
        missing = [lev for lev in levels if lev not in per]
        if missing:
            raise RuntimeError(f"no FE curve for alpha {a:g}, Gamma {G:g} on levels {missing}")
        x = np.asarray(per[levels[0]]["x"], float)
        for i, xi in enumerate(x):
            fs = [float(np.asarray(per[lev]["f"])[i]) for lev in levels]
            p, est = richardson(fs, h)
            points.append(dict(alpha=a, Gamma=G, x=float(xi), f_levels=dict(zip(map(str, levels), fs)),
                               observed_order=float(p), f_ref=float(est)))  # fmt: skip
    return dict(levels=levels, h=h, points=points)


def reference_error(ref: dict, law: Any = None) -> tuple[float, str]:
    """Largest |f_law / f_ref - 1| over a :func:`reference`'s points (``law``: a ``reduced.capillary.Capillary``,
    default the shipped one) and where it is."""
    from tissuemech.reduced import capillary as cap

    law = cap.Capillary() if law is None else law
    worst, at = 0.0, ""
    for pt in ref["points"]:
        f = float(law.curve(alpha=pt["alpha"], radius=1.0, C=1.0, surface_tension=pt["Gamma"])(pt["x"]))
        e = abs(f / pt["f_ref"] - 1.0)
        if e > worst:
            worst, at = e, f"alpha {pt['alpha']:g} Gamma {pt['Gamma']:g} x {pt['x']:.4g}"
    return worst, at


def run(a: Any, command: str) -> int:
    """The work of ``tissuemech calibrate-capillary`` (its parsed options ``a``, see
    ``compare.cli.calibrate_capillary``; ``command``: the provenance line written into the metadata): a converged
    reference (``--reference``) or the table (and its metadata), printed as JSON."""
    if a.reference:
        cols = [(float(c.split(":")[0]), float(c.split(":")[1])) for c in a.reference_columns.split(",")]
        ref = reference(cols, levels=[int(v) for v in a.reference_levels.split(",")])
        ref["command"] = command
        Path(a.reference).write_text(json.dumps(ref, indent=1))
        print(json.dumps({k: v for k, v in ref.items() if k != "points"}, indent=1))
        return 0
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
        "command": command,
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
    if a.against:
        from tissuemech.reduced import capillary as cap

        err, at = reference_error(
            json.loads(Path(a.against).read_text()), cap.Capillary(table=cap.capillary_table(a.out))
        )
        meta.update(reference_error_f=err, reference_error_at=at, reference=str(a.against))
        write(a.out, tab, meta)
    print(json.dumps(meta, indent=1))
    return 0


def main(argv: list[str] | None = None) -> int:
    """``python -m tissuemech.compare.calibrate_capillary``: an alias of ``tissuemech calibrate-capillary``."""
    from tissuemech.compare.cli.calibrate_capillary import main as cli_main

    return cli_main(argv)


if __name__ == "__main__":
    sys.exit(main())
