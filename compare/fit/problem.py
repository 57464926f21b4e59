"""The statistical model's weighted residuals (data and model-error factors) and the bounded least-squares solver."""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

__all__ = ["Problem", "least_squares_in_bounds", "masked_solver", "safe"]


class Problem:
    """Weighted residuals of the statistical model in z = (theta (P), eta (R, model-error factors))."""

    def __init__(self, recs, res_fn, jac_fn, scale, P, eps, binned=None):
        self.res_fn, self.jac_fn, self.scale = res_fn, jac_fn, scale
        self.y = np.concatenate([r.nominal_stress for r in recs])
        self.idx = np.concatenate([np.full(r.time.size, j) for j, r in enumerate(recs)])
        self.R, self.P, self.eps = len(recs), P, float(eps)
        self.nz = P + (self.R if self.eps > 0 else 0)
        # compressed records (``binned``: per record a compare.fit.compress.Binned or None): each point a bin mean
        # of ``count`` samples (noise sd s / sqrt(count)); the scatter inside the bins joins the noise estimate
        self.count = np.ones(self.y.size)
        self.within = np.zeros((self.R, 2))  # per record: sum of squares inside the bins (Pa^2), its dof
        for j, b in enumerate(binned or ()):
            if b is not None:
                self.count[self.idx == j] = b.count
                self.within[j] = (b.ss_within, b.dof_within)
        self.samples = int(round(float(np.sum(self.count))))
        self.sig = np.full(self.y.size, scale)  # per-point noise sd (Pa), set by set_noise

    def point_sd(self, s: np.ndarray | float) -> np.ndarray:
        """Per-point noise sd (Pa) from the per-sample sd of each record (``s``: per record or one value)."""
        s_pts = np.asarray(s, dtype=float)[self.idx] if np.ndim(s) else np.full(self.y.size, float(s))
        return s_pts / np.sqrt(self.count)

    def model(self, th: np.ndarray) -> np.ndarray:
        return np.asarray(self.res_fn(jnp.asarray(th))) * self.scale + self.y

    def factor(self, z: np.ndarray) -> np.ndarray | float:
        return np.exp(z[self.P :])[self.idx] if self.eps > 0 else 1.0

    def data_residual(self, z: np.ndarray) -> np.ndarray:
        """Model minus data (Pa), model-error factors applied."""
        return self.model(z[: self.P]) * self.factor(z) - self.y

    def resid(self, z: np.ndarray) -> np.ndarray:
        r = self.data_residual(z) / self.sig
        if self.eps > 0:
            r = np.concatenate([r, z[self.P :] / self.eps])
        return r

    def jac(self, z: np.ndarray) -> np.ndarray:
        th = jnp.asarray(z[: self.P])
        f = self.factor(z)
        Jm = np.asarray(self.jac_fn(th)) * self.scale  # d model / d theta (Pa)
        J = Jm * (f / self.sig)[:, None]
        if self.eps > 0:
            m = self.model(z[: self.P])
            Je = np.zeros((self.y.size, self.R))
            Je[np.arange(self.y.size), self.idx] = m * f / self.sig
            J = np.vstack([np.hstack([J, Je]), np.hstack([np.zeros((self.R, self.P)), np.eye(self.R) / self.eps])])
        return J

    def set_noise(self, z: np.ndarray, floor: np.ndarray) -> np.ndarray:
        """Per-record noise sd s_j^2 = RSS_j / (n_j - P n_j / N) from the residuals at z (Pa)."""
        r = self.data_residual(z)
        n = self.y.size
        s = np.empty(self.R)
        for j in range(self.R):
            m = self.idx == j
            rj = r[m]
            dof = max(rj.size * (1.0 - self.P / n), 1.0) + self.within[j, 1]
            s[j] = math.sqrt((float(rj @ (rj * self.count[m])) + self.within[j, 0]) / dof)
        self.sig = self.point_sd(np.maximum(s, floor))
        return s


def least_squares_in_bounds(fun, jac, z0, lo, hi, max_nfev):
    """scipy's trust-region least squares within [lo, hi]; its overflow warnings on trial points far out (which
    ``safe`` turns into a large residual, so the step is refused) are not the user's concern and stay here."""
    import warnings

    from scipy.optimize import least_squares

    with warnings.catch_warnings(), np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)
        return least_squares(
            fun,
            np.clip(z0, lo + 1e-12, hi - 1e-12),
            jac=jac,
            bounds=(lo, hi),
            method="trf",
            x_scale="jac",
            xtol=1e-12,
            ftol=1e-12,
            gtol=1e-12,
            max_nfev=max_nfev,
        )


def masked_solver(fun, jac, z_template, free, lo, hi):
    """least squares over the ``free`` components of z only (the others held at ``z_template``);
    the returned solution's ``x`` is the full z."""
    if free.all():
        return lambda z0, n: least_squares_in_bounds(fun, jac, z0, lo, hi, n)

    def solve(z0, n):
        def full(w):
            z = np.asarray(z_template, dtype=float).copy()
            z[free] = w
            return z

        sol = least_squares_in_bounds(
            lambda w: fun(full(w)), lambda w: jac(full(w))[:, free], z0[free], lo[free], hi[free], n
        )
        sol.x = full(sol.x)
        return sol

    return solve


def safe(fn):
    def wrapped(z):
        r = fn(z)
        return r if np.all(np.isfinite(r)) else np.full_like(r, 1e6)  # steer away from failed evaluations

    return wrapped
