r"""Fung hyperelastic law: the one constitutive source of tissuemech (``fem`` imports it too).

Isochoric energy per reference volume (Pa)::

    W(Ibar1) = C / alpha * (exp(alpha * (Ibar1 - 3)) - 1)

with ``C`` in Pa (shear modulus mu = 2 C, Young's modulus E = 6 C) and the dimensionless
stiffening exponent ``alpha >= 0``. For ``alpha -> 0`` it is neo-Hookean, ``W = C (Ibar1 - 3)``;
it is evaluated through ``expm1(alpha x) / alpha`` (and a Taylor series for tiny ``alpha x``), so
``alpha = 0`` is exact, ``alpha = 1e-5`` loses no digits and the derivative in ``alpha`` is smooth.

Volumetric energy (Pa): ``U(J) = kappa / 2 (J - 1)^2`` (``kappa`` the bulk modulus).

All functions are array-generic: they use NumPy for NumPy input (the FE assembles with it)
and ``jax.numpy`` for JAX arrays and tracers (jit/vmap/grad work).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tissuemech.reduced.validation import (  # re-exported: the historical home of the checks
    InputError,
    InputTypeError,
    as_array,
    is_traced,
    validate_branches,
    validate_finite,
    validate_int,
    validate_material,
    validate_nonnegative,
    validate_positive,
    validate_radii,
)

try:  # jax is a core dependency; keep this module importable for pure-NumPy callers anyway
    import jax
    import jax.numpy as jnp
except ImportError:  # pragma: no cover
    jax = None  # type: ignore[assignment]  # optional-module fallback
    jnp = None  # type: ignore[assignment]  # optional-module fallback

__all__ = [
    "hertz_plate_f",
    "probe_share",
    "fung_energy",
    "dW_dI1",
    "d2W_dI1",
    "volumetric_energy",
    "dU_dJ",
    "principal_cauchy_stress",
    "incompressible_stress_difference",
    "validate_material",
    "validate_positive",
    "validate_nonnegative",
    "validate_radii",
    "validate_branches",
    "validate_finite",
    "validate_int",
    "as_array",
    "is_traced",
    "InputError",
    "InputTypeError",
]

_SERIES_CUTOFF = 1e-3  # |alpha x| below this uses the 4-term Taylor series (error < 1e-14 rel.)


def _xp(*args: Any):
    """NumPy for NumPy/Python input, jax.numpy if any argument is a JAX array or tracer."""
    if jax is not None and any(isinstance(a, jax.Array) for a in args):
        return jnp
    return np


def _expm1_over(alpha, x):
    """(exp(alpha x) - 1) / alpha, exact and smooth through alpha = 0 (value x)."""
    xp = _xp(alpha, x)
    ax = alpha * x
    small = xp.abs(ax) < _SERIES_CUTOFF
    series = x * (1.0 + ax / 2.0 * (1.0 + ax / 3.0 * (1.0 + ax / 4.0)))
    safe_alpha = xp.where(small, 1.0, alpha)
    safe_ax = xp.where(small, 0.0, ax)
    return xp.where(small, series, xp.expm1(safe_ax) / safe_alpha)


def hertz_plate_f(x):
    """The small-strain Hertz law of a Fung ball between two rigid frictionless plates, in master-curve form:
    f(x) = F / (C a0^2) = (32/3) x^(3/2) at x = delta / (2 a0) (delta the total approach, a0 the radius).

    Each plate makes a Hertz contact with the ball and takes half the approach: F = (4/3) E* sqrt(a0)
    (delta/2)^(3/2) with E* = E / (1 - nu^2) = 8 C, the incompressible small-strain limit of this law (shear
    modulus 2 C, Young's modulus 6 C; alpha drops out). The one definition of the law: the reduced model, the FE
    scene and the references all call it. x <= 0 (no contact) gives 0; the derivative 16 sqrt(x) is finite (0)
    at first contact, under JAX too. NumPy or JAX by the input; no input check.
    """
    xp = _xp(x)
    x = xp.maximum(xp.asarray(x, dtype=float) if xp is np else x, 0.0)
    root = xp.sqrt(xp.where(x > 0, x, 1.0)) * (x > 0)
    return (32.0 / 3.0) * x * root


def probe_share(radius, probe_radius):
    """d_1 / delta: the probe-ball contact's share of the approach of a rigid sphere (radius ``probe_radius`` R_p)
    pressed on a ball (``radius`` a0, ``inf`` for a half-space) that rests on a rigid plate, at small strain: two
    Hertz contacts in series carry one force, so d_i ~ R_i^(-1/3) with R_1 = R_p a0 / (R_p + a0) (probe-ball) and
    R_2 = a0 (ball-plate): d_1 / delta = R_1^(-1/3) / (R_1^(-1/3) + a0^(-1/3)) (``reduced.indentation`` derives
    it; ``fem.indentation`` sizes its meshes with it). Any consistent length unit; NumPy or JAX by the input."""
    xp = _xp(radius, probe_radius)
    a = xp.asarray(radius, dtype=float) if xp is np else radius
    w1 = (probe_radius / (1.0 + probe_radius / a)) ** (-1.0 / 3.0)
    return w1 / (w1 + a ** (-1.0 / 3.0))


def fung_energy(I1bar, C, alpha):
    """Isochoric Fung energy W = C/alpha (exp(alpha (I1bar - 3)) - 1) in Pa (J/m^3).

    ``I1bar`` (dimensionless) is the first isochoric invariant J^(-2/3) tr(F^T F);
    ``C`` in Pa; ``alpha`` >= 0 dimensionless. Exact at alpha = 0 (neo-Hookean C (I1bar - 3)).
    """
    return C * _expm1_over(alpha, I1bar - 3.0)


def dW_dI1(I1bar, C, alpha):
    """dW/dI1bar = C exp(alpha (I1bar - 3)) in Pa."""
    xp = _xp(I1bar, C, alpha)
    return C * xp.exp(alpha * (I1bar - 3.0))


def d2W_dI1(I1bar, C, alpha):
    """d^2W/dI1bar^2 = C alpha exp(alpha (I1bar - 3)) in Pa (zero for neo-Hookean)."""
    xp = _xp(I1bar, C, alpha)
    return C * alpha * xp.exp(alpha * (I1bar - 3.0))


def volumetric_energy(J, kappa):
    """U(J) = kappa/2 (J - 1)^2 in Pa; ``kappa`` the bulk modulus in Pa."""
    return 0.5 * kappa * (J - 1.0) ** 2


def dU_dJ(J, kappa):
    """U'(J) = kappa (J - 1) in Pa (the hydrostatic pressure is -U'(J))."""
    return kappa * (J - 1.0)


def principal_cauchy_stress(l1, l2, l3, *, C, alpha, kappa):
    """Principal Cauchy stresses (Pa) of the nearly incompressible Fung law.

    sigma_i = (2/J) W'(Ibar1) (lbar_i^2 - Ibar1/3) + kappa (J - 1),
    with J = l1 l2 l3 and lbar_i = J^(-1/3) l_i. Returns a tuple (s1, s2, s3).
    """
    J = l1 * l2 * l3
    Jm23 = J ** (-2.0 / 3.0)
    b = [Jm23 * l1**2, Jm23 * l2**2, Jm23 * l3**2]
    I1bar = b[0] + b[1] + b[2]
    w1 = dW_dI1(I1bar, C, alpha)
    pvol = dU_dJ(J, kappa)
    return tuple(2.0 / J * w1 * (bi - I1bar / 3.0) + pvol for bi in b)


def incompressible_stress_difference(li, lj, I1, C, alpha):
    """sigma_i - sigma_j = 2 W'(I1) (li^2 - lj^2) (Pa) for the incompressible Fung law."""
    return 2.0 * dW_dI1(I1, C, alpha) * (li**2 - lj**2)


# ---------------------------------------------------------------------------------------------
# Validation lives in ``reduced.validation``; the names stay importable from here.
# ---------------------------------------------------------------------------------------------
