"""fem.viscoelastic: the exact Maxwell recursion and its algorithmic stress."""

import numpy as np
import pytest

from tissuemech.fem import viscoelastic as ve


def _conv_exact(t, beta, tau, rate):
    """Q(t) for S_iso(t) = rate * t from rest: beta rate tau (1 - e^{-t/tau})."""
    return beta * rate * tau * (1 - np.exp(-t / tau))


def test_maxwell_update_exact_for_linear_history_any_step():
    beta, tau, rate = np.array([0.4, 1.2]), np.array([2.0, 50.0]), 3.0
    st = ve.initial_state(2, (1, 1, 5))
    t = 0.0
    for dt in [0.1, 3.0, 40.0, 0.5, 200.0]:
        t += dt
        S = np.full((1, 1, 5), rate * t)
        st = ve.update(st, beta, tau, dt, S)
    for m in range(2):
        assert np.allclose(st.Q[m], _conv_exact(t, beta[m], tau[m], rate), rtol=1e-13)


def test_maxwell_hold_decays_exactly_and_algorithmic_stress_matches():
    beta, tau = np.array([0.7]), np.array([10.0])
    S = np.full((2, 3, 5), 2.0)
    st = ve.MaxwellState(np.full((1, 2, 3, 5), 0.5), S)
    dt = 37.0
    iso_scale, extra = ve.algorithmic(st, beta, tau, dt)
    new = ve.update(st, beta, tau, dt, S)  # S_iso constant over the hold step
    assert np.allclose(new.Q, 0.5 * np.exp(-dt / 10.0), rtol=1e-14)
    # S_iso + Q^{n+1} == iso_scale * S^{n+1} + extra for any S^{n+1}
    S1 = S * 1.3
    new1 = ve.update(st, beta, tau, dt, S1)
    assert np.allclose(S1 + new1.Q[0], iso_scale * S1 + extra, rtol=1e-14)
    assert ve.algorithmic(ve.initial_state(0, (2, 3, 5)), [], [], 1.0) == (1.0, None)
    _, g = ve.coefficients(np.array([1.0]), np.array([1.0]), 1e-12)
    assert abs(g[0] - 1.0) < 1e-12
    with pytest.raises(ValueError, match="time step must be positive"):
        ve.coefficients(np.array([1.0]), np.array([1.0]), 0.0)


# ---- time stepping -----------------------------------------------------------------------------
