"""The fit itself: :func:`relaxation` (weighted least squares in log-parameters, per-record noise, the
model-error factors, 95 % intervals; the statistics are in :mod:`tissuemech.compare.fit`'s doc)."""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import jax.numpy as jnp
import numpy as np

from tissuemech.compare.fit.compress import bin_record, bins_for
from tissuemech.compare.fit.diagnostics import ERROR_MODELS, residual_diagnostics, robust_covariance
from tissuemech.compare.fit.intervals import LOG_SPAN, Profiler, exp_or_inf, identifiability, inverse_eigenvalues
from tissuemech.compare.fit.model import (
    BETA_BOUNDS,
    TABLE_EDGE_MODEL_ERROR,
    TABLE_EDGE_X,
    default_model,
    initial_guess,
    model_error_of,
    parameter_names,
    ramp_model_error,
    residual_builder,
    sample_evaluator,
    search_bounds,
    stated_accuracy,
    table_of,
)
from tissuemech.compare.fit.problem import Problem, masked_solver, safe
from tissuemech.compare.fit.records import Record, as_records, check_information, check_ramp
from tissuemech.compare.fit.result import FitResult
from tissuemech.reduced.material import validate_positive

__all__ = [
    "relaxation",
    "estimate",
    "model_error_value",
    "starting_point",
    "NOISE_FREE_REL",
    "hertz_range",
    "HERTZ_X_WARN",
    "HERTZ_X_MAX",
    "HertzRangeWarning",
    "FullRecords",
    "full_record_terms",
]

NOISE_FREE_REL = 1e-9  # RMS residual below this fraction of the record's peak: noise-free (synthetic) data
HERTZ_X_WARN = 0.1  # approach / diameter beyond which the small-strain Hertz law's force error exceeds ~15 %
HERTZ_X_MAX = 0.5  # ... and beyond which (an approach past the radius) a Hertz fit is refused


@dataclasses.dataclass(frozen=True)
class FullRecords:
    """The records a compressed fit was binned from (:mod:`tissuemech.compare.fit.compress`), for the error model of
    its intervals: ``records`` every sample, ``evaluate`` theta (log-parameters) -> (model Pa, d model / d theta Pa)
    at all of them (:func:`tissuemech.compare.fit.model.sample_evaluator`)."""

    records: Sequence[Record]
    evaluate: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


class HertzRangeWarning(UserWarning):
    """A fit with the small-strain Hertz law at a compression where it misses the equilibrium force (estimated
    from the FE master table)."""


def hertz_range(x: float) -> None:
    """Warn (:class:`HertzRangeWarning`) for a Hertz fit at approach/diameter ``x`` > :data:`HERTZ_X_WARN`, with the
    law's expected force error from the FE master table (FE / Hertz - 1 over its alpha range); ValueError beyond
    :data:`HERTZ_X_MAX`, where small-strain Hertz means nothing."""
    if x <= HERTZ_X_WARN:
        return
    from tissuemech.reduced.spheroid import hertz_f

    mc = table_of("fem")
    xe = min(x, mc.x_max)
    lo_a, hi_a = mc.alpha_range
    errs = [100.0 * (float(mc.f(xe, a)) / float(hertz_f(xe)) - 1.0) for a in (lo_a, hi_a)]
    at = f"at x = {xe:.3g}" if xe == x else f"already at x = {xe:.3g} (the table's end)"
    expected = f"the FE master table puts the equilibrium force {min(errs):.0f}-{max(errs):.0f} % above Hertz {at}"
    if x > HERTZ_X_MAX:
        raise ValueError(
            f"equilibrium='hertz' at an approach of {x:.3g} of the ball's diameter: the small-strain Hertz law holds "
            f"for small compressions only (x < {HERTZ_X_WARN:g}); {expected}: use the FE table (equilibrium='fem', up "
            f"to x = {mc.x_max:.3g}) or check the displacement and radius (m)"
        )
    warnings.warn(
        f"equilibrium='hertz' at an approach of {x:.3g} of the ball's diameter, beyond the small-strain range "
        f"(x < {HERTZ_X_WARN:g}): {expected}; C is biased by about as much (equilibrium='fem' has the table)",
        HertzRangeWarning,
        stacklevel=3,
    )


