r"""Exact inflation of a thick, incompressible, hyperelastic (Fung) hollow sphere.

Reference sphere: inner radius ``A`` and outer radius ``B`` (m); Fung law with stiffness ``C`` (Pa)
and exponent ``alpha`` (dimensionless, ``alpha = 0`` is neo-Hookean), see ``reduced.material``.
Internal pressure ``p`` (Pa, a follower load), outer surface free.

Kinematics (incompressible, spherically symmetric): a material sphere of reference radius ``R``
moves to ``r`` with ``r^3 - R^3 = a^3 - A^3``; hoop stretch ``l = r/R``, radial stretch ``l^-2``;

    lambda_b^3 = 1 + (lambda_a^3 - 1) k,        k = (A/B)^3,

with the inner stretch ``lambda_a = a/A`` and the outer stretch ``lambda_b = b/B``.
Equilibrium ``d sigma_r/dr = 2 (sigma_theta - sigma_r)/r`` with
``sigma_theta - sigma_r = 2 W'(I1) (l^2 - l^-4)``, ``I1 = 2 l^2 + l^-4``, ``sigma_r(b) = 0``,
``sigma_r(a) = -p``, integrates (``dr/r = -dl / (l (l^3 - 1))``) to

    p(lambda_a) = int_{lambda_b}^{lambda_a} g(l) dl,
    g(l) = 4 W'(I1(l)) (l^3 + 1) / l^5 = 4 C exp(alpha (2 l^2 + l^-4 - 3)) (l^3 + 1) / l^5.

Numerics (everything is computed for ``p / C`` as a function of ``(lambda_a, k, alpha)``):

* ``method="quadrature"``: the substitution ``l = exp(s)`` turns the integrand into
  ``G(s) = 4 exp(alpha (2 e^{2s} + e^{-4s} - 3)) (e^{3s} + 1) e^{-4s}``, an entire function of
  ``s`` (no pole at ``l = 0`` limits the convergence), integrated by a fixed ``N``-point
  Gauss-Legendre rule on ``[log lambda_b, log lambda_a]``. The interval length is formed without
  cancellation: ``log(lambda_a / lambda_b) = log1p(e (1 - k) / (1 + e k)) / 3`` with
  ``e = lambda_a^3 - 1 = expm1(3 log lambda_a)`` and ``1 - k = (B - A)(B^2 + AB + A^2)/B^3``, so ``p``
  keeps full relative accuracy at ``lambda_a = 1 + 1e-9`` (where ``p ~ 8 C (1 - k)(lambda_a - 1)``).
* ``method="ode"``: the radial equilibrium ODE integrated through the deformed wall with diffrax
  (Dopri8, PID control, rtol = atol = 1e-13), in the variable ``s = log l`` as well:
  ``d(sigma_r/C)/ds = -G(s)`` from ``s_b = log lambda_b`` (``sigma_r = 0``) to ``s_a = log lambda_a``;
  ``p = -sigma_r(a)``. The two paths agree to ~1e-13 relative (tested to 1e-10).

Stretch domain: ``lambda_a > 0``. ``lambda_a < 1`` is deflation (negative pressure, physical down to
the collapse ``lambda_a -> 0`` where ``p -> -infinity``); the quadrature is accurate to 1e-12 relative
for ``0.5 <= lambda_a <= 5`` and ``alpha <= 0.5`` (see the tests); ``lambda_a <= 0`` or non-finite
values raise ``ValueError`` in eager calls (inside ``jit`` no check can run: results there are NaN
for ``lambda_a <= 0``).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from reduced.material import (
    dW_dI1,
    is_traced,
    validate_material,
    validate_positive,
    validate_radii,
)

__all__ = [
    "pressure",
    "pressure_derivative",
    "inner_stretch",
    "inner_stretch_solve",
    "limit_point",
    "outer_stretch",
    "profiles",
    "Profiles",
    "LimitPoint",
    "NoLimitPoint",
]

Array = Any

# ---------------------------------------------------------------------------------------------
# Fixed Gauss-Legendre rule on [-1, 1]; N chosen for 1e-12 relative accuracy (see module docstring)
# ---------------------------------------------------------------------------------------------
N_GAUSS = 20
_X, _W = np.polynomial.legendre.leggauss(N_GAUSS)


def _check_stretch(name: str, value: Any) -> None:
    """Eager check: stretch finite and > 0 (``< 1`` is deflation and allowed)."""
    if is_traced(value):
        return
    v = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be a finite number (a/A, dimensionless); got {value!r}")
    if np.any(v <= 0):
        raise ValueError(
            f"{name} must be positive (a/A > 0; values below 1 mean the cavity shrinks); "
            f"got {np.min(v):g}"
        )


def _validate(inner_radius, outer_radius, C=None, alpha=None) -> None:
    validate_radii(inner_radius, outer_radius)
    if C is not None:
        validate_material(C, alpha)


def _geometry(inner_radius, outer_radius):
    """k = (A/B)^3 and 1 - k, the latter without cancellation for thin walls."""
    A = jnp.asarray(inner_radius, dtype=jnp.float64)
    B = jnp.asarray(outer_radius, dtype=jnp.float64)
    k = (A / B) ** 3
    one_minus_k = (B - A) * (B * B + A * B + A * A) / B**3
    return k, one_minus_k


def _log_stretches(la, k, one_minus_k):
    """(log lambda_b, log(lambda_a / lambda_b)) without cancellation near lambda_a = 1."""
    sa = jnp.log(la)
    e = jnp.expm1(3.0 * sa)  # lambda_a^3 - 1
    sb = jnp.log1p(e * k) / 3.0
    width = jnp.log1p(e * one_minus_k / (1.0 + e * k)) / 3.0  # = sa - sb
    return sb, width


def _G(s, alpha):
    """Integrand in s = log l, divided by C: 4 W'(I1)/C (l^3 + 1) / l^4 (dimensionless)."""
    l2 = jnp.exp(2.0 * s)
    lm4 = jnp.exp(-4.0 * s)
    I1 = 2.0 * l2 + lm4
    return 4.0 * dW_dI1(I1, 1.0, alpha) * (l2 * jnp.exp(s) + 1.0) * lm4


