"""compare.studies.stability: update-formula orders and stability, argument checks (fast parts)."""

import pytest

from tissuemech.compare.studies import stability


def test_update_formulas_orders_and_stability():
    df, bounds = stability.viscous_step_map([0.05, 0.1, 1.0, 10.0, 500.0])
    e = df.pivot(index="step [s]", columns="update", values="error")
    # backward Euler is first order in the hold step: halving h halves the error
    assert e.loc[0.1, "backward Euler"] / e.loc[0.05, "backward Euler"] == pytest.approx(2.0, rel=0.15)
    # the exact-linear update is exact in the hold: only the ramp's curvature is left, for any hold step
    assert e["exact-linear"].max() < 1e-4
    # forward Euler is unstable beyond h = 2 tau
    assert e.loc[500.0, "forward Euler"] > 1.0
    b = bounds.set_index("update")
    assert b.loc["exact-linear", "limited_by_range"]
    assert b.loc["backward Euler", "largest ok step [s]"] == 1.0


def test_bad_inputs_raise_clear_errors():
    with pytest.raises(ValueError, match="tau must be a positive"):
        stability.viscous_step_map([1.0], tau=0.0)
    with pytest.raises(ValueError, match="steps must be"):
        stability.viscous_step_map([-1.0])
    with pytest.raises(ValueError, match="below 1"):
        stability.compression_map([0.5, 1.2])
    with pytest.raises(ValueError, match="inner radius"):
        stability.limit_point_map([40.0])