def relaxation(
    records: Sequence[Any],
    *,
    radius: float,
    ramp_time: float,
    n_branches: int = 1,
    equilibrium: Any = "fem",
    initial: dict[str, float] | Sequence[float] | None = None,
    model: Callable | None = None,
    max_nfev: int = 200,
    model_error: float | str | None = "auto",
    intervals: str = "profile",
    errors: str = "robust",
    misfit: float = 0.0,
    compress: bool | int | str | None = "auto",
) -> FitResult:
    r"""Fit ``(C, alpha, beta_m, tau_m)`` to compression-relaxation records (module doc: the statistics).

    records      list of ``(time [s], nominal_stress [Pa], displacement [m])``, one per compression
                 level (``displacement`` is the total plate approach reached at the end of the ramp).
    radius       reference ball radius a0 (m); ramp_time the loading ramp duration (s).
    n_branches   number of Maxwell branches (parameters ``beta``, ``tau`` or ``beta_1.., tau_1..``).
    equilibrium  the equilibrium law passed to the model ("fem" table, "hertz", an (x, f) table, a callable).
    initial      optional starting values (dict by name, or a sequence in :func:`parameter_names` order).
    model        ``model(t, *, radius, C, alpha, branches, displacement, ramp_time, equilibrium)`` ->
                 nominal stress (Pa), JAX-traceable; default ``reduced.spheroid.nominal_stress``.
    model_error  relative 1-sigma error of the model's force per record (e.g. 0.005), ``"auto"``
                 (:func:`model_error_of`: the FE table's ``model_error_rel``), or None/0 for none.
    errors       the error model of the intervals (:mod:`tissuemech.compare.fit.diagnostics`): "robust"
                 (default: a smooth discrepancy of estimated size plus an autocorrelation- and
                 heteroscedasticity-consistent noise covariance) or "white" (white noise, the model exact:
                 the Gauss-Newton covariance); "ess", "hac", "discrepancy" for comparison.
    misfit       lower bound of the smooth discrepancy's relative size (RMS per shape term, e.g. 0.002), for
                 "robust" and "discrepancy": a misfit that mimics a change of the parameters cannot show in
                 the residuals, so what is known of the model's accuracy must be given (default 0: none).
    intervals    "profile" (Wald checked against, and where poor replaced by, the profile likelihood)
                 or "wald" (Gauss-Newton ellipse only; fast, for large studies of well-posed problems).
    compress     dense records fitted as bin means (:mod:`tissuemech.compare.fit.compress`: the ramp in equal
                 bins, the hold in log-time bins, each weighted by its sample count, the noise estimated from
                 all samples): "auto" (default: records of more than 20000 samples, in 2000 bins), True (every
                 record), a number of bins per record, or False (sample by sample).

    Returns a :class:`FitResult` (95 % intervals, flags and the identifiability report).
    Raises ValueError for malformed or uninformative records (fewer points than parameters, constant
    or non-positive stress, compression beyond the table) and RuntimeError when the model fails at
    the starting point.
    """
    call = dict(locals())  # the arguments, for the refit with the ramp's model error below
    recs = as_records(records)
    validate_positive("radius (of the spheroid)", radius, "m")
    validate_positive("ramp_time (duration of the loading ramp)", ramp_time, "s")
    names = parameter_names(n_branches)
    check_information(recs, names)
    for k, rec in enumerate(recs):
        check_ramp(rec.time, rec.nominal_stress, float(ramp_time), f"record {k}")
    n_bins = [bins_for(compress, r.time.size) for r in recs]
    binned = [bin_record(r.time, r.nominal_stress, float(ramp_time), b) if b else None for r, b in zip(recs, n_bins)]
    fitted = [r if b is None else Record(b.time, b.stress, r.displacement) for r, b in zip(recs, binned)]
    if intervals not in ("profile", "wald"):
        raise ValueError(f"intervals must be 'profile' or 'wald'; got {intervals!r}")
    if not (math.isfinite(misfit) and misfit >= 0):
        raise ValueError(
            f"misfit (relative RMS size of the model's smooth misfit, -) must be a finite number >= 0; got {misfit}"
        )
    if errors not in ERROR_MODELS:
        raise ValueError(f"errors must be one of {', '.join(map(repr, ERROR_MODELS))}; got {errors!r}")
    mc = table_of(equilibrium)
    x = max(r.displacement for r in recs) / (2 * radius)
    if x >= 0.999:  # the plates would (nearly) touch: no law of this model holds there
        d_max = max(r.displacement for r in recs)
        raise ValueError(
            f"the plates approach by {d_max * 1e6:.4g} um, {x:.3g} times the ball's diameter of {2e6 * radius:.4g} um "
            f"(radius {1e6 * radius:.4g} um), but they touch when the approach reaches the diameter: check the "
            "displacement and the radius (given in m; on the command line --displacement-um and --radius-um, in um)"
        )
    if mc is not None and x > mc.x_max * (1 + 1e-12):
        raise ValueError(
            f"the approach is {x:.4g} of the ball's diameter, beyond the calibrated table (it reaches "
            f"{mc.x_max:.4g}): use equilibrium='hertz' (small compressions only) or a shorter approach"
        )
    if isinstance(equilibrium, str) and equilibrium == "hertz":
        hertz_range(x)
    eps = model_error_value(model_error, equilibrium)
    if isinstance(model_error, str) and table_of(equilibrium) is not None and x > TABLE_EDGE_X:
        eps = max(eps, TABLE_EDGE_MODEL_ERROR)  # the table's last x intervals (issue 35): measured between nodes
    model = default_model() if model is None else model
    p0 = starting_point(initial, names, lambda: initial_guess(recs, radius, ramp_time, n_branches))
    res_fn, jac_fn, scale = residual_builder(fitted, float(radius), float(ramp_time), n_branches, equilibrium, model)
    res = estimate(
        fitted,
        res_fn,
        jac_fn,
        scale,
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
        binned=binned,
        full=None
        if all(b is None or b.count.max() == 1 for b in binned)  # nothing averaged: the bins are the samples
        else FullRecords(recs, sample_evaluator(recs, radius, ramp_time, n_branches, equilibrium, model)),
    )
    if isinstance(model_error, str):  # "auto": the lumped model's ramp error for the fitted branches (issue 35)
        ramp_eps = ramp_model_error(dict(res.params), n_branches, float(ramp_time), x)
        if ramp_eps > eps:
            res = relaxation(**{**call, "model_error": float(ramp_eps), "initial": dict(res.params)})
            note = (
                f"model_error 'auto' raised from {eps:.2g} (the table's) to {ramp_eps:.2g}: a fitted tau is near the "
                "ramp, where the lumped model is up to 0.11 % off the FE (reduced.spheroid.lumped_ramp_error)"
            )
            return dataclasses.replace(res, flags=res.flags + (note,))
    return res


