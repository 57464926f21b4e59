r"""A rigid spherical probe pressed on a ball resting on a rigid plate: the lumped generalized-Maxwell force.

Geometry (SI units): a rigid sphere of radius ``probe_radius`` R_p (m, the AFM colloidal probe) pushes on a
ball of radius ``radius`` a0 (m, the cell, oocyte or spheroid) that rests on a rigid, frictionless plate;
``delta`` (m) is the approach of the probe towards the plate since first contact (the AFM "indentation":
piezo travel minus cantilever deflection). ``radius=math.inf`` is the classical half-space (a probe on a
thick flat sample).

Equilibrium law (small strain)
------------------------------
Two Hertz contacts in series carry the same force F: probe on ball (rigid sphere R_p on an elastic sphere
a0: effective radius R_1 = R_p a0 / (R_p + a0)) and ball on plate (elastic sphere on a rigid flat: R_2 = a0).
Each obeys F = (4/3) E* sqrt(R_i) d_i^(3/2) with E* = E / (1 - nu^2) (the other body rigid). For the Fung
material, the small-strain shear modulus is mu = 2 C; incompressible (nu = 1/2) gives E = 3 mu = 6 C and

    E* = E / (1 - 1/4) = (4/3) 6 C = 8 C.

The approaches add, delta = d_1 + d_2, and d_i = (F / k_i)^(2/3) with k_i = (4/3) E* sqrt(R_i), so

    delta = F^(2/3) (k_1^(-2/3) + k_2^(-2/3)),   i.e.   F_eq(delta) = (4/3) E* sqrt(R_s) delta^(3/2)
    = (32/3) C sqrt(R_s) delta^(3/2),   R_s = (R_1^(-1/3) + R_2^(-1/3))^(-3)

(:func:`series_radius`): one Hertz law with a series radius R_s < min(R_1, R_2). The split is
d_i / delta = R_i^(-1/3) / (R_1^(-1/3) + R_2^(-1/3)) (:func:`contact_depths`). Limits: a0 -> inf gives
R_1 -> R_p, R_2^(-1/3) -> 0, so R_s -> R_p and F = (4/3) E* sqrt(R_p) delta^(3/2) (the half-space Hertz
law); two plates on a ball (reduced.spheroid's Hertz law) is the case R_1 = R_2 = a0, R_s = a0 / 8.

Validity: small strain only (Hertz: contact radii small against R_1 and a0; linear elasticity, so the Fung
exponent ``alpha`` does not enter and is not identifiable from this law: it is accepted, checked and
unused, for the FE-calibrated correction table that does not exist yet for this scene). The expected error
is that of Hertz against finite strain: for the ball between two plates (reduced.spheroid) Hertz is 3 %
soft of the FE at 1 % compression (delta / (2 a0) = 0.01), 4 % at 5 %, 30 % at 30 %; expect the same
order here at the same contact-depth ratios d_i / R_i. Eager calls reject a probe-contact depth beyond
its effective radius (d_1 >= R_1) or a plate-contact depth beyond the ball's radius (d_2 >= a0), where
the law means nothing.

Viscoelasticity (the lumped convolution of :mod:`tissuemech.reduced.spheroid`)
----------------------------------------------------------------------------
    F(t) = F_eq(delta(t)) + sum_m beta_m int_0^t exp(-(t - s)/tau_m) dF_eq(delta(s))/ds ds

with energy factors beta_m (-) and relaxation times tau_m (s). reduced.spheroid's Hertz law for a ball of
radius a' between two plates is F = C a'^2 (32/3) (delta / (2 a'))^(3/2) = (32/3) C sqrt(a'/8) delta^(3/2):
the law above with a' = 8 R_s. :func:`force` therefore calls ``spheroid.force(..., radius=8 R_s,
equilibrium="hertz")`` (the check d_1 < R_1 keeps delta < 16 R_s = 2 a', inside that law's range), so the
spheroid's quadrature (ramp and hold, exact kernel) and its diffrax path (any history) are reused, not copied.

Loading (``displacement``)
--------------------------
* a number (m) with ``ramp_time`` (s): a linear ramp to it, then held (quadrature, ~1e-9 accurate);
* a measured history ``(times, approaches)`` (s, m; 1-D, times strictly increasing from >= 0, approaches
  >= 0 and 0 at the first time, the first contact): piecewise linear between the samples and held after the
  last one (diffrax at ``rtol``/``atol``; an eager call makes every sample a jump time of the solver; under
  jit, where the samples are traced, give output times at the samples, as ``compare.afm.fit`` does, so the
  steps land on the kinks). Thin a long record first (a few hundred knots: the cost grows with their number).

Every function is jit / vmap / grad-able in float64 (parameters broadcast: output shape
``broadcast(params).shape + t.shape``); eager calls check their inputs (messages name the quantity and unit).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import jax.numpy as jnp
import numpy as np

import tissuemech.reduced  # noqa: F401  (float64 in JAX)
from tissuemech.reduced import spheroid
from tissuemech.reduced.material import probe_share
from tissuemech.reduced.validation import (
    InputError,
    is_traced,
    validate_finite,
    validate_material,
    validate_positive,
    validate_times,
)

__all__ = ["series_radius", "contact_depths", "equilibrium_force", "force", "history"]

HERTZ_PREFACTOR = 32.0 / 3.0  # F = (4/3) E* sqrt(R) d^1.5 with E* = 8 C: (32/3) C sqrt(R) d^1.5


def _check_radii(radius: Any, probe_radius: Any) -> None:
    """radius (ball) > 0 and may be inf (half-space); probe_radius > 0 and finite."""
    validate_positive("probe_radius (radius of the spherical AFM probe)", probe_radius, "m")
    if not is_traced(radius):
        r = np.asarray(radius, dtype=float) if not isinstance(radius, str) else None
        if r is None or r.size == 0 or np.any(np.isnan(r)) or np.any(r <= 0):
            raise InputError(
                f"radius (of the indented ball, in m) must be positive (math.inf for a half-space); got {radius!r}"
            )


def series_radius(radius: Any, probe_radius: Any) -> jnp.ndarray:
    """Series radius R_s = (R_1^(-1/3) + a0^(-1/3))^(-3) in m of the two Hertz contacts (module doc).

    radius        ball radius a0 (m); ``math.inf`` for a half-space (then R_s = probe_radius).
    probe_radius  probe radius R_p (m). R_1 = R_p a0 / (R_p + a0) is the probe-ball effective radius.
    """
    if not is_traced(radius, probe_radius):
        _check_radii(radius, probe_radius)
    a = jnp.asarray(radius, dtype=jnp.float64)
    rp = jnp.asarray(probe_radius, dtype=jnp.float64)
    r1 = rp / (1.0 + rp / a)  # = R_p a0 / (R_p + a0), finite for a0 = inf
    return (r1 ** (-1.0 / 3.0) + a ** (-1.0 / 3.0)) ** -3.0


def contact_depths(displacement: Any, *, radius: Any, probe_radius: Any) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(d_1, d_2) in m: the approach ``displacement`` delta (m) split into the probe-ball depth d_1 and the
    ball-plate depth d_2 (d_1 + d_2 = delta; d_i proportional to R_i^(-1/3); d_2 = 0 for a half-space)."""
    if not is_traced(displacement, radius, probe_radius):
        _check_radii(radius, probe_radius)
        validate_finite("displacement (approach of the probe since contact)", displacement, "m")
    a = jnp.asarray(radius, dtype=jnp.float64)
    rp = jnp.asarray(probe_radius, dtype=jnp.float64)
    d = jnp.asarray(displacement, dtype=jnp.float64)
    d1 = d * probe_share(a, rp)
    return d1, d - d1