def _g(l, alpha):
    """Integrand in l, divided by C: g(l)/C = 4 W'(I1)/C (l^3 + 1)/l^5 (dimensionless)."""
    return _G(jnp.log(l), alpha) / l


def _p_over_C_quad(la, k, one_minus_k, alpha):
    sb, h = _log_stretches(la, k, one_minus_k)
    x = jnp.asarray(_X)
    w = jnp.asarray(_W)
    s = sb[..., None] + 0.5 * h[..., None] * (x + 1.0)
    vals = _G(s, jnp.asarray(alpha)[..., None])
    return 0.5 * h * jnp.sum(w * vals, axis=-1)


def _p_over_C_ode(la, k, one_minus_k, alpha):
    la, k, one_minus_k, alpha = jnp.broadcast_arrays(la, k, one_minus_k, alpha)
    sb, h = _log_stretches(la, k, one_minus_k)

    def one(sb_i, h_i, alpha_i):
        import diffrax

        def rhs(t, y, args):
            return h_i * _G(sb_i + h_i * t, alpha_i)

        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(rhs),
            diffrax.Dopri8(),
            t0=0.0,
            t1=1.0,
            dt0=None,
            y0=jnp.zeros((), dtype=jnp.float64),
            stepsize_controller=diffrax.PIDController(rtol=1e-13, atol=1e-300),
            max_steps=4096,
            saveat=diffrax.SaveAt(t1=True),
            throw=False,
        )
        return jnp.where(sol.result == diffrax.RESULTS.successful, sol.ys[-1], jnp.nan)

    flat = jax.vmap(one)(sb.ravel(), h.ravel(), alpha.ravel())
    return flat.reshape(la.shape)


