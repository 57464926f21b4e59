r"""Residual diagnostics of a fit, per record, and the error model that makes the 95 % intervals honest when the
residuals are not the white noise the least-squares weights assume.

Diagnostics (:func:`residual_diagnostics`): the lag-1 autocorrelation ``r1`` of a record's residuals in time order
and the Wald-Wolfowitz runs test of their signs (``runs`` sign changes + 1 against ``(2 n+ n- / n) + 1`` expected
for independent residuals; ``runs_z`` its normal score, ``runs_p`` the two-sided p-value). White noise gives
r1 ~ 0 +- 1/sqrt(n) and runs_p uniform; correlated noise or a model that misses the shape of the curve gives r1
well above 0 and too few runs (runs_z << 0).

Error model of the intervals (:func:`robust_covariance`; ``errors="robust"``, the default of
:func:`tissuemech.compare.fit.relaxation`). The estimate itself is the weighted least-squares one; only its
covariance changes. In the fit's weighted units (residual r_k, Jacobian rows J_k, per record j):

* a smooth discrepancy: r = D a + u with D_j = the record's model times K orthonormal Legendre polynomials in
  log(t + ramp time) (K = :data:`DISCREPANCY_TERMS`), a ~ N(0, eps_d^2) per coefficient (a relative error of the
  curve's shape, the same prior for every record and term). eps_d^2 is estimated by restricted maximum likelihood
  (REML) from the residuals with the parameter directions projected out, so it measures the misfit the
  parameters cannot absorb and assumes the part they do absorb is of the same size; its degrees of freedom (for the
  Student quantile) are Satterthwaite's effective number, sum_b (lambda mu_b / (1 + lambda mu_b))^2 over the
  estimable directions, at least :data:`DISCREPANCY_MIN_DOF`: a small estimate from directions the noise dominates
  is an uncertain one;
* the rest, u, by a heteroscedasticity- and autocorrelation-consistent (HAC) long-run covariance of the scores
  g_k = J_k u_k: AR(1) prewhitening with the residuals' lag-1 autocorrelation (clipped to [0, 0.97]), a Bartlett
  kernel of Andrews' automatic bandwidth on the whitened scores, recoloured by 1 / (1 - rho)^2
  (Andrews & Monahan 1992); a record fitted as bin means (:mod:`.compress`) gets all of this from its samples
  (the model and its Jacobian at every sample, at the binned estimate), as its full fit would;
* cov = A^-1 B A^-1 with A = J'J (the Gauss-Newton matrix, model-error factors included) and
  B = HAC(u) + eps_d^2 J'D D'J (+ the model-error factors' prior rows).

``errors="white"`` keeps the Gauss-Newton covariance (white noise, the model exact up to the model-error factor);
``"ess"``, ``"hac"`` and ``"discrepancy"`` are the single ingredients (``"ess"``: the white covariance with each
record's information divided by (1 + r1) / (1 - r1), its effective-sample-size inflation), kept for comparison.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "RecordDiagnostics",
    "residual_diagnostics",
    "ERROR_MODELS",
    "DISCREPANCY_TERMS",
    "RHO_MAX",
    "DISCREPANCY_MIN_DOF",
    "discrepancy_basis",
    "ErrorModelFit",
    "robust_covariance",
    "orthonormal_basis",
]

ERROR_MODELS = ("robust", "white", "ess", "hac", "discrepancy")
DISCREPANCY_TERMS = 6  # Legendre terms (degree 0..5) of each record's smooth discrepancy
RHO_MAX = 0.97  # the lag-1 autocorrelation used for prewhitening is clipped to [0, RHO_MAX]
# the fewest degrees of freedom the discrepancy's size is given (Satterthwaite's effective number can fall below 1
# when REML finds a small discrepancy in white noise: the Student quantile of 12.7 then tripled a dense record's C
# interval; with 3, 200 fits per row (seeds 1, 2): dense misfit C 88.5 -> 94.5 %, white-noise rows unchanged)
DISCREPANCY_MIN_DOF = 3.0


@dataclass(frozen=True)
class RecordDiagnostics:
    """Residual diagnostics of one record (module doc): ``n`` samples, lag-1 autocorrelation ``r1``, the runs test
    (``runs`` observed, ``runs_expected``, normal score ``runs_z``, two-sided ``runs_p``)."""

    n: int
    r1: float
    runs: int
    runs_expected: float
    runs_z: float
    runs_p: float

    @property
    def correlated(self) -> bool:
        """True when the residuals are clearly not independent: too few runs (p < 0.001) or r1 > 0.3."""
        return bool((self.runs_p < 1e-3 and self.runs_z < 0) or self.r1 > 0.3)

    def text(self) -> str:
        return (
            f"lag-1 autocorrelation {self.r1:+.2f}, runs {self.runs} (expected {self.runs_expected:.0f}, "
            f"z {self.runs_z:+.1f}, p {self.runs_p:.2g})"
        )


def lag1(x: np.ndarray) -> float:
    """Lag-1 autocorrelation of ``x`` about its mean (0 for fewer than 3 values or a constant)."""
    x = np.asarray(x, dtype=float) - np.mean(x)
    den = float(x @ x)
    if x.size < 3 or den <= 0:
        return 0.0
    return float(x[1:] @ x[:-1]) / den


def residual_diagnostics(residual: np.ndarray) -> RecordDiagnostics:
    """Lag-1 autocorrelation and runs test of one record's residuals (in time order; zeros are dropped for the
    runs test)."""
    from scipy.stats import norm

    r = np.asarray(residual, dtype=float)
    s = np.sign(r[r != 0])
    n_pos, n_neg = int(np.sum(s > 0)), int(np.sum(s < 0))
    n = n_pos + n_neg
    runs = int(1 + np.sum(s[1:] != s[:-1])) if n else 0
    if n_pos == 0 or n_neg == 0:
        mu, z, p = float(runs), (-math.inf if n > 1 else 0.0), (0.0 if n > 1 else 1.0)
    else:
        mu = 2.0 * n_pos * n_neg / n + 1.0
        var = (mu - 1.0) * (mu - 2.0) / (n - 1.0)
        z = (runs - mu) / math.sqrt(var) if var > 0 else 0.0
        p = float(2 * norm.sf(abs(z)))
    return RecordDiagnostics(int(r.size), lag1(r), runs, float(mu), float(z), float(p))


def discrepancy_basis(t: np.ndarray, ramp_time: float, k: int = DISCREPANCY_TERMS) -> np.ndarray:
    """(n, k) columns: Legendre polynomials of degree 0..k-1 in u = log(t + ramp_time) mapped to [-1, 1] over the
    record, scaled by sqrt(2 b + 1) (orthonormal over u: a coefficient is the root-mean-square relative size of
    that shape over the record's log-time span, however the samples are spread over it)."""
    x = np.log(np.asarray(t, dtype=float) + ramp_time)
    span = float(np.ptp(x))
    u = 2.0 * (x - x.min()) / span - 1.0 if span > 0 else np.zeros_like(x)
    k = max(1, min(k, int(np.unique(u).size)))
    return np.polynomial.legendre.legvander(u, k - 1) * np.sqrt(2.0 * np.arange(k) + 1.0)


def _bartlett(g: np.ndarray, bandwidth: int) -> np.ndarray:
    """sum_{|l| <= L} (1 - |l| / (L + 1)) sum_k g_k g_{k+l}^T of scores ``g`` (n, p)."""
    S = g.T @ g
    for lag in range(1, min(bandwidth, g.shape[0] - 1) + 1):
        G = g[lag:].T @ g[:-lag]
        S = S + (1.0 - lag / (bandwidth + 1.0)) * (G + G.T)
    return S


def hac(g: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, float]:
    """Long-run covariance of the sum of scores ``g`` (n, p) whose residuals ``u`` (n) may be autocorrelated:
    AR(1) prewhitening with rho = lag-1 autocorrelation of u (clipped to [0, RHO_MAX]), Bartlett kernel with
    Andrews' automatic bandwidth on the whitened scores, recoloured by 1 / (1 - rho)^2. Returns (matrix, rho)."""
    rho = min(max(lag1(u), 0.0), RHO_MAX)
    n = g.shape[0]
    if n < 3:
        return g.T @ g, rho
    w = g[1:] - rho * g[:-1]
    e = u[1:] - rho * u[:-1]
    r_w = max(min(lag1(e), 0.97), -0.97)
    a1 = 4 * r_w**2 / ((1 - r_w) ** 2 * (1 + r_w) ** 2)
    bandwidth = int(min(math.ceil(1.1447 * (a1 * n) ** (1 / 3)), n // 4))
    S = _bartlett(w, bandwidth) * (n / (n - 1))  # n - 1 whitened scores stand for n
    return S / (1.0 - rho) ** 2, rho


@dataclass
class ErrorModelFit:
    """What :func:`robust_covariance` found: the log-parameter covariance under each error model
    (``covariances``, P x P by name in :data:`ERROR_MODELS`), the discrepancy's estimated relative size
    ``discrepancy`` (eps_d, RMS per term), the rho used per record, and ``dof_discrepancy`` (the effective degrees of
    freedom of eps_d^2: at most the number of discrepancy coefficients the parameters leave estimable, less where
    the noise outweighs the discrepancy along some of them)."""

    covariances: dict[str, np.ndarray]
    discrepancy: float
    rho: tuple[float, ...]
    dof_discrepancy: float
    discrepancy_share: np.ndarray  # per parameter: fraction of the robust variance from the discrepancy term


def orthonormal_basis(X: np.ndarray, rtol: float = 1e-14) -> np.ndarray:
    """An orthonormal basis (n, rank) of the column space of a tall ``X`` (n, m), rank-revealing: the columns
    scaled to unit norm, then twice X <- X V diag(lambda)^-1/2 from the eigenpairs of X'X, dropping on the first
    pass the directions with lambda <= ``rtol`` lambda_max (singular values below ~1e-7 of the largest; the
    second pass restores orthogonality to round-off, as CholeskyQR2). Dependent columns, such as the fit's d model /
    d ln C and the discrepancy's constant term (the model is proportional to C), add no direction: a Householder
    QR gave them a column of rounding noise whose squares put a leverage of up to ~1 on single rows. Two Gram
    products and two thin products: cheaper on a tall X than a QR that forms Q."""
    s = np.linalg.norm(X, axis=0)
    Q = X[:, s > 0] / s[s > 0]
    for first in (True, False):
        lam, V = np.linalg.eigh(Q.T @ Q)
        keep = lam > (rtol if first else 0.5) * max(float(lam.max()), 1e-300) if lam.size else lam > 0
        Q = Q @ (V[:, keep] / np.sqrt(lam[keep]))
    return Q


def _reml_discrepancy(r: np.ndarray, X: np.ndarray, D: np.ndarray) -> tuple[float, float]:
    """REML estimate of lambda in r = X b + D a + e, a ~ N(0, lambda I), e ~ N(0, I): with P the projection off X,
    maximise -1/2 sum_b [log(1 + lambda mu_b) - lambda c_b^2 / (1 + lambda mu_b)] over lambda >= 0, where mu_b are
    the eigenvalues of D'PD and c = U'D'P r. Returns (lambda, its effective degrees of freedom): Satterthwaite's
    nu = 2 lambda^2 / var(lambda) with the REML information, nu = sum_b (lambda mu_b / (1 + lambda mu_b))^2: each
    estimable direction counts as much as the discrepancy outweighs the noise along it (the number of estimable
    directions when lambda = 0 or every direction is discrepancy-dominated)."""
    from scipy.optimize import minimize_scalar

    Qx, sx, _ = np.linalg.svd(X, full_matrices=False)
    Qx = Qx[:, sx > 1e-10 * max(float(sx.max()), 1e-300)]
    PD = D - Qx @ (Qx.T @ D)
    Pr = r - Qx @ (Qx.T @ r)
    mu, U = np.linalg.eigh(PD.T @ PD)
    keep = mu > 1e-8 * max(float(mu.max()), 1e-300)
    mu, U = mu[keep], U[:, keep]
    if mu.size == 0:
        return 0.0, 0.0
    c2 = (U.T @ (PD.T @ Pr)) ** 2

    def nll(log_lam: float) -> float:
        lam = math.exp(log_lam)
        return float(np.sum(np.log1p(lam * mu) - lam * c2 / (1 + lam * mu)))

    # the likelihood's slope at lambda = 0 is sum (c^2 - mu) / 2: no discrepancy unless the projected residual
    # carries more than the noise along D
    if float(np.sum(c2 - mu)) <= 0:
        return 0.0, float(mu.size)
    hi = math.log(1e4 / float(mu.min()))
    lo = math.log(1e-8 / float(mu.max()))
    sol = minimize_scalar(nll, bounds=(lo, hi), method="bounded", options={"xatol": 1e-3})
    lam = math.exp(float(sol.x))
    if nll(float(sol.x)) >= 0.0:
        return 0.0, float(mu.size)
    # a direction along which the noise outweighs the discrepancy hardly informs lambda: a small estimate from
    # weakly informative directions has few degrees of freedom (dense records with a 0.5 % misfit: estimates 10x
    # below the truth came with the 8 directions' Student quantile and C missed by 6 of its sd)
    g = lam * mu / (1.0 + lam * mu)
    return lam, float(max(np.sum(g**2), min(DISCREPANCY_MIN_DOF, mu.size)))


def robust_covariance(
    J: np.ndarray,
    r: np.ndarray,
    idx: np.ndarray,
    n_data: int,
    P: int,
    model: np.ndarray,
    sig: np.ndarray,
    times: Sequence[np.ndarray],
    ramp_time: float,
    white: np.ndarray | None = None,
    misfit: float = 0.0,
) -> ErrorModelFit:
    """Covariances of the log-parameters under each error model (module doc).

    J       Jacobian of the weighted residuals in z (rows: the n_data data points, then the prior rows of the
            model-error factors), r the weighted residuals at the estimate (same rows), idx each data point's
            record, P the number of parameters (the first P components of z), ``model`` the model (Pa, with
            the model-error factors applied) and ``sig`` the noise sd (Pa) of each data point, ``times`` each
            record's times (s); ``white`` the Gauss-Newton covariance of the log-parameters if already
            computed (else from J); ``misfit`` a lower bound of the discrepancy's relative size (RMS per shape
            term), what is known of the model's accuracy beyond what the residuals show. A compressed fit
            passes every sample here (:func:`tissuemech.compare.fit.estimation.full_record_terms`), not its bins.
    """
    Jd, rd = J[:n_data], r[:n_data]
    Jp = J[n_data:]
    A = J.T @ J
    lam_A, V_A = np.linalg.eigh(0.5 * (A + A.T))
    Ainv = (V_A / np.maximum(lam_A, max(float(lam_A.max()), 1e-300) * 1e-14)) @ V_A.T
    nz = J.shape[1]
    R = int(idx.max()) + 1 if idx.size else 0
    # the discrepancy design in the fit's weighted units: model x Legendre(log t) / sd, per record
    blocks = []
    for j in range(R):
        rows = np.nonzero(idx == j)[0]
        Bj = discrepancy_basis(times[j], ramp_time)
        Dj = np.zeros((n_data, Bj.shape[1]))
        Dj[rows] = Bj * (model[rows] / sig[rows])[:, None]
        blocks.append(Dj)
    D = np.hstack(blocks) if blocks else np.zeros((n_data, 0))
    # rough residual: what is left after the parameters' and the smooth discrepancy's linear fit
    Q = orthonormal_basis(np.hstack([Jd, D]))
    u = rd - Q @ (Q.T @ rd)
    # per record: the rough noise scale (the fit's weights assumed white noise of RSS_j / dof), for the REML
    scale = np.empty(R)
    n_par = Q.shape[1]
    for j in range(R):
        uj = u[idx == j]
        dof = max(uj.size * (1.0 - n_par / max(n_data, 1)), 1.0)
        scale[j] = math.sqrt(float(uj @ uj) / dof) if uj.size else 1.0
    scale = np.maximum(scale, 1e-12)
    # HAC of the rough residual's scores, per record (records independent); each residual scaled by
    # 1 / sqrt(1 - leverage) of the linear fit that made it (HC2: unbiased for white noise of any leverage)
    lev = np.clip(np.sum(Q**2, axis=1), 0.0, 0.99)
    uh = u / np.sqrt(1.0 - lev)
    B_hac = np.zeros((nz, nz))
    rhos = []
    for j in range(R):
        rows = np.nonzero(idx == j)[0]
        S, rho = hac(Jd[rows] * uh[rows, None], uh[rows])
        B_hac += S
        rhos.append(rho)
    # REML of the discrepancy's size, with each record's correlated noise at its long-run level along the smooth
    # shapes ((1 + rho) / (1 - rho) times its variance): correlated noise is not taken for a misfit
    longrun = np.array([(1.0 + r_) / (1.0 - r_) for r_ in rhos]) if R else np.ones(0)
    w = 1.0 / (scale * np.sqrt(longrun))[idx]
    lam, n_est = _reml_discrepancy(rd * w, Jd * w[:, None], D * w[:, None])
    if misfit > 0 and misfit**2 >= lam:  # the user's lower bound: a known prior, no estimation uncertainty
        lam, n_est = misfit**2, 1e9
    B_prior = Jp.T @ Jp
    JD = Jd.T @ D
    B_disc = lam * (JD @ JD.T)
    # white noise at the rough scale, for the "discrepancy" model alone
    Jw = Jd * (scale[idx] ** 1)[:, None]
    B_white_rough = Jw.T @ Jw
    # effective-sample-size inflation: record j's information divided by (1 + r1) / (1 - r1)
    B_ess = np.zeros((nz, nz))
    for j in range(R):
        rows = np.nonzero(idx == j)[0]
        r1 = min(max(lag1(rd[rows]), 0.0), RHO_MAX)
        Jj = Jd[rows]
        B_ess += (Jj.T @ Jj) * (1 + r1) / (1 - r1)
    sandwich = lambda B: (Ainv @ B @ Ainv)[:P, :P]
    covs = {
        "white": Ainv[:P, :P] if white is None else np.asarray(white),
        "ess": sandwich(B_ess + B_prior),
        "hac": sandwich(B_hac + B_prior),
        "discrepancy": sandwich(B_white_rough + B_disc + B_prior),
    }
    # robust: the HAC noise term, but per parameter never below the white-noise one, with or without the smooth part
    # of the residual (a sandwich estimate is noisy where few samples carry a parameter's information: alone it
    # covered the truth ~85 % of the time on white noise), so no interval is narrower than the Gauss-Newton one
    hac_d = sandwich(B_hac + B_disc + B_prior)
    v_max = np.maximum(np.maximum(np.diag(hac_d), np.diag(covs["discrepancy"])), np.diag(covs["white"]))
    k_r = np.sqrt(v_max / np.where(np.diag(hac_d) > 0, np.diag(hac_d), 1.0))
    covs["robust"] = hac_d * np.outer(k_r, k_r)
    disc_var = np.diag(sandwich(B_disc))
    tot = np.diag(covs["robust"])
    share = np.where(tot > 0, disc_var / np.where(tot > 0, tot, 1.0), 0.0)
    return ErrorModelFit(covs, math.sqrt(lam), tuple(rhos), n_est, share)
