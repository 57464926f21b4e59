"""compare.fit.diagnostics: residual diagnostics (lag-1 autocorrelation, runs test) and the "robust" error model
of the intervals (a smooth discrepancy of estimated size plus an autocorrelation-consistent noise term), checked
with the fake model of tests/fakes.py on dense records: white noise keeps its intervals, correlated noise and a
smooth misfit widen them to where they hold the truth."""

from __future__ import annotations

import math

import numpy as np
import pytest
from fakes import fake_nominal_stress

from tissuemech.compare import fit
from tissuemech.compare.fit import diagnostics

A0, TR = 500e-6, 0.2
TRUE = dict(C=150.0, alpha=0.2, beta=0.4, tau=200.0)
DENSE = np.linspace(0.75, 1500.0, 2000)


def _clean(times=DENSE, levels=(50e-6, 200e-6)):
    out = []
    for d in levels:
        y = fake_nominal_stress(
            times, radius=A0, C=150.0, alpha=0.2, branches=[(0.4, 200.0)], displacement=d, ramp_time=TR
        )
        out.append((times, np.asarray(y), d))
    return out


def _ar1(n, rho, rng):
    e = rng.standard_normal(n)
    x = np.empty(n)
    x[0] = e[0]
    for k in range(1, n):
        x[k] = rho * x[k - 1] + math.sqrt(1 - rho * rho) * e[k]
    return x


def _fit(recs, **kw):
    return fit.relaxation(recs, radius=A0, ramp_time=TR, model=fake_nominal_stress, model_error=0.0, **kw)


def _inside(res, name, ivals=None):
    lo, hi = (ivals or res.intervals)[name]
    return lo <= TRUE[name] <= hi


def test_runs_test_and_lag1_by_hand():
    d = diagnostics.residual_diagnostics(np.array([1.0, 2.0, -1.0, -0.5, 3.0]))
    # signs + + - - +: 3 runs; n+ = 3, n- = 2: expected 2 n+ n- / n + 1 = 3.4, variance (mu-1)(mu-2)/(n-1) = 0.84
    assert d.runs == 3 and d.runs_expected == pytest.approx(3.4)
    assert d.runs_z == pytest.approx((3 - 3.4) / math.sqrt(2.4 * 1.4 / 4))
    x = np.array([1.0, -1.0, 1.0, -1.0])
    assert diagnostics.lag1(x) == pytest.approx(-3 / 4)


def test_white_and_correlated_residuals_are_told_apart():
    rng = np.random.default_rng(0)
    white = diagnostics.residual_diagnostics(rng.standard_normal(2000))
    assert abs(white.r1) < 4 / math.sqrt(2000) and white.runs_p > 1e-3 and not white.correlated
    red = diagnostics.residual_diagnostics(_ar1(2000, 0.9, rng))
    assert red.r1 == pytest.approx(0.9, abs=0.05) and red.runs_z < -10 and red.correlated


def test_discrepancy_basis_is_orthonormal_over_log_time():
    t = np.exp(np.linspace(np.log(1.0), np.log(1000.0), 4001)) - TR
    B = diagnostics.discrepancy_basis(t, TR)
    assert B.shape == (4001, diagnostics.DISCREPANCY_TERMS)
    assert np.allclose(B.T @ B / 4001, np.eye(B.shape[1]), atol=5e-3)  # the trapezoid-free sum's end effects


def test_white_noise_keeps_its_intervals_and_reports_white_residuals():
    rng = np.random.default_rng(1)
    recs = [(t, y + 0.01 * y.max() * rng.standard_normal(y.size), d) for t, y, d in _clean()]
    res = _fit(recs)
    assert res.errors == "robust" and len(res.diagnostics) == 2
    assert all(not d.correlated for d in res.diagnostics)
    for n in TRUE:
        lo, hi = res.intervals[n]
        wlo, whi = res.wald_by_error_model["white"][n]
        assert _inside(res, n)
        assert 0.999 <= (math.log(hi) - math.log(lo)) / (math.log(whi) - math.log(wlo)) < 2.0, n
    text = res.summary()
    assert "residuals of record 1: lag-1 autocorrelation" in text and "not white noise" not in text
    d = res.to_dict()
    assert d["errors"] == "robust" and len(d["residual_diagnostics"]) == 2
    assert set(d["covariance_log_by_error_model"]) == set(diagnostics.ERROR_MODELS)


