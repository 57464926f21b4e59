r"""Experiment design for compression-relaxation fits: predicted interval widths from the Fisher matrix.

Given a candidate protocol (compression levels, ramp time, sampling times, noise level) and a guess of
the parameters, the Fisher matrix of the fit's statistical model (:mod:`tissuemech.compare.fit`: white noise of sd
``noise`` x each record's peak stress, optionally the per-record model-error factor) predicts each
parameter's 95 % interval before any measurement:

    F = sum_j [ J_j^T J_j / s_j^2 - b_j b_j^T / c_j ],   b_j = J_j^T m_j / s_j^2,  c_j = |m_j|^2 / s_j^2 + 1/eps^2

(J_j = d m_j / d log p for record j, m_j its model curve, s_j its noise sd in Pa, eps the relative
model error; the second term marginalises the record's model-error factor, absent for eps = 0), and
sd_i = sqrt((F^-1)_ii) the standard deviation of log p_i: the 95 % interval is about
p_i exp(+-1.96 sd_i), a relative width 2 sinh(1.96 sd_i). The contributions of the levels add, so a
scan over level pairs and triples costs one Jacobian per candidate level.

    tissuemech design [--first-um 50] [--noise 0.01] [--out design.png] [--check 100]
    (or python -m tissuemech.compare.design ...)

prints the predicted widths of the default protocol, the level pair and triple (within the master
table's range) that identify alpha best, a table of the predicted widths against the second level,
writes the figure, and with ``--check N`` fits N noisy reduced-made records per protocol for several
protocols and compares the predicted sd with the observed spread of the estimates.
"""

from __future__ import annotations

import itertools
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any, cast

import jax.numpy as jnp
import numpy as np
import pandas as pd

from tissuemech.compare.fit.intervals import Z95
from tissuemech.compare.fit.model import default_model, parameter_names, residual_builder, table_of
from tissuemech.compare.fit.records import Record
from tissuemech.reduced.material import validate_positive

__all__ = [
    "Protocol",
    "Prediction",
    "level_fisher",
    "fe_level_fisher",
    "FE_X_MAX",
    "predict",
    "scan_second_level",
    "recommend",
    "check",
    "CHECK_PROTOCOLS",
    "DEFAULT_TRUTH",
    "NAMES",
    "Z95",
    "check_truth",
    "check_levels",
]

DEFAULT_TRUTH = dict(C=150.0, alpha=0.2, beta=0.4, tau=200.0)
NAMES = parameter_names(1)


def _default_times() -> tuple[float, ...]:
    return tuple(np.concatenate([np.linspace(0.0, 0.2, 11)[1:], np.geomspace(0.3, 1500.0, 60)]))


@dataclass(frozen=True)
class Protocol:
    """A candidate experiment.

    levels     total plate approach of each record (m)
    ramp_time  loading ramp duration (s); times: sampling times of every record (s, > 0)
    noise      white-noise sd relative to each record's peak stress (-), e.g. 0.01
    radius     ball radius a0 (m)
    """

    levels: tuple[float, ...] = (50e-6, 200e-6)
    ramp_time: float = 0.2
    times: tuple[float, ...] = field(default_factory=_default_times)
    noise: float = 0.01
    radius: float = 500e-6

    def validate(self) -> None:
        if len(self.levels) < 1:
            raise ValueError("a protocol needs at least one compression level (m)")
        for d in self.levels:
            validate_positive("compression level (total approach of the plates)", d, "m")
        validate_positive("ramp_time (duration of the loading ramp)", self.ramp_time, "s")
        validate_positive("noise (sd relative to the peak stress)", self.noise, "-")
        validate_positive("radius (of the spheroid)", self.radius, "m")
        t = np.asarray(self.times, dtype=float)
        if t.size < 3 or np.any(t <= 0) or not np.all(np.isfinite(t)):
            raise ValueError("sampling times must be >= 3 positive, finite numbers (s)")

    def label(self) -> str:
        lv = "+".join(f"{d * 1e6:.4g}" for d in self.levels)
        return f"{lv} um, ramp {self.ramp_time:g} s, {len(self.times)} samples, noise {100 * self.noise:g} %"


