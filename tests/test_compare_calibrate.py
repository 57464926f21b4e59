"""compare.calibrate: tabulation machinery (batch, interpolation, file format) on a fake static FE curve.

The fake is the Hertz law with a Fung factor, F = C a0^2 (32/3) x^1.5 exp(alpha x), r_mid = a0 (1 + x/2),
sampled on an irregular approach grid, so the table must reproduce it to interpolation accuracy.
"""

from __future__ import annotations

import numpy as np
import pytest

from tissuemech.compare import calibrate


def fake_curve(*, alpha, x_max, mesh="default"):
    a0, C = 500e-6, 200.0
    x = np.sort(np.r_[np.geomspace(1e-4, x_max, 300), x_max])
    return {
        "approach": 2 * a0 * x,
        "force": C * a0**2 * (32 / 3) * x**1.5 * np.exp(alpha * x),
        "midplane_radius": a0 * (1 + x / 2),
        "radius": a0,
        "C": C,
    }


def test_tabulate_reproduces_curve_and_file_roundtrip(tmp_path):
    curves = calibrate.tabulate(
        alphas=(0.0, 0.5, 1.0), n_x=16, x_max=0.3, executor="serial", store=str(tmp_path / "s"), curve=fake_curve
    )
    x = curves.x
    assert x[0] == 0.0 and x[-1] == pytest.approx(0.3)
    exact = calibrate.hertz_f(x)[None, :] * np.exp(curves.alpha[:, None] * x[None, :])
    assert np.allclose(curves.f, exact, rtol=2e-3, atol=1e-6)
    assert np.allclose(curves.g, 1 + x / 2, rtol=1e-12)
    out = tmp_path / "master.npz"
    calibrate.write(out, curves, {"mesh": "fake"})
    back, meta = calibrate.load(out)
    assert meta == {"mesh": "fake"} and np.array_equal(back.f, curves.f)
    with np.load(out) as z:
        r = z["f_over_hertz"]
    assert np.allclose(r[:, 1:], np.exp(curves.alpha[:, None] * x[None, 1:]), rtol=2e-3)
    assert np.all(r[:, 0] == 1.0)  # Hertz limit at x -> 0
    # the grid: fine steps to x_small, then the main run's states
    assert np.allclose(x[:6], [0, 0.0025, 0.005, 0.0075, 0.01, 0.02])


def test_sqrt_basis_contains_the_small_x_law():
    """h = 1 + c1 sqrt(x) + c2 x is represented exactly by the sqrt(x) basis (an x ln x basis cannot)."""
    x = calibrate.table_grid(19, 0.36)
    h = 1 + 0.3 * np.sqrt(x) + 0.5 * x
    c = calibrate.MasterCurves(x, np.array([0.0]), (calibrate.hertz_f(x) * h)[None], (1 + x / 2)[None])
    sm, change = calibrate.smooth(c, degree=4)
    assert change < 1e-12 and np.allclose(sm.f, c.f, rtol=1e-12, atol=1e-15)


def _short_curve(*, alpha, x_max, mesh="default"):
    d = fake_curve(alpha=alpha, x_max=x_max / 2)
    return d


def test_short_run_and_bad_input_raise():
    with pytest.raises(RuntimeError, match="stopped at"):
        calibrate.tabulate(alphas=(0.2,), executor="serial", curve=_short_curve)
    with pytest.raises(ValueError, match="x_max"):
        calibrate.tabulate(x_max=0.7, executor="serial", curve=fake_curve)
