"""The forward model of the fit and its search space: parameter names and units, the residual (log-parameters ->
model minus data, scaled) with its exact ``jax.jacfwd`` Jacobian, the starting guess, the search bounds, the
equilibrium table behind a law and its stated accuracy (the model-error term)."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

import tissuemech.reduced  # noqa: F401  (enables float64 in JAX)
from tissuemech.compare.fit.records import Record

__all__ = [
    "TABLE_EDGE_X",
    "TABLE_EDGE_MODEL_ERROR",
    "ALPHA_BOUNDS",
    "BETA_BOUNDS",
    "TAU_SPAN",
    "DEFAULT_MODEL_ERROR_REL",
    "PARAMETER_UNITS",
    "parameter_names",
    "default_model",
    "incompressible_model",
    "initial_guess",
    "residual_builder",
    "EVALUATION_CHUNK",
    "sample_evaluator",
    "table_of",
    "model_error_of",
    "stated_accuracy",
    "search_bounds",
]

ALPHA_BOUNDS = (1e-6, 10.0)
BETA_BOUNDS = (1e-8, 1e4)
# tau is searched within TAU_SPAN = (1e-3 ramp times, 1e3 times the last record time): beyond either end a branch is
# indistinguishable in the records from one at that end (relaxed within the ramp's start / not relaxing during the
# records: extra permanent stiffness), and an unbounded search ran tau to 1e302 s on records that do not relax
TAU_SPAN = (1e-3, 1e3)
DEFAULT_MODEL_ERROR_REL = 0.005  # 1-sigma relative error of F_eq assumed for a table without `model_error_rel`
# The shipped plate table between its nodes (issue 35, docs/validation.md): within its stated accuracy up to
# x = 0.31, but in the last two x intervals (x > 0.32) up to an estimated 4e-5 (alpha >= 1.4) off the converged
# force, 1.6x its metadata's 2-sigma bound: "auto" uses this 1-sigma term for records reaching beyond TABLE_EDGE_X.
TABLE_EDGE_X = 0.32
TABLE_EDGE_MODEL_ERROR = 2.4e-5
PARAMETER_UNITS = {"C": "Pa", "alpha": "-", "beta": "-", "tau": "s"}  # by name stem (beta_1 -> beta)


def parameter_names(n_branches: int = 1) -> tuple[str, ...]:
    """``(C, alpha, beta, tau)`` for one branch, ``(C, alpha, beta_1, .., tau_1, ..)`` for more."""
    if n_branches < 1:
        raise ValueError(f"n_branches must be at least 1; got {n_branches}")
    if n_branches == 1:
        return ("C", "alpha", "beta", "tau")
    return (
        ("C", "alpha")
        + tuple(f"beta_{m}" for m in range(1, n_branches + 1))
        + tuple(f"tau_{m}" for m in range(1, n_branches + 1))
    )


def default_model() -> Callable:
    """``reduced.spheroid.nominal_stress`` (the fit differentiates it with ``jax.jacfwd``; the same function
    object every call, so compiled residuals are reused between fits)."""
    from tissuemech.reduced import spheroid

    return spheroid.nominal_stress


@functools.lru_cache(maxsize=1)
def incompressible_model() -> Callable:
    """``reduced.spheroid.nominal_stress`` with the incompressible midplane estimate r_mid = a0 / sqrt(1 - x): the
    model for records given as forces (:func:`~tissuemech.compare.fit.records.load_records` divides them by that
    area); cached, so compiled residuals are reused between fits."""
    from tissuemech.reduced import spheroid

    return functools.partial(spheroid.nominal_stress, midplane="incompressible")


def initial_guess(records: Sequence[Record], radius: float, ramp_time: float, n_branches: int = 1) -> np.ndarray:
    """Rough starting point (in the order of :func:`parameter_names`) from the curves' shape.

    C from the Hertz law at the long-time stress (sigma_end ~ (32/3) C sqrt(a0) (delta/2)^1.5 / (pi a0^2)),
    alpha = 0.1, sum beta = peak/end - 1, tau's log-spaced over the hold.
    """
    ends, peaks, spans = [], [], []
    for r in records:
        hertz = (32.0 / 3.0) * math.sqrt(radius) * (r.displacement / 2.0) ** 1.5 / (math.pi * radius**2)
        tail = r.nominal_stress[-max(1, r.time.size // 20) :]
        ends.append(np.mean(tail) / hertz)
        peaks.append(np.max(r.nominal_stress) / max(np.mean(tail), 1e-300))
        spans.append(r.time.max())
    C0 = max(float(np.median(ends)), 1e-3)
    beta_tot = max(float(np.median(peaks)) - 1.0, 0.05)
    span = max(float(np.max(spans)) - ramp_time, 10 * ramp_time)
    taus = np.geomspace(span / 20.0, span / 3.0, n_branches) if n_branches > 1 else np.array([span / 8.0])
    betas = np.full(n_branches, beta_tot / n_branches)
    return np.concatenate([[C0, 0.1], betas, taus])


def _predict(theta, ts, ds, radius, ramp_time, model, equilibrium, nb):
    p = jnp.exp(theta)
    branches = [(p[2 + m], p[2 + nb + m]) for m in range(nb)]
    return [
        model(
            t,
            radius=radius,
            C=p[0],
            alpha=p[1],
            branches=branches,
            displacement=d,
            ramp_time=ramp_time,
            equilibrium=equilibrium,
        )
        for t, d in zip(ts, ds)
    ]


def _residual(theta, ts, ys, ds, scale, radius, ramp_time, model, equilibrium, nb):
    pred = _predict(theta, ts, ds, radius, ramp_time, model, equilibrium, nb)
    return jnp.concatenate([(m - y) / scale for m, y in zip(pred, ys)])


def _value_and_jacobian(theta, t, d, radius, ramp_time, model, equilibrium, nb):
    """One record's model (Pa) at times ``t`` and its Jacobian in theta (Pa per unit log-parameter), one pass."""

    def f(th):
        m = _predict(th, (t,), (d,), radius, ramp_time, model, equilibrium, nb)[0]
        return m, m

    jac, value = jax.jacfwd(f, has_aux=True)(theta)
    return value, jac


