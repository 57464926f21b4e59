"""The shared Fung law: exact neo-Hookean limit, derivatives, stresses, validation."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tissuemech.reduced  # noqa: F401  (enables x64)
from tissuemech.reduced import material as m


def test_neo_hookean_limit_is_exact():
    x = np.linspace(3.0, 12.0, 7)
    assert np.allclose(m.fung_energy(x, 200.0, 0.0), 200.0 * (x - 3.0), rtol=0, atol=1e-12)
    # alpha = 1e-5 differs from neo-Hookean only by the O(alpha) term C alpha x^2 / 2
    w = m.fung_energy(x, 200.0, 1e-5)
    nh = 200.0 * (x - 3.0)
    assert np.allclose(w - nh, 200.0 * 1e-5 * (x - 3.0) ** 2 / 2, rtol=1e-4, atol=1e-14)


@pytest.mark.parametrize("alpha", [0.0, 1e-7, 1e-3, 0.2, 1.0])
def test_energy_matches_direct_formula_and_series_switch(alpha):
    x = np.array([3.0 + 1e-6, 3.001, 3.3, 4.0, 9.0])
    w = m.fung_energy(x, 150.0, alpha)
    ref = 150.0 * (x - 3.0) if alpha == 0 else 150.0 / alpha * np.expm1(alpha * (x - 3.0))
    assert np.allclose(w, ref, rtol=1e-13, atol=0)


@pytest.mark.parametrize("alpha", [0.0, 1e-5, 0.3])
def test_derivatives_match_finite_differences(alpha):
    x, h = 4.2, 1e-5
    fd1 = (m.fung_energy(x + h, 200.0, alpha) - m.fung_energy(x - h, 200.0, alpha)) / (2 * h)
    assert np.isclose(m.dW_dI1(x, 200.0, alpha), fd1, rtol=1e-8)
    fd2 = (m.dW_dI1(x + h, 200.0, alpha) - m.dW_dI1(x - h, 200.0, alpha)) / (2 * h)
    assert np.isclose(m.d2W_dI1(x, 200.0, alpha), fd2, rtol=1e-6, atol=1e-9)


def test_jax_and_numpy_agree_and_grad_in_alpha_is_smooth_through_zero():
    x = 3.5
    assert float(m.fung_energy(jnp.asarray(x), 200.0, 0.2)) == pytest.approx(
        m.fung_energy(np.asarray(x), 200.0, 0.2), rel=1e-15
    )
    g = jax.grad(lambda a: m.fung_energy(x, 200.0, a))
    # dW/dalpha at alpha = 0 is C (x-3)^2 / 2
    assert float(g(0.0)) == pytest.approx(200.0 * 0.25 / 2, rel=1e-12)
    assert float(g(1e-9)) == pytest.approx(float(g(0.0)), rel=1e-6)


def test_principal_cauchy_stress_uniaxial_incompressible_limit():
    # Isochoric uniaxial stretch: sigma_1 - sigma_2 = 2 W'(I1) (l^2 - 1/l)
    lam = 1.7
    s1, s2, s3 = m.principal_cauchy_stress(lam, lam**-0.5, lam**-0.5, C=200.0, alpha=0.2, kappa=1e9)
    I1 = lam**2 + 2 / lam
    assert s2 == pytest.approx(s3)
    assert s1 - s2 == pytest.approx(
        float(m.incompressible_stress_difference(lam, lam**-0.5, I1, 200.0, 0.2)), rel=1e-12
    )
    # pure volume change gives pressure kappa (J - 1) and no deviator
    s = m.principal_cauchy_stress(1.01, 1.01, 1.01, C=200.0, alpha=0.2, kappa=1e6)
    assert np.allclose(s, 1e6 * (1.01**3 - 1), rtol=1e-12)


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda: m.validate_material(-1.0, 0.2), "C"),
        (lambda: m.validate_material(0.0, 0.2), "positive"),
        (lambda: m.validate_material(200.0, -0.1), "alpha"),
        (lambda: m.validate_material(200.0, np.nan), "alpha"),
        (lambda: m.validate_material(200.0, 0.1, kappa=-5), "kappa"),
        (lambda: m.validate_radii(-1e-6, 75e-6), "inner_radius"),
        (lambda: m.validate_radii(75e-6, 50e-6), "smaller"),
        (lambda: m.validate_branches([(0.4, 0.0)]), "tau"),
        (lambda: m.validate_branches([(-0.4, 200.0)]), "beta"),
        (lambda: m.validate_branches([0.4]), "pair"),
    ],
)
def test_bad_input_raises_plain_value_error(call, words):
    with pytest.raises(ValueError, match=words):
        call()


def test_validation_is_skipped_under_jit():
    @jax.jit
    def f(c):
        m.validate_material(c, 0.1)
        return m.fung_energy(4.0, c, 0.1)

    # the value of the law (not just a finite number), and a bad C under jit is computed, not raised
    assert float(f(200.0)) == pytest.approx(200.0 / 0.1 * np.expm1(0.1), rel=1e-14)
    assert float(f(-1.0)) == pytest.approx(-1.0 / 0.1 * np.expm1(0.1), rel=1e-14)