@dataclass
class Prediction:
    """Predicted precision of a protocol: ``sd`` of log p (per name), ``width`` = relative 95 % width
    2 sinh(1.96 sd), ``interval`` = (p e^{-1.96 sd}, p e^{1.96 sd}), ``fisher`` (P x P, log space)."""

    protocol: Protocol
    truth: dict[str, float]
    sd: dict[str, float]
    width: dict[str, float]
    interval: dict[str, tuple[float, float]]
    fisher: np.ndarray


_UNITS = dict(C="Pa", alpha="-", beta="-", tau="s")


def check_truth(truth: Any, equilibrium: Any = "fem") -> dict[str, float]:
    """The parameter guess as floats: ValueError (one line, naming the parameter and unit) unless ``truth`` is a
    mapping with exactly the keys :data:`NAMES`, each positive and finite (the design works in log parameters), and
    alpha within the equilibrium table's calibrated range."""
    if not isinstance(truth, dict):
        raise ValueError(f"truth must be a dict of {list(NAMES)} (C Pa, alpha -, beta -, tau s); got {truth!r}")
    missing = [n for n in NAMES if n not in truth]
    unknown = sorted(set(map(str, truth)) - set(NAMES))
    if missing or unknown:
        raise ValueError(
            f"truth needs exactly the parameters {list(NAMES)} (C Pa, alpha -, beta -, tau s)"
            + (f"; missing {missing}" if missing else "")
            + (f"; unknown {unknown}" if unknown else "")
        )
    out = {}
    for n in NAMES:
        try:
            v = float(truth[n])
        except (TypeError, ValueError):
            raise ValueError(f"truth {n} ({_UNITS[n]}) must be a number; got {truth[n]!r}") from None
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"truth {n} ({_UNITS[n]}) must be positive and finite (the design is in log p); got {v}")
        out[n] = v
    mc = table_of(equilibrium)
    if mc is not None and mc.alpha is not None:
        lo, hi = mc.alpha_range
        if not lo <= out["alpha"] <= hi * (1 + 1e-12):
            raise ValueError(
                f"truth alpha (-) = {out['alpha']:g} is outside the equilibrium table's calibrated range "
                f"[{lo:g}, {hi:g}]: its predictions there would be extrapolated"
            )
    return out


def check_levels(levels: Any, protocol: Protocol, equilibrium: Any = "fem", what: str = "compression level") -> None:
    """ValueError (one line, naming the level in um) for a compression level (total approach, m) that is not
    positive and finite, reaches the ball's diameter, or lies beyond the equilibrium table's range."""
    mc = table_of(equilibrium)
    diameter = 2 * float(protocol.radius)
    for d in np.atleast_1d(np.asarray(levels, dtype=float)):
        if not (math.isfinite(d) and d > 0):
            raise ValueError(f"{what} (total approach of the plates, m) must be positive and finite; got {d}")
        x = d / diameter
        if x >= 1:
            raise ValueError(
                f"{what} {d * 1e6:.4g} um reaches the ball's diameter ({diameter * 1e6:.4g} um): the plates would touch"
            )
        if mc is not None and x > mc.x_max * (1 + 1e-12):
            raise ValueError(
                f"{what} {d * 1e6:.4g} um (delta/(2 a0) = {x:.4g}) is beyond the master table (up to {mc.x_max:.4g}, "
                f"{mc.x_max * diameter * 1e6:.4g} um for radius {protocol.radius * 1e6:.4g} um)"
            )


def level_fisher(
    level: float,
    protocol: Protocol,
    truth: dict[str, float] = DEFAULT_TRUTH,
    *,
    equilibrium: Any = "fem",
    model_error: float = 0.0,
) -> np.ndarray:
    """Fisher matrix (4 x 4, log parameters) of ONE record at total approach ``level`` (m), with the
    record's model-error factor (relative sd ``model_error``) marginalised. ValueError (one line) for a bad
    protocol, truth (:func:`check_truth`) or level (:func:`check_levels`)."""
    protocol.validate()
    truth = check_truth(truth, equilibrium)
    check_levels(level, protocol, equilibrium)
    t = np.asarray(protocol.times, dtype=float)
    p = np.array([truth[n] for n in NAMES], dtype=float)
    theta = np.log(p)
    ones = np.ones_like(t)
    res_fn, jac_fn, scale = residual_builder(
        [Record(t, ones, float(level))],
        float(protocol.radius),
        float(protocol.ramp_time),
        1,
        equilibrium,
        default_model(),
    )
    m = np.asarray(res_fn(jnp.asarray(theta))) * scale + ones  # residual = (m - 1) / scale
    J = np.asarray(jac_fn(jnp.asarray(theta))) * scale
    return _record_fisher(J, m, protocol.noise, model_error, level, truth)


