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


# ---- viscoelastic liquids: branches by their moduli, C_inf = 0 -------------------------------------------------
def test_relative_branches_of_a_solid_and_of_a_liquid():
    """A solid keeps the seed's scaling (C_ref = C, beta_m = C_m / C); a liquid is scaled by sum_m C_m, weight 0."""
    rb = ve.relative_branches(100.0, [(0.4, 20.0), ve.Branch(30.0, 10.0)])
    assert rb.reference == 100.0 and rb.long_time == 1.0
    np.testing.assert_array_equal(rb.beta, [0.4, 0.3])
    np.testing.assert_array_equal(rb.tau, [20.0, 10.0])
    liq = ve.relative_branches(0.0, [ve.Branch(150.0, 1500.0), ve.Branch(50.0, 10.0)])
    assert liq.reference == 200.0 and liq.long_time == 0.0
    np.testing.assert_allclose(liq.beta, [0.75, 0.25], rtol=1e-15)


@pytest.mark.parametrize(
    "C, branches, match",
    [
        (0.0, [], "needs at least one Maxwell branch"),
        (0.0, [(0.5, 10.0)], "energy factor"),
        (-1.0, [ve.Branch(1.0, 1.0)], "C_inf"),
        (0.0, [ve.Branch(-1.0, 1.0)], "modulus"),
        (0.0, [ve.Branch(1.0, 0.0)], "tau"),
    ],
)
def test_relative_branches_bad_input(C, branches, match):
    with pytest.raises(ValueError, match=match):
        ve.relative_branches(C, branches)


def test_algorithmic_stress_of_a_liquid_has_no_long_time_term():
    """iso_scale = long_time + sum beta_m g_m: a liquid's (weight 0) tends to 0 over a long step (nothing holds a
    shear), a solid's to 1."""
    st = ve.initial_state(1, (2, 3, 5))
    beta, tau = np.array([1.0]), np.array([2.0])
    s_liq, _ = ve.algorithmic(st, beta, tau, 1e6, long_time=0.0)
    s_sol, _ = ve.algorithmic(st, beta, tau, 1e6)
    assert s_liq == pytest.approx(2e-6, rel=1e-12) and s_sol == pytest.approx(1 + 2e-6, rel=1e-12)
    s0, _ = ve.algorithmic(st, beta, tau, 1e-12, long_time=0.0)
    assert s0 == pytest.approx(1.0, rel=1e-12)  # instantaneously the liquid is the solid of modulus sum C_m


A0_S180 = 175e-6  # m


def _held(**kw):
    from tissuemech.fem import spheroid as sph

    args = dict(radius=A0_S180, alpha=0.2, displacement=0.2 * A0_S180, ramp_time=1.0, mesh=0, n_hold=20)
    return sph.compress(**{**args, **kw})


def test_moduli_and_factors_give_the_same_solid():
    """Branch(modulus = beta C, tau) and (beta, tau) are the same material (C > 0: the same scaling)."""
    a = _held(C=170.0, branches=[(0.5, 30.0)], end_time=300.0)
    b = _held(C=170.0, branches=[ve.Branch(85.0, 30.0)], end_time=300.0)
    np.testing.assert_allclose(b.force, a.force, rtol=1e-12)
    assert b.parameters["branches"] == a.parameters["branches"] == ((0.5, 30.0),)


def test_a_liquid_relaxes_completely_under_held_plates():
    """C = 0, one branch (S180: E0 = 1 kPa, tau = 3 eta / E0 = 1500 s for eta = 5e5 Pa s), no tension: at the end
    of the ramp the force is the instantaneous solid's (C = 167 Pa), then it falls as e^{-t / tau} (the approach
    held: S_iso constant) to nothing. Node-by-node contact: the fitted edge's condition N_edge / F = 0 has no
    meaning once F is round-off."""
    E0, tau = 1e3, 1500.0
    liq = _held(C=0.0, branches=[ve.Branch(E0 / 6, tau)], ramp_time=1.0, end_time=30 * tau, contact="nodal")
    sol = _held(C=E0 / 6, static=True, contact="nodal")
    k = int(np.argmin(np.abs(liq.time - 1.0)))
    # the ramp (1 s << tau) is the instantaneous solid's to ~1e-3 (the relaxation during the ramp)
    assert liq.force[k] == pytest.approx(sol.force[-1], rel=2e-3)
    decay = liq.force[k:] / liq.force[k]
    np.testing.assert_allclose(decay, np.exp(-(liq.time[k:] - liq.time[k]) / tau), rtol=2e-3, atol=1e-12)
    assert liq.force[-1] < 1e-9 * liq.force[k]
    p = liq.parameters
    assert p["C"] == 0.0 and p["reference_modulus"] == pytest.approx(E0 / 6)
    assert p["branches"] == (ve.Branch(E0 / 6, tau),)


def test_a_liquid_refuses_static_and_gradient_runs():
    from tissuemech.fem import spheroid as sph

    with pytest.raises(ValueError, match="static=True needs a long-time modulus"):
        _held(C=0.0, branches=[sph.Branch(100.0, 10.0)], static=True)
    with pytest.raises(ValueError, match="gradient=True needs a long-time modulus"):
        _held(C=0.0, branches=[sph.Branch(100.0, 10.0)], end_time=10.0, gradient=True, contact="nodal")
    with pytest.raises(ValueError, match="Branch"):
        _held(C=0.0, branches=[(0.5, 10.0)], end_time=10.0)
