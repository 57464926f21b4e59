r"""Fitting any protocol a lab runs: relaxation, creep and measured-history records, alone or mixed in one fit.

Each record says its protocol by its type (SI units):

* :class:`~tissuemech.compare.fit.records.Record` ``(time [s], nominal_stress [Pa], displacement [m])``: a
  compression-relaxation record (linear ramp to ``displacement`` over ``ramp_time``, then held); the model is
  ``reduced.spheroid.nominal_stress``, fitted to the nominal stress (as :func:`~tissuemech.compare.fit.relaxation`);
* :class:`CreepRecord` ``(time [s], approach [m], force [N])``: a plate force ramped linearly to ``force`` over
  ``ramp_time`` and held (creep); the model is ``reduced.spheroid.approach`` driven by that force, fitted to the
  measured approach;
* :class:`HistoryRecord` ``(time [s], approach [m], force [N])``: the approach the instrument recorded drives the
  model of ``reduced.spheroid.force(displacement=(times, approaches))`` (linear between samples), fitted to the
  measured force; :func:`history_force` evaluates it by an exact exponential recursion on a refined grid (the ODE
  would have to find every sample's kink).

:func:`records_fit` fits ``(C, alpha, beta_m, tau_m)`` to any mix of them (records of the same spheroid share the
parameters) with the statistics of :func:`~tissuemech.compare.fit.relaxation` (per-record noise, the model-error
factors, the robust error model, profile-checked 95 % intervals, identifiability): each record's residuals are
taken relative to its own peak, so records of different observables (Pa, m, N) are weighted by their own noise.
:func:`creep_level` reads the held force of a creep file (and refuses a force that is not held);
:func:`read_protocol_csv` reads a ``time, approach, force`` file and infers its protocol.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

import tissuemech.reduced  # noqa: F401  (enables float64 in JAX)
from tissuemech.compare.fit.diagnostics import ERROR_MODELS
from tissuemech.compare.fit.estimation import estimate, model_error_value, starting_point
from tissuemech.compare.fit.model import default_model, initial_guess, parameter_names, table_of
from tissuemech.compare.fit.records import (
    UM,
    Record,
    as_records,
    check_ramp,
    check_record,
    header_columns,
    read_table,
)
from tissuemech.compare.fit.result import FitResult
from tissuemech.reduced.material import validate_positive

__all__ = [
    "CreepRecord",
    "HistoryRecord",
    "PROTOCOLS",
    "protocol_of",
    "check_samples",
    "creep_level",
    "records_fit",
    "predict",
    "read_protocol_csv",
    "HELD_TOL",
    "history_force",
    "HISTORY_SUBSTEPS",
]

PROTOCOLS = ("relaxation", "creep", "history")
HELD_TOL = 0.02  # a creep record's force must stay within 2 % of its level over the hold (beyond 5 noise sd)


class CreepRecord(NamedTuple):
    """A creep record: ``time`` (s), the measured ``approach`` (m), the held plate ``force`` (N, reached linearly at
    the fit's ``ramp_time``)."""

    time: np.ndarray
    approach: np.ndarray
    force: float


class HistoryRecord(NamedTuple):
    """A measured-history record: ``time`` (s, from first contact), the measured ``approach`` (m; the model's input,
    linear between samples) and the measured plate ``force`` (N; the observable)."""

    time: np.ndarray
    approach: np.ndarray
    force: np.ndarray


def protocol_of(record: Any) -> str:
    """ "creep", "history" or "relaxation" (a :class:`Record` or a ``(time, stress, displacement)`` tuple)."""
    if isinstance(record, CreepRecord):
        return "creep"
    if isinstance(record, HistoryRecord):
        return "history"
    return "relaxation"


def check_samples(t: Any, ys: dict[str, Any], what: str) -> tuple[np.ndarray, ...]:
    """(time, *columns) as float arrays after the checks every record's samples need: equal lengths, >= 8 samples,
    finite, time >= 0 and strictly increasing (ValueError naming ``what``, the sample and the times: time running
    backwards, duplicated times)."""
    tv = np.asarray(t, dtype=float).ravel()
    out = [tv]
    for name, y in ys.items():
        yv = np.asarray(y, dtype=float).ravel()
        if yv.shape != tv.shape:
            raise ValueError(f"{what}: time and {name} need the same length; got {tv.size} and {yv.size}")
        if not np.all(np.isfinite(yv)):
            raise ValueError(f"{what}: {name} must be finite numbers (found NaN or inf)")
        out.append(yv)
    if tv.size < 8:
        raise ValueError(f"{what}: {tv.size} samples; a record needs at least 8")
    if not np.all(np.isfinite(tv)):
        raise ValueError(f"{what}: time must be finite numbers (found NaN or inf)")
    if np.any(tv < 0):
        raise ValueError(f"{what}: time must not be negative (s, from first contact); got {tv.min():g} s")
    dt = np.diff(tv)
    if np.any(dt < 0):
        i = int(np.flatnonzero(dt < 0)[0]) + 1
        raise ValueError(
            f"{what}: time runs backwards at sample {i + 1} ({tv[i - 1]:g} s, then {tv[i]:g} s): give the samples in "
            "time order (and check that the columns are not swapped)"
        )
    if np.any(dt == 0):
        i = int(np.flatnonzero(dt == 0)[0]) + 1
        k = int(np.sum(dt == 0))
        raise ValueError(
            f"{what}: duplicated time {tv[i]:g} s at samples {i} and {i + 1} ({k} duplicate(s) in all): a time "
            "stamp appears twice (a logger's repeated line, or times rounded too coarsely); drop or average the "
            "duplicates, or export the times with more digits"
        )
    return tuple(out)


def _held(t: Any, force: Any, ramp_time: float, what: str) -> tuple[float, float, float, float, tuple[float, float]]:
    """(median force over the hold, at its start, at its end, the tolerance, (first, last) hold time) (N, s)."""
    t, f = np.asarray(t, dtype=float), np.asarray(force, dtype=float)
    hold = t >= ramp_time
    if np.sum(hold) < 4:
        raise ValueError(
            f"{what}: fewer than 4 samples after the ramp ({ramp_time:g} s): a creep record holds the force; check "
            "the ramp time and the time unit"
        )
    fh, th = f[hold], t[hold]
    level = float(np.median(fh))
    if not level > 0:
        raise ValueError(f"{what}: the held force must be positive (N, compression); its median is {level:g} N")
    d2 = np.diff(fh, 2) if fh.size > 3 else np.zeros(1)
    noise = 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)
    k = max(2, fh.size // 10)
    head, tail = float(np.median(fh[:k])), float(np.median(fh[-k:]))
    return level, head, tail, max(HELD_TOL * level, 5.0 * noise), (float(th[0]), float(th[-1]))


def creep_level(t: Any, force: Any, ramp_time: float, what: str = "creep record", stated: float | None = None) -> float:
    """The held force (N) of a creep record's measured force column: the median over the hold (t >= ``ramp_time``).
    ValueError when the force is not held as the protocol states: it drifts over the hold or departs from
    ``stated`` (N) by more than :data:`HELD_TOL` of the level and 5 noise sd (then fit it as a measured history),
    or no sample lies in the hold."""
    level, head, tail, tol, (t0, t1) = _held(t, force, ramp_time, what)
    if abs(tail - head) > tol:
        raise ValueError(
            f"{what}: the force is not held: it goes from {head:.4g} N to {tail:.4g} N over the hold "
            f"({t0:g}-{t1:g} s, {100 * (tail - head) / level:+.2g} %), but a creep record holds it after the "
            "ramp: fit the file as a measured history (--protocol history: the approach drives the model, the force "
            "is fitted), or check the ramp time"
        )
    if stated is not None and abs(level - stated) > tol:
        raise ValueError(
            f"{what}: the force column holds {level:.4g} N, not the stated {stated:.4g} N "
            f"({100 * (level - stated) / stated:+.2g} %): check the force (and its unit) or leave it to the file"
        )
    return level if stated is None else float(stated)


def _as_protocol_records(records: Any) -> list[Any]:
    if isinstance(records, (Record, CreepRecord, HistoryRecord)):
        records = [records]
    out: list[Any] = []
    for k, r in enumerate(records):
        what = f"record {k}"
        if isinstance(r, CreepRecord):
            t, d = check_samples(r.time, {"approach": r.approach}, what)
            validate_positive(f"{what}: force (the held plate force)", r.force, "N")
            if np.mean(d) <= 0 or np.max(d) <= 0:
                raise ValueError(
                    f"{what}: the approach must be positive in compression (m); its mean is {np.mean(d):g}"
                )
            if np.ptp(d) == 0:
                raise ValueError(f"{what}: the approach is constant ({d[0]:g} m): no information on the parameters")
            out.append(CreepRecord(t, d, float(r.force)))
        elif isinstance(r, HistoryRecord):
            t, d, f = check_samples(r.time, {"approach": r.approach, "force": r.force}, what)
            if np.max(d) <= 0:
                raise ValueError(
                    f"{what}: the approach must be positive in compression (m); its largest is {d.max():g}"
                )
            if np.mean(f) <= 0 or np.ptp(f) == 0:
                raise ValueError(
                    f"{what}: the force must vary and be positive in compression (N); its mean is {np.mean(f):g} N"
                )
            out.append(HistoryRecord(t, d, f))
        else:
            rec = as_records([r])[0]
            check_samples(rec.time, {}, what)
            out.append(rec)
    if not out:
        raise ValueError("at least one record is needed")
    return out


def _observed(r: Any) -> np.ndarray:
    if isinstance(r, CreepRecord):
        return r.approach
    if isinstance(r, HistoryRecord):
        return r.force
    return r.nominal_stress


def _driving_history(r: HistoryRecord) -> tuple[np.ndarray, np.ndarray]:
    """The approach history from first contact: (0 s, 0 m) put first where the record starts later."""
    if r.time[0] > 0:
        return np.concatenate([[0.0], r.time]), np.concatenate([[0.0], r.approach])
    return r.time, r.approach


@functools.lru_cache(maxsize=1)
def _forward_ode() -> Any:
    """The ODE method of the creep and history models in the fit: forward-mode sensitivities (``jax.jacfwd``)."""
    from tissuemech.reduced import spheroid

    return spheroid.ODE(adjoint="forward")


HISTORY_SUBSTEPS = 8  # each interval between a history's samples is cut into this many for F_eq (module doc)


def history_force(
    t, times, approaches, *, radius, C, alpha, branches, equilibrium="fem", substeps=HISTORY_SUBSTEPS, coupling="auto"
):
    r"""The lumped model's plate force (N) at ``t`` (s; each one a sample time of ``times``) under the measured
    approach history ``(times, approaches)`` (s, strictly increasing from 0; m, linear between the samples): what
    ``reduced.spheroid.force(displacement=(times, approaches), coupling=coupling)`` integrates with diffrax, here by
    the exact recursion for an F_eq linear in time on each of ``substeps`` parts of a sample interval. The branch
    equation dq_m/dt = -q_m / tau_m + beta_m dF_eq/dt + p max(dx/dt, 0) (q_m - beta_m F_eq) (x = delta / (2 a0), p the
    geometric coupling ``reduced.spheroid.branch_coupling``) has on a part of length h with x' constant and
    F_eq = F_0 + r s, with k = 1/tau_m - p x'^+ and c = p x'^+,

        q_m(h) = q_m(0) e^{-k h} + beta_m [(r - c F_0) E_1 - c r E_2],  E_1 = (1 - e^{-k h}) / k,  E_2 = (h - E_1) / k

    (p = 0: q_m(t + h) = q_m(t) e^{-h/tau_m} + beta_m tau_m r (1 - e^{-h/tau_m})), second-order in h (the curvature of
    F_eq(delta(t)) within a part). JAX-traceable (jit, jacfwd), ~1000 times faster than the ODE on a record of noisy
    samples (every sample a kink the adaptive ODE steps must find); agrees with ``reduced.spheroid.force`` to 1e-5 of
    the peak on the tests' histories (tests/test_compare_fit_protocols.py)."""
    from tissuemech.reduced import spheroid

    p = spheroid.branch_coupling(coupling, equilibrium)
    times, approaches = jnp.asarray(times), jnp.asarray(approaches)
    w = jnp.arange(substeps) / substeps
    tf = jnp.concatenate([(times[:-1, None] + jnp.diff(times)[:, None] * w).ravel(), times[-1:]])
    df = jnp.concatenate([(approaches[:-1, None] + jnp.diff(approaches)[:, None] * w).ravel(), approaches[-1:]])
    feq = spheroid.equilibrium_force(jnp.maximum(df, 0.0), radius=radius, C=C, alpha=alpha, equilibrium=equilibrium)
    h = jnp.diff(tf)
    rate = jnp.diff(feq) / h
    c = p * jnp.maximum(jnp.diff(df) / (2.0 * radius), 0.0) / h  # p x'^+ (1/s) on each part
    total = feq
    for beta, tau in branches:
        k = 1.0 / tau - c
        kh = k * h
        small = jnp.abs(kh) < 1e-3
        ks = jnp.where(small, 1.0, k)
        e1 = jnp.where(small, h * (1.0 - kh / 2.0 + kh**2 / 6.0), -jnp.expm1(-kh) / ks)
        e2 = jnp.where(small, h**2 * (0.5 - kh / 6.0 + kh**2 / 24.0), (h - e1) / ks)
        a = jnp.exp(-kh)
        inc = beta * ((rate - c * feq[:-1]) * e1 - c * rate * e2)

        def step(q, ai):
            q = ai[0] * q + ai[1]
            return q, q

        _, q = jax.lax.scan(step, jnp.zeros(()), jnp.stack([a, inc], axis=1))
        total = total + jnp.concatenate([jnp.zeros(1), q])
    return jnp.interp(jnp.asarray(t), tf, total)


def _one(kind, p, nb, data, radius, ramp_time, equilibrium):
    """The model's prediction of one record's observable at its times (JAX-traceable)."""
    from tissuemech.reduced import spheroid

    branches = [(p[2 + m], p[2 + nb + m]) for m in range(nb)]
    kw = dict(radius=radius, C=p[0], alpha=p[1], branches=branches, equilibrium=equilibrium)
    if kind == "creep":
        t, level = data
        return spheroid.approach(t, force=level, ramp_time=ramp_time, method=_forward_ode(), **kw)
    if kind == "history":
        t, ht, hd = data
        return history_force(t, ht, hd, **kw)
    t, d = data
    return default_model()(t, displacement=d, ramp_time=ramp_time, **kw)


def _residual(theta, data, ys, peaks, kinds, radius, ramp_time, equilibrium, nb):
    p = jnp.exp(theta)
    return jnp.concatenate(
        [(_one(k, p, nb, d, radius, ramp_time, equilibrium) - y) / s for k, d, y, s in zip(kinds, data, ys, peaks)]
    )


_STATIC = ("kinds", "radius", "ramp_time", "equilibrium", "nb")
_residual_jit = jax.jit(_residual, static_argnames=_STATIC)
_jacobian_jit = jax.jit(jax.jacfwd(_residual), static_argnames=_STATIC)


def _model_data(r: Any) -> tuple:
    if isinstance(r, CreepRecord):
        return (jnp.asarray(r.time), jnp.asarray(r.force))
    if isinstance(r, HistoryRecord):
        ht, hd = _driving_history(r)
        return (jnp.asarray(r.time), jnp.asarray(ht), jnp.asarray(hd))
    return (jnp.asarray(r.time), jnp.asarray(r.displacement))


def _hertz_c(force: float, approach: float, radius: float) -> float:
    """C (Pa) of the Hertz law F = (32/3) C sqrt(a0) (delta/2)^1.5 through one (approach m, force N) point."""
    return force / ((32.0 / 3.0) * math.sqrt(radius) * (max(approach, 1e-300) / 2.0) ** 1.5)


def _guess(recs: Sequence[Any], radius: float, ramp_time: float, nb: int) -> np.ndarray:
    """A rough start from each record's shape (the relaxation records by :func:`initial_guess`)."""
    cs, betas, spans = [], [], []
    for r in recs:
        spans.append(float(r.time.max()))
        n_tail = max(1, r.time.size // 20)
        if isinstance(r, CreepRecord):
            d_end = float(np.mean(r.approach[-n_tail:]))
            after = r.approach[r.time >= ramp_time]
            d_0 = float(np.mean(after[: max(1, min(3, after.size))])) if after.size else d_end
            cs.append(_hertz_c(r.force, d_end, radius))
            betas.append((d_end / max(d_0, 1e-300)) ** 1.5 - 1.0)
        elif isinstance(r, HistoryRecord):
            f_end, d_end = float(np.mean(r.force[-n_tail:])), float(np.mean(r.approach[-n_tail:]))
            cs.append(_hertz_c(f_end, d_end, radius))
            betas.append(float(np.max(r.force)) / max(f_end, 1e-300) - 1.0)
        else:
            g = initial_guess([r], radius, ramp_time, 1)
            cs.append(float(g[0]))
            betas.append(float(g[2]))
    C0 = max(float(np.median(cs)), 1e-3)
    beta_tot = max(float(np.median(betas)), 0.05)
    span = max(float(np.max(spans)) - ramp_time, 10 * ramp_time)
    taus = np.geomspace(span / 20.0, span / 3.0, nb) if nb > 1 else np.array([span / 8.0])
    return np.concatenate([[C0, 0.1], np.full(nb, beta_tot / nb), taus])


def _check_geometry(recs: Sequence[Any], radius: float, equilibrium: Any) -> None:
    """ValueError when an approach reaches the ball's diameter or leaves the equilibrium table."""
    d_max = max(float(r.displacement) if isinstance(r, Record) else float(np.max(r.approach)) for r in recs)
    x = d_max / (2 * radius)
    if x >= 0.999:
        raise ValueError(
            f"the plates approach by {d_max / UM:.4g} um, {x:.3g} times the ball's diameter of {2 * radius / UM:.4g} "
            f"um (radius {radius / UM:.4g} um), but they touch when the approach reaches the diameter: check the "
            "approach and the radius (given in m; on the command line in um)"
        )
    mc = table_of(equilibrium)
    if mc is not None and x > mc.x_max * (1 + 1e-12):
        raise ValueError(
            f"the approach reaches {x:.4g} of the ball's diameter, beyond the calibrated table (it reaches "
            f"{mc.x_max:.4g}): use equilibrium='hertz' (small compressions only) or records of smaller approaches"
        )


def records_fit(
    records: Sequence[Any],
    *,
    radius: float,
    ramp_time: float | None = None,
    n_branches: int = 1,
    equilibrium: Any = "fem",
    initial: dict[str, float] | Sequence[float] | None = None,
    max_nfev: int = 200,
    model_error: float | str | None = "auto",
    intervals: str = "profile",
    errors: str = "robust",
    misfit: float = 0.0,
) -> FitResult:
    r"""Fit ``(C, alpha, beta_m, tau_m)`` to relaxation, creep and measured-history records of one spheroid (module
    doc), alone or mixed; the keywords and the statistics are those of :func:`~tissuemech.compare.fit.relaxation`.

    records     :class:`~tissuemech.compare.fit.records.Record` (relaxation; or a ``(time, nominal_stress,
                displacement)`` tuple), :class:`CreepRecord`, :class:`HistoryRecord`, in any mix (SI units).
    radius      ball radius a0 (m).
    ramp_time   duration of the loading ramp (s) of the relaxation and creep records; for measured histories alone
                it may be None (the time the first record's approach reaches 90 % of its largest value then sets
                the lower bound of the relaxation times and the discrepancy's log-time axis).

    Returns a :class:`~tissuemech.compare.fit.FitResult` whose ``noise`` is each record's noise sd in its own unit
    (``units``: Pa, m or N) and whose ``residual`` is the RMS residual relative to each record's peak (-).
    Raises ValueError for malformed or uninformative records (time not increasing, duplicated times, too few
    samples, a non-positive observable, an approach past the diameter or the table) and RuntimeError when the
    model fails at the starting point.
    """
    recs = _as_protocol_records(records)
    validate_positive("radius (of the spheroid)", radius, "m")
    kinds = tuple(protocol_of(r) for r in recs)
    if ramp_time is None:
        if any(k != "history" for k in kinds):
            raise ValueError(
                "ramp_time (s) is needed for relaxation and creep records: the duration of the loading ramp"
            )
        h = next(r for r in recs if isinstance(r, HistoryRecord))
        ramp_time = float(h.time[int(np.argmax(h.approach >= 0.9 * np.max(h.approach)))]) or float(h.time[1])
    validate_positive("ramp_time (duration of the loading ramp)", ramp_time, "s")
    names = parameter_names(n_branches)
    for k, r in enumerate(recs):
        if isinstance(r, Record):
            check_record(r, f"record {k}")
            check_ramp(r.time, r.nominal_stress, float(ramp_time), f"record {k}")
    if sum(r.time.size for r in recs) <= len(names):
        raise ValueError(f"the records hold too few data points for the {len(names)} parameters {names}")
    if intervals not in ("profile", "wald"):
        raise ValueError(f"intervals must be 'profile' or 'wald'; got {intervals!r}")
    if not (math.isfinite(misfit) and misfit >= 0):
        raise ValueError(
            f"misfit (relative RMS size of the model's smooth misfit, -) must be a finite number >= 0; got {misfit}"
        )
    if errors not in ERROR_MODELS:
        raise ValueError(f"errors must be one of {', '.join(map(repr, ERROR_MODELS))}; got {errors!r}")
    _check_geometry(recs, float(radius), equilibrium)
    eps = model_error_value(model_error, equilibrium)
    p0 = starting_point(initial, names, lambda: _guess(recs, float(radius), float(ramp_time), n_branches))
    peaks = tuple(float(np.max(np.abs(_observed(r)))) for r in recs)
    # the core fits each record's observable relative to its peak (the residual's scale is 1)
    pseudo = [Record(r.time, _observed(r) / s, 1.0) for r, s in zip(recs, peaks)]
    args = (
        tuple(_model_data(r) for r in recs),
        tuple(jnp.asarray(_observed(r)) for r in recs),
        tuple(jnp.asarray(s) for s in peaks),
    )
    kw = dict(kinds=kinds, radius=float(radius), ramp_time=float(ramp_time), equilibrium=equilibrium, nb=n_branches)
    res_fn: Callable
    jac_fn: Callable
    try:
        hash(equilibrium)
        res_fn = functools.partial(_residual_jit, data=args[0], ys=args[1], peaks=args[2], **kw)
        jac_fn = functools.partial(_jacobian_jit, data=args[0], ys=args[1], peaks=args[2], **kw)
    except TypeError:  # an unhashable law (arrays): closed over
        f = lambda th: _residual(th, *args, **kw)
        res_fn, jac_fn = jax.jit(f), jax.jit(jax.jacfwd(f))
    res = estimate(
        pseudo,
        res_fn,
        jac_fn,
        1.0,
        names=names,
        p0=p0,
        n_branches=n_branches,
        equilibrium=equilibrium,
        ramp_time=float(ramp_time),
        eps=eps,
        max_nfev=max_nfev,
        intervals=intervals,
        errors=errors,
        misfit=misfit,
    )
    units = tuple({"creep": "m", "history": "N", "relaxation": "Pa"}[k] for k in kinds)
    return dataclasses.replace(
        res, noise=tuple(s * pk for s, pk in zip(res.noise, peaks)), units=units, protocols=kinds
    )


def predict(
    record: Any,
    params: dict[str, float],
    *,
    radius: float,
    ramp_time: float,
    equilibrium: Any = "fem",
    times: Any = None,
) -> np.ndarray:
    """The fitted model's prediction of a record's observable (Pa, m or N) at ``times`` (s; default the record's
    own), for ``params`` by name (a :class:`FitResult`'s ``params``)."""
    nb = sum(1 for n in params if n.startswith("beta"))
    names = parameter_names(max(nb, 1))
    p = jnp.asarray([params[n] for n in names])
    r = _as_protocol_records([record])[0]
    data = list(_model_data(r))
    if times is not None:
        data[0] = jnp.asarray(times, dtype=float)
    return np.asarray(_one(protocol_of(r), p, max(nb, 1), tuple(data), radius, ramp_time, equilibrium))


def read_protocol_csv(
    path: str | Path, *, protocol: str = "auto", ramp_time: float | None = None, force: float | None = None
) -> tuple[Any, str, str]:
    """A creep or measured-history record from a CSV file with ``time``, ``approach`` and ``force`` columns (units in
    the header: ``time [min], approach [um], force [uN]``; :data:`~tissuemech.compare.fit.records.COLUMN_UNITS`).

    protocol   "creep" (the held force, :func:`creep_level`, drives the model; the approach is fitted), "history"
               (the approach drives, the force is fitted) or "auto": creep when the force is held after
               ``ramp_time`` (s), else history.
    force      the stated held force (N) of a creep record; None: read from the file's force column.
    Returns (record, protocol, why: one line saying how the protocol was chosen). ValueError (one line naming the
    file) for a file without these columns and for the traps of :func:`check_samples` and :func:`creep_level`.
    """
    if protocol not in ("auto", "creep", "history"):
        raise ValueError(
            f"protocol must be 'auto', 'creep' or 'history' for a time, approach, force file; got {protocol!r}"
        )
    table = read_table(path)
    cols = header_columns(table)
    missing = [k for k in ("time", "approach", "force") if k not in cols]
    if missing:
        raise ValueError(
            f"{table.path}: no {' or '.join(missing)} column in the header {list(table.header)}: a creep or "
            "measured-history file needs 'time [s], approach [um], force [uN]' (any known units)"
        )
    (ti, tf), (di, df), (fi, ff) = cols["time"], cols["approach"], cols["force"]
    t, d, f = check_samples(
        table.values[:, ti] * tf,
        {"approach": table.values[:, di] * df, "force": table.values[:, fi] * ff},
        str(table.path),
    )
    if protocol == "history":
        return HistoryRecord(t, d, f), "history", "history (as asked)"
    if ramp_time is None:
        raise ValueError(f"{table.path}: the ramp time (s) is needed to read a creep record (--ramp-time)")
    if protocol == "creep":
        return CreepRecord(t, d, creep_level(t, f, ramp_time, str(table.path), force)), "creep", "creep (as asked)"
    level, head, tail, tol, _ = _held(t, f, ramp_time, str(table.path))
    if abs(tail - head) > tol:
        why = (
            f"history (inferred: the force is not held after the {ramp_time:g} s ramp, it goes from {head:.4g} N to "
            f"{tail:.4g} N)"
        )
        return HistoryRecord(t, d, f), "history", why
    level = creep_level(t, f, ramp_time, str(table.path), force)
    why = f"creep (inferred: the force is held at {level / 1e-6:.4g} uN after the {ramp_time:g} s ramp)"
    return CreepRecord(t, d, level), "creep", why
