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
``compare.scan.spot_check`` and ``compare.batch``) at ``k`` of the points, chosen spread over the design; its outputs are added as
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
from tissuemech.compare.scan.fe_checks import spot_check
from tissuemech.compare.scan.table import BLASTULA_PARAMS, SPHEROID_PARAMS, UNITS, column, unit_words
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

__all__ = [
    "design",
    "spheroid",
    "blastula",
    "default_times",
    "spheroid_times",
    "summaries",
    "evaluate_in_chunks",
    "check_normal",
    "MAX_SCAN_BYTES",
    "BLOCK",
    "vmap_in_blocks",
    "CHUNK",
    "TINY",
]

MAX_SCAN_BYTES = 2 * 1024**3  # a design (or its curves) larger than this is refused up front
CHUNK = 8192  # points per reduced-model call of evaluate_in_chunks (one compiled shape)
# spheroid curves evaluated together (one vmap) inside a call on a CPU, the blocks one after the other
# (``jax.lax.map``): the temporaries of a block of 200-time curves stay ~20 MB (~200 bytes per curve and time)
# where a whole chunk's were mapped and zeroed afresh by every call (`python -m tissuemech.compare.bench
# scan-kernel` runs the same kernel; a GPU takes the whole chunk in one vmap)
BLOCK = 512


def vmap_in_blocks(fn: Callable, args: Any) -> Any:
    """``jax.vmap(fn)(args)`` over the leading axis of the pytree ``args``, on a CPU in blocks of :data:`BLOCK`
    rows one after the other (``jax.lax.map(..., batch_size=BLOCK)``): the same values, flat temporaries."""
    if jax.default_backend() == "cpu":
        return jax.lax.map(fn, args, batch_size=BLOCK)
    return jax.vmap(fn)(args)


TINY = float(np.finfo(np.float64).tiny)  # the smallest normal float64 (2.2e-308)


def check_normal(points: pd.DataFrame) -> None:
    """Refuse parameter values that are not zero but below the smallest normal float64 (``TINY``, 2.2e-308): the
    model's arithmetic underflows with them (zero stresses, NaN summaries). Raises ValueError naming the
    parameter, its unit and the point."""
    for k in points.columns:
        v = points[k].to_numpy(dtype=float)
        bad = np.flatnonzero((v != 0) & (np.abs(v) < TINY))
        if bad.size:
            i = int(bad[0])
            unit = unit_words(str(k))
            raise ValueError(
                f"{k} ({unit}) is {v[i]:.3g} at point {i}: below the smallest normal float64 number ({TINY:.3g}), "
                f"so the computation underflows; give {k} in {unit} as a number of ordinary size"
            )


def _number(name: str, value: Any, unit: str) -> float:
    """``value`` as a finite float (the validation's error naming ``name`` and ``unit`` otherwise)."""
    v = validate_finite(name, value, unit)
    if v is None:  # a traced value: scans take numbers
        raise TypeError(f"{name} must be a number, not a traced JAX value")
    return float(v)


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
    df = pd.DataFrame(points).rename(columns={column(k): k for k in params})
    unknown = set(df.columns) - set(params)
    if unknown:
        raise ValueError(f"points has unknown columns {sorted(unknown)}; expected some of {list(params)}")
    for k, v in params.items():
        if k not in df.columns:
            if _is_range(v) or np.ndim(v) > 0:
                raise ValueError(f"{k}: give it in points or as a single number, not a range, when points= is used")
            df[k] = _number(f"{k} ({unit_words(k)})", v, unit_words(k))
    for k in params:
        validate_finite(f"points[{k!r}] ({unit_words(k)})", df[k].to_numpy(dtype=object), unit_words(k))
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
        lo, hi = (_number(f"range of {k} ({unit_words(k)})", v, unit_words(k)) for v in params[k])
        if lo > hi:
            raise ValueError(f"range of {k} must be (low, high) with low <= high; got {params[k]}")
    for k in names:
        if not _is_range(params[k]):
            validate_finite(f"{k} ({unit_words(k)})", params[k], unit_words(k))
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


def evaluate_in_chunks(
    function: Callable[..., pd.DataFrame],
    points: pd.DataFrame,
    varied: Sequence[str],
    kw: Mapping[str, Any],
    *,
    progress: bool = True,
    stiff_row: int | None = None,
    chunk: int = CHUNK,
) -> pd.DataFrame:
    """``function(points=..., **kw)`` (:func:`spheroid` or :func:`blastula`) on a large design, ``chunk`` points
    per call, ticking a progress bar: the table of one call.

    Each call gets the same number of points (the last chunk padded) plus the design rows where each
    varied parameter takes its extremes (and ``stiff_row``: the spheroid's stiffest point), so every call
    compiles to the same evaluator (same varied set, same stiffness choice) and is reused; padding and extra
    rows are dropped."""
    from tqdm.auto import tqdm

    chunk = validate_int("chunk (points per call)", chunk, minimum=1)
    n = len(points)
    if n <= chunk:
        with tqdm(total=n, disable=not progress, desc="reduced", unit="pt") as bar:
            df = function(points=points, batch_size=max(n, 1), **kw)
            bar.update(n)
        return df
    extra = {int(points[k].to_numpy().argmin()) for k in varied} | {int(points[k].to_numpy().argmax()) for k in varied}
    if stiff_row is not None:
        extra.add(int(stiff_row))
    extra_rows = points.iloc[sorted(extra)]
    parts = []
    attrs: dict = {}
    with tqdm(total=n, disable=not progress, desc="reduced", unit="pt") as bar:
        for s in range(0, n, chunk):
            sub = points.iloc[s : s + chunk]
            m = len(sub)
            call = pd.concat([sub, points.iloc[[0] * (chunk - m)], extra_rows], ignore_index=True)
            df = function(points=call, batch_size=len(call), **kw)
            attrs = dict(df.attrs)
            df.attrs = {}  # concat compares attrs (arrays: ambiguous); set once below
            parts.append(df.iloc[:m])
            bar.update(m)
    out = pd.concat(parts, ignore_index=True)
    out.attrs = attrs
    return out