def model_error_value(model_error: float | str | None, equilibrium: Any) -> float:
    """The relative model-error term of ``model_error`` ("auto": :func:`model_error_of` the law; None: 0); ValueError
    for anything else than a finite number >= 0."""
    if isinstance(model_error, str):
        if model_error != "auto":
            raise ValueError(
                f"model_error must be a number (relative, e.g. 0.005), 'auto' or None; got {model_error!r}"
            )
        return model_error_of(equilibrium)
    eps = 0.0 if model_error is None else float(model_error)
    if not (math.isfinite(eps) and eps >= 0):
        raise ValueError(
            f"model_error (relative 1-sigma error of the force, -) must be a finite number >= 0; got {model_error}"
        )
    return eps


def starting_point(
    initial: dict[str, float] | Sequence[float] | None, names: tuple[str, ...], guess: Callable[[], np.ndarray]
) -> np.ndarray:
    """The starting parameters (in ``names`` order): ``initial`` (a dict by name, the rest from ``guess()``, or a
    full sequence) or ``guess()``; ValueError for a wrong length or a non-positive value."""
    if initial is None:
        p0 = np.asarray(guess(), dtype=float)
    elif isinstance(initial, dict):
        unknown = sorted(set(map(str, initial)) - set(names))
        if unknown:
            raise ValueError(f"initial: unknown parameter name(s) {unknown}; the valid names are {list(names)}")
        p0 = np.array([float(initial.get(n, g)) for n, g in zip(names, guess())])
    else:
        p0 = np.asarray(initial, dtype=float)
        if p0.shape != (len(names),):
            raise ValueError(f"initial needs {len(names)} values in the order {names}; got {p0.size}")
    if np.any(p0 <= 0) or not np.all(np.isfinite(p0)):
        raise ValueError(f"initial values must be positive and finite; got {dict(zip(names, p0))}")
    return p0


