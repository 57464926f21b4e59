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

``python -m tissuemech.compare.calibrate [--out PATH] [--store DIR] [--workers N] [--n-x N] [--x-max X] [--alphas a,b,..]
[--mesh M] [--error-mesh M] [--check-alphas a,b,..] [--reference JSON]`` regenerates it through ``compare.batch``
(resumable with ``--store``; the table and its finer-level check share one pool of ``--workers`` processes, default every
core). With ``--reference`` (converged Richardson forces, e.g. tests/data/plate_reference_levels1-3.json)
the metadata also gets ``model_error_rel`` = half the table's largest error against that reference (the relative
1-sigma error of F_eq that ``compare.fit`` adds with ``model_error="auto"``; the finer-level check alone does not
set it).

Table regeneration machinery (any FE-made table: plates here; indentation and surface tension reuse it)
----------------------------------------------------------------------------------------------------
A table is described by a :class:`Table`: its ``name``, the module-level FE function ``run`` (picklable: it runs in
worker processes), its ``columns`` (per column, e.g. per alpha, the keyword dicts of that column's runs, SI units),
``assemble`` (the post-processing: the runs' results, column by column, in the order given, -> the table) and
``metadata`` (what the writer stores with it), plus ``cost`` (a relative cost per run, for scheduling only).
:func:`build` runs the runs of one or more tables through ``compare.batch`` (resumable with ``store``) on one
process pool of ``workers`` processes (default: every core this process may use; one BLAS thread each), the most
expensive runs first (largest-processing-time order: the long finer-level check runs of a table no longer start last
and leave one core idle), and returns each table's ``assemble`` output. Every run is one independent process-local
computation, so the results do not depend on the number of workers or on the order (a test builds a table in
parallel and serially and compares them bit for bit). Runs of the tables given to one :func:`build` that share their
``run`` function go through one batch; a table with another function follows on the same pool.

    spec = plate_table(alphas=(0.0, 0.5, 1.0), mesh=3)            # or a Table(...) of your own
    curves, = build([spec], workers=2, store="store-dir")

Warm starts. Along x a column's states come from one static continuation (each state starts from the secant
through the two before it, ``fem.contact.static_fitted``). Along alpha nothing is carried: measured on level 3
(n_x = 19, Newton iterations per state, edge search included) the first state costs 21 / 46 / 64 iterations at
alpha = 0 / 0.5 / 1.5 against 14-30 for every later one, so a perfect start from the neighbouring alpha's first state
could save at most 0-12 % of a column (12 % at alpha = 1.5), while it would chain the alphas (less parallel work) and
move the states by the solver tolerance (the table would no longer be the one its command makes run by run). Not kept.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from tissuemech.reduced.material import hertz_plate_f

__all__ = [
    "MasterCurves",
    "Table",
    "build",
    "plate_table",
    "plate_cost",
    "default_workers",
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


@dataclass(frozen=True)
class Table:
    """One FE-made table (module doc): ``run(**kw)`` for every ``kw`` of every column, then ``assemble``.

    name      what the table is (for messages).
    run       module-level (picklable) function of keyword arguments: one FE run.
    columns   per column (e.g. per alpha) the keyword dicts of its runs (SI units).
    assemble  ``assemble(results)``: ``results[i][j]`` the result of ``columns[i][j]`` (a ``compare.batch.Stored``:
              a dict of NumPy arrays) -> the table.
    cost      relative cost of one run from its keywords (scheduling only; default 1).
    metadata  stored with the table by its writer (mesh, command, error estimates ...).
    """

    name: str
    run: Callable[..., Any]
    columns: tuple[tuple[dict, ...], ...]
    assemble: Callable[[list[list[Any]]], Any]
    cost: Callable[[Mapping[str, Any]], float] | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not callable(self.run) or not callable(self.assemble):
            raise ValueError(f"table {self.name!r}: run and assemble must be callables")
        cols = tuple(tuple(dict(kw) for kw in col) for col in self.columns)
        if not cols or any(not col for col in cols):
            raise ValueError(f"table {self.name!r}: every column needs at least one run (keyword dict)")
        object.__setattr__(self, "columns", cols)

    def runs(self) -> list[dict]:
        """The keyword dicts of all runs, column by column."""
        return [kw for col in self.columns for kw in col]


def default_workers() -> int:
    """The cores this process may use (``os.sched_getaffinity`` where it exists, else ``os.cpu_count()``)."""
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:  # not on every platform
        return max(os.cpu_count() or 1, 1)


def build(
    tables: Sequence[Table],
    *,
    workers: int | None = None,
    executor: Any = None,
    store: str | None = None,
    progress: bool = True,
) -> list[Any]:
    """Run every table's runs (module doc), the most expensive first, and return each table's ``assemble`` output.

    workers   local processes (default :func:`default_workers`, at most one per run); ignored with ``executor``.
    executor  as ``compare.batch.run``'s ("serial", a ``concurrent.futures.Executor``, a dask Client); None: a
              process pool of ``workers`` (``compare.batch.process_pool``).
    store     folder of per-run results (``compare.batch``): a rerun resumes; runs shared by two tables run once.
    Raises ``compare.batch.BatchError`` naming the first failed run (finished runs are stored: rerun with the same
    store to retry only the failed ones).
    """
    from tissuemech.compare import batch

    tables = list(tables)
    if not all(isinstance(t, Table) for t in tables):
        raise ValueError("tables must be a sequence of compare.calibrate.Table")
    flat = [(ti, ci, ri) for ti, t in enumerate(tables) for ci, col in enumerate(t.columns) for ri in range(len(col))]
    kw_of = lambda k: tables[k[0]].columns[k[1]][k[2]]
    cost_of = lambda k: float(tables[k[0]].cost(kw_of(k))) if tables[k[0]].cost is not None else 1.0
    order = sorted(flat, key=lambda k: -cost_of(k))  # stable: equal costs keep the tables' order
    groups: dict[Any, list] = {}
    for k in order:
        groups.setdefault(tables[k[0]].run, []).append(k)
    owned = None
    if executor is None:
        n = default_workers() if workers is None else workers
        owned = batch.process_pool(min(n, len(flat)))
        executor = owned
    out: dict[tuple, Any] = {}
    try:
        for fn, keys in groups.items():
            runs = batch.run(fn, [kw_of(k) for k in keys], executor=executor, store=store, progress=progress)
            out.update(zip(keys, runs, strict=True))
    finally:
        if owned is not None:
            owned.shutdown(wait=True, cancel_futures=True)
    return [
        t.assemble([[out[(ti, ci, ri)] for ri in range(len(col))] for ci, col in enumerate(t.columns)])
        for ti, t in enumerate(tables)
    ]


def plate_cost(kw: Mapping[str, Any]) -> float:
    """Relative cost of one static plate run: its steps x the level's cost per step (measured, one BLAS thread: 0.6 s
    per state on level 3, 1.7 s on level 4 (n_x = 19, alpha = 1): ~2.8 x per level); a named or mesh-object level
    counts as level 1."""
    mesh = kw.get("mesh", 1)
    level = mesh if isinstance(mesh, int) and not isinstance(mesh, bool) else 1
    return float(kw.get("n") or 8) * 2.8**level


def plate_table(
    *,
    alphas: Sequence[float] = DEFAULT_ALPHAS,
    n_x: int = 37,
    x_max: float = 0.36,
    x_small: float = 0.01,
    n_small: int = 4,
    mesh: Any = 2,
    curve: Callable[..., Any] = static_curve,
    name: str = "plate master curves",
    metadata: Mapping[str, Any] | None = None,
) -> Table:
    """The plate table as a :class:`Table`: per alpha one static run to x_max in n_x - 1 equal steps and one to
    x_small in n_small steps (skipped if n_small = 0); assembled into :class:`MasterCurves` on ``table_grid``."""
    if not 0 < x_max < 0.5:
        raise ValueError(f"x_max = delta/(2 a0) must be in (0, 0.5); got {x_max}")
    if any(a < 0 for a in alphas):
        raise ValueError("alpha must be >= 0 (0 is neo-Hookean)")
    x = table_grid(n_x, x_max, x_small if n_small else 0.0, n_small)
    small = bool(n_small) and x[1] < x_max / (n_x - 1) * (1 - 1e-9)
    columns = []
    for a in alphas:
        col = [dict(alpha=float(a), x_max=float(x_max), mesh=mesh, n=n_x - 1)]
        if small:
            col.append(dict(alpha=float(a), x_max=float(x_small), mesh=mesh, n=n_small))
        if curve is not static_curve:  # a user/fake curve may not take n
            col = [{k: v for k, v in j.items() if k != "n"} for j in col]
        columns.append(tuple(col))

    def assemble(results: list[list[Any]]) -> MasterCurves:
        fg = [_to_master(_merged(parts), x) for parts in results]
        return MasterCurves(
            x, np.asarray(alphas, dtype=float), np.array([f for f, _ in fg]), np.array([g for _, g in fg])
        )

    return Table(name, curve, tuple(columns), assemble, plate_cost, dict(metadata or {}))


def _merged(parts: list[Any]) -> dict:
    """The runs of one column as one run (their states concatenated)."""
    return {
        "approach": np.concatenate([p["approach"] for p in parts]),
        "force": np.concatenate([p["force"] for p in parts]),
        "midplane_radius": np.concatenate([p["midplane_radius"] for p in parts]),
        "radius": parts[0]["radius"],
        "C": parts[0]["C"],
    }


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
    workers: int | None = None,
) -> MasterCurves:
    """Static FE curves per alpha (:func:`plate_table` through :func:`build`): one run to x_max in n_x - 1 equal
    steps and one to x_small in n_small steps (skipped if n_small = 0); f, g on ``table_grid`` (the run states)."""
    spec = plate_table(alphas=alphas, n_x=n_x, x_max=x_max, x_small=x_small, n_small=n_small, mesh=mesh, curve=curve)
    return build([spec], workers=workers, executor=executor, store=store)[0]


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
