r"""Independent references, defined once: what the models are checked against.

* ``shell_pressure(la, ...)``: the exact incompressible Fung thick shell (docs/physics.md),

      p(lambda_a) = int_{lambda_b}^{lambda_a} 4 C exp(alpha (2 l^2 + l^-4 - 3)) (l^3 + 1) / l^5 dl,
      lambda_b^3 = 1 + (lambda_a^3 - 1) (A/B)^3,

  by ``scipy.integrate.quad`` at rtol 1e-13 (independent of ``reduced.blastula``'s Gauss-Legendre
  path); ``shell_inner_stretch(p, ...)`` its inverse by ``brentq`` (rising branch).
* ``exact_lumped_force(t, ...)``: the lumped generalized-Maxwell force under the Hertz-shaped ramp,
  in closed form with Dawson's integral (any tau, no quadrature).
* ``hertz_force(delta, ...)``: the small-strain Hertz force of an incompressible ball between plates.

Defaults of the shell functions are the seed's blastula (A = 50 um, B = 75 um, C = 200 Pa).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tissuemech.compare.cases import BLASTULA_C, BLASTULA_INNER_RADIUS, FIG4_OUTER_RADIUS
from tissuemech.reduced.material import hertz_plate_f

__all__ = ["shell_pressure", "shell_inner_stretch", "exact_lumped_force", "lumped_equilibrium", "hertz_force"]


def shell_pressure(
    la: float,
    *,
    alpha: float,
    inner_radius: float = BLASTULA_INNER_RADIUS,
    outer_radius: float = FIG4_OUTER_RADIUS,
    C: float = BLASTULA_C,
) -> float:
    """Exact internal pressure (Pa) of the thick Fung shell at inner stretch ``la`` (scipy quad, rtol 1e-13).

    Args: la inner stretch a/A (-); alpha Fung exponent (-); inner_radius, outer_radius A, B (m); C (Pa).
    Returns the pressure p in Pa (negative for la < 1).
    """
    from scipy.integrate import quad

    la = float(la)
    lb = (1.0 + (la**3 - 1.0) * (inner_radius / outer_radius) ** 3) ** (1.0 / 3.0)
    g = lambda l: 4 * C * np.exp(alpha * (2 * l * l + l**-4 - 3)) * (l**3 + 1) / l**5
    return float(quad(g, lb, la, epsabs=0.0, epsrel=1e-13, limit=200)[0])


def shell_inner_stretch(p: float, *, alpha: float, upper: float = 20.0, **geometry: Any) -> float:
    """Inner stretch (-) of the thick Fung shell at pressure ``p`` (Pa), by ``brentq`` on ``shell_pressure``.

    Searches lambda_a in [1, ``upper``] (the rising branch for p >= 0); ``geometry``: inner_radius,
    outer_radius (m), C (Pa) as in ``shell_pressure``. Raises ValueError when no root is bracketed
    (p above the limit pressure).
    """
    from scipy.optimize import brentq

    if float(p) == 0.0:
        return 1.0
    return float(brentq(lambda l: shell_pressure(l, alpha=alpha, **geometry) - float(p), 1.0, upper, xtol=1e-14))


def lumped_equilibrium(t: np.ndarray, ramp_time: float) -> np.ndarray:
    """Dimensionless Hertz-shaped equilibrium force F_eq(t) = (min(t, t_r)/t_r)^(3/2) (times t in s)."""
    return np.clip(np.asarray(t, float) / ramp_time, 0.0, 1.0) ** 1.5


def exact_lumped_force(t: np.ndarray, *, beta: float, tau: float, ramp_time: float) -> np.ndarray:
    r"""Exact F(t) = F_eq(t) + beta int_0^t e^{-(t-s)/tau} F_eq'(s) ds, F_eq = (min(t, t_r)/t_r)^(3/2).

    During the ramp (T = t/tau, D = Dawson's integral, scipy.special.dawsn)
        q(t) = (3/2) beta (tau/t_r)^{3/2} (sqrt(T) - D(sqrt(T)))
    (from int_0^T e^v sqrt(v) dv = e^T (sqrt(T) - D(sqrt(T)))); after it q(t) = q(t_r) e^{-(t - t_r)/tau}.
    Args: t times (s); beta branch energy factor (-); tau relaxation time (s); ramp_time t_r (s).
    Returns the dimensionless force (F_eq(t_r) = 1); accurate to round-off for any tau.
    """
    t = np.asarray(t, float)
    tt = np.minimum(t, ramp_time)
    x = np.sqrt(tt / tau)
    q = 1.5 * beta * (tau / ramp_time) ** 1.5 * _x_minus_dawson(x)
    q = q * np.exp(-np.maximum(t - ramp_time, 0.0) / tau)
    return lumped_equilibrium(t, ramp_time) + q


def _x_minus_dawson(x: np.ndarray) -> np.ndarray:
    """x - D(x) without cancellation: the series sum_{n>=1} (-1)^(n+1) 2^n x^(2n+1) / (2n+1)!! for x < 0.5."""
    from scipy.special import dawsn

    x = np.asarray(x, float)
    out = np.atleast_1d(x - dawsn(x)).astype(float)
    xa = np.atleast_1d(x)
    small = xa < 0.5
    if np.any(small):
        xs = xa[small]
        term, acc = xs.copy(), np.zeros_like(xs)
        for n in range(1, 20):  # 0.5^38 / 39!! is far below round-off
            term = -term * 2.0 * xs * xs / (2 * n + 1)
            acc -= term
        out[small] = acc
    return out.reshape(x.shape)


def hertz_force(delta: np.ndarray, *, radius: float, C: float) -> np.ndarray:
    """Small-strain Hertz force (N) of an incompressible ball (shear modulus 2C) between two rigid plates.

    F = (32/3) C a0^2 x^(3/2), x = delta / (2 a0). Args: delta total plate approach (m); radius a0 (m);
    C Fung stiffness (Pa).
    """
    return C * radius**2 * hertz_plate_f(np.asarray(delta, float) / (2 * radius))
