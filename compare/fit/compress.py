r"""Dense records compressed before the fit: a record of 1e5-1e6 samples (an instrument sampling at kHz for
minutes) carries the information of a few thousand well-chosen averages, and the fit's cost follows the number
of model evaluations.

:func:`bin_record` averages a record in bins: the loading ramp in ``ramp_bins`` bins of equal width (the ramp's
end is a bin edge, so no bin straddles the kink of the loading), the hold in bins of equal width in
log(t - ramp_time) (the relaxation's time scales are spread in log time). Each bin keeps the mean time, the mean
stress and its sample count; empty bins are dropped (a bin narrower than the sampling keeps single samples, so a
short record comes back unchanged).

The statistics stay those of the full record (:func:`tissuemech.compare.fit.relaxation`, ``compress=``):

* a bin mean of ``n_b`` samples has the noise variance s^2 / n_b: its weight in the least squares is ``n_b``,
  so the Gauss-Newton information J'WJ is the full record's (to the extent the model is linear in t across a
  bin: the bins are at most ~1 % of log time wide, where the model's curvature changes the mean by far less than
  the noise of the mean);
* the noise sd s_j of each record is estimated from both the bin means' weighted residuals (B_j - P B_j / B
  degrees of freedom) and the scatter inside the bins about each bin's least-squares line (n_b - 2 each), i.e.
  from nearly all the samples, like the full fit's RSS_j / (n_j - P n_j / N);
* the robust error model (:mod:`.diagnostics`) runs on the bin means in the fit's weighted units, except for its
  noise term: the bin means get the covariance that AR(1) noise of the samples implies
  (:func:`ar1_mean_covariance`, neighbouring bins' correlation included), with the lag-1 correlation and variance
  of the samples' residuals computed from the bins' sums (:func:`sample_ar1`: the numbers the full record's fit
  prewhitens with), so the binned fit needs no floor on the bin size. A HAC estimate on the bin means (the
  earlier method, with bins of at least twice the integrated correlation time, :func:`min_samples`) rested on the
  13-26 ramp bins that carry C and alpha: under AR(1) noise of lag-1 correlation 0.9 its widths scattered by
  +-20 % over noise realisations. A smooth misfit shows in the bins as it does in the samples (the discrepancy's
  REML statistics are the same sums over time; each bin mean at the samples' long-run variance);
* the residual diagnostics (lag-1 autocorrelation, runs test) are those of the bin means: they test the model's
  shape (a misfit stands out more clearly once the noise is averaged), not the samples' short-range correlation.

``python -m tissuemech.compare.bench fit-dense`` measures estimates and interval widths of the binned against the
full fit on a 1e5-sample record, and the end-to-end time of ``tissuemech fit`` on 1e6 samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "DEFAULT_BINS",
    "AUTO_MIN_SAMPLES",
    "RAMP_SHARE",
    "Binned",
    "bin_record",
    "bins_for",
    "sample_ar1",
    "ar1_mean_covariance",
]

DEFAULT_BINS = 2000  # bins per record of a compressed fit (about 1/4 over the ramp, the rest log-spaced in the hold)
AUTO_MIN_SAMPLES = 20_000  # compress="auto" bins the records longer than this (shorter ones: fitted sample by sample)
RAMP_SHARE = 0.25  # share of the bins spent on the loading ramp


@dataclass(frozen=True)
class Binned:
    """A record averaged in bins (:func:`bin_record`): ``time`` (s) and ``stress`` (Pa) bin means, ``count``
    samples per bin, ``ss_within`` (Pa^2) the scatter inside the bins about each bin's least-squares line and
    ``dof_within`` its degrees of freedom (sum of n_b - 2 over bins of 3 samples or more), ``samples`` the
    record's length."""

    time: np.ndarray
    stress: np.ndarray
    count: np.ndarray
    ss_within: float
    dof_within: int
    samples: int
    lag_stats: np.ndarray | None = None  # (bins, 10) sums for the samples' lag-1 correlation (:func:`sample_ar1`)


def bin_edges(t_end: float, ramp_time: float, bins: int, dt_min: float) -> np.ndarray:
    """Edges: ``round(RAMP_SHARE bins)`` equal bins over [0, ramp_time], then log-spaced in t - ramp_time from
    ``dt_min`` (about one sample spacing) to the record's end."""
    n_ramp = max(1, int(round(RAMP_SHARE * bins)))
    ramp = np.linspace(0.0, ramp_time, n_ramp + 1)
    span = t_end - ramp_time
    if span <= 0:
        return np.linspace(0.0, max(t_end, ramp_time), bins + 1)
    lo = min(max(dt_min, 1e-12 * span), span)
    hold = ramp_time + np.geomspace(lo, span, max(bins - n_ramp, 1))
    return np.concatenate([ramp, hold[hold > ramp_time]])


