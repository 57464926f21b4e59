"""Dense records fitted in bins (compare.fit.compress, relaxation(compress=...)): the bins keep the statistics of
the samples, and a binned fit gives the full fit's estimates and 95 % intervals."""

from __future__ import annotations

import numpy as np
import pytest

from tissuemech.compare import fit
from tissuemech.compare.fit.compress import AUTO_MIN_SAMPLES, DEFAULT_BINS, bin_record, bins_for


def test_bins_keep_sums_and_the_ramp_end():
    t = np.linspace(0.001, 50.0, 50_000)
    y = 3.0 * t + 1.0  # a line: each bin's mean is the line at the bin's mean time, nothing scatters about it
    b = bin_record(t, y, ramp_time=1.0, bins=400)
    assert b.count.sum() == t.size and b.samples == t.size
    np.testing.assert_allclose(b.stress, 3.0 * b.time + 1.0, rtol=1e-12)
    assert b.ss_within < 1e-12 * float(np.sum(y**2))
    assert np.all(np.diff(b.time) > 0)
    # no bin straddles the end of the ramp: every bin lies wholly on one side of t = 1 s
    starts = np.concatenate([[0], np.cumsum(b.count)[:-1]]).astype(int)
    ends = (np.cumsum(b.count) - 1).astype(int)
    assert not np.any((t[starts] <= 1.0) & (t[ends] > 1.0))
    assert b.count.size <= 400


def test_within_bin_scatter_measures_the_noise():
    rng = np.random.default_rng(3)
    t = np.linspace(0.01, 100.0, 100_000)
    y = np.exp(-t / 30.0) + 0.05 * rng.standard_normal(t.size)
    b = bin_record(t, y, ramp_time=0.5)
    sd = np.sqrt(b.ss_within / b.dof_within)
    assert sd == pytest.approx(0.05, rel=0.02)


def test_a_short_record_comes_back_unchanged():
    t = np.linspace(0.1, 10.0, 50)
    y = np.sqrt(t)
    b = bin_record(t, y, ramp_time=1.0)
    assert b.count.size == t.size and np.all(b.count == 1)
    np.testing.assert_array_equal(b.time, t)


def test_compress_choices():
    assert bins_for("auto", AUTO_MIN_SAMPLES) == 0
    assert bins_for("auto", AUTO_MIN_SAMPLES + 1) == DEFAULT_BINS
    assert bins_for(True, 10) == DEFAULT_BINS and bins_for(False, 10**7) == 0 and bins_for(None, 10**7) == 0
    assert bins_for(500, 10) == 500 and bins_for(0, 10**7) == 0
    for bad in ("yes", 1, -3, 2.5):
        with pytest.raises(ValueError, match="compress"):
            bins_for(bad, 10)


def _record(n: int, seed: int | None = 5):
    from tissuemech.reduced import spheroid

    t = np.arange(1, n + 1) * (200.0 / n)
    y = np.asarray(
        spheroid.nominal_stress(
            t, radius=500e-6, C=150.0, alpha=0.2, branches=[(0.4, 20.0)], displacement=200e-6, ramp_time=2.0
        )
    )
    if seed is None:  # the noise-free curve
        return t, y
    return t, y + 0.01 * y.max() * np.random.default_rng(seed).standard_normal(n)


@pytest.mark.slow
def test_binned_fit_matches_the_full_fit():
    """2e4 samples in ~1500 bins: the estimates move by a small fraction of the interval, the 95 % widths agree
    within 5 %, the noise estimate within 1 %; the result says how many bins were fitted."""
    t, y = _record(20_000)
    rec = [(t, y, 200e-6)]
    full = fit.relaxation(rec, radius=500e-6, ramp_time=2.0, compress=False)
    binned = fit.relaxation(rec, radius=500e-6, ramp_time=2.0, compress=True)
    assert full.bins == (0,) and 100 < binned.bins[0] < 2000
    assert binned.dof == full.dof  # degrees of freedom of the samples, not of the bins
    assert binned.noise[0] == pytest.approx(full.noise[0], rel=0.01)
    assert binned.residual == pytest.approx(full.residual, rel=0.01)
    for n in full.names:
        lo, hi = full.intervals[n]
        blo, bhi = binned.intervals[n]
        assert abs(binned.params[n] - full.params[n]) < 0.1 * (hi - lo), n
        assert (bhi - blo) == pytest.approx(hi - lo, rel=0.05), n
    assert "bin means" in binned.summary()