_STATIC = ("radius", "ramp_time", "model", "equilibrium", "nb")
_residual_jit = jax.jit(_residual, static_argnames=_STATIC)
_jacobian_jit = jax.jit(jax.jacfwd(_residual), static_argnames=_STATIC)
_value_and_jacobian_jit = jax.jit(_value_and_jacobian, static_argnames=_STATIC)

EVALUATION_CHUNK = 2**16  # samples per call of :func:`sample_evaluator`'s compiled program (one shape for any record)


def sample_evaluator(records, radius, ramp_time, n_branches, equilibrium, model, chunk: int = EVALUATION_CHUNK):
    """theta (log-parameters) -> (model (Pa), d model / d theta (Pa)) at every sample of ``records``, in their
    order: what a compressed fit's error model needs of the full records (:mod:`tissuemech.compare.fit.compress`).
    The samples go through one compiled program in chunks of ``chunk`` (the last one padded with its last time), so
    records of any length share it and memory stays flat in their length."""
    radius, ramp_time = float(radius), float(ramp_time)
    try:
        hash(equilibrium)
        kw = dict(radius=radius, ramp_time=ramp_time, model=model, equilibrium=equilibrium, nb=n_branches)
        call = lambda th, t, d: _value_and_jacobian_jit(th, t, d, **kw)
    except TypeError:  # unhashable equilibria (arrays) are closed over
        call = jax.jit(
            lambda th, t, d: _value_and_jacobian(th, t, d, radius, ramp_time, model, equilibrium, n_branches)
        )

    def evaluate(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        th = jnp.asarray(theta, dtype=float)
        values, jacs = [], []
        for rec in records:
            t = np.asarray(rec.time, dtype=float)
            d = jnp.asarray(float(rec.displacement))
            for lo in range(0, t.size, chunk):
                piece = t[lo : lo + chunk]
                n = piece.size
                if n < chunk:
                    piece = np.concatenate([piece, np.full(chunk - n, piece[-1])])
                v, j = call(th, jnp.asarray(piece), d)
                values.append(np.asarray(v)[:n])
                jacs.append(np.asarray(j)[:n])
        return np.concatenate(values), np.concatenate(jacs)

    return evaluate


def residual_builder(records, radius, ramp_time, n_branches, equilibrium, model):
    """residual(theta) and its jacfwd Jacobian (theta = log params), jit-compiled once per model,
    equilibrium and record shapes (records enter as arguments, so a refit of new data of the same
    shape does not recompile). Unhashable equilibria (arrays) are closed over instead."""
    args = (
        tuple(jnp.asarray(r.time) for r in records),
        tuple(jnp.asarray(r.nominal_stress) for r in records),
        tuple(jnp.asarray(r.displacement) for r in records),
    )
    scale = float(max(np.max(np.abs(r.nominal_stress)) for r in records)) or 1.0
    rest = (jnp.asarray(scale), float(radius), float(ramp_time))  # geometry static (Python floats)
    try:
        hash(equilibrium)
        kw = dict(model=model, equilibrium=equilibrium, nb=n_branches)
        return (
            lambda th: _residual_jit(th, *args, *rest, **kw),
            lambda th: _jacobian_jit(th, *args, *rest, **kw),
            scale,
        )
    except TypeError:
        f = lambda th: _residual(th, *args, *rest, model, equilibrium, n_branches)
        return jax.jit(f), jax.jit(jax.jacfwd(f)), scale


def table_of(equilibrium: Any):
    """The master-curve object behind an equilibrium spec ("fem", a MasterCurve or a FEMTable), else None."""
    from tissuemech.reduced import spheroid

    if isinstance(equilibrium, str) and equilibrium == "fem":
        return spheroid.master_curve()
    if isinstance(equilibrium, spheroid.MasterCurve):
        return equilibrium
    if isinstance(equilibrium, spheroid.FEMTable):
        return equilibrium.master
    return None


def model_error_of(equilibrium: Any) -> float:
    """The relative 1-sigma model error of an equilibrium law's force (the ``"auto"`` choice).

    For the FE master table ("fem" or a MasterCurve): its metadata ``model_error_rel``, else
    :data:`DEFAULT_MODEL_ERROR_REL`. For "hertz", an (x, f) table or a callable: 0 (taken as exact;
    pass ``model_error=`` to :func:`relaxation` to add one).
    """
    if table_of(equilibrium) is None:
        return 0.0
    v = stated_accuracy(equilibrium)
    return DEFAULT_MODEL_ERROR_REL if v is None else v


def ramp_model_error(params: dict[str, float], n_branches: int, ramp_time: float, x: float = 0.1) -> float:
    """The lumped model's own 1-sigma error during the ramp for fitted branches ``params`` (names of
    :func:`parameter_names`): half (a 2-sigma bound, as the table's ``model_error_rel``) of
    ``reduced.spheroid.lumped_ramp_error`` at the largest approach ``x`` = delta/(2 a0). A branch whose tau is near
    the ramp (tau / ramp_time 0.05-3) makes it 0.01-0.06 % with the default coupled law (0.05-0.25 % with the plain
    one), far above the table's 1.5e-5 (issue 35)."""
    from tissuemech.reduced.spheroid import lumped_ramp_error

    names = parameter_names(n_branches)
    beta = [params[n] for n in names[2 : 2 + n_branches]]
    tau = [params[n] for n in names[2 + n_branches :]]
    return 0.5 * lumped_ramp_error(tau, float(ramp_time), beta, x=x)


def stated_accuracy(equilibrium: Any) -> float | None:
    """The equilibrium table's own stated accuracy (metadata ``model_error_rel``, relative, >= 0), or None where
    the law is no table or states none. ``relaxation`` flags records that scatter about the model by less than
    it: they carry no noise the intervals could rest on."""
    mc = table_of(equilibrium)
    if mc is None:
        return None
    try:
        v = float(mc.metadata.get("model_error_rel"))
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) and v >= 0 else None


def search_bounds(names, n_branches, equilibrium, ramp_time: float, t_end: float):
    lo = np.full(len(names), -np.inf)
    hi = np.full(len(names), np.inf)
    a_lo, a_hi = ALPHA_BOUNDS
    mc = table_of(equilibrium)
    if mc is not None and mc.alpha is not None:
        a_lo, a_hi = max(a_lo, mc.alpha_range[0]), min(a_hi, mc.alpha_range[1])
    lo[1], hi[1] = np.log(a_lo), np.log(a_hi)
    lo[2 : 2 + n_branches], hi[2 : 2 + n_branches] = np.log(BETA_BOUNDS[0]), np.log(BETA_BOUNDS[1])
    taus = slice(2 + n_branches, 2 + 2 * n_branches)
    lo[taus], hi[taus] = np.log(TAU_SPAN[0] * ramp_time), np.log(TAU_SPAN[1] * max(t_end, ramp_time))
    return lo, hi
