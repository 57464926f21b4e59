"""95 % intervals and identifiability: the Fisher matrix's eigen-decomposition (:class:`Identifiability`), Wald
ends checked against the profile likelihood (:class:`Profiler`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tissuemech.compare.fit.problem import least_squares_in_bounds, safe

__all__ = [
    "Z95",
    "POOR_SD",
    "WALD_TOL",
    "LOG_SPAN",
    "Identifiability",
    "identifiability",
    "inverse_eigenvalues",
    "Profiler",
    "exp_or_inf",
]

Z95 = 1.959963984540054  # two-sided 95 % normal quantile
POOR_SD = 0.5  # a log-combination with standard deviation above this (a factor ~2.7 at 95 %) is "poor"
WALD_TOL = 0.10  # accept a Wald end when the profile chi-square rise there is within 10 % of t^2
LOG_SPAN = 12.0  # profile search at most e^12 away from the estimate (beyond: unbounded)


@dataclass
class Identifiability:
    """Eigen-decomposition of the Gauss-Newton Fisher matrix in log-parameter space.

    eigenvalues   ascending (1 / variance of each log-combination)
    eigenvectors  columns, in the order of ``names``
    names         parameter names
    sd            standard deviation of each log-combination, 1/sqrt(eigenvalue)
    poorly        indices of the poorly determined combinations (sd > POOR_SD)
    report        human-readable summary
    """

    eigenvalues: np.ndarray
    eigenvectors: np.ndarray
    names: tuple[str, ...]
    sd: np.ndarray
    poorly: tuple[int, ...]
    report: str

    def combination(self, i: int, threshold: float = 0.01) -> str:
        """The i-th eigen-direction as a product of powers, e.g. ``C^0.71 * alpha^0.70``."""
        v = self.eigenvectors[:, i]
        v = v * np.sign(v[np.argmax(np.abs(v))])
        parts = [f"{n}^{c:+.3g}" for n, c in zip(self.names, v) if abs(c) >= threshold]
        return " * ".join(parts)

    def correlation(self) -> np.ndarray:
        """Correlation matrix of the log-parameters (from the pseudo-inverse Fisher matrix)."""
        lam, V = self.eigenvalues, self.eigenvectors
        cov = (V * inverse_eigenvalues(lam)) @ V.T
        d = np.sqrt(np.abs(np.diag(cov)))
        return cov / np.outer(d, d)

    def mixes(self, a: str, b: str, threshold: float = 0.9) -> bool:
        """True if log(a) and log(b) are correlated beyond ``threshold`` (they trade off in the fit)
        and the weakest direction carries weight on both (|v| >= 0.01)."""
        ia, ib = self.names.index(a), self.names.index(b)
        v = self.eigenvectors[:, 0]
        return abs(self.correlation()[ia, ib]) >= threshold and abs(v[ia]) >= 0.01 and abs(v[ib]) >= 0.01


def inverse_eigenvalues(lam: np.ndarray) -> np.ndarray:
    """1/lambda with a relative floor (1e-16 of the largest): a null direction gets a huge but finite
    variance, so it does not leak round-off into the well-determined parameters."""
    floor = max(float(np.max(lam)), 1e-300) * 1e-16
    return 1.0 / np.maximum(lam, floor)


def identifiability(fisher: np.ndarray, names: tuple[str, ...], dead: Sequence[int] = ()) -> Identifiability:
    """Eigen-decomposition of the log-space Fisher matrix (already in units of the noise)."""
    lam, V = np.linalg.eigh(0.5 * (fisher + fisher.T))
    lam = np.where(lam > 1e-13 * max(float(np.max(lam)), 1e-300), lam, 0.0)
    with np.errstate(divide="ignore"):
        sd = 1.0 / np.sqrt(lam)
    poorly = tuple(int(i) for i in np.nonzero(sd > POOR_SD)[0])
    ident = Identifiability(lam, V, names, sd, poorly, "")
    lines = ["Identifiability (Fisher matrix in log-parameters; each row a combination prod p_i^v_i):"]
    for i in range(len(lam)):
        tag = "POORLY determined" if i in poorly else "well determined"
        rel = f"+-{100 * (math.exp(Z95 * sd[i]) - 1):.3g} %" if np.isfinite(sd[i]) and sd[i] < 20 else "unbounded"
        lines.append(f"  {ident.combination(i):<45} eigenvalue {lam[i]:10.3e}  95% factor {rel:>12}  {tag}")
    for i in dead:
        lines.append(
            f"  -> the model does not depend on {names[i]} at the estimate (alpha with equilibrium='hertz'; a "
            "relaxation time whose branch has vanished, beta -> 0, as in records that do not relax): "
            "it is not identified by these data."
        )
    if poorly:
        weak = [ident.combination(i) for i in poorly]
        lines.append("  -> the data cannot separate the parameters along: " + "; ".join(weak) + ".")
        if "C" in names and "alpha" in names and ident.mixes("C", "alpha"):
            lines.append(
                "  -> C and alpha trade off: one compression level only fixes the equilibrium force "
                "F_eq(delta) (a single combination of C and alpha). Add records at two or more "
                "compression levels (or resolve the loading ramp) to identify them separately."
            )
    else:
        lines.append("  -> all parameters are identified by these records.")
    ident.report = "\n".join(lines)
    return ident


class Profiler:
    """chi2_profile(theta_i = c) - chi2_min by re-optimising the other components of z."""

    def __init__(self, prob, z_hat, chi2_min, cov_z, lo, hi, max_nfev=30):
        self.prob, self.z_hat, self.chi2_min, self.cov = prob, z_hat, chi2_min, cov_z
        self.lo, self.hi, self.max_nfev = lo, hi, max_nfev
        self.better: np.ndarray | None = None  # a point with lower chi2 than the "optimum", if met
        self.free = np.ones(z_hat.size, dtype=bool)  # components re-optimised (not held fixed)

    def delta(self, i: int, c: float) -> float:
        keep = (np.arange(self.z_hat.size) != i) & self.free

        def full(w):
            z = self.z_hat.copy()
            z[keep], z[i] = w, c
            return z

        fun = safe(lambda w: self.prob.resid(full(w)))
        jac = lambda w: np.nan_to_num(self.prob.jac(full(w))[:, keep], nan=0.0, posinf=0.0, neginf=0.0)
        if keep.sum() == 0:
            r = fun(np.zeros(0))
            chi2 = float(r @ r)
        else:
            # start: the conditional optimum of the quadratic approximation (clipped), or the estimate
            ci = self.cov[:, i] / self.cov[i, i] if self.cov[i, i] > 0 else np.zeros(self.z_hat.size)
            move = np.nan_to_num(np.clip((c - self.z_hat[i]) * ci, -LOG_SPAN, LOG_SPAN))
            starts = [np.clip((self.z_hat + move)[keep], self.lo[keep], self.hi[keep]), self.z_hat[keep]]
            cost = [float(np.sum(fun(w) ** 2)) for w in starts]
            w0 = starts[int(np.argmin(cost))]
            sol = least_squares_in_bounds(fun, jac, w0, self.lo[keep], self.hi[keep], self.max_nfev)
            chi2 = float(sol.fun @ sol.fun)
            if chi2 < self.chi2_min - max(1e-3, 1e-8 * self.chi2_min):  # 1e-3 << t^2 ~ 3.8
                self.better = full(sol.x)
        return max(chi2 - self.chi2_min, 0.0)

    def end(self, i: int, side: int, h: float, q: float) -> tuple[float, str]:
        """(theta_i at the interval end on this side, how: 'wald' | 'profile' | 'bound' | 'open')."""
        from scipy.optimize import brentq

        th0 = self.z_hat[i]
        bound = self.hi[i] if side > 0 else self.lo[i]
        limit = th0 + side * LOG_SPAN
        edge = bound if np.isfinite(bound) else limit
        if side * (edge - th0) <= 1e-12:
            return float(edge), "bound"
        h = min(max(h, 1e-6), LOG_SPAN) if np.isfinite(h) else 1.0
        c = th0 + side * min(h, side * (edge - th0))
        D = self.delta(i, c)
        if abs(D - q) <= WALD_TOL * q and side * (edge - c) > 1e-12:
            return float(c), "wald"
        below = th0
        for _ in range(12):
            if D >= q:
                break
            below = c
            if side * (edge - c) <= 1e-12:
                return float(edge), ("bound" if np.isfinite(bound) else "open")
            step = abs(c - th0) * (math.sqrt(q / D) * 1.3 if D > 1e-12 * q else 4.0)
            step = min(max(step, 1.5 * abs(c - th0)), 4.0 * abs(c - th0) + 1.0)
            c = th0 + side * min(step, side * (edge - th0))
            D = self.delta(i, c)
        if D < q:
            return float(c), ("bound" if np.isfinite(bound) else "open")
        g = lambda x: math.sqrt(self.delta(i, x)) - math.sqrt(q)
        root = brentq(g, below, c, xtol=1e-3 * max(abs(c - th0), 1e-6), rtol=1e-10, maxiter=30)
        return float(root), "profile"


def exp_or_inf(th: float) -> float:
    """exp(th), inf beyond the float range (a Wald end of a poorly determined log-parameter can lie there)."""
    return math.exp(th) if th < 709.0 else math.inf