def _check_depth(dmax: Any, radius: Any, probe_radius: Any) -> None:
    """Eager: the small-strain law must at least be geometric sense (d_1 < R_1, d_2 < a0)."""
    d = np.max(np.asarray(dmax, dtype=float))
    a = np.asarray(radius, dtype=float)
    rp = np.asarray(probe_radius, dtype=float)
    d1, d2 = (np.asarray(v) for v in contact_depths(d, radius=a, probe_radius=rp))
    r1 = rp / (1.0 + rp / a)
    if np.any(d1 >= r1):
        raise InputError(
            f"displacement (approach of the probe, in m): {d:.4g} m puts the probe-ball contact {np.max(d1):.4g} m "
            f"deep, beyond its effective radius R_p a0/(R_p + a0) = {np.min(r1):.4g} m; the small-strain Hertz law "
            "holds only for depths well below it (check the units: m, not um)"
        )
    if np.any(d2 >= a):
        raise InputError(
            f"displacement (approach of the probe, in m): {d:.4g} m puts the ball-plate contact {np.max(d2):.4g} m "
            f"deep, beyond the ball's radius {np.min(a):.4g} m (check the units: m, not um)"
        )


def equilibrium_force(displacement: Any, *, radius: Any, probe_radius: Any, C: Any, alpha: Any = 0.0) -> jnp.ndarray:
    """Elastic (long-time) force F_eq = (32/3) C sqrt(R_s) delta^(3/2) in N (module doc: two Hertz contacts).

    displacement  approach delta of the probe since first contact (m), >= 0 (negative: no contact, 0 N).
    radius        ball radius a0 (m), ``math.inf`` for a half-space.   probe_radius  R_p (m).
    C, alpha      Fung parameters (Pa, -); alpha is unused by the small-strain law (checked only).
    """
    if not is_traced(displacement, radius, probe_radius, C, alpha):
        _check_radii(radius, probe_radius)
        validate_material(C, alpha)
        dv = validate_finite("displacement (approach of the probe since contact)", displacement, "m")
        _check_depth(dv, radius, probe_radius)
    d = jnp.maximum(jnp.asarray(displacement, dtype=jnp.float64), 0.0)
    rs = series_radius(radius, probe_radius)
    return HERTZ_PREFACTOR * jnp.asarray(C, dtype=jnp.float64) * jnp.sqrt(rs) * d * jnp.sqrt(d)