def pressure(
    inner_stretch: Array,
    *,
    inner_radius: Array,
    outer_radius: Array,
    C: Array,
    alpha: Array,
    method: str = "quadrature",
) -> Array:
    r"""Internal pressure p (Pa) that holds the shell at inner stretch ``lambda_a = a/A``.

    p(lambda_a) = int_{lambda_b}^{lambda_a} 4 C exp(alpha (2 l^2 + l^-4 - 3)) (l^3 + 1)/l^5 dl,
    lambda_b^3 = 1 + (lambda_a^3 - 1)(A/B)^3.

    Parameters (all broadcast; jit/vmap/grad-able in every argument except ``method``):
    inner_stretch  lambda_a = a/A (dimensionless, > 0; < 1 is deflation, p < 0);
    inner_radius   A in m; outer_radius B in m (A < B); C in Pa (> 0); alpha >= 0.
    method         "quadrature" (20-point Gauss-Legendre in log l, the fast default) or "ode"
                   (diffrax Dopri8 through the wall; a check, ~100x slower).
    Returns p in Pa, shape of the broadcast inputs.
    """
    _check_stretch("inner_stretch", inner_stretch)
    _validate(inner_radius, outer_radius, C, alpha)
    la = jnp.asarray(inner_stretch, dtype=jnp.float64)
    k, omk = _geometry(inner_radius, outer_radius)
    alpha = jnp.asarray(alpha, dtype=jnp.float64)
    if method == "quadrature":
        la, k, omk, alpha = jnp.broadcast_arrays(la, k, omk, alpha)
        pc = _p_over_C_quad(la, k, omk, alpha)
    elif method == "ode":
        pc = _p_over_C_ode(la, k, omk, alpha)
    else:
        raise ValueError(f'method must be "quadrature" or "ode"; got {method!r}')
    return jnp.asarray(C, dtype=jnp.float64) * pc


def _dp_over_C(la, k, alpha):
    """d(p/C)/d lambda_a = g(lambda_a) - g(lambda_b) k lambda_a^2 / lambda_b^2 (Leibniz)."""
    lb = jnp.cbrt(1.0 + (la**3 - 1.0) * k)
    return _g(la, alpha) - _g(lb, alpha) * k * la**2 / lb**2


def pressure_derivative(
    inner_stretch: Array, *, inner_radius: Array, outer_radius: Array, C: Array, alpha: Array
) -> Array:
    r"""dp/d lambda_a in Pa, closed form (Leibniz rule on the pressure integral):

    dp/d lambda_a = g(lambda_a) - g(lambda_b) d lambda_b/d lambda_a,
    d lambda_b/d lambda_a = (A/B)^3 lambda_a^2 / lambda_b^2,  g(l) = 4 W'(I1(l)) (l^3 + 1)/l^5.
    """
    _check_stretch("inner_stretch", inner_stretch)
    _validate(inner_radius, outer_radius, C, alpha)
    la = jnp.asarray(inner_stretch, dtype=jnp.float64)
    k, _ = _geometry(inner_radius, outer_radius)
    return jnp.asarray(C, dtype=jnp.float64) * _dp_over_C(la, k, jnp.asarray(alpha, dtype=jnp.float64))


def outer_stretch(inner_stretch: Array, *, inner_radius: Array, outer_radius: Array) -> Array:
    r"""Outer stretch lambda_b = b/B from incompressibility (dimensionless):

    lambda_b^3 = 1 + (lambda_a^3 - 1)(A/B)^3,  A = inner_radius, B = outer_radius (m).
    """
    _check_stretch("inner_stretch", inner_stretch)
    validate_radii(inner_radius, outer_radius)
    la = jnp.asarray(inner_stretch, dtype=jnp.float64)
    k, omk = _geometry(inner_radius, outer_radius)
    sb, _ = _log_stretches(la, k, omk)
    return jnp.exp(sb)
