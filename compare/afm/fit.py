r"""Fit the lumped generalized-Maxwell probe model to the hold of one AFM stress-relaxation curve.

Model: :func:`tissuemech.reduced.indentation.force`, a rigid sphere (``probe_radius`` R_p, m) on a ball
(``radius`` a0, m; ``math.inf``: half-space) resting on a plate, driven by the MEASURED indentation history
delta(t) of the curve (:func:`tissuemech.compare.afm.contact.indentation`: the loading ramp in contact, then
the hold with the tip's creep), with parameters C (Pa), beta_m (-), tau_m (s). The Fung exponent alpha is
not identifiable from one indentation depth at small strain (the Hertz law does not depend on it): it is
fixed at 0 and not fitted. The law is the Hertz series law (``law="hertz"``): AFM depths (delta / R_s ~ 0.75 in the
example records) lie far beyond the FE-calibrated indentation table's reach (delta / R_s <= 0.1).
Only the force over the hold is fitted (the ramp enters through the history);
the model's force over the ramp is returned too, as a check (:attr:`CurveFit.ramp_model`).

Geometry: beta_m and tau_m do not depend on R_p and a0 (the Hertz law scales F by sqrt(R_s) only, module doc
of ``reduced.indentation``); C scales as R_s^(-1/2): with another geometry, C_new = C sqrt(R_s / R_s,new).

Why not :func:`tissuemech.compare.fit.relaxation`: its records are a linear ramp to a number and a hold (the
model is called with ``displacement=`` a number), its noise model is white, and its parameters include alpha.
Here the approach is a measured history (a pair of arrays), and real residuals are correlated: the lag-1
autocorrelation of the residuals is reported for every fit (0.9 and above on the records of docs/afm.md), so
white-noise intervals would be far too narrow.

Estimation: ``scipy.optimize.least_squares`` (trust region, bounds) in log-parameters, with the exact
Jacobian ``jax.jacfwd`` through the model (diffrax forward-mode sensitivities). The history is resampled on
fixed counts of knots (``n_ramp`` over the ramp, ``n_hold`` bin means over the hold) so that every curve of a
study shares one compiled residual and Jacobian. The ODE is integrated by diffrax's explicit Tsit5 at
rtol = atol = 1e-6 (:data:`RTOL`), 2e-6 of the force from a 1e-8 solution.

Covariance: heteroskedasticity-and-autocorrelation-consistent (Newey-West, Bartlett weights) sandwich
(J'J)^-1 S (J'J)^-1, S = sum_|l|<=L w_l sum_t (J_t r_t)(J_{t-l} r_{t-l})', with the bandwidth from the
measured lag-1 autocorrelation rho (Andrews' AR(1) plug-in, L = 1.1447 (4 rho^2 n / ((1 - rho)^2 (1 + rho)^2))^(1/3),
at most n/2). Intervals (95 %): exp(log p +- 1.96 sd). Diagnostics: lag-1 autocorrelation, the runs test on
the residuals' signs (z and two-sided p), RMS residual; AIC = n log(RSS/n) + 2P and BIC = n log(RSS/n) +
P log n compare one and two branches (both assume independent residuals: with correlated ones they overstate
the evidence for the larger model; read them with the residual plots).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
from scipy.optimize import least_squares
from scipy.stats import norm

import tissuemech.reduced  # noqa: F401  (float64)
from tissuemech.compare import fit as relaxation_fit
from tissuemech.compare.afm.contact import Indentation, lag1
from tissuemech.reduced import indentation as probe_model
from tissuemech.reduced.validation import InputError, validate_int, validate_positive

__all__ = ["CurveFit", "fit_curve", "resample", "runs_test", "hac_covariance", "parameter_names", "spread"]

Z95 = relaxation_fit.Z95  # two-sided 95 % normal quantile
BETA_BOUNDS = (1e-6, 1e3)
TAU_BOUNDS = (1e-2, 1e4)  # s
# the explicit Tsit5 at rtol = atol = 1e-6: 0.06 s per model and 0.05 s per Jacobian on the records of docs/afm.md
# (Kvaerno5 at 1e-8: 0.5 s and 1.8 s); the force differs from the 1e-8 solution by 2e-6 of its value, far below
# the records' noise (~1 % of the force)
RTOL = 1e-6


def parameter_names(n_branches: int) -> tuple[str, ...]:
    """``(C, beta, tau)`` for one branch, ``(C, beta_1, .., tau_1, ..)`` for more."""
    n = validate_int("n_branches (Maxwell branches)", n_branches, minimum=1)
    if n == 1:
        return ("C", "beta", "tau")
    return ("C",) + tuple(f"beta_{m}" for m in range(1, n + 1)) + tuple(f"tau_{m}" for m in range(1, n + 1))


@dataclass
class CurveFit:
    """One curve, one model. ``params`` and 95 % ``intervals`` (C Pa, beta -, tau s); ``sd_log`` (HAC
    standard deviation of log p); ``time``/``force``/``model``/``residual`` over the fitted hold (s, N);
    ``ramp_time``/``ramp_force``/``ramp_model`` over the ramp (not fitted); diagnostics ``rms`` (N), ``lag1``,
    ``runs_z``, ``runs_p``, ``aic``, ``bic``, ``hac_lag``; ``seconds`` of the fit (compile excluded when warm)."""

    name: str
    n_branches: int
    params: dict[str, float]
    intervals: dict[str, tuple[float, float]]
    sd_log: dict[str, float]
    time: np.ndarray
    force: np.ndarray
    model: np.ndarray
    ramp_time: np.ndarray
    ramp_force: np.ndarray
    ramp_model: np.ndarray
    rms: float
    lag1: float
    runs_z: float
    runs_p: float
    aic: float
    bic: float
    hac_lag: int
    success: bool
    message: str
    nfev: int
    seconds: float
    geometry: dict[str, float] = field(default_factory=dict)

    @property
    def residual(self) -> np.ndarray:
        """data - model over the hold (N)."""
        return self.force - self.model

    def row(self) -> dict[str, Any]:
        """A flat dict (one table row): parameters, interval ends, diagnostics."""
        out: dict[str, Any] = {"curve": self.name, "branches": self.n_branches}
        for k, v in self.params.items():
            lo, hi = self.intervals[k]
            out.update({k: v, f"{k}_lo": lo, f"{k}_hi": hi})
        out.update(
            rms_nN=self.rms * 1e9,
            lag1=self.lag1,
            runs_z=self.runs_z,
            aic=self.aic,
            bic=self.bic,
            hac_lag=self.hac_lag,
            success=self.success,
            seconds=self.seconds,
        )
        return out


def runs_test(r: np.ndarray) -> tuple[float, float]:
    """Wald-Wolfowitz runs test on the signs of ``r``: (z, two-sided p). Few runs (z << 0): structure."""
    s = np.asarray(r) > 0
    n1, n2 = int(s.sum()), int((~s).sum())
    n = n1 + n2
    if n1 == 0 or n2 == 0:
        return -math.inf, 0.0
    runs = 1 + int(np.sum(s[1:] != s[:-1]))
    mu = 2.0 * n1 * n2 / n + 1.0
    var = (mu - 1.0) * (mu - 2.0) / (n - 1.0)
    z = (runs - mu) / math.sqrt(var) if var > 0 else 0.0
    return float(z), float(2.0 * norm.sf(abs(z)))


def hac_covariance(J: np.ndarray, r: np.ndarray, rho: float | None = None) -> tuple[np.ndarray, int]:
    """Newey-West covariance of least-squares estimates (module doc) and its bandwidth L (lags)."""
    n, P = J.shape
    rho = lag1(r) if rho is None else rho
    rho = min(max(rho, 0.0), 0.995)
    alpha1 = 4.0 * rho**2 / ((1.0 - rho) ** 2 * (1.0 + rho) ** 2)
    L = int(min(n // 2, math.ceil(1.1447 * (alpha1 * n) ** (1.0 / 3.0))))
    u = J * r[:, None]
    S = u.T @ u
    for lag in range(1, L + 1):
        G = u[lag:].T @ u[:-lag]
        S += (1.0 - lag / (L + 1.0)) * (G + G.T)
    B = np.linalg.pinv(J.T @ J)
    return (n / max(n - P, 1)) * B @ S @ B, L


def resample(ind: Indentation, *, n_ramp: int = 48, n_hold: int = 240) -> tuple[np.ndarray, ...]:
    """(t, delta, F, hold_mask): ``n_ramp`` points over the ramp (delta and F interpolated, t = 0 first, at
    contact) and ``n_hold`` bin means over the hold. Fixed counts: one compiled fit for every curve."""
    n_ramp = validate_int("n_ramp (knots over the ramp)", n_ramp, minimum=4)
    n_hold = validate_int("n_hold (bins over the hold)", n_hold, minimum=8)
    ramp = ~ind.hold
    if ind.hold.sum() < n_hold:
        raise InputError(f"curve {ind.name!r}: the hold has {ind.hold.sum()} samples, fewer than n_hold = {n_hold}")
    tr = np.linspace(0.0, float(ind.time[ramp][-1]), n_ramp)
    dr = np.interp(tr, ind.time[ramp], ind.approach[ramp])
    fr = np.interp(tr, ind.time[ramp], ind.force[ramp])
    idx = np.array_split(np.flatnonzero(ind.hold), n_hold)
    th = np.array([ind.time[i].mean() for i in idx])
    dh = np.array([ind.approach[i].mean() for i in idx])
    fh = np.array([ind.force[i].mean() for i in idx])
    t = np.concatenate([tr, th])
    if np.any(np.diff(t) <= 0):
        raise InputError(f"curve {ind.name!r}: resampled times are not increasing (hold starts before the ramp ends)")
    return t, np.concatenate([dr, dh]), np.concatenate([fr, fh]), np.r_[np.zeros(n_ramp, bool), np.ones(n_hold, bool)]


def _predict(theta, t, d, radius, probe_radius, nb):
    p = jnp.exp(theta)
    branches = [(p[1 + m], p[1 + nb + m]) for m in range(nb)]
    return probe_model.force(
        t,
        radius=radius,
        probe_radius=probe_radius,
        C=p[0],
        alpha=0.0,
        branches=branches,
        law="hertz",
        displacement=(t, d),
        adjoint="forward",
        rtol=RTOL,
        atol=RTOL,
        solver=diffrax.Tsit5(),
    )


@functools.lru_cache(maxsize=8)
def _compiled(nb: int):
    """(Jacobian, model) in one compiled function (jacfwd with the model as its auxiliary output: one trace, and a
    Jacobian costs about what the model alone does), once per branch count (and shapes)."""

    def both(theta, *args):
        out = _predict(theta, *args, nb=nb)
        return out, out

    return jax.jit(jax.jacfwd(both, has_aux=True))


def _initial(t, d, f, hold, rs, nb):
    fh, th = f[hold], t[hold]
    f_end = float(np.mean(fh[-max(3, fh.size // 20) :]))
    d_end = float(np.mean(d[hold][-max(3, fh.size // 20) :]))
    C0 = max(f_end, 1e-3 * float(np.max(f))) / ((32.0 / 3.0) * math.sqrt(rs) * d_end**1.5)
    beta0 = max(float(fh[0]) / max(f_end, 1e-30) - 1.0, 0.1)
    target = f_end + (fh[0] - f_end) / math.e
    k = int(np.argmax(fh <= target))
    tau0 = max(float(th[k] - th[0]), 0.2)
    if nb == 1:
        return np.log([C0, beta0, tau0])
    betas = [beta0 / nb] * nb
    taus = list(tau0 * np.geomspace(0.2, 5.0, nb))
    return np.log([C0, *betas, *taus])


def fit_curve(
    ind: Indentation,
    *,
    probe_radius: float,
    radius: float,
    n_branches: int = 1,
    initial: Sequence[float] | None = None,
    n_ramp: int = 48,
    n_hold: int = 240,
    max_nfev: int = 60,
) -> CurveFit:
    """Fit C (Pa), beta_m (-), tau_m (s) of the probe model to the hold of one indentation (module doc).

    ind           :func:`tissuemech.compare.afm.contact.indentation` of a curve.
    probe_radius  R_p (m); radius  ball radius a0 (m) or ``math.inf`` (half-space).
    initial       start values in :func:`parameter_names` order (default: from the record's levels).
    Returns a :class:`CurveFit`. Raises ValueError for bad inputs or a history beyond the law's range.
    """
    validate_positive("probe_radius (radius of the spherical AFM probe)", probe_radius, "m")
    if not (radius == math.inf or (isinstance(radius, (int, float)) and radius > 0)):
        raise InputError(f"radius (of the indented ball, in m) must be positive or math.inf; got {radius!r}")
    names = parameter_names(n_branches)
    t, d, f, hold = resample(ind, n_ramp=n_ramp, n_hold=n_hold)
    probe_model.equilibrium_force(
        float(np.max(d)), radius=radius, probe_radius=probe_radius, C=1.0, law="hertz"
    )  # depth check
    rs = float(probe_model.series_radius(radius, probe_radius))
    theta0 = np.asarray(initial, dtype=float) if initial is not None else _initial(t, d, f, hold, rs, n_branches)
    if initial is not None:
        if theta0.shape != (len(names),) or np.any(theta0 <= 0):
            raise InputError(f"initial needs {len(names)} positive values in the order {names}")
        theta0 = np.log(theta0)
    nb = n_branches
    lo = np.log([1e-6] + [BETA_BOUNDS[0]] * nb + [TAU_BOUNDS[0]] * nb)
    hi = np.log([1e12] + [BETA_BOUNDS[1]] * nb + [TAU_BOUNDS[1]] * nb)
    theta0 = np.clip(theta0, lo + 1e-6, hi - 1e-6)
    both = _compiled(nb)
    args = (jnp.asarray(t), jnp.asarray(d), jnp.asarray(float(radius)), jnp.asarray(float(probe_radius)))
    scale = float(np.max(np.abs(f[hold]))) or 1.0
    fh = f[hold]
    start = time.perf_counter()

    last: dict[str, Any] = {}

    def evaluate(th):  # model and Jacobian at th, kept for the call at the same point that follows
        key = np.asarray(th, dtype=float).tobytes()
        if last.get("key") != key:
            J, out = both(jnp.asarray(th), *args)
            last.update(key=key, J=np.asarray(J), out=np.asarray(out))
        return last["out"], last["J"]

    def fun(th):
        return (evaluate(th)[0][hold] - fh) / scale

    def jf(th):
        return np.nan_to_num(evaluate(th)[1][hold] / scale)

    r0 = fun(theta0)
    if not np.all(np.isfinite(r0)):
        raise RuntimeError(f"curve {ind.name!r}: the model gave NaN at the start {dict(zip(names, np.exp(theta0)))}")
    sol = least_squares(
        lambda th: np.nan_to_num(fun(th), nan=1e3), theta0, jac=jf, bounds=(lo, hi), max_nfev=max_nfev, x_scale="jac"
    )
    seconds = time.perf_counter() - start
    full = evaluate(sol.x)[0]
    r = (fh - full[hold]) / scale
    J = jf(sol.x)
    rho = lag1(r)
    cov, L = hac_covariance(J, r, rho)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    n, P = r.size, len(names)
    rss = float(np.sum((r * scale) ** 2))
    z, p = runs_test(r)
    params = dict(zip(names, np.exp(sol.x).tolist()))
    intervals = {k: (math.exp(sol.x[i] - Z95 * sd[i]), math.exp(sol.x[i] + Z95 * sd[i])) for i, k in enumerate(names)}
    at_bound = [k for i, k in enumerate(names) if sol.x[i] <= lo[i] + 1e-3 or sol.x[i] >= hi[i] - 1e-3]
    message = sol.message + (f"; at a search bound: {', '.join(at_bound)}" if at_bound else "")
    return CurveFit(
        name=ind.name,
        n_branches=nb,
        params=params,
        intervals=intervals,
        sd_log=dict(zip(names, sd.tolist())),
        time=t[hold],
        force=fh,
        model=full[hold],
        ramp_time=t[~hold],
        ramp_force=f[~hold],
        ramp_model=full[~hold],
        rms=float(np.sqrt(rss / n)),
        lag1=rho,
        runs_z=z,
        runs_p=p,
        aic=n * math.log(rss / n) + 2 * P,
        bic=n * math.log(rss / n) + P * math.log(n),
        hac_lag=L,
        success=bool(sol.success) and not at_bound,
        message=message,
        nfev=int(sol.nfev),
        seconds=seconds,
        geometry={"probe_radius": float(probe_radius), "radius": float(radius), "series_radius": rs},
    )


def spread(fits: Sequence[CurveFit]) -> dict[str, dict[str, float]]:
    """Across curves, per parameter: median, quartiles, min, max and the coefficient of variation (sd/mean)."""
    if not fits:
        raise InputError("spread needs at least one fit")
    out = {}
    for k in fits[0].params:
        v = np.array([fi.params[k] for fi in fits])
        q1, med, q3 = np.percentile(v, [25, 50, 75])
        out[k] = {
            "median": float(med),
            "q1": float(q1),
            "q3": float(q3),
            "min": float(v.min()),
            "max": float(v.max()),
            "cv": float(np.std(v, ddof=1) / np.mean(v)) if v.size > 1 else 0.0,
        }
    return out