def history(times: Any, approaches: Any) -> tuple[jnp.ndarray, jnp.ndarray]:
    """A measured approach history, checked: ``times`` (s, 1-D, strictly increasing, >= 0) and ``approaches``
    (m, same length, finite, >= 0, 0 at the first sample: first contact). Returns both as float64 arrays;
    pass the pair as ``displacement=`` to :func:`force`."""
    if not is_traced(times, approaches):
        t = validate_times("times (of the measured approach history)", times, ascending=True, strictly=True, ndim1=True)
        d = validate_finite("approaches (of the measured approach history)", approaches, "m")
        if t is None or d is None:
            raise InputError("the measured history needs numbers: (times in s, approaches in m)")
        if d.shape != t.shape:
            raise InputError(f"approaches (m) need one value per time (s): got {d.size} approaches for {t.size} times")
        if t.size < 2:
            raise InputError(f"the measured history needs at least 2 samples (times in s); got {t.size}")
        if np.any(d < 0):
            raise InputError(
                f"approaches (of the measured history, m) must not be negative (no contact); got {np.min(d):.4g} m"
            )
        if d[0] != 0.0:
            raise InputError(
                f"approaches (m): the history starts at first contact, approach 0 m at the first time; got {d[0]:.4g} m"
            )
    return jnp.asarray(times, dtype=jnp.float64), jnp.asarray(approaches, dtype=jnp.float64)