def _record_fisher(
    J: np.ndarray, m: np.ndarray, noise: float, model_error: float, level: float, truth: dict
) -> np.ndarray:
    """The Fisher matrix of one record (module doc) from its model ``m`` (Pa) and ``J = dm / dlog p``."""
    s = noise * np.max(np.abs(m))
    if not (np.all(np.isfinite(J)) and np.all(np.isfinite(m))):
        raise ValueError(
            f"the model is not finite at compression level {level * 1e6:.4g} um and truth {truth}: no prediction"
        )
    A = J.T @ J / s**2
    if model_error and model_error > 0:
        b = J.T @ m / s**2
        c = float(m @ m) / s**2 + 1.0 / model_error**2
        A = A - np.outer(b, b) / c
    return A


FE_X_MAX = 0.5  # the FE design's candidate levels reach delta/(2 a0) = 0.5 (the reduced table stops at 0.36)


def fe_level_fisher(
    level: float,
    protocol: Protocol,
    truth: dict[str, float] = DEFAULT_TRUTH,
    *,
    mesh: Any = "coarse",
    model_error: float = 0.0,
    n_ramp: int = 10,
    n_hold: int = 60,
) -> np.ndarray:
    """:func:`level_fisher` with the FE as the model: ``fem.spheroid.compress(gradient=True)`` (node-by-node contact
    on ``mesh``; its exact sensitivities of the nominal stress, linear between the FE's steps at the protocol's
    times), where the reduced model's table does not reach (alpha beyond its range, levels beyond x = 0.36). One FE
    run with gradients per call (seconds on the coarse mesh). ValueError (one line) for a bad protocol or truth or
    a level at the ball's diameter."""
    from tissuemech.fem import spheroid as fem_spheroid

    protocol.validate()
    truth = check_truth(truth, equilibrium=None)  # no table: any positive alpha
    check_levels(level, protocol, equilibrium=None)
    t = np.asarray(protocol.times, dtype=float)
    r = fem_spheroid.compress(radius=float(protocol.radius), C=truth["C"], alpha=truth["alpha"],
                              branches=[(truth["beta"], truth["tau"])], displacement=float(level),
                              ramp_time=float(protocol.ramp_time), end_time=float(t.max()), mesh=mesh,
                              contact="nodal", n_ramp=n_ramp, n_hold=n_hold, gradient=True)  # fmt: skip
    tt = np.concatenate([[0.0], r.time])
    m = np.interp(t, tt, np.concatenate([[0.0], r.nominal_stress]))
    grad = r.gradient or {}
    J = np.stack(
        [np.interp(t, tt, np.concatenate([[0.0], grad[n]["nominal_stress"]])) * truth[n] for n in NAMES], axis=1
    )
    return _record_fisher(J, m, protocol.noise, model_error, level, truth)


def _from_fisher(F: np.ndarray, protocol: Protocol, truth: dict[str, float]) -> Prediction:
    lam, V = np.linalg.eigh(0.5 * (F + F.T))
    inv = (V / np.maximum(lam, 1e-300 + 1e-16 * max(float(lam.max()), 1e-300))) @ V.T
    sd = np.sqrt(np.abs(np.diag(inv)))
    sdd = {n: float(v) for n, v in zip(NAMES, sd)}
    width = {n: float(2 * math.sinh(min(Z95 * v, 700.0))) for n, v in sdd.items()}
    ival = {
        n: (truth[n] * math.exp(-min(Z95 * v, 700)), truth[n] * math.exp(min(Z95 * v, 700))) for n, v in sdd.items()
    }
    return Prediction(protocol, dict(truth), sdd, width, ival, F)