def bin_record(
    time: np.ndarray, stress: np.ndarray, ramp_time: float, bins: int = DEFAULT_BINS, min_count: int = 1
) -> Binned:
    """Average one record (times ascending, s; stress Pa) in about ``bins`` bins (module doc); ``ramp_time`` (s)
    the loading ramp's duration. Bins without samples are dropped; bins of fewer than ``min_count`` samples are
    merged with their neighbours (e.g. ``min_samples(stress)``: nearly independent bin means under correlated
    noise; not needed by the fit, whose noise term covers the bin means' correlation)."""
    t = np.asarray(time, dtype=float)
    y = np.asarray(stress, dtype=float)
    if bins < 2:
        raise ValueError(f"bins (per record of a compressed fit) must be at least 2; got {bins}")
    dt = np.diff(t)
    dt_min = float(np.median(dt)) if dt.size else 1.0
    edges = bin_edges(float(t[-1]), float(ramp_time), bins, dt_min)
    # bin k holds edges[k - 1] < t <= edges[k] (the ramp's end sample stays in the ramp), t = 0 in bin 1
    which = np.searchsorted(edges, t, side="left")
    which = np.maximum(which, 1)
    starts = np.flatnonzero(np.concatenate([[True], which[1:] != which[:-1]]))
    starts = merge_short(starts, t, float(ramp_time), min_count)
    count = np.diff(np.concatenate([starts, [t.size]]))
    t_mean = np.add.reduceat(t, starts) / count
    y_mean = np.add.reduceat(y, starts) / count
    dtb = t - np.repeat(t_mean, count)
    dyb = y - np.repeat(y_mean, count)
    stt = np.add.reduceat(dtb * dtb, starts)
    sty = np.add.reduceat(dtb * dyb, starts)
    syy = np.add.reduceat(dyb * dyb, starts)
    line = np.where(stt > 0, sty**2 / np.where(stt > 0, stt, 1.0), 0.0)
    ss = np.maximum(syy - line, 0.0)
    big = count >= 3
    # the sums :func:`sample_ar1` needs: products of neighbouring samples of one bin (each about its bin's mean time
    # and stress), and each bin's first and last sample
    bin_of = np.repeat(np.arange(count.size), count)
    same = np.append(bin_of[1:] == bin_of[:-1], False)  # sample k and k + 1 lie in one bin

    def pair_sum(p: np.ndarray) -> np.ndarray:
        return np.add.reduceat(np.where(same, np.append(p, 0.0), 0.0), starts)

    ends = starts + count - 1
    lag_stats = np.column_stack(
        [
            syy,
            sty,
            stt,
            pair_sum(dyb[:-1] * dyb[1:]),
            pair_sum(dyb[:-1] * dtb[1:] + dtb[:-1] * dyb[1:]),
            pair_sum(dtb[:-1] * dtb[1:]),
            dyb[starts],
            dtb[starts],
            dyb[ends],
            dtb[ends],
        ]
    )
    return Binned(
        time=t_mean,
        stress=y_mean,
        count=count.astype(float),
        ss_within=float(np.sum(ss[big])),
        dof_within=int(np.sum(count[big] - 2)),
        samples=int(t.size),
        lag_stats=lag_stats,
    )


def sample_ar1(binned: Binned, offset: np.ndarray, slope: np.ndarray) -> tuple[float, float]:
    """Lag-1 autocorrelation rho and mean square s^2 (Pa^2) of the samples' residuals (data - model) over the
    whole record, from the bins' sums (``binned.lag_stats``) with the model linear across each bin: ``offset``
    (Pa) each bin mean's residual, ``slope`` (Pa/s) the model's time derivative in each bin. These are the
    numbers the full record's fit prewhitens with (:func:`tissuemech.compare.fit.diagnostics.hac`); the noise
    inside a bin, its slope included, counts as in the samples."""
    if binned.lag_stats is None:
        raise ValueError("the bins carry no lag sums (lag_stats): bin the record with bin_record")
    syy, sty, stt, saa1, sat1, stt1, a_f, t_f, a_l, t_l = binned.lag_stats.T
    n, c, d = binned.count, np.asarray(offset, dtype=float), np.asarray(slope, dtype=float)
    s0 = syy - 2.0 * d * sty + d * d * stt + n * c * c
    s1 = saa1 - d * sat1 + d * d * stt1 - c * (a_f + a_l) + c * d * (t_f + t_l) + (n - 1.0) * c * c
    first, last = a_f - d * t_f + c, a_l - d * t_l + c
    total = float(np.sum(s0))
    if total <= 0:
        return 0.0, 0.0
    rho = (float(np.sum(s1)) + float(last[:-1] @ first[1:])) / total
    return rho, total / binned.samples


