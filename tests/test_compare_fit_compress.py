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
    within 1 % (the error model runs on the samples at the binned estimate), the noise estimate within 1 %; the
    result says how many bins were fitted."""
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
        assert (bhi - blo) == pytest.approx(hi - lo, rel=0.01), n
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


@pytest.mark.slow
def test_binned_fit_under_ar1_noise_matches_the_full_fit():
    """AR(1) noise of lag-1 correlation 0.9 on 3e4 samples: the binned fit's estimates are the full fit's, and its
    error model runs on every sample at its estimate, so the correlation it finds and the 95 % widths of all four
    parameters are the full fit's (C and alpha rest on the 2 s ramp, where the HAC is an estimate from few
    samples: an error model on the bin means missed the full fit's widths there by up to 23 %)."""
    t, y0 = _record(30_000, seed=None)
    y = y0 + 0.01 * float(y0.max()) * _ar1_noise(t.size, 0.9, 7)
    rec = [(t, y, 200e-6)]
    full = fit.relaxation(rec, radius=500e-6, ramp_time=2.0, compress=False)
    binned = fit.relaxation(rec, radius=500e-6, ramp_time=2.0, compress=True)
    assert 100 < binned.bins[0] < 2000
    assert binned.correlation[0] == pytest.approx(full.correlation[0], abs=0.005)
    for n in full.names:
        lo, hi = full.intervals[n]
        blo, bhi = binned.intervals[n]
        assert abs(binned.params[n] - full.params[n]) < 0.02 * (hi - lo), n
        assert (bhi - blo) == pytest.approx(hi - lo, rel=0.01), n


def test_sample_evaluator_is_the_residuals_model_and_jacobian_in_any_chunks():
    """The error model's pass over every sample (chunks of one compiled shape, the last one padded) gives the
    model and its Jacobian of the fit's own residual, to round-off, for two records of different lengths."""
    import jax.numpy as jnp

    from tissuemech.compare.fit.model import default_model, residual_builder, sample_evaluator
    from tissuemech.compare.fit.records import Record

    t1, y1 = _record(2_300)
    t2, y2 = _record(900, seed=6)
    recs = [Record(t1, y1, 200e-6), Record(t2, 0.5 * y2, 150e-6)]
    theta = np.log([140.0, 0.3, 0.5, 15.0])
    res, jac, scale = residual_builder(recs, 500e-6, 2.0, 1, "fem", default_model())
    model_ref = np.asarray(res(jnp.asarray(theta))) * scale + np.concatenate([y1, 0.5 * y2])
    jac_ref = np.asarray(jac(jnp.asarray(theta))) * scale
    model, J = sample_evaluator(recs, 500e-6, 2.0, 1, "fem", default_model(), chunk=700)(theta)
    assert model.shape == (3_200,) and J.shape == (3_200, 4)
    np.testing.assert_allclose(model, model_ref, rtol=1e-12, atol=1e-12 * float(np.abs(model_ref).max()))
    np.testing.assert_allclose(J, jac_ref, rtol=1e-10, atol=1e-10 * float(np.abs(jac_ref).max()))