def predict(
    protocol: Protocol,
    truth: dict[str, float] = DEFAULT_TRUTH,
    *,
    equilibrium: Any = "fem",
    model_error: float = 0.0,
    model: str = "reduced",
    mesh: Any = "coarse",
) -> Prediction:
    """Predicted standard deviations of log p and 95 % interval widths of a protocol (module doc).

    truth        the parameters at which to evaluate (C Pa, alpha -, beta -, tau s): a prior guess.
    model_error  relative 1-sigma model error of the force per record (0: none; as in compare.fit).
    model        "reduced" (default) or "fe": the FE's exact sensitivities (:func:`fe_level_fisher` on ``mesh``),
                 for truths and levels beyond the reduced model's table (one FE run per level).
    Raises ValueError for an invalid protocol or a level beyond the master table.
    """
    protocol.validate()
    if model == "fe":
        truth = check_truth(truth, equilibrium=None)
        check_levels(protocol.levels, protocol, equilibrium=None)
        F = sum(fe_level_fisher(d, protocol, truth, mesh=mesh, model_error=model_error) for d in protocol.levels)
        return _from_fisher(np.asarray(F), protocol, truth)
    _check_model(model)
    truth = check_truth(truth, equilibrium)
    check_levels(protocol.levels, protocol, equilibrium)
    F = sum(level_fisher(d, protocol, truth, equilibrium=equilibrium, model_error=model_error) for d in protocol.levels)
    return _from_fisher(np.asarray(F), protocol, truth)


def _check_model(model: str) -> None:
    if model not in ("reduced", "fe"):
        raise ValueError(f"model must be 'reduced' (the FE-calibrated lumped model) or 'fe'; got {model!r}")


def _candidates(protocol: Protocol, n: int = 15, equilibrium: Any = "fem") -> np.ndarray:
    mc = table_of(equilibrium)
    x_max = mc.x_max if mc is not None else 0.3
    return np.linspace(0.02, x_max, n) * 2 * protocol.radius


def scan_second_level(
    first: float,
    protocol: Protocol = Protocol(),
    truth: dict[str, float] = DEFAULT_TRUTH,
    *,
    candidates: Sequence[float] | None = None,
    model_error: float = 0.0,
    model: str = "reduced",
    mesh: Any = "coarse",
) -> pd.DataFrame:
    """Predicted relative 95 % widths (%) of each parameter for levels (first, second), second over
    ``candidates`` (m; default 15 levels up to the table's end). ``model="fe"``: the FE's sensitivities
    (:func:`fe_level_fisher` on ``mesh``, one FE run per level; default candidates 8 levels up to x =
    :data:`FE_X_MAX`, beyond the table), for truths (alpha > 1.5) and levels the reduced model does not reach."""
    _check_model(model)
    protocol.validate()
    fe = model == "fe"
    law = None if fe else "fem"
    truth = check_truth(truth, law)
    check_levels(first, protocol, law, what="first level")
    if candidates is None:
        cand = np.linspace(0.04, FE_X_MAX, 8) * 2 * protocol.radius if fe else _candidates(protocol)
    else:
        cand = np.asarray(candidates, dtype=float).ravel()
    check_levels(cand, protocol, law, what="candidate level")

    def fisher(d: float) -> np.ndarray:
        if fe:
            return fe_level_fisher(d, protocol, truth, mesh=mesh, model_error=model_error)
        return level_fisher(d, protocol, truth, model_error=model_error)

    F1 = fisher(first)
    rows = []
    for d in cand:
        pr = _from_fisher(F1 + fisher(float(d)), protocol, truth)
        rows.append(
            {"first um": first * 1e6, "second um": d * 1e6, **{f"{n} width %": 100 * pr.width[n] for n in NAMES}}
        )
    return pd.DataFrame(rows)


