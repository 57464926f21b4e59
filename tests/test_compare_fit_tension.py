"""Fitting the surface tension gamma from relaxation records (tissuemech.compare.fit.tension)."""

import numpy as np
import pytest

from tissuemech.compare.fit.tension import tension_relaxation
from tissuemech.reduced import spheroid as sph

A0, C, ALPHA = 175e-6, 170.0, 0.5  # S180: radius (m), C (Pa, E ~ 1 kPa)
GAMMA = 0.3 * C * A0  # N/m (about 9 mN/m: elastocapillary number 0.3)
BRANCH = (2.0, 30.0)  # beta, tau (s)
TR = 1.0  # ramp (s)
LEVELS = (0.1, 0.2, 0.3)  # x = delta / (2 a0)


def records(seed: int, noise: float = 0.01):
    t = np.r_[np.linspace(0.05, TR, 10), np.geomspace(1.2, 300.0, 50)]
    rng = np.random.default_rng(seed)
    out = []
    for x in LEVELS:
        d = 2 * A0 * x
        s = np.asarray(sph.nominal_stress(t, radius=A0, C=C, alpha=ALPHA, branches=[BRANCH], displacement=d,
                                          ramp_time=TR, surface_tension=GAMMA))  # fmt: skip
        out.append((t, s + noise * s.max() * rng.standard_normal(t.size), d))
    return out


def test_noise_free_records_return_the_truth():
    fit = tension_relaxation(records(0, noise=0.0), radius=A0, ramp_time=TR, alpha=ALPHA)
    assert fit.success
    assert abs(fit.params["gamma"] / GAMMA - 1) < 1e-5
    assert abs(fit.params["C"] / C - 1) < 1e-5


def test_one_percent_noise_interval_covers_gamma():
    fit = tension_relaxation(records(1), radius=A0, ramp_time=TR, alpha=ALPHA)
    lo, hi = fit.intervals["gamma"]
    assert lo < GAMMA < hi
    assert hi / lo < 1.5  # informative: gamma is separated from C by the three levels
    lo, hi = fit.intervals["C"]
    assert lo < C < hi


def test_too_few_points_raise():
    t = np.array([0.5, 1.0, 2.0])
    with pytest.raises(ValueError):
        tension_relaxation([(t, np.array([1.0, 2.0, 1.5]), 1e-5)], radius=A0, ramp_time=TR)


@pytest.mark.slow
def test_coverage_of_gamma_over_noise_draws():
    """20 draws of 1 % noise, alpha fitted too: the 95 % interval of gamma covers the truth in >= 17 of them."""
    hits = 0
    for seed in range(20):
        fit = tension_relaxation(records(100 + seed), radius=A0, ramp_time=TR)
        lo, hi = fit.intervals["gamma"]
        hits += lo < GAMMA < hi
    assert hits >= 17
