"""Parameter scans on the reduced models, with optional FE spot-checks, as tidy pandas tables.

Every parameter of a scan is given as
* a number: held fixed;
* a pair ``(lo, hi)``: a range, sampled by the design;
* a list/array of values (grid design only): used as given.

Designs (``design=``): ``"grid"`` (``n`` values per ranged parameter, full factorial), ``"random"``
(``n`` uniform points) and ``"lhs"`` (``n`` points of a Latin hypercube, ``scipy.stats.qmc``).
Parameters named in ``log`` are sampled uniformly in their logarithm.

The reduced model is evaluated in ``jax.vmap``-ed, jit-compiled batches of ``batch_size`` points.
The returned DataFrame has one row per point and units in the column names (``C [Pa]``,
``sigma_peak [Pa]``, ``inner_stretch [-]``...). With ``fe_checks=k`` the FE model is run (through
``compare.batch``) at ``k`` of the points, chosen spread over the design; its outputs are added as
``fe_...`` columns and ``deviation [-]`` (the largest relative difference between the reduced and
FE outputs at that point; NaN where no FE run was made), so each scan says how far it can be trusted.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd

import tissuemech.reduced  # noqa: F401  (float64)
from tissuemech.reduced.validation import (
    validate_choice,
    validate_finite,
    validate_int,
    validate_material,
    validate_nonnegative,
    validate_positive,
    validate_radii,
    validate_times,
)

__all__ = ["design", "spheroid", "blastula", "spread_indices", "to_xarray", "from_xarray", "to_netcdf"]

UNITS = {
    "radius": "m",
    "C": "Pa",
    "alpha": "-",
    "beta": "-",
    "tau": "s",
    "displacement": "m",
    "ramp_time": "s",
    "inner_radius": "m",
    "outer_radius": "m",
    "pressure": "Pa",
    "sigma_peak": "Pa",
    "sigma_end": "Pa",
    "relaxed_fraction": "-",
    "t_half": "s",
    "inner_stretch": "-",
    "outer_stretch": "-",
    "p_limit": "Pa",
    "bursts": "-",
    "fe_sigma_peak": "Pa",
    "fe_sigma_end": "Pa",
    "fe_inner_stretch": "-",
    "deviation": "-",
}


def _col(name: str) -> str:
    return f"{name} [{UNITS[name]}]"


def _unit(name: str) -> str:
    return {"-": "dimensionless"}.get(UNITS.get(name, ""), UNITS.get(name, ""))


MAX_SCAN_BYTES = 2 * 1024**3  # a design (or its curves) larger than this is refused up front


def _check_memory(points: int, values_per_point: int, what: str) -> None:
    """Refuse a scan whose table would need more than MAX_SCAN_BYTES (with the estimate)."""
    need = float(points) * float(values_per_point) * 8.0 * 3.0  # the table, its copy and the results
    if need > MAX_SCAN_BYTES:
        raise ValueError(
            f"the {what} has {points:.4g} points: about {need / 1024**3:.3g} GiB of memory "
            f"(limit {MAX_SCAN_BYTES / 1024**3:.3g} GiB); scan fewer points (n) or split the scan into parts"
        )


def _points(params: dict, points: Any, n: int, method: str, seed: int, log: Sequence[str]) -> pd.DataFrame:
    """The design: a user-given table of points (plain names or unit-labelled columns; parameters it
    lacks are taken from the fixed keyword values) or one generated from the ranges."""
    if points is None:
        return design(params, n=n, method=method, seed=seed, log=log)
    df = pd.DataFrame(points).rename(columns={_col(k): k for k in params})
    unknown = set(df.columns) - set(params)
    if unknown:
        raise ValueError(f"points has unknown columns {sorted(unknown)}; expected some of {list(params)}")
    for k, v in params.items():
        if k not in df.columns:
            if _is_range(v) or np.ndim(v) > 0:
                raise ValueError(f"{k}: give it in points or as a single number, not a range, when points= is used")
            df[k] = float(validate_finite(f"{k} ({_unit(k)})", v, _unit(k)))
    for k in params:
        validate_finite(f"points[{k!r}] ({_unit(k)})", df[k].to_numpy(dtype=object), _unit(k))
    _check_memory(len(df), len(params), "design")
    return df[list(params)].astype(float).reset_index(drop=True)


def _is_range(v: Any) -> bool:
    return isinstance(v, tuple) and len(v) == 2


def design(
    params: Mapping[str, Any], *, n: int, method: str = "lhs", seed: int = 0, log: Sequence[str] = ()
) -> pd.DataFrame:
    """Points of a design as a DataFrame (plain parameter names, SI values).

    params  name -> number (fixed), (lo, hi) (range) or list of values (grid only).
    n       grid: values per ranged parameter; random/lhs: number of points.
    method  "grid", "random" or "lhs"; ``log`` names the parameters sampled in log scale.
    """
    n = validate_int("n (the number of points)", n, minimum=1)
    validate_choice("design method", method, ("grid", "random", "lhs"))
    names = list(params)
    ranged = [k for k in names if _is_range(params[k])]
    for k in ranged:
        lo, hi = (float(validate_finite(f"range of {k} ({_unit(k)})", v, _unit(k))) for v in params[k])
        if lo > hi:
            raise ValueError(f"range of {k} must be (low, high) with low <= high; got {params[k]}")
    for k in names:
        if not _is_range(params[k]):
            validate_finite(f"{k} ({_unit(k)})", params[k], _unit(k))
    if method == "grid":
        size = 1
        for k in names:
            size *= n if _is_range(params[k]) else int(np.size(params[k]))
    else:
        size = n
    _check_memory(size, len(names), "design")
    for k in ranged:
        if k in log and params[k][0] <= 0:
            raise ValueError(f"{k} is sampled in log scale, so its range must be positive; got {params[k]}")

    def scale(k, u):
        lo, hi = params[k]
        if k in log:
            return np.exp(np.log(lo) + u * (np.log(hi) - np.log(lo)))
        return lo + u * (hi - lo)

    if method == "grid":
        axes = []
        for k in names:
            v = params[k]
            if _is_range(v):
                axes.append(scale(k, np.linspace(0.0, 1.0, n)) if n > 1 else np.array([scale(k, 0.5)]))
            else:
                axes.append(np.atleast_1d(np.asarray(v, dtype=float)))
        rows = np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, len(names))
        return pd.DataFrame(rows, columns=names)
    if method not in ("random", "lhs"):
        raise ValueError(f'method must be "grid", "random" or "lhs"; got {method!r}')
    for k in names:
        if not _is_range(params[k]) and np.ndim(params[k]) > 0:
            raise ValueError(f"{k}: lists of values need design='grid'; give a (low, high) range instead")
    if method == "random":
        u = np.random.default_rng(seed).random((n, len(ranged)))
    else:
        from scipy.stats import qmc

        u = qmc.LatinHypercube(d=max(len(ranged), 1), seed=seed).random(n)[:, : len(ranged)]
    cols = {}
    for k in names:
        cols[k] = scale(k, u[:, ranged.index(k)]) if k in ranged else np.full(n, float(params[k]))
    return pd.DataFrame(cols)


def spread_indices(points: pd.DataFrame, k: int, seed: int = 0) -> np.ndarray:
    """``k`` row indices spread over the design (greedy max-min distance in the unit-scaled box)."""
    k = min(int(k), len(points))
    if k <= 0:
        return np.zeros(0, dtype=int)
    x = points.to_numpy(dtype=float)
    span = x.max(axis=0) - x.min(axis=0)
    x = (x - x.min(axis=0)) / np.where(span > 0, span, 1.0)
    rng = np.random.default_rng(seed)
    cand = rng.choice(len(x), size=min(len(x), 2000), replace=False)
    chosen = [int(cand[np.argmin(np.abs(x[cand] - 0.5).sum(axis=1))])]  # start near the centre
    d = np.linalg.norm(x[cand] - x[chosen[0]], axis=1)
    for _ in range(k - 1):
        j = int(cand[np.argmax(d)])
        chosen.append(j)
        d = np.minimum(d, np.linalg.norm(x[cand] - x[j], axis=1))
    return np.array(chosen)


def _batched(fn: Callable, arrays: dict[str, np.ndarray], batch_size: int) -> dict[str, np.ndarray]:
    """Apply a jitted, vmapped fn(**arrays) chunk by chunk (last chunk padded with the first row)."""
    n = len(next(iter(arrays.values())))
    outs: dict[str, list] = {}
    for s in range(0, n, batch_size):
        chunk = {k: v[s : s + batch_size] for k, v in arrays.items()}
        m = len(next(iter(chunk.values())))
        if m < batch_size and n > batch_size:  # keep one compiled shape
            chunk = {k: np.concatenate([v, np.repeat(v[:1], batch_size - m)]) for k, v in chunk.items()}
        res = fn(**{k: jnp.asarray(v) for k, v in chunk.items()})
        for k, v in res.items():
            outs.setdefault(k, []).append(np.asarray(v)[:m])
    return {k: np.concatenate(v) for k, v in outs.items()}


# ---------------------------------------------------------------------------------------------
# Spheroid compression-relaxation
# ---------------------------------------------------------------------------------------------

SPHEROID_PARAMS = ("radius", "C", "alpha", "beta", "tau", "displacement", "ramp_time")


def default_times(ramp_time: float, end_time: float, n: int = 200) -> np.ndarray:
    """Output times in s: 20 intervals through the ramp, the rest log-spaced through the hold."""
    ramp = np.linspace(0.0, ramp_time, 21)
    hold = np.geomspace(ramp_time, end_time, n - 20)[1:]
    return np.concatenate([ramp, hold])


def _summaries(t, s):
    """sigma_peak, sigma_end, relaxed fraction and half-relaxation time of curves s (..., T)."""
    peak = jnp.max(s, axis=-1)
    ipk = jnp.argmax(s, axis=-1)
    end = s[..., -1]
    half = 0.5 * (peak + end)
    after = (jnp.arange(s.shape[-1]) > ipk[..., None]) & (s <= half[..., None])
    j = jnp.argmax(after, axis=-1)
    jm = jnp.maximum(j - 1, 0)
    s0 = jnp.take_along_axis(s, jm[..., None], -1)[..., 0]
    s1 = jnp.take_along_axis(s, j[..., None], -1)[..., 0]
    w = jnp.where(s0 != s1, (s0 - half) / (s0 - s1), 0.0)
    th = t[jm] + w * (t[j] - t[jm])
    th = jnp.where(jnp.any(after, axis=-1), th, jnp.nan)
    return dict(sigma_peak=peak, sigma_end=end, relaxed_fraction=1.0 - end / peak, t_half=th)


def _fe_spheroid(*, radius, C, alpha, beta, tau, displacement, ramp_time, end_time):
    """One FE spheroid run (module level, so process pools can pickle it): time and nominal stress."""
    from tissuemech.fem import spheroid as fem_spheroid

    r = fem_spheroid.compress(
        radius=radius,
        C=C,
        alpha=alpha,
        branches=[(beta, tau)],
        displacement=displacement,
        ramp_time=ramp_time,
        end_time=end_time,
    )
    return {"time": np.asarray(r.time), "nominal_stress": np.asarray(r.nominal_stress)}


def spheroid(
    *,
    radius: Any = 500e-6,
    C: Any = 200.0,
    alpha: Any = 0.2,
    beta: Any = 1.2,
    tau: Any = 200.0,
    displacement: Any = 200e-6,
    ramp_time: Any = 0.2,
    end_time: float = 1500.0,
    times: np.ndarray | None = None,
    n: int = 10,
    design_method: str = "grid",
    log: Sequence[str] = ("tau",),
    seed: int = 0,
    equilibrium: Any = "fem",
    batch_size: int = 8192,
    curves: bool = False,
    fe_checks: int = 0,
    fe_executor: Any = None,
    fe_store: str | None = None,
    model: Callable | None = None,
    fe_function: Callable | None = None,
    fe_progress: bool = True,
    points: Any = None,
    rtol: float = 1e-6,
) -> pd.DataFrame:
    """Scan the reduced spheroid compression-relaxation over parameters (one Maxwell branch).

    Parameters radius (m), C (Pa), alpha (-), beta (-), tau (s), displacement (total approach, m),
    ramp_time (s): each a number, a (lo, hi) range or (grid) a list. ``times`` (s) default: 200
    times to ``end_time`` (20 in the ramp, log-spaced hold). Returns a DataFrame with the
    parameters and ``sigma_peak [Pa]``, ``sigma_end [Pa]``, ``relaxed_fraction [-]``
    (1 - end/peak), ``t_half [s]`` (time at which the stress has fallen half-way from peak to
    end); with ``curves=True`` also a column ``sigma [Pa]`` holding each curve (and
    ``df.attrs["time [s]"]``). ``fe_checks=k``: FE runs (``fem.spheroid.compress``) at k spread
    points, adding ``fe_sigma_peak [Pa]``, ``fe_sigma_end [Pa]`` and ``deviation [-]``. ``fe_progress``: the FE runs' progress bar
    (default on).
    ``model``: the reduced nominal-stress function (default ``reduced.spheroid.nominal_stress``).
    ``rtol``: the ODE tolerance of the default model for non-stiff designs (Tsit5, rtol = atol; 1e-6 keeps
    the curves within ~1e-6 of the exact ones because steps land on the output times); stiff designs
    (ramp_time / tau > 10 somewhere) use the exact-kernel quadrature instead.
    ``points``: a ready design (DataFrame or dict of arrays, plain or unit-labelled column names);
    parameters it lacks come from the keyword values (numbers).
    """
    params = dict(radius=radius, C=C, alpha=alpha, beta=beta, tau=tau, displacement=displacement, ramp_time=ramp_time)
    batch_size = validate_int("batch_size", batch_size, minimum=1)
    fe_checks = validate_int("fe_checks (number of FE spot checks)", fe_checks, minimum=0)
    pts = _points(params, points, n, design_method, seed, log)
    validate_positive("radius", pts["radius"].to_numpy(), "m")
    validate_material(pts["C"].to_numpy(), pts["alpha"].to_numpy())
    validate_nonnegative("beta (the energy factor of the Maxwell branch)", pts["beta"].to_numpy())
    validate_positive("tau (the relaxation time)", pts["tau"].to_numpy(), "s")
    validate_positive("displacement (total approach)", pts["displacement"].to_numpy(), "m")
    validate_positive("ramp_time", pts["ramp_time"].to_numpy(), "s")
    _check_spheroid_design(pts, equilibrium if model is None else None)
    if times is None:
        validate_positive("end_time (end of the hold)", end_time, "s")
        if pts["ramp_time"].nunique() != 1:
            raise ValueError("with a range of ramp_time, give the output times explicitly (times=...)")
        if float(end_time) <= float(pts["ramp_time"].iloc[0]):
            raise ValueError(
                f"end_time ({end_time:g} s) must be after the ramp (ramp_time {float(pts['ramp_time'].iloc[0]):g} s)"
            )
        times = default_times(float(pts["ramp_time"].iloc[0]), end_time)
    tt = validate_times("times (output times)", times, unit="s", ascending=True, strictly=True)
    if tt.ndim != 1 or tt.size < 2:
        raise ValueError(f"times (output times, s) must be a 1-D array of at least 2 times; got shape {tt.shape}")
    if curves:
        _check_memory(len(pts), tt.size, "scan's curves")
    t = jnp.asarray(tt)
    if model is None:
        # the design is known here. Non-stiff (ramp_time / tau <= 10 everywhere): the explicit Tsit5 ODE
        # path at rtol (1e-6: curves within ~1e-6, 2x faster than the quadrature with a spline table);
        # stiff: the exact-kernel quadrature (any tau, ~1e-10)
        stiff = float(np.max(pts["ramp_time"].to_numpy() / pts["tau"].to_numpy())) > 10.0
        model = _default_spheroid_model(stiff, float(rtol))

    # parameters that do not vary enter as Python floats (models may branch on geometry), the rest vmapped
    fixed = tuple((k, float(pts[k].iloc[0])) for k in SPHEROID_PARAMS if pts[k].nunique() == 1)
    varying = tuple(k for k in SPHEROID_PARAMS if k not in dict(fixed))
    try:  # compiled once per (model, law, fixed values, output shape): repeated scans reuse it
        jitted = _spheroid_evaluator(model, equilibrium, fixed, varying, bool(curves))
    except TypeError:  # an unhashable equilibrium (arrays): compile for this call only
        jitted = _spheroid_evaluator.__wrapped__(model, equilibrium, fixed, varying, bool(curves))

    def evaluate(**kw):
        return jitted(t, kw)

    if varying:
        res = _batched(evaluate, {k: pts[k].to_numpy() for k in varying}, batch_size)
    else:
        res = {k: np.asarray(v) for k, v in evaluate().items()}
    df = pts.rename(columns={k: _col(k) for k in pts.columns})
    for k in ("sigma_peak", "sigma_end", "relaxed_fraction", "t_half"):
        df[_col(k)] = res[k]
    if curves:
        df["sigma [Pa]"] = list(res["sigma"])
        df.attrs["time [s]"] = np.asarray(t)
    if fe_checks:
        idx = spread_indices(pts, fe_checks, seed)
        fe_pts = [dict(pts.iloc[i].to_dict(), end_time=float(np.max(times))) for i in idx]
        fe = _run_fe(fe_function or _fe_spheroid, fe_pts, fe_executor, fe_store, fe_progress)
        for name in ("fe_sigma_peak", "fe_sigma_end", "deviation"):
            df[_col(name)] = np.nan
        for i, r in zip(idx, fe):
            if r is None:
                continue
            s_fe = np.interp(np.asarray(t), r["time"], r["nominal_stress"])
            peak, end = float(np.max(s_fe)), float(s_fe[-1])
            df.loc[i, _col("fe_sigma_peak")] = peak
            df.loc[i, _col("fe_sigma_end")] = end
            df.loc[i, _col("deviation")] = max(
                abs(res["sigma_peak"][i] / peak - 1.0), abs(res["sigma_end"][i] / end - 1.0)
            )
    return df


def _check_spheroid_design(pts: pd.DataFrame, equilibrium: Any) -> None:
    """Up-front checks of a spheroid design (the scan itself runs inside jit, where nothing can raise):
    the approach below the diameter, and inside the equilibrium table (approach and alpha). ``equilibrium``
    None: a user model, whose equilibrium spec is its own business."""
    x = pts["displacement"].to_numpy() / (2.0 * pts["radius"].to_numpy())
    if np.any(x >= 1.0):
        i = int(np.argmax(x))
        raise ValueError(
            f"displacement (total approach, m) must be smaller than the ball's diameter 2 * radius; "
            f"point {i} has {pts['displacement'].iloc[i]:g} m at radius {pts['radius'].iloc[i]:g} m"
        )
    if equilibrium is None:
        return
    if isinstance(equilibrium, str) and equilibrium not in ("fem", "hertz"):
        raise ValueError(f"equilibrium must be 'hertz', 'fem', an (x, f) table or a callable; got {equilibrium!r}")
    from tissuemech.reduced import spheroid as red

    law = red.as_equilibrium_law(equilibrium)
    type(law).check(law, float(np.max(x)), pts["alpha"].to_numpy())


@functools.lru_cache(maxsize=8)
def _default_spheroid_model(stiff: bool, rtol: float) -> Callable:
    """reduced.spheroid.nominal_stress configured for scans (one object per setting, so compiled
    evaluators are reused)."""
    import diffrax

    from tissuemech.reduced import spheroid as red

    if stiff:
        return functools.partial(red.nominal_stress, method="quadrature")
    return functools.partial(red.nominal_stress, method="ode", solver=diffrax.Tsit5(), rtol=rtol, atol=rtol)


@functools.lru_cache(maxsize=16)
def _spheroid_evaluator(model: Callable, equilibrium: Any, fixed: tuple, varying: tuple, curves: bool) -> Callable:
    """jit(t, {varying: arrays}) -> summaries (and curves) of vmapped reduced spheroid curves."""
    fixed_d = dict(fixed)

    def one(t, **kw):
        p = {**fixed_d, **kw}
        return model(
            t,
            radius=p["radius"],
            C=p["C"],
            alpha=p["alpha"],
            branches=[(p["beta"], p["tau"])],
            displacement=p["displacement"],
            ramp_time=p["ramp_time"],
            equilibrium=equilibrium,
        )

    @jax.jit
    def evaluate(t, kw):
        s = jax.vmap(lambda k: one(t, **k))(kw) if kw else one(t)[None, :]
        out = _summaries(t, s)
        if curves:
            out["sigma"] = s
        return out

    return evaluate


def _blastula_one(inner_radius, outer_radius, C, alpha, pressure):
    """Exact shell at one point: inner/outer stretch (NaN where it bursts) and the limit pressure."""
    from tissuemech.reduced import blastula as red

    geo = dict(inner_radius=inner_radius, outer_radius=outer_radius)
    lim = red.limit_point(**geo, C=C, alpha=alpha)
    # the state reached by inflating from rest: on the first rising branch, below the limit stretch
    # (past the limit pressure the shell bursts, even where a Fung shell re-stiffens far beyond it)
    la, _ = red.inner_stretch_solve(pressure, **geo, C=C, alpha=alpha, max_inner_stretch=lim.inner_stretch)
    lb = red.outer_stretch(jnp.where(jnp.isnan(la), 1.0, la), **geo)
    return dict(inner_stretch=la, outer_stretch=jnp.where(jnp.isnan(la), jnp.nan, lb), p_limit=lim.pressure)


_blastula_evaluate = jax.jit(jax.vmap(_blastula_one))  # compiled once per batch shape, reused by every scan


def _polish_blastula(res: dict[str, np.ndarray], pts: pd.DataFrame) -> None:
    """Solve again, eagerly, the points the compiled solve left NaN below their limit pressure (or without one).

    Under jit the inverse is NaN where its one-panel rule cannot be trusted to 1e-10 (very stiff states, e.g. thick
    shells at high pressure; ``reduced.blastula.inner_stretch_solve``); the eager ``inner_stretch`` takes the
    error-controlled rule there. Points it cannot solve either (a stretch outside 0.5..10) stay NaN: they hold, but
    beyond the stretch range the scan covers; only a pressure at or above the limit pressure is a burst."""
    from tissuemech.reduced import blastula as red

    la, p, lim = res["inner_stretch"], pts["pressure"].to_numpy(), res["p_limit"]
    redo = np.flatnonzero(np.isnan(la) & ~(p >= lim))
    if redo.size == 0:
        return
    kw = {k: pts[k].to_numpy()[redo] for k in ("inner_radius", "outer_radius", "C", "alpha")}
    try:  # all at once (the usual case) ...
        la[redo] = np.asarray(red.inner_stretch(p[redo], **kw))
    except ValueError:  # ... else point by point: some have no state in the stretch range searched (0.5..10)
        for j, i in enumerate(redo):
            try:
                la[i] = float(red.inner_stretch(p[i], **{k: float(v[j]) for k, v in kw.items()}))
            except ValueError:
                continue
    ok = np.isfinite(la[redo])
    geo = {k: kw[k][ok] for k in ("inner_radius", "outer_radius")}
    res["outer_stretch"][redo[ok]] = np.asarray(red.outer_stretch(la[redo[ok]], **geo))


def _run_fe(function, points, executor, store, progress: bool = True):
    from tissuemech.compare import batch

    return batch.run(function, points, executor=executor, store=store, raise_on_error=False, progress=progress)


# ---------------------------------------------------------------------------------------------
# Blastula inflation
# ---------------------------------------------------------------------------------------------

BLASTULA_PARAMS = ("inner_radius", "outer_radius", "C", "alpha", "pressure")


def _fe_blastula(*, inner_radius, outer_radius, C, alpha, pressure):
    """One FE blastula run to ``pressure`` (module level for process pools): final inner stretch."""
    from tissuemech.fem import blastula as fem_blastula

    ps = np.linspace(0.0, pressure, 11)[1:]
    r = fem_blastula.inflate(inner_radius=inner_radius, outer_radius=outer_radius, C=C, alpha=alpha, pressures=ps)
    return {"inner_stretch": float(np.asarray(r.inner_stretch)[-1])}


def blastula(
    *,
    inner_radius: Any = 50e-6,
    outer_radius: Any = 75e-6,
    C: Any = 200.0,
    alpha: Any = 0.2,
    pressure: Any = (0.0, 100.0),
    n: int = 10,
    design_method: str = "grid",
    log: Sequence[str] = (),
    seed: int = 0,
    batch_size: int = 8192,
    fe_checks: int = 0,
    fe_executor: Any = None,
    fe_store: str | None = None,
    fe_function: Callable | None = None,
    fe_progress: bool = True,
    points: Any = None,
) -> pd.DataFrame:
    """Scan the exact thick-shell blastula (``reduced.blastula``) over parameters.

    Parameters inner_radius, outer_radius (m), C (Pa), alpha (-), pressure (Pa): each a number,
    a (lo, hi) range or (grid) a list. Returns a DataFrame with the parameters and
    ``inner_stretch [-]``, ``outer_stretch [-]`` (NaN where the shell bursts, or where its state lies outside the
    stretch range 0.5..10 searched), ``p_limit [Pa]`` (limit pressure, NaN if none up to stretch 10) and
    ``bursts [-]`` (True where the pressure is at or above the limit pressure). ``fe_checks=k`` adds
    ``fe_inner_stretch [-]`` and ``deviation [-]`` (relative difference of the inner stretch) from
    ``fem.blastula.inflate`` at k spread points (``fe_progress``: their progress bar, default on).
    ``points``: a ready design (DataFrame or dict of arrays), as in :func:`spheroid`.
    """
    params = dict(inner_radius=inner_radius, outer_radius=outer_radius, C=C, alpha=alpha, pressure=pressure)
    batch_size = validate_int("batch_size", batch_size, minimum=1)
    fe_checks = validate_int("fe_checks (number of FE spot checks)", fe_checks, minimum=0)
    pts = _points(params, points, n, design_method, seed, log)
    validate_radii(pts["inner_radius"].to_numpy(), pts["outer_radius"].to_numpy())
    validate_material(pts["C"].to_numpy(), pts["alpha"].to_numpy())
    validate_finite("pressure", pts["pressure"].to_numpy(), "Pa")

    res = _batched(lambda **kw: _blastula_evaluate(**kw), {k: pts[k].to_numpy() for k in BLASTULA_PARAMS}, batch_size)
    _polish_blastula(res, pts)
    df = pts.rename(columns={k: _col(k) for k in pts.columns})
    for k in ("inner_stretch", "outer_stretch", "p_limit"):
        df[_col(k)] = res[k]
    p = pts["pressure"].to_numpy()
    df[_col("bursts")] = np.isnan(res["inner_stretch"]) & (p > 0) & (p >= res["p_limit"])  # NaN p_limit: False
    if fe_checks:
        ok = np.nonzero(~np.isnan(res["inner_stretch"]) & (pts["pressure"].to_numpy() > 0))[0]
        sub = spread_indices(pts.iloc[ok].reset_index(drop=True), fe_checks, seed)
        idx = ok[sub]
        fe = _run_fe(
            fe_function or _fe_blastula, [pts.iloc[i].to_dict() for i in idx], fe_executor, fe_store, fe_progress
        )
        df[_col("fe_inner_stretch")] = np.nan
        df[_col("deviation")] = np.nan
        for i, r in zip(idx, fe):
            if r is None:
                continue
            la_fe = float(r["inner_stretch"])
            df.loc[i, _col("fe_inner_stretch")] = la_fe
            df.loc[i, _col("deviation")] = abs(res["inner_stretch"][i] / la_fe - 1.0)
    return df


# ---------------------------------------------------------------------------------------------
# Export: xarray Dataset and netCDF
# ---------------------------------------------------------------------------------------------

_LONG_NAMES = {
    "radius": "ball radius a0",
    "C": "Fung stiffness C",
    "alpha": "Fung exponent alpha",
    "beta": "energy factor beta of the Maxwell branch",
    "tau": "relaxation time tau of the Maxwell branch",
    "displacement": "total approach of the plates",
    "ramp_time": "duration of the loading ramp",
    "inner_radius": "inner radius A of the shell",
    "outer_radius": "outer radius B of the shell",
    "pressure": "internal pressure p",
    "sigma_peak": "nominal stress F/A_mid at the end of the ramp (peak)",
    "sigma_end": "nominal stress at the end of the hold",
    "relaxed_fraction": "relaxed fraction 1 - sigma_end/sigma_peak",
    "t_half": "time at which the stress has fallen half-way from peak to end",
    "inner_stretch": "inner stretch a/A (NaN where the shell bursts or leaves 0.5..10)",
    "outer_stretch": "outer stretch b/B (NaN where the shell bursts or leaves 0.5..10)",
    "p_limit": "limit (burst) pressure of the exact shell (NaN: none up to stretch 10)",
    "bursts": "the pressure is at or above the limit pressure",
    "fe_sigma_peak": "FE nominal stress at the end of the ramp",
    "fe_sigma_end": "FE nominal stress at the end of the hold",
    "fe_inner_stretch": "FE inner stretch a/A",
    "deviation": "largest relative difference reduced vs FE (NaN: no FE run at this point)",
    "sigma": "nominal stress F/A_mid",
    "time": "time since first contact",
}


def _split_col(col: str) -> tuple[str, str]:
    """``"C [Pa]"`` -> ``("C", "Pa")``; a column without a unit -> ``(col, "")``."""
    if col.endswith("]") and " [" in col:
        name, unit = col[:-1].rsplit(" [", 1)
        return name, unit
    return col, ""


def _scene_params(names: Sequence[str]) -> tuple[str, tuple[str, ...]]:
    if set(SPHEROID_PARAMS) <= set(names):
        return "spheroid", SPHEROID_PARAMS
    if set(BLASTULA_PARAMS) <= set(names):
        return "blastula", BLASTULA_PARAMS
    raise ValueError(
        "table is not a scan table: it needs the parameter columns of scan.spheroid "
        f"({', '.join(_col(k) for k in SPHEROID_PARAMS)}) or of scan.blastula ({', '.join(_col(k) for k in BLASTULA_PARAMS)})"
    )


def _cf_units(unit: str) -> str:
    return "1" if unit == "-" else unit


def to_xarray(table: pd.DataFrame) -> Any:
    """A scan table (from :func:`spheroid` or :func:`blastula`) as an ``xarray.Dataset``.

    Variables carry the plain names (``C``, ``sigma_peak``, ``inner_stretch``, ``deviation``...) with
    ``units`` (SI; "1" for dimensionless) and ``long_name`` attributes. Dimensions are the varied
    parameters when the table is a full factorial grid over them (``design_method="grid"``): one
    dimension per varied parameter, its sorted values as the coordinate. Other designs (random,
    Latin hypercube, ``points=``) have one dimension ``point`` with the parameters as coordinates
    along it. Parameters held fixed are scalar coordinates. A curves column (``sigma [Pa]``, from
    ``curves=True``) becomes the variable ``sigma`` with the extra dimension ``time`` (s).
    ``ds.attrs``: ``scene`` ("spheroid" or "blastula"), ``layout`` ("grid" or "points").

    Raises ValueError if ``table`` lacks the parameter columns of a scan.
    """
    import xarray as xr

    cols = {_split_col(c)[0]: c for c in table.columns}
    scene, params = _scene_params(list(cols))
    n = len(table)
    if n == 0:
        raise ValueError("table is empty (no scan points)")
    values = {k: table[cols[k]].to_numpy(dtype=float) for k in params}
    varied = [k for k in params if np.unique(values[k]).size > 1]
    fixed = [k for k in params if k not in varied]

    levels = {k: np.unique(values[k]) for k in varied}
    shape = tuple(levels[k].size for k in varied)
    codes = [np.searchsorted(levels[k], values[k]) for k in varied]
    grid = bool(varied) and int(np.prod(shape)) == n
    if grid:
        flat = np.ravel_multi_index(codes, shape)
        grid = np.unique(flat).size == n
    if grid:
        dims: tuple[str, ...] = tuple(varied)
        order = np.argsort(flat)  # rows in C order of the grid
    else:
        dims = ("point",)
        shape = (n,)
        order = np.arange(n)

    def attrs(name: str, unit: str) -> dict:
        a = {"units": _cf_units(unit)}
        if name in _LONG_NAMES:
            a["long_name"] = _LONG_NAMES[name]
        return a

    coords: dict[str, Any] = {}
    for k in params:
        unit = _split_col(cols[k])[1]
        if k in fixed:
            coords[k] = ((), float(values[k][0]), attrs(k, unit))
        elif grid:
            coords[k] = ((k,), levels[k], attrs(k, unit))
        else:
            coords[k] = (("point",), values[k], attrs(k, unit))
    if not grid:
        coords["point"] = (("point",), np.arange(n), {"long_name": "index of the point in the scan table"})
    data_vars: dict[str, Any] = {}
    curves = None
    for name, col in cols.items():
        if name in params:
            continue
        unit = _split_col(col)[1]
        if table[col].dtype == object:  # curves: one array per row
            arr = np.stack([np.asarray(v, dtype=float) for v in table[col].to_numpy()[order]])
            curves = (name, unit)
            data_vars[name] = (dims + ("time",), arr.reshape(shape + arr.shape[1:]), attrs(name, unit))
            continue
        v = table[col].to_numpy()[order]
        v = v.astype(bool) if v.dtype == bool else v.astype(float)
        data_vars[name] = (dims, v.reshape(shape), attrs(name, unit))
    if curves is not None:
        t = table.attrs.get("time [s]")
        if t is None:
            raise ValueError(
                'a curves column needs the output times in table.attrs["time [s]"] (as scan.spheroid sets)'
            )
        coords["time"] = (("time",), np.asarray(t, dtype=float), attrs("time", "s"))
    ds = xr.Dataset(data_vars, coords=coords)
    ds.attrs.update(scene=scene, layout="grid" if grid else "points", source="tissuemech.compare.scan")
    return ds


def from_xarray(ds: Any) -> pd.DataFrame:
    """The scan table of a Dataset from :func:`to_xarray` (or read back from :func:`to_netcdf`).

    Unit-labelled columns as the scans return them (parameters first); rows in the Dataset's order
    (C order of the grid dimensions, or the ``point`` order); curves back as a ``sigma [Pa]`` column of
    arrays with ``attrs["time [s]"]``.
    """
    scene, params = _scene_params(list(ds.variables))

    def label(name: str) -> str:
        u = ds[name].attrs.get("units", "")
        return f"{name} [{'-' if u == '1' else u}]"

    dims = [d for d in ds.dims if d != "time"]
    n = int(np.prod([ds.sizes[d] for d in dims])) if dims else 1
    out: dict[str, Any] = {}
    for k in params:
        v = ds[k].reset_coords(drop=True)
        for d in dims:
            if d not in v.dims:
                v = v.expand_dims({d: ds.sizes[d]})
        out[label(k)] = np.asarray(v.transpose(*dims).values, dtype=float).reshape(n)
    names = sorted(ds.data_vars, key=lambda v: "time" in ds[v].dims)  # curves last, as the scans return them
    for name in names:
        var = ds[name]
        if "time" in var.dims:
            arr = np.asarray(var.transpose(*dims, "time").values).reshape(n, -1)
            out[label(name)] = list(arr)
        else:
            out[label(name)] = np.asarray(var.transpose(*dims).values).reshape(n)
    df = pd.DataFrame(out)
    if "time" in ds.coords:
        df.attrs["time [s]"] = np.asarray(ds["time"].values, dtype=float)
    return df


def to_netcdf(table_or_dataset: Any, path: Any, *, engine: str = "scipy") -> Any:
    """Write a scan table (DataFrame, converted by :func:`to_xarray`) or a Dataset to a netCDF file.

    engine  ``"scipy"`` (default; netCDF3 64-bit offset, needs nothing beyond scipy) or
            ``"h5netcdf"`` / ``"netcdf4"`` (netCDF4, if that package is installed).
    Returns the path (``pathlib.Path``). Read back with ``xarray.open_dataset(path)`` and
    :func:`from_xarray`.
    """
    from pathlib import Path

    import xarray as xr

    ds = table_or_dataset if isinstance(table_or_dataset, xr.Dataset) else to_xarray(table_or_dataset)
    path = Path(path)
    if engine == "scipy":
        ds.to_netcdf(path, engine="scipy", format="NETCDF3_64BIT")
    elif engine in ("h5netcdf", "netcdf4"):
        ds.to_netcdf(path, engine=engine)  # type: ignore[call-overload]  # xarray stubs: engine is a checked str, not a Literal
    else:
        raise ValueError(f'engine must be "scipy", "h5netcdf" or "netcdf4"; got {engine!r}')
    return path
