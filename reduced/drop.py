r"""A liquid drop compressed between two parallel rigid plates: the exact Young-Laplace solution.

The long-time limit of a tissue that flows like a liquid (a cell aggregate with tissue surface tension
gamma): a drop of volume V0 = (4/3) pi a0^3 squeezed by two parallel plates to the gap 2 h = 2 a0 - delta
(``delta``: the total approach of the plates since the undeformed sphere touched both, m). Gravity is
neglected (S180 aggregates: Bond number rho g a0^2 / gamma ~ 5e-6). SI units at the API: m, N/m, Pa, N.

Equations
---------
By symmetry the drop is a surface of revolution, mirror-symmetric about the midplane z = 0. Its meridian
(upper half) is written in arc length s from the equator (r, z) = (R2, 0):

    dr/ds = cos psi,   dz/ds = sin psi,   dpsi/ds = Delta_p / gamma - sin(psi) / r,

psi the angle of the tangent to the r-axis (psi = pi/2 at the equator, where the surface is vertical).
The last line is the Young-Laplace equation Delta_p = gamma (k_1 + k_2) with the meridional curvature
k_1 = dpsi/ds and the azimuthal one k_2 = sin(psi) / r. The meniscus ends on the plate z = h at arc length
L where psi = theta, the contact angle measured through the liquid (theta = pi: the surface leaves the
plate tangentially, a non-wetting plate; theta = pi/2: it meets it at a right angle). The half volume
V0 / 2 = int_0^L pi r^2 sin(psi) ds closes the problem. The ODE is integrated from the contact line (r, z, psi) =
(R3, h, theta) down to the equator (regular there even for a tiny contact disc, unlike the pole end of a
shot from the equator); with the unknowns (R3, Delta_p, L) the three conditions z = 0, psi = pi/2 and
V = V0/2 at the equator are solved by shooting (the ODE on the fixed interval sigma = L t, t in [0, 1]).
Large compressions and other angles are reached by continuation (log h, theta linear) from a sphere cut
by the plates at h = (1 - 1e-4) a0; delta = 0 at theta = pi is the sphere in closed form.

Why scipy and not diffrax: the problem is one small boundary-value solve (3 unknowns) per approach,
done in milliseconds with DOP853 at rtol 1e-12 and MINPACK's hybrid Newton; nothing here is traced or
differentiated (the force is needed as data: a reference curve and the tensiometry check), and a
continuation with step cut-backs is plain Python control flow.

Force (derivation)
------------------
Lengths scale by a0, pressures by gamma / a0, forces by gamma a0: the solution depends on delta / a0 and
theta only. Along the meniscus the quantity

    Phi(s) = pi r^2 Delta_p - 2 pi r gamma sin(psi)

is constant: dPhi/ds = 2 pi r Delta_p cos(psi) - 2 pi gamma (cos(psi) sin(psi) + r cos(psi) dpsi/ds)
= 2 pi r cos(psi) (Delta_p - gamma (sin(psi)/r + dpsi/ds)) = 0 by Young-Laplace. Phi is the axial
force that the part of the drop above a horizontal cut carries: the pressure excess on the cut disc
pushes up, the tension along the cut circle (of inclination psi) pulls down (the ambient pressure on
a closed surface sums to zero). At the plate (r = R3, psi = theta) it is the plate force,

    F = pi R3^2 Delta_p - 2 pi R3 gamma sin(theta)          (theta = pi: F = pi R3^2 Delta_p),

and at the equator (r = R2, psi = pi/2) the same force is F = pi R2^2 Delta_p - 2 pi R2 gamma, with
Delta_p = gamma (1/R1 + 1/R2) (R1 = 1 / k_1 at the equator): F = pi gamma R2 (R2 / R1 - 1). The two
forms agree to the integration's accuracy (a test). At theta = pi this gives the classic plate
tensiometry formula F / (pi R3^2) = gamma (1/R1 + 1/R2) (Norotte et al. 2008; Forgacs et al. 1998).

Closed forms used as checks
---------------------------
* delta = 0, theta = pi: the sphere (Delta_p = 2 gamma / a0, F = 0, R3 = 0).
* A truncated sphere of radius a cut at z = +-h meets the plates at theta = pi/2 + asin(h / a), carries
  Delta_p = 2 gamma / a and F = 0 (pi R3^2 2 gamma / a - 2 pi R3 gamma R3 / a).
* theta = pi/2: the cylinder R2 = R3 = sqrt(V0 / (2 pi h)), Delta_p = gamma / R2, F = -pi gamma R2
  (the bridge pulls the plates together).
* thin drop (h << R2) at theta = pi: Delta_p -> gamma / h (the meniscus is a half circle of radius h;
  2 gamma / gap), F -> gamma V0 / (2 h^2).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import root

from tissuemech.reduced.validation import validate_positive

__all__ = ["DropState", "compress", "force"]

_RTOL = 1e-12  # the ODE's relative tolerance
_ATOL = 1e-14  # and absolute (scaled lengths ~ 1)


class DropState(NamedTuple):
    """The drop at one approach (SI). ``profile_r``, ``profile_z``: the meniscus of the upper half from the
    equator (R2, 0) to the contact line (R3, h) (m; mirror it for the lower half; at theta = pi the flat
    contact disc r < R3, z = h closes it); ``R1`` is the meridional radius of curvature at the equator
    (m; inf for a cylinder, negative for a neck, theta < pi/2)."""

    approach: float  # m, total approach of the plates delta
    half_gap: float  # m, h = a0 - delta/2
    force: float  # N, plate force (> 0 pushes the plates apart)
    pressure: float  # Pa, Delta_p = p_inside - p_outside
    contact_radius: float  # m, R3
    equatorial_radius: float  # m, R2
    meridional_radius: float  # m, R1 at the equator
    contact_angle: float  # rad, theta
    volume: float  # m^3, the solved volume (= (4/3) pi a0^3 to the solver's tolerance)
    force_equator: float  # N, the same force from the equator balance pi R2^2 Delta_p - 2 pi R2 gamma
    profile_r: np.ndarray  # m
    profile_z: np.ndarray  # m


def _rhs(_t: float, y: np.ndarray, P: float, L: float) -> list[float]:
    # t in [0, 1] runs from the contact line (t = 0) down to the equator (t = 1): sigma = L t = L - s
    r, _z, psi, _v = y
    sn, c = math.sin(psi), math.cos(psi)
    return [-L * c, -L * sn, -L * (P - sn / r), L * math.pi * r * r * sn]


def _shoot(p, h, theta, dense: bool = False):
    R3, P, L = p
    if not (R3 > 0 and L > 0):
        return None
    sol = solve_ivp(
        _rhs, (0.0, 1.0), [R3, h, theta, 0.0], method="DOP853", args=(P, L), rtol=_RTOL, atol=_ATOL,
        dense_output=dense,
    )  # fmt: skip
    if not sol.success or np.any(sol.y[0] <= 0):
        return None
    return sol


def _residual(p, h, theta):
    sol = _shoot(p, h, theta)
    if sol is None:
        return np.full(3, 1e3)
    _r, z, psi, v = sol.y[:, -1]
    return np.array([z, psi - math.pi / 2, v - 2.0 * math.pi / 3.0])


def _solve(p0, h, theta):
    """(R3, P, L) scaled (a0 = gamma = 1) at half gap h and angle theta from the guess p0, or None."""
    out = root(_residual, p0, args=(h, theta), method="hybr", options=dict(xtol=1e-14))
    if not np.all(np.isfinite(out.x)) or np.max(np.abs(_residual(out.x, h, theta))) > 1e-11:
        return None
    return out.x


_H0 = 1.0 - 1e-4  # the continuation's first half gap (scaled), guessed as a sphere cut by the plates


def _path(h_end: float, theta_end: float, max_cuts: int = 30) -> np.ndarray:
    """Continuation from a just-touching sphere (theta = pi) to (h_end, theta_end): the scaled (R3, P, L)."""
    h0 = max(h_end, _H0)
    lh0, lh1 = math.log(h0), math.log(h_end)

    def point(t: float) -> tuple[float, float]:  # the path: h in log, theta linear
        return math.exp(lh0 + t * (lh1 - lh0)), math.pi + t * (theta_end - math.pi)

    sols: list[tuple[float, np.ndarray]] = []
    t, dt, cuts = 0.0, 0.2, 0
    while True:
        if not sols:
            t1 = 0.0
            guess = np.array([math.sqrt(1 - h0 * h0), 2.0, math.acos(math.sqrt(1 - h0 * h0))])
        else:
            t1 = min(1.0, t + dt)
            if len(sols) >= 2:
                (ta, pa), (tb, pb) = sols[-2], sols[-1]
                guess = pb + (pb - pa) * (t1 - tb) / (tb - ta)
            else:
                guess = sols[-1][1]
        h, th = point(t1)
        p = _solve(guess, h, th)
        if p is None:
            cuts += 1
            if cuts > max_cuts or not sols:
                raise ValueError(
                    f"no symmetric meniscus found at half gap h = {h:.6g} a0, contact angle {math.degrees(th):.6g} deg "
                    "(the drop may have no equilibrium there, e.g. a bridge stretched past its stability limit)"
                )
            dt /= 2
            continue
        sols.append((t1, p))
        t = t1
        if t >= 1.0:
            return p
        dt = min(dt * 1.5, 0.34)


def compress(
    approach: float, *, radius: float, surface_tension: float, contact_angle: float = math.pi, n_profile: int = 101
) -> DropState:
    """The drop of radius ``radius`` a0 (m, volume (4/3) pi a0^3) squeezed by the plate approach ``approach``
    delta (m, 0 <= delta < 2 a0) with tension ``surface_tension`` gamma (N/m) and ``contact_angle`` theta
    (rad, 0 < theta <= pi, measured through the liquid; default pi: non-wetting plates). Returns
    ``DropState`` (SI); ``n_profile`` points of the meniscus. Raises ValueError on an input out of range or
    when no symmetric meniscus exists (see the module for the equations)."""
    validate_positive("radius (the drop radius a0)", radius, "m")
    validate_positive("surface_tension (gamma)", surface_tension, "N/m")
    a0, gamma = float(radius), float(surface_tension)
    d = float(approach)
    if not math.isfinite(d) or d < 0 or d >= 2 * a0:
        raise ValueError(
            f"approach (the total approach delta of the plates) must be in [0, 2 a0) = [0, {2 * a0:g}) m; got {approach!r} m"
        )
    th = float(contact_angle)
    if not math.isfinite(th) or th <= 0 or th > math.pi:
        raise ValueError(
            f"contact_angle must be in (0, pi] rad (measured through the liquid); got {contact_angle!r} rad"
        )
    if int(n_profile) < 2:
        raise ValueError(f"n_profile must be >= 2, got {n_profile!r}")
    h = 1.0 - d / (2 * a0)
    if d == 0 and th == math.pi:  # the undeformed sphere (closed form; the ODE is singular at the pole)
        s = np.linspace(0, math.pi / 2, int(n_profile))
        return DropState(0.0, a0, 0.0, 2 * gamma / a0, 0.0, a0, a0, th, 4 / 3 * math.pi * a0**3, 0.0,
                         a0 * np.cos(s), a0 * np.sin(s))  # fmt: skip
    r3, P, L = _path(h, th)
    sol = _shoot((r3, P, L), h, th, dense=True)
    assert sol is not None  # the converged state integrates
    R2, _z, _psi, v = sol.y[:, -1]
    psi = th
    k1 = P - 1.0 / R2
    R1 = math.inf if k1 == 0 else 1.0 / k1
    F = math.pi * r3**2 * P - 2 * math.pi * r3 * math.sin(psi)
    Feq = math.pi * R2**2 * P - 2 * math.pi * R2
    prof = sol.sol(np.linspace(1.0, 0.0, int(n_profile)))
    return DropState(
        approach=d,
        half_gap=h * a0,
        force=F * gamma * a0,
        pressure=P * gamma / a0,
        contact_radius=r3 * a0,
        equatorial_radius=R2 * a0,
        meridional_radius=R1 * a0,
        contact_angle=th,
        volume=2 * v * a0**3,
        force_equator=Feq * gamma * a0,
        profile_r=prof[0] * a0,
        profile_z=prof[1] * a0,
    )


def force(approach, *, radius: float, surface_tension: float, contact_angle: float = math.pi) -> np.ndarray:
    """Plate force F (N) at each approach delta (m, array-like): :func:`compress` per entry."""
    d = np.atleast_1d(np.asarray(approach, float))
    out = [
        compress(x, radius=radius, surface_tension=surface_tension, contact_angle=contact_angle).force
        for x in d.ravel()
    ]
    return np.asarray(out).reshape(np.shape(approach))