def estimate(
    recs: Sequence[Record],
    res_fn: Callable,
    jac_fn: Callable,
    scale: float,
    *,
    names: tuple[str, ...],
    p0: np.ndarray,
    n_branches: int,
    equilibrium: Any,
    ramp_time: float,
    eps: float,
    max_nfev: int,
    intervals: str,
    errors: str,
    misfit: float,
    binned: Sequence[Any] | None = None,
    full: FullRecords | None = None,
) -> FitResult:
    """The fit behind :func:`relaxation` and :func:`tissuemech.compare.fit.protocols.records_fit`: weighted least
    squares from ``p0`` of the residual ``res_fn`` (log-parameters -> (model - data) / ``scale``, its Jacobian
    ``jac_fn``) against the records' observed values (``recs[j].nominal_stress``, the observable of each record in
    the units of ``scale``), per-record noise, the model-error factors ``eps``, the error model and the 95 % intervals
    (module doc of :mod:`tissuemech.compare.fit`). ``ramp_time`` (s) sets the relaxation times' lower search bound and
    the discrepancy's log-time axis. ``binned``: per record its bins (:mod:`tissuemech.compare.fit.compress`) when
    ``recs[j]`` holds bin means, else None; ``full`` then the records they were binned from: the error model of the
    intervals runs on every sample at the estimate (:func:`full_record_terms`), as the full record's fit's does."""
    P, R = len(names), len(recs)
    binned = list(binned) if binned is not None else [None] * R
    lo_t, hi_t = search_bounds(
        names, n_branches, equilibrium, float(ramp_time), max(float(np.max(r.time)) for r in recs)
    )
    theta0 = np.clip(np.log(p0), lo_t + 1e-9, hi_t - 1e-9)
    if not np.all(np.isfinite(np.asarray(res_fn(jnp.asarray(theta0))))):
        raise RuntimeError(
            f"the model returned NaN/inf at the starting point {dict(zip(names, p0))}. "
            "Hint: give initial=... closer to the data, or check units (m, Pa, s)."
        )
    prob = Problem(recs, res_fn, jac_fn, scale, P, eps, binned)
    extra = prob.nz - P
    lo = np.concatenate([lo_t, np.full(extra, -np.inf)])
    hi = np.concatenate([hi_t, np.full(extra, np.inf)])
    peaks = np.array([np.max(np.abs(r.nominal_stress)) for r in recs])
    floor = NOISE_FREE_REL * 1e-3 * peaks  # keeps the weights finite for noise-free data
    fun = safe(prob.resid)
    jac = lambda z: np.nan_to_num(prob.jac(z), nan=0.0, posinf=0.0, neginf=0.0)

    # pass 1: common weights; noise estimate per record; pass 2: weighted by each record's noise
    prob.sig = prob.point_sd(0.01 * scale)
    z0 = np.concatenate([theta0, np.zeros(extra)])
    # a parameter the model does not depend on (alpha with the Hertz law) is held at its start value
    norm0 = np.linalg.norm(jac(z0)[: prob.y.size, :P], axis=0)
    dead0 = [i for i in range(P) if norm0[i] <= 1e-10 * max(float(np.max(norm0)), 1e-300)]
    free = np.array([i not in dead0 for i in range(prob.nz)])
    solve = masked_solver(fun, jac, z0, free, lo, hi)
    sol = solve(z0, max_nfev)
    nfev = int(sol.nfev)
    noise = prob.set_noise(sol.x, floor)
    if R > 1 or extra:
        for _ in range(2):  # weights from the previous pass's residuals; the last pass is optimal for its weights
            sol = solve(sol.x, max_nfev)
            nfev += int(sol.nfev)
            noise_prev, noise = noise, prob.set_noise(sol.x, floor)
            if np.all(np.abs(noise - noise_prev) <= 0.01 * noise_prev):
                break
        prob.sig = prob.point_sd(np.maximum(noise_prev, floor))  # the weights z is the optimum for
    z = sol.x
    flags: list[str] = []
    noise_free = bool(np.any(noise < NOISE_FREE_REL * peaks))
    if noise_free:
        flags.append(
            "the residuals are at round-off level (noise-free, synthetic data?): there is no noise to "
            "estimate, so no confidence interval can be given (intervals are NaN); add the measurement noise"
        )
    r = prob.resid(z)
    chi2 = float(r @ r)
    Jz = prob.jac(z)
    if not np.all(np.isfinite(Jz)):
        flags.append("the model's sensitivities are not finite at the estimate: the intervals cannot be trusted")
        Jz = np.nan_to_num(Jz, nan=0.0, posinf=0.0, neginf=0.0)
    N = prob.y.size
    dof = prob.samples - P  # samples, not bins, on compressed records
    from scipy.stats import t as student_t

    tq = float(student_t.ppf(0.975, dof))
    fisher_z = Jz.T @ Jz
    lam, V = np.linalg.eigh(0.5 * (fisher_z + fisher_z.T))
    cov_z = (V * inverse_eigenvalues(lam)) @ V.T
    cov = cov_z[:P, :P]
    colnorm = np.linalg.norm(Jz[:N, :P], axis=0)
    dead = sorted(set(dead0) | {i for i in range(P) if colnorm[i] <= 1e-10 * max(float(np.max(colnorm)), 1e-300)})
    lam_t, V_t = np.linalg.eigh(0.5 * (cov + cov.T))
    fisher_t = (V_t * inverse_eigenvalues(lam_t)) @ V_t.T  # marginal Fisher of theta
    for i in dead:
        fisher_t[i, :] = fisher_t[:, i] = 0.0
    ident = identifiability(fisher_t, names, dead)
    at_bound = [names[i] for i in range(P) if min(z[i] - lo[i], hi[i] - z[i]) < 1e-6 and i not in dead]
    if at_bound:
        ident.report += (
            "\n  -> at a bound of the search: "
            + ", ".join(at_bound)
            + f" (alpha in [{math.exp(lo[1]):.3g}, {math.exp(hi[1]):.3g}], beta in {BETA_BOUNDS}, tau in "
            f"[{math.exp(lo[2 + n_branches]):.3g}, {math.exp(hi[2 + n_branches]):.3g}] s); e.g. alpha "
            "at its lower bound means the data are consistent with a neo-Hookean law (alpha = 0), tau at its upper "
            "bound that a branch does not relax within the records (beta then trades off against C)."
        )
    if not sol.success:
        flags.append(f"the optimizer did not converge: {sol.message}")
    acc = stated_accuracy(equilibrium) or 0.0
    too_clean = [] if noise_free else [j for j in range(R) if noise[j] < acc * peaks[j]]
    if too_clean:
        flags.append(
            f"record(s) {', '.join(str(j + 1) for j in too_clean)} scatter about the model by less (noise sd "
            f"{min(noise[j] / peaks[j] for j in too_clean):.2g} of the peak stress) than the equilibrium table is "
            f"accurate ({acc:.2g}, its model_error_rel): the residuals are then the records' own discretisation "
            "error and the model's, not noise, and the intervals can miss the truth (noise-free synthetic data?); "
            "add the measurement noise"
        )

    # the error model: per-record residual diagnostics, and the covariance the intervals rest on
    model_z = prob.model(z[:P]) * prob.factor(z)
    rdata_w = prob.data_residual(z) / prob.sig
    diags = tuple(residual_diagnostics(rdata_w[prob.idx == j]) for j in range(R))
    wald_by_model: dict[str, dict[str, tuple[float, float]]] = {}
    if noise_free:
        emf = None
        cov_used = cov
        tqs = np.full(P, tq)
    else:
        if full is None:
            terms = (Jz, r, prob.idx, N, model_z, prob.sig, [rec.time for rec in recs])
        else:
            terms = full_record_terms(full, z, prob)
        J_e, r_e, idx_e, n_e, model_e, sig_e, times_e = terms
        emf = robust_covariance(
            J_e, r_e, idx_e, n_e, P, model_e, sig_e, times_e, float(ramp_time), white=cov, misfit=misfit
        )
        for m, c_m in emf.covariances.items():  # Wald intervals under every error model, for comparison studies
            t_m = _quantiles(emf, m, P, dof)
            h_m = t_m * np.sqrt(np.abs(np.diag(c_m)))
            wald_by_model[m] = {
                nm: (exp_or_inf(float(max(z[i] - h_m[i], lo[i]))), exp_or_inf(float(min(z[i] + h_m[i], hi[i]))))
                for i, nm in enumerate(names)
            }
        cov_used = emf.covariances[errors]
        tqs = _quantiles(emf, errors, P, dof)
    sd_white = np.sqrt(np.abs(np.diag(cov)))
    sd = np.sqrt(np.abs(np.diag(cov_used)))
    # the profile likelihood is in the fit's (white) units: its threshold grows with the variance inflation
    inflation = np.where(sd_white > 0, (sd / np.where(sd_white > 0, sd_white, 1.0)) ** 2, 1.0)
    p = np.exp(z[:P])
    ivals: dict[str, tuple[float, float]] = {}
    kinds: dict[str, str] = {}
    methods: dict[str, str] = {}
    phys_lo = np.where(np.isfinite(lo_t), 0.0, 0.0)  # a lower search bound stands for the limit 0

    def to_linear(i, th, how, side):
        if how in ("bound", "open"):
            if side < 0:
                return float(phys_lo[i])
            return math.inf if how == "open" else exp_or_inf(th)
        return exp_or_inf(th)

    prof = Profiler(prob, z, chi2, cov_z, lo, hi)
    prof.free = free.copy()
    prof.free[dead] = False
    for i, nm in enumerate(names):
        if i in dead:
            ivals[nm] = (float(phys_lo[i]), float(math.exp(hi_t[i])) if np.isfinite(hi_t[i]) else math.inf)
            kinds[nm], methods[nm] = "none", "bound"
            continue
        if noise_free:
            ivals[nm], kinds[nm], methods[nm] = (math.nan, math.nan), "n/a", "n/a"
            continue
        h = tqs[i] * sd[i]
        q_i = tqs[i] ** 2 * max(float(inflation[i]), 1e-12)
        ends, hows = [], []
        for side in (-1, 1):
            if intervals == "wald":
                c = z[i] + side * h
                edge = hi[i] if side > 0 else lo[i]
                if side * (c - edge) >= 0:
                    c, how = edge, "bound"
                elif not np.isfinite(c):
                    c, how = z[i] + side * LOG_SPAN, "open"
                else:
                    how = "wald"
            else:
                c, how = prof.end(i, side, h, q_i)
            ends.append(to_linear(i, c, how, side))
            hows.append(how)
        lo_open = hows[0] in ("bound", "open")
        hi_open = hows[1] in ("bound", "open")
        kinds[nm] = "none" if (lo_open and hi_open) else "upper" if lo_open else "lower" if hi_open else "two-sided"
        real = [h_ for h_ in hows if h_ in ("wald", "profile")]
        methods[nm] = "profile" if "profile" in real else "wald" if real else "bound"
        ivals[nm] = (ends[0], ends[1])
    if prof.better is not None:
        flags.append(
            "the profile search met parameters fitting better than the reported optimum (a local "
            "minimum): refit with initial= near the profile's values"
        )
    for nm in names:
        if kinds[nm] == "upper":
            ident.report += f"\n  -> {nm}: only an upper bound at 95 %: {nm} < {ivals[nm][1]:.4g}"
        elif kinds[nm] == "lower":
            ident.report += f"\n  -> {nm}: only a lower bound at 95 %: {nm} > {ivals[nm][0]:.4g}"
        elif kinds[nm] == "none" and names.index(nm) not in dead:
            ident.report += f"\n  -> {nm}: not bounded by these records at 95 % (any value in the search range fits)"
    rdata = prob.data_residual(z)
    success = bool(sol.success) and not noise_free and not too_clean and prof.better is None
    return FitResult(
        params={nm: float(v) for nm, v in zip(names, p)},
        intervals=ivals,
        residual=float(np.sqrt(np.mean(rdata**2)))
        if not any(binned)
        else math.sqrt(_binned_rss(prob, rdata, noise) / prob.samples),
        identifiability=ident,
        covariance=cov_used,
        success=success,
        message=str(sol.message) + "".join(f"; {f}" for f in flags),
        nfev=nfev,
        names=names,
        kinds=kinds,
        methods=methods,
        noise=tuple(float(s) for s in noise),
        model_error=eps,
        flags=tuple(flags),
        dof=int(dof),
        model_error_factors=tuple(float(v) for v in np.exp(z[P:])) if extra else (),
        diagnostics=diags,
        errors=errors if emf is not None else "white",
        discrepancy=float(emf.discrepancy) if emf is not None else 0.0,
        covariances=dict(emf.covariances) if emf is not None else {"white": cov},
        correlation=tuple(emf.rho) if emf is not None else (),
        wald_by_error_model=wald_by_model,
        bins=tuple(0 if b is None else int(b.count.size) for b in binned),
    )