def test_correlated_noise_gets_longer_bins():
    """AR(1) noise of lag-1 correlation 0.9: with ``min_count=min_samples(...)`` bins hold at least ~2 integrated
    correlation times (38 samples), so bin means are nearly independent; white noise keeps single-sample bins where
    the log-time bins are narrow."""
    from scipy.signal import lfilter

    from tissuemech.compare.fit.compress import min_samples, noise_correlation

    rng = np.random.default_rng(0)
    t = np.linspace(0.002, 200.0, 100_000)
    signal = 75.0 * np.minimum(t / 2.0, 1.0) ** 1.5
    white = signal + 0.75 * rng.standard_normal(t.size)
    ar = signal + 0.75 * lfilter([np.sqrt(1 - 0.81)], [1.0, -0.9], rng.standard_normal(t.size))
    assert noise_correlation(white) < 0.05 and min_samples(white) == 1
    assert noise_correlation(ar) == pytest.approx(0.9, abs=0.02)
    b = bin_record(t, ar, ramp_time=2.0, min_count=min_samples(ar))
    assert b.count.min() >= min_samples(ar) >= 30 and b.count.sum() == t.size
    assert bin_record(t, white, ramp_time=2.0, min_count=min_samples(white)).count.min() == 1


def _ar1_noise(n: int, rho: float, seed: int) -> np.ndarray:
    from scipy.signal import lfilter

    e = np.random.default_rng(seed).standard_normal(n)
    return lfilter([np.sqrt(1 - rho**2)], [1.0, -rho], e)


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.9])
def test_bin_means_covariance_is_the_samples_ar1_covariance(rho):
    """The bin means' covariance under AR(1) noise (closed form, summed over neighbouring bins until rho^gap
    underflows) equals A R A' with R_ik = rho^|i - k| the samples' correlation and A the averaging matrix."""
    from tissuemech.compare.fit.compress import ar1_mean_covariance

    rng = np.random.default_rng(2)
    count = rng.integers(1, 40, size=60).astype(float)
    n = int(count.sum())
    k = np.arange(n)
    R = rho ** np.abs(k[:, None] - k[None, :])
    A = np.zeros((count.size, n))
    ends = np.cumsum(count).astype(int)
    for b, (lo, hi) in enumerate(zip(ends - count.astype(int), ends)):
        A[b, lo:hi] = 1.0 / (hi - lo)
    K = A @ R @ A.T
    X = rng.standard_normal((count.size, 3))
    M, k_diag = ar1_mean_covariance(count, rho, X)
    np.testing.assert_allclose(k_diag, np.diag(K), rtol=1e-12)
    np.testing.assert_allclose(M, X.T @ K @ X, rtol=1e-10, atol=1e-12 * float(np.abs(M).max()))


def test_sample_correlation_from_the_bins_is_the_samples():
    """The samples' residual lag-1 correlation and mean square, from the bins' sums and a model linear in each bin,
    are those computed sample by sample (to round-off), for any bin offsets and slopes."""
    from tissuemech.compare.fit.compress import sample_ar1

    t = np.linspace(0.01, 20.0, 5000)
    y = np.sin(t) + 0.1 * _ar1_noise(t.size, 0.8, 4)
    b = bin_record(t, y, ramp_time=2.0, bins=120)
    rng = np.random.default_rng(5)
    offset = 0.01 * rng.standard_normal(b.count.size)
    slope = 0.1 * rng.standard_normal(b.count.size)
    c = b.count.astype(int)
    model = np.repeat(b.stress - offset, c) + np.repeat(slope, c) * (t - np.repeat(b.time, c))
    r = y - model
    rho, s2 = sample_ar1(b, offset, slope)
    assert rho == pytest.approx(float(r[1:] @ r[:-1]) / float(r @ r), rel=1e-10)
    assert s2 == pytest.approx(float(r @ r) / t.size, rel=1e-10)


@pytest.mark.slow
def test_binned_fit_under_ar1_noise_matches_the_full_fit():
    """AR(1) noise of lag-1 correlation 0.9 on 2e4 samples: the binned fit's estimates are the full fit's (every
    ramp sample its own bin, no bin-size floor), the samples' correlation is found from the bins' sums, and the 95 %
    widths of beta and tau agree within 5 %. C and alpha rest on the 2 s ramp, where the full fit's HAC is itself an
    estimate from few samples: over noise realisations (5e4 samples, seeds 1-4) the ratio binned / full was
    0.94-1.23 while the binned widths stayed within 4 % of the exact AR(1) sandwich at the truth."""
    t, y0 = _record(20_000, seed=None)
    y = y0 + 0.01 * float(y0.max()) * _ar1_noise(t.size, 0.9, 7)
    rec = [(t, y, 200e-6)]
    full = fit.relaxation(rec, radius=500e-6, ramp_time=2.0, compress=False)
    binned = fit.relaxation(rec, radius=500e-6, ramp_time=2.0, compress=True)
    assert binned.correlation[0] == pytest.approx(full.correlation[0], abs=0.01)
    for n in full.names:
        lo, hi = full.intervals[n]
        blo, bhi = binned.intervals[n]
        assert abs(binned.params[n] - full.params[n]) < 0.02 * (hi - lo), n
        ratio = (bhi - blo) / (hi - lo)
        assert 0.95 < ratio < 1.05 if n in ("beta", "tau") else 0.75 < ratio < 1.35, (n, ratio)