def test_correlated_noise_widens_the_intervals_to_hold_the_truth():
    """AR(1) noise, lag-1 correlation 0.9, 2000 samples: the white-noise intervals are ~sqrt(19) too narrow (the
    long-run variance of AR(1) is (1 + rho) / (1 - rho) = 19 times its variance); the robust ones are that much
    wider and flag the residuals."""
    rng = np.random.default_rng(2)
    recs = [(t, y + 0.01 * y.max() * _ar1(y.size, 0.9, rng), d) for t, y, d in _clean()]
    res = _fit(recs)
    assert all(d.correlated and d.r1 > 0.8 for d in res.diagnostics)
    assert "not white noise" in res.summary()
    for n in TRUE:
        lo, hi = res.intervals[n]
        wlo, whi = res.wald_by_error_model["white"][n]
        ratio = (math.log(hi) - math.log(lo)) / (math.log(whi) - math.log(wlo))
        assert 2.5 < ratio < 8.0, (n, ratio)
    assert sum(_inside(res, n) for n in TRUE) >= 3  # one draw: the coverage study counts the rest


def test_smooth_misfit_is_estimated_and_covered():
    """A 0.5 % smooth misfit (a log-time shape the parameters cannot absorb) on 0.2 % noise: the white intervals
    miss the truth, the robust ones hold it and say how large the misfit is."""
    rng = np.random.default_rng(3)
    recs = []
    for t, y, d in _clean():
        x = np.log(t + TR)
        u = 2 * (x - x.min()) / np.ptp(x) - 1
        shape = 0.005 * math.sqrt(2) * np.sin(2.5 * u + rng.uniform(0, 2 * math.pi))
        recs.append((t, y * (1 + shape) + 0.002 * y.max() * rng.standard_normal(y.size), d))
    res = _fit(recs)
    assert 0.001 < res.discrepancy < 0.02
    assert not all(_inside(res, n, res.wald_by_error_model["white"]) for n in TRUE)
    assert all(_inside(res, n) for n in TRUE), res.summary()
    assert "a smooth model misfit (estimated" in res.summary()


def test_error_model_argument_is_checked():
    with pytest.raises(ValueError, match="errors must be one of 'robust', 'white'"):
        _fit(_clean(), errors="bogus")
    rng = np.random.default_rng(4)
    recs = [(t, y + 0.01 * y.max() * rng.standard_normal(y.size), d) for t, y, d in _clean(DENSE[::10])]
    res = _fit(recs, errors="white")
    assert res.errors == "white"
    assert np.allclose(res.covariance, res.covariances["white"])


def test_a_declared_misfit_bounds_the_discrepancy_from_below():
    """A misfit the parameters absorb does not show in the residuals: misfit= states it (relative RMS per shape
    term); the intervals widen accordingly, and a negative value is refused."""
    rng = np.random.default_rng(5)
    recs = [(t, y + 0.01 * y.max() * rng.standard_normal(y.size), d) for t, y, d in _clean(DENSE[::10])]
    r0 = _fit(recs)
    r1 = _fit(recs, misfit=0.01)
    assert r1.discrepancy == pytest.approx(max(0.01, r0.discrepancy))
    w = lambda r, n: math.log(r.intervals[n][1] / r.intervals[n][0])
    assert w(r1, "C") > 3 * w(r0, "C")
    with pytest.raises(ValueError, match="misfit"):
        _fit(recs, misfit=-0.1)


def test_orthonormal_basis_reveals_the_rank_and_gives_the_hat_matrix_leverages():
    """Columns with exact dependences (as the fit's d model / d ln C and the discrepancy's constant term, the model
    being proportional to C) and one nearly dependent one (1e-5 apart): the basis has the rank's columns, is
    orthonormal to round-off, spans the columns, and its squared rows are the hat matrix's diagonal from an SVD cut
    at the rank (sum = rank); a plain QR's leverages sum to the column count instead."""
    rng = np.random.default_rng(3)
    n = 500
    A = rng.standard_normal((n, 4)) * np.exp(rng.standard_normal(n))[:, None]
    X = np.column_stack([A, 3.0 * A[:, 0], A[:, 1] - 2.0 * A[:, 2], A[:, 3] + 1e-5 * rng.standard_normal(n)])
    Q = diagnostics.orthonormal_basis(X)
    assert Q.shape == (n, 5)
    np.testing.assert_allclose(Q.T @ Q, np.eye(5), atol=1e-12)
    np.testing.assert_allclose(Q @ (Q.T @ X), X, atol=1e-10 * float(np.abs(X).max()))
    U, s, _ = np.linalg.svd(X, full_matrices=False)
    hat = np.sum(U[:, s > 1e-9 * s[0]] ** 2, axis=1)
    np.testing.assert_allclose(np.sum(Q**2, axis=1), hat, atol=1e-10)
    assert np.sum(np.linalg.qr(X)[0] ** 2) == pytest.approx(7.0)  # what the leverages summed to before
