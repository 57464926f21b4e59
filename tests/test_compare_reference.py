"""compare.reference: the independent references against quadrature and known limits."""

import numpy as np
import pytest

from tissuemech.compare import reference


def test_exact_lumped_force_matches_quadrature_and_limits():
    from scipy.integrate import quad

    beta, tau, tr = 1.2, 0.05, 0.2
    t = np.array([0.03, 0.1, 0.2, 0.5])
    F = reference.exact_lumped_force(t, beta=beta, tau=tau, ramp_time=tr)
    for ti, Fi in zip(t, F):
        tt = min(ti, tr)
        q = beta * quad(lambda s: np.exp(-(tt - s) / tau) * 1.5 * np.sqrt(s) / tr**1.5, 0, tt, epsrel=1e-12)[0]
        q *= np.exp(-max(ti - tr, 0) / tau)
        assert Fi == pytest.approx(min(ti / tr, 1) ** 1.5 + q, rel=1e-10)
    # glassy limit (tau >> ramp): F(t_r) = 1 + beta; relaxed (tau << ramp): F(t_r) = 1
    assert reference.exact_lumped_force([tr], beta=beta, tau=1e9, ramp_time=tr)[0] == pytest.approx(1 + beta, rel=1e-8)
    assert reference.exact_lumped_force([tr], beta=beta, tau=1e-9, ramp_time=tr)[0] == pytest.approx(1.0, rel=1e-6)


def test_shell_pressure_neo_hookean_closed_form_and_inverse():
    A, B, C = 50e-6, 75e-6, 200.0
    for la in (1.2, 1.6, 2.5):
        lb = (1 + (la**3 - 1) * (A / B) ** 3) ** (1 / 3)
        closed = 4 * C * (1 / lb + 1 / (4 * lb**4) - 1 / la - 1 / (4 * la**4))
        assert reference.shell_pressure(la, alpha=0.0) == pytest.approx(closed, rel=1e-12)
    p = reference.shell_pressure(2.0, alpha=0.2)
    assert reference.shell_inner_stretch(p, alpha=0.2) == pytest.approx(2.0, rel=1e-12)
    assert reference.shell_inner_stretch(0.0, alpha=0.2) == 1.0


def test_hertz_force_matches_fem_and_reduced_forms():
    from tissuemech.fem.spheroid import hertz_force

    d = np.array([1e-6, 1e-5, 5e-5])
    np.testing.assert_allclose(
        reference.hertz_force(d, radius=500e-6, C=150.0), hertz_force(d, 500e-6, 150.0), rtol=1e-13
    )
