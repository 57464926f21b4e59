r"""Contact point on the approach, and the indentation history it defines.

Contact point (:func:`find_contact`): the force on the approach, as a function of the probe height h, is
fitted by a piecewise law, a flat baseline before contact and a power law after it,

    F(h) = F_0 + K max(h_c - h, 0)^n,   n in [0.5, 3]

(Hertz gives n = 3/2; the exponent is free so that a soft outer layer or a shell-like start does not bias
h_c). The fit uses the samples of the pause before the approach (when the curve has one) and the approach up
to ``window`` (default 20 %) of its force rise: near contact, where the power law describes the curve,
not the deep indentation. Start: a grid over h_c (linear least squares for F_0, K at n = 3/2), then
``scipy.optimize.least_squares`` on (F_0, log K, h_c, n). Uncertainty of h_c (m): the Gauss-Newton standard
deviation, inflated by sqrt((1 + r_1) / (1 - r_1)) with r_1 the lag-1 autocorrelation of the residuals
(correlated residuals carry fewer independent samples than their count). A contact at the first approach
sample (the probe already touching when the motion starts) is flagged: the baseline is then not a free
cantilever's and the indentation is a lower bound.

Indentation (:func:`indentation`): delta = (h_c - h) - (F - F_0) / k, the piezo travel since contact minus
the cantilever deflection (k the spring constant), and the force above the baseline, from the contact time
on: the approach in contact (the loading ramp) and the hold. During the hold the height is constant but the
cantilever relaxes, so the tip creeps into the sample: delta grows a little while the force relaxes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from tissuemech.compare.afm.records import Curve
from tissuemech.reduced.validation import InputError

__all__ = ["ContactPoint", "Indentation", "find_contact", "indentation", "lag1"]


@dataclass(frozen=True)
class ContactPoint:
    """height (m) and its standard deviation ``height_sd`` (m); ``time`` (s) when the approach crosses it;
    ``baseline`` F_0 (N); ``exponent`` n and prefactor ``K`` (N/m^n) of the power law near contact;
    ``lag1`` residual autocorrelation; ``at_start``: contact at (or above) the first approach sample."""

    height: float
    height_sd: float
    time: float
    baseline: float
    exponent: float
    K: float
    lag1: float
    at_start: bool
    n_points: int


@dataclass(frozen=True)
class Indentation:
    """From the contact on: ``time`` (s, 0 at contact), ``approach`` delta (m), ``force`` (N, above the
    baseline), ``phase`` ("approach" or "hold" per sample); ``ramp_time`` (s, contact to the hold's start);
    ``creep`` (m): the growth of delta over the hold."""

    time: np.ndarray
    approach: np.ndarray
    force: np.ndarray
    phase: np.ndarray
    ramp_time: float
    creep: float
    name: str = ""

    @property
    def hold(self) -> np.ndarray:
        """Mask of the hold samples."""
        return self.phase == "hold"


def lag1(r: np.ndarray) -> float:
    """Lag-1 autocorrelation of a residual series (0 for white noise)."""
    r = np.asarray(r, dtype=float) - np.mean(r)
    den = float(np.dot(r, r))
    return float(np.dot(r[1:], r[:-1]) / den) if den > 0 else 0.0


def _model(p: np.ndarray, h: np.ndarray) -> np.ndarray:
    f0, logk, hc, n = p
    d = np.maximum(hc - h, 0.0)
    return f0 + np.exp(logk) * d**n


def find_contact(curve: Curve, *, window: float = 0.2) -> ContactPoint:
    """The contact point of ``curve`` on its approach (module doc: method and uncertainty)."""
    if not 0 < window <= 1:
        raise InputError(f"window (fraction of the approach's force rise fitted) must be in (0, 1]; got {window}")
    appr = curve.part("approach")
    if appr.sum() < 8:
        raise InputError(f"curve {curve.name!r}: the approach has {appr.sum()} samples; the contact fit needs >= 8")
    h_a, f_a, t_a = curve.height[appr], curve.force[appr], curve.time[appr]
    if "pause" in curve.segment_names and curve.part("pause").any():
        pause = curve.part("pause")
        h_b, f_b = curve.height[pause], curve.force[pause]
    else:
        k0 = max(4, appr.sum() // 20)
        h_b, f_b = h_a[:0], f_a[:0]
        f_base_guess = float(np.median(f_a[:k0]))
    f_base_guess = float(np.median(f_b)) if f_b.size else float(np.median(f_a[: max(4, appr.sum() // 20)]))
    rise = float(np.max(f_a) - f_base_guess)
    if not rise > 0:
        raise InputError(f"curve {curve.name!r}: the force does not rise on the approach: no contact to find")
    last = int(np.argmax(f_a - f_base_guess >= window * rise))
    last = max(last, 8)
    h = np.concatenate([h_b, h_a[: last + 1]])
    f = np.concatenate([f_b, f_a[: last + 1]])
    scale_f, scale_h = rise, float(np.ptp(h)) or 1.0
    hs = (h - h_a[0]) / scale_h  # dimensionless: 0 at the approach start, negative on approach
    fs = (f - f_base_guess) / scale_f
    # grid over h_c (from slightly above the start to the window's end), n = 3/2, linear LS for F_0, K
    best = (np.inf, 0.0, 0.0, 1.0)
    for hc in np.linspace(float(hs.min()), 0.0, 201):
        d = np.maximum(hc - hs, 0.0) ** 1.5
        A = np.c_[np.ones_like(d), d]
        coef, *_ = np.linalg.lstsq(A, fs, rcond=None)
        if coef[1] <= 0:
            continue
        rss = float(np.sum((A @ coef - fs) ** 2))
        if rss < best[0]:
            best = (rss, hc, coef[0], coef[1])
    _, hc0, f00, k00 = best
    p0 = np.array([f00, math.log(max(k00, 1e-12)), hc0, 1.5])
    lo = np.array([-np.inf, -np.inf, float(hs.min()), 0.5])
    hi = np.array([np.inf, np.inf, 0.0 + 1e-9, 3.0])
    sol = least_squares(lambda p: _model(p, hs) - fs, np.clip(p0, lo + 1e-12, hi - 1e-12), bounds=(lo, hi), x_scale=1.0)
    r = sol.fun
    J = sol.jac
    dof = max(r.size - 4, 1)
    s2 = float(r @ r) / dof
    rho = lag1(r)
    try:
        cov = s2 * np.linalg.pinv(J.T @ J)
        sd_hc = math.sqrt(max(cov[2, 2], 0.0)) * math.sqrt((1 + max(rho, 0.0)) / (1 - min(max(rho, 0.0), 0.99)))
    except np.linalg.LinAlgError:  # pragma: no cover
        sd_hc = math.nan
    f0, logk, hc_s, n = sol.x
    hc = h_a[0] + hc_s * scale_h
    at_start = hc_s >= -1e-6 or hc >= h_a[0] - 0.5 * abs(h_a[1] - h_a[0])
    # contact time: where the approach height crosses h_c (heights decrease along the approach)
    tc = float(np.interp(-hc, -h_a, t_a)) if not at_start else float(t_a[0])
    return ContactPoint(
        height=float(hc),
        height_sd=float(sd_hc * scale_h),
        time=tc,
        baseline=float(f_base_guess + f0 * scale_f),
        exponent=float(n),
        K=float(math.exp(logk) * scale_f / scale_h**n),
        lag1=rho,
        at_start=bool(at_start),
        n_points=int(r.size),
    )


def indentation(curve: Curve, contact: ContactPoint | None = None) -> Indentation:
    """The indentation history from the contact on (module doc): approach in contact, then the hold.

    ``contact``: from :func:`find_contact` (found here when None). The first sample is the contact itself
    (t = 0, delta = 0, F = 0); delta is clipped at 0 (noise just after contact)."""
    c = find_contact(curve) if contact is None else contact
    appr, hold = curve.part("approach"), curve.part("hold")
    if hold.sum() < 4:
        raise InputError(f"curve {curve.name!r}: the hold segment has {hold.sum()} samples; a relaxation needs more")
    keep = (appr & (curve.height < c.height) & (curve.time > c.time)) | hold
    t = curve.time[keep] - c.time
    d = (c.height - curve.height[keep]) - (curve.force[keep] - c.baseline) / curve.spring_constant
    f = curve.force[keep] - c.baseline
    phase = np.where(hold[keep], "hold", "approach")
    t = np.concatenate([[0.0], t])
    d = np.maximum(np.concatenate([[0.0], d]), 0.0)
    f = np.concatenate([[0.0], f])
    phase = np.concatenate([["approach"], phase])
    ramp = float(curve.time[hold][0] - c.time)
    dh = d[phase == "hold"]
    return Indentation(t, d, f, phase, ramp, float(dh[-1] - dh[0]), curve.name)
