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
* the error model of the intervals (:mod:`.diagnostics`: HAC noise term, smooth discrepancy) runs on every
  sample, at the binned estimate: one pass of the model and its Jacobian over the records (in chunks of one
  compiled shape, :func:`tissuemech.compare.fit.model.sample_evaluator`), so a compressed fit's intervals are its
  full fit's, up to the estimate's shift. Earlier error models on the bin means missed the full fit's widths: a HAC
  of the bin means rested on the 13-26 ramp bins that carry C and alpha (+-20 % under AR(1) noise), a parametric
  AR(1) term of the bin means (the samples' rho) was closer to the exact AR(1) sandwich than the full fit's HAC but
  9 % narrower than it on white noise (the full record's HAC estimates C's noise from the few hundred ramp samples
  that carry it and errs upward there: docs/benchmarks.md, issue 40);
* the residual diagnostics (lag-1 autocorrelation, runs test) are those of the bin means: they test the model's
  shape (a misfit stands out more clearly once the noise is averaged), not the samples' short-range correlation.

``python -m tissuemech.compare.bench fit-dense`` measures estimates and interval widths of the binned against the
full fit on a 1e5-sample record, and the end-to-end time of ``tissuemech fit`` on 1e6 samples.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "DEFAULT_BINS",
    "AUTO_MIN_SAMPLES",
    "RAMP_SHARE",
    "Binned",
    "bin_record",
    "bins_for",
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
    noise; not needed by the fit, whose error model runs on the samples)."""
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
    return Binned(
        time=t_mean,
        stress=y_mean,
        count=count.astype(float),
        ss_within=float(np.sum(ss[big])),
        dof_within=int(np.sum(count[big] - 2)),
        samples=int(t.size),
    )


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