# ---------------------------------------------------------------------------------------------
# Spheroid compression-relaxation
# ---------------------------------------------------------------------------------------------


def spheroid_times(ramp_times: Any, end_time: float) -> np.ndarray:
    """Output times (s) for a design's ramp times: :func:`default_times` for one ramp time; with a range of
    ramp times, 20 intervals up to the shortest ramp, 20 across the ramp range, log-spaced hold.
    Raises ValueError unless ``end_time`` is after the longest ramp."""
    ramp = np.asarray(ramp_times, dtype=float)
    lo, hi = float(np.min(ramp)), float(np.max(ramp))
    if not end_time > hi:
        raise ValueError(f"end_time ({end_time:g} s) must be after the end of the ramp ({hi:g} s)")
    if lo == hi:
        return default_times(lo, end_time)
    t = np.concatenate([np.linspace(0, lo, 21), np.linspace(lo, hi, 21), np.geomspace(hi, end_time, 160)])
    return np.unique(t)


def default_times(ramp_time: float, end_time: float, n: int = 200) -> np.ndarray:
    """Output times in s: 20 intervals through the ramp, the rest log-spaced through the hold."""
    ramp = np.linspace(0.0, ramp_time, 21)
    hold = np.geomspace(ramp_time, end_time, n - 20)[1:]
    return np.concatenate([ramp, hold])


def summaries(t, s):
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
    check_normal(pts)
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
    if tt is None:
        raise TypeError("times (output times, s) must be numbers, not a traced JAX value")
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
    peak = np.asarray(res["sigma_peak"], dtype=float)
    bad = np.flatnonzero(~(np.isfinite(peak) & (peak >= TINY)))
    if bad.size:  # the model never gives a zero or NaN peak stress for a compression: the numbers failed
        i = int(bad[0])
        at = ", ".join(f"{k}={float(pts[k].iloc[i]):.4g} {UNITS[k]}" for k in SPHEROID_PARAMS)
        raise ValueError(
            f"the reduced spheroid model gives a peak nominal stress of {peak[i]:.3g} Pa at {bad.size} of {len(pts)} "
            f"points, e.g. point {i} ({at}): its parameters underflow or overflow float64 arithmetic; scan "
            "parameters of ordinary size (SI units)"
        )
    df = pts.rename(columns={k: column(k) for k in pts.columns})
    for k in ("sigma_peak", "sigma_end", "relaxed_fraction", "t_half"):
        df[column(k)] = res[k]
    if curves:
        df["sigma [Pa]"] = list(res["sigma"])
        df.attrs["time [s]"] = np.asarray(t)
    if fe_checks:
        spot_check(
            df,
            fe_checks,
            times=np.asarray(t),
            seed=seed,
            executor=fe_executor,
            store=fe_store,
            function=fe_function,
            progress=fe_progress,
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
        s = vmap_in_blocks(lambda k: one(t, **k), kw) if kw else one(t)[None, :]
        out = summaries(t, s)
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


# ---------------------------------------------------------------------------------------------
# Blastula inflation
# ---------------------------------------------------------------------------------------------


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
    check_normal(pts)
    validate_radii(pts["inner_radius"].to_numpy(), pts["outer_radius"].to_numpy())
    validate_material(pts["C"].to_numpy(), pts["alpha"].to_numpy())
    validate_finite("pressure", pts["pressure"].to_numpy(), "Pa")

    res = _batched(lambda **kw: _blastula_evaluate(**kw), {k: pts[k].to_numpy() for k in BLASTULA_PARAMS}, batch_size)
    _polish_blastula(res, pts)
    df = pts.rename(columns={k: column(k) for k in pts.columns})
    for k in ("inner_stretch", "outer_stretch", "p_limit"):
        df[column(k)] = res[k]
    p = pts["pressure"].to_numpy()
    df[column("bursts")] = np.isnan(res["inner_stretch"]) & (p > 0) & (p >= res["p_limit"])  # NaN p_limit: False
    if fe_checks:
        spot_check(
            df, fe_checks, seed=seed, executor=fe_executor, store=fe_store, function=fe_function, progress=fe_progress
        )
    return df