def full_record_terms(full: FullRecords, z: np.ndarray, prob: Problem) -> tuple:
    """What :func:`tissuemech.compare.fit.diagnostics.robust_covariance` needs, at every sample of the records a
    compressed fit was binned from, at its estimate ``z``: the weighted Jacobian and residual (model-error factors'
    columns and prior rows included, as :meth:`Problem.jac`), each sample's record, their number, the model with
    its factors (Pa), each sample's noise sd (Pa: its record's, the one the bins were weighted with) and the
    records' times (s). One pass of the model and its Jacobian over the samples (chunked): the intervals are then
    the full record's fit's, up to the estimate's shift (bins move it by a small fraction of the interval)."""
    P = prob.P
    model, Jm = full.evaluate(z[:P])
    # the same weighted residual as the fit's, over the samples: its model and Jacobian are those just evaluated at z
    # (the only point asked for)
    y = np.concatenate([rec.nominal_stress for rec in full.records])
    samples = Problem(full.records, lambda th: model - y, lambda th: Jm, 1.0, P, prob.eps)
    first = np.array([int(np.flatnonzero(prob.idx == j)[0]) for j in range(prob.R)])
    samples.sig = samples.point_sd((prob.sig * np.sqrt(prob.count))[first])  # each record's per-sample sd (Pa)
    model_f = samples.model(z[:P]) * samples.factor(z)
    times = [rec.time for rec in full.records]
    return samples.jac(z), samples.resid(z), samples.idx, samples.y.size, model_f, samples.sig, times