def ar1_mean_covariance(count: np.ndarray, rho: float, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """X' K X and diag(K), with K the covariance of the bin means (bins of ``count`` consecutive samples, in time
    order) of AR(1) noise of lag-1 correlation ``rho`` (0 <= rho < 1) and unit variance: the sum over a bin of
    n samples has variance n (1 + rho) / (1 - rho) - 2 rho (1 - rho^n) / (1 - rho)^2, two bins a gap of g samples
    apart (last of the one to first of the other) the covariance rho^g (1 - rho^n_a) (1 - rho^n_b) / (1 - rho)^2.
    ``X`` (bins, p); the bins' covariances are summed until rho^gap underflows."""
    n = np.asarray(count, dtype=float)
    X = np.asarray(X, dtype=float)
    if rho <= 0.0:
        k_diag = 1.0 / n
        return (X * k_diag[:, None]).T @ X, k_diag
    q = 1.0 - rho
    k_diag = (n * (1.0 + rho) / q - 2.0 * rho * (1.0 - rho**n) / q**2) / n**2
    out = (X * k_diag[:, None]).T @ X
    ends = np.cumsum(n)  # one past each bin's last sample
    starts = ends - n
    tail = (1.0 - rho**n) / (q * n)  # (1 - rho^n) / ((1 - rho) n) per bin
    log_rho = math.log(rho)
    for lag in range(1, n.size):
        gap = starts[lag:] - (ends[:-lag] - 1.0)
        w = np.exp(gap * log_rho) * tail[:-lag] * tail[lag:]
        if float(np.max(w)) < 1e-17 * float(np.max(k_diag)):
            break
        G = (X[:-lag] * w[:, None]).T @ X[lag:]
        out = out + G + G.T
    return out, k_diag


def noise_correlation(y: np.ndarray, window: int = 25) -> float:
    """Lag-1 autocorrelation rho of the noise (clipped to [0, 0.97]) from the first differences of a densely sampled
    record, where the signal's change from one sample to the next is negligible against the noise: for AR(1) noise
    the differences have lag-1 correlation -(1 - rho) / 2. Where it is not (the differences' running mean over
    ``window`` samples carries more than 10 % of their variance: a smooth, noise-free or sparse record), 0."""
    d = np.diff(np.asarray(y, dtype=float))
    if d.size < 4 * window:
        return 0.0
    d = d - np.mean(d)
    den = float(d @ d)
    if den <= 0:
        return 0.0
    trend = np.convolve(d, np.full(window, 1.0 / window), mode="valid")
    if float(trend @ trend) / trend.size > 0.1 * den / d.size:
        return 0.0
    c1 = float(d[1:] @ d[:-1]) / den
    return float(np.clip(1.0 + 2.0 * c1, 0.0, 0.97))


def min_samples(y: np.ndarray) -> int:
    """The fewest samples a bin may hold: about twice the noise's integrated correlation time (1 + rho) / (1 - rho)
    (:func:`noise_correlation`), so that bin means are nearly independent (1 for white noise)."""
    rho = noise_correlation(y)
    return max(1, int(round(2.0 * (1.0 + rho) / (1.0 - rho) - 1.0)))


def merge_short(starts: np.ndarray, t: np.ndarray, ramp_time: float, m: int) -> np.ndarray:
    """Bin starts (sample indices) with bins of fewer than ``m`` samples merged into the next ones, never across the
    end of the ramp (a short last bin of the ramp or of the record joins the bin before it)."""
    if m <= 1:
        return starts
    n = t.size
    split = int(np.searchsorted(t, ramp_time, side="right"))  # first sample of the hold
    out: list[int] = []
    for lo, hi in ((0, split), (split, n)):
        seg = [int(i) for i in starts if lo <= i < hi]
        if not seg:
            continue
        kept = [seg[0]]
        for i in seg[1:]:
            if i - kept[-1] >= m:
                kept.append(i)
        if len(kept) > 1 and hi - kept[-1] < m:
            kept.pop()
        out += kept
    return np.asarray(out, dtype=int)


def bins_for(compress: bool | int | str | None, samples: int) -> int:
    """The number of bins a record of ``samples`` samples is fitted in (0: not compressed) for the ``compress``
    choice of :func:`tissuemech.compare.fit.relaxation`: "auto" (records longer than :data:`AUTO_MIN_SAMPLES` in
    :data:`DEFAULT_BINS` bins), True (every record in DEFAULT_BINS bins), a whole number (that many bins),
    False / None / 0 (never)."""
    if compress is None or compress is False:
        return 0
    if isinstance(compress, str):
        if compress != "auto":
            raise ValueError(f"compress must be 'auto', True, False or a number of bins (>= 2); got {compress!r}")
        return DEFAULT_BINS if samples > AUTO_MIN_SAMPLES else 0
    if compress is True:
        return DEFAULT_BINS
    if isinstance(compress, (int, np.integer)) and not isinstance(compress, bool):
        if compress == 0:
            return 0
        if compress < 2:
            raise ValueError(f"compress (bins per record) must be at least 2; got {compress}")
        return int(compress)
    raise ValueError(f"compress must be 'auto', True, False or a number of bins (>= 2); got {compress!r}")