def recommend(
    protocol: Protocol = Protocol(),
    truth: dict[str, float] = DEFAULT_TRUTH,
    *,
    n_levels: int = 2,
    candidates: Sequence[float] | None = None,
    target: str = "alpha",
    model_error: float = 0.0,
) -> tuple[tuple[float, ...], Prediction]:
    """The ``n_levels`` compression levels (m, from ``candidates``, default within the table's range)
    that minimise the predicted interval width of ``target``; returns (levels, Prediction). ValueError (one line)
    for a bad truth, a candidate beyond the table or the diameter, or fewer candidates than ``n_levels``."""
    if n_levels < 1:
        raise ValueError(f"n_levels must be at least 1; got {n_levels}")
    if target not in NAMES:
        raise ValueError(f"target must be one of {NAMES}; got {target!r}")
    protocol.validate()
    truth = check_truth(truth)
    cand = _candidates(protocol) if candidates is None else np.asarray(candidates, dtype=float).ravel()
    check_levels(cand, protocol, what="candidate level")
    if len(cand) < n_levels:
        raise ValueError(f"{n_levels} levels are asked for, but only {len(cand)} candidate level(s) were given (m)")
    Fs = [level_fisher(float(d), protocol, truth, model_error=model_error) for d in cand]
    best, best_w = None, math.inf
    for combo in itertools.combinations(range(len(cand)), n_levels):
        pr = _from_fisher(cast(np.ndarray, sum(Fs[k] for k in combo)), protocol, truth)
        if pr.width[target] < best_w:
            best, best_w = combo, pr.width[target]
    if best is None:
        raise ValueError(f"no combination of the candidate levels gives a finite width of {target}")
    levels = tuple(float(cand[k]) for k in best)
    return levels, _from_fisher(cast(np.ndarray, sum(Fs[k] for k in best)), replace(protocol, levels=levels), truth)


def check(
    protocols: Sequence[Protocol],
    truth: dict[str, float] = DEFAULT_TRUTH,
    n_draws: int = 100,
    seed: int = 1,
    log=sys.stderr,
) -> pd.DataFrame:
    """Predicted sd of log p against the observed spread of fits to ``n_draws`` noisy reduced-made
    records per protocol (model_error = 0), and against the median width of the fits' intervals."""
    from tissuemech.compare.fit.estimation import relaxation
    from tissuemech.compare.studies import coverage

    rng = np.random.default_rng(seed)
    rows = []
    for pc in protocols:
        pr = predict(pc, truth)
        prot = dict(radius=pc.radius, levels=pc.levels, ramp_time=pc.ramp_time, times=pc.times)
        clean = coverage.reduced_records(truth, prot)
        est: dict[str, list[float]] = {n: [] for n in NAMES}
        wid: dict[str, list[float]] = {n: [] for n in NAMES}
        inside = {n: 0 for n in NAMES}
        nfit = 0
        for _ in range(n_draws):
            recs = coverage.add_noise(clean, pc.noise, rng)
            try:
                res = relaxation(recs, radius=pc.radius, ramp_time=pc.ramp_time, model_error=0.0)
            except (ValueError, RuntimeError):
                continue
            nfit += 1
            for n in NAMES:
                est[n].append(math.log(res.params[n]))
                lo, hi = res.intervals[n]
                wid[n].append((hi - lo) / truth[n])
                inside[n] += lo <= truth[n] <= hi
        for n in NAMES:
            obs = float(np.std(est[n], ddof=1))
            rows.append(
                {
                    "protocol": pc.label(),
                    "parameter": n,
                    "predicted sd(log p)": pr.sd[n],
                    "observed sd(log p)": obs,
                    "ratio pred/obs": pr.sd[n] / obs,
                    "predicted width %": 100 * pr.width[n],
                    "median fitted width %": 100 * float(np.median(wid[n])),
                    "coverage %": 100 * inside[n] / max(nfit, 1),
                    "fits": nfit,
                }
            )
        print(f"checked {pc.label()}: {nfit} fits", file=log)
    return pd.DataFrame(rows)


CHECK_PROTOCOLS = (
    Protocol(levels=(50e-6, 200e-6), noise=0.01),
    Protocol(levels=(50e-6, 100e-6), noise=0.01),
    Protocol(levels=(25e-6, 100e-6, 250e-6), noise=0.03),
    Protocol(levels=(100e-6, 300e-6), noise=0.005),
)