def _binned_rss(prob: Problem, rdata: np.ndarray, noise: np.ndarray) -> float:
    """The residual sum of squares of all samples (Pa^2) on compressed records: the bins' weighted residuals, the
    scatter inside the bins about their lines, and the one degree of freedom per bin (of 2 samples or more) the
    line takes beyond the model's own shape, at the noise's level."""
    lost = np.array([np.sum(prob.count[prob.idx == j] >= 2) for j in range(prob.R)])
    return float(rdata @ (rdata * prob.count)) + float(np.sum(prob.within[:, 0])) + float(np.sum(lost * noise**2))


def _quantiles(emf: Any, errors: str, P: int, dof: int) -> np.ndarray:
    """97.5 % Student quantile per parameter: N - P degrees of freedom for the noise, and where a discrepancy term
    carries part of the variance, Satterthwaite's effective degrees of freedom (the discrepancy's size is estimated
    from only the coefficients the parameters leave estimable)."""
    from scipy.stats import t as student_t

    if errors in ("robust", "discrepancy") and emf.discrepancy > 0:
        share = np.clip(emf.discrepancy_share, 0.0, 1.0)
        nu_d = max(float(emf.dof_discrepancy), 1.0)
    else:
        share, nu_d = np.zeros(P), math.inf
    nu = 1.0 / np.maximum(share**2 / nu_d + (1.0 - share) ** 2 / max(dof, 1), 1e-300)
    return np.array([float(student_t.ppf(0.975, max(v, 1.0))) for v in nu])