class _PiecewiseLinear:
    """delta(t) = interp(t; times, approaches), 0 before the first time, held after the last. Hashable by
    content (spheroid.force keys its compiled code on the history callable): equal records reuse it."""

    def __init__(self, times: Any, approaches: Any):
        self.t = jnp.asarray(times, dtype=jnp.float64)
        self.d = jnp.asarray(approaches, dtype=jnp.float64)
        traced = is_traced(self.t, self.d)
        self._key = None if traced else (np.asarray(self.t).tobytes(), np.asarray(self.d).tobytes())

    def __call__(self, t: Any) -> jnp.ndarray:
        return jnp.interp(t, self.t, self.d, left=0.0)

    def __hash__(self) -> int:
        return hash(self._key) if self._key is not None else id(self)

    def __eq__(self, other: object) -> bool:
        if self._key is None or not isinstance(other, _PiecewiseLinear):
            return self is other
        return self._key == other._key


def force(
    t: Any,
    *,
    radius: Any,
    probe_radius: Any,
    C: Any,
    alpha: Any = 0.0,
    branches: Sequence[tuple[Any, Any]] = (),
    displacement: Any,
    ramp_time: Any = None,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_steps: int = 65536,
    solver: Any = None,
    adjoint: Any = "reverse",
) -> jnp.ndarray:
    r"""Probe force F(t) in N of the lumped generalized-Maxwell ball under a spherical probe (module doc).

    t             output times (s), any shape, >= 0 (t = 0 is first contact).
    radius        ball radius a0 (m), ``math.inf`` for a half-space.   probe_radius  R_p (m).
    C, alpha      Fung parameters (Pa, -); alpha unused by the small-strain law.
    branches      sequence of (beta, tau): energy factor (-) and relaxation time (s); () = elastic.
    displacement  approach of the probe (m) reached at ``ramp_time`` (s) by a linear ramp and then held; or a
                  measured history ``(times, approaches)`` (s, m), piecewise linear, held after its end.
    rtol, atol, max_steps, solver, adjoint   diffrax options of the measured-history path
                  (``adjoint="forward"`` for ``jax.jacfwd``).
    Returns F (N), shape ``broadcast(params).shape + t.shape``. Raises ValueError (eager) for bad inputs.
    """
    measured = isinstance(displacement, tuple)
    if measured:
        if len(displacement) != 2:
            raise InputError("displacement as a measured history is a pair (times in s, approaches in m)")
        times, approaches = history(*displacement)
    eager = not is_traced(t, radius, probe_radius, C, alpha, *(v for b in branches for v in b))
    if eager:
        validate_times("t (output times, t = 0 is first contact)", t, unit="s")
        _check_radii(radius, probe_radius)
        validate_material(C, alpha)
        if measured:
            if not is_traced(approaches):
                _check_depth(np.max(np.asarray(approaches)), radius, probe_radius)
        else:
            validate_positive("displacement (approach of the probe at the end of the ramp)", displacement, "m")
            if ramp_time is None:
                raise InputError("ramp_time (s) is needed with a numeric displacement (linear ramp, then hold)")
            validate_positive("ramp_time (duration of the loading ramp)", ramp_time, "s")
            _check_depth(displacement, radius, probe_radius)
    rs = series_radius(radius, probe_radius)
    a_equiv = 8.0 * rs  # the spheroid's Hertz law with this radius and C' = C sqrt(8 R_s / a') = C (module doc)
    common = dict(radius=a_equiv, C=C, alpha=alpha, branches=branches, equilibrium="hertz")
    if measured:
        return spheroid.force(
            t,
            **common,
            displacement=_PiecewiseLinear(times, approaches),
            jump_times=None if is_traced(times) else tuple(float(v) for v in np.asarray(times)),
            rtol=rtol,
            atol=atol,
            max_steps=max_steps,
            solver=solver,
            adjoint=adjoint,
        )
    return spheroid.force(t, **common, displacement=displacement, ramp_time=ramp_time)
