"""The Young-Laplace drop between plates (tissuemech.reduced.drop): closed forms and limits."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from tissuemech.reduced import drop

A0 = 175e-6  # m (S180 aggregate)
GAMMA = 6e-3  # N/m
V0 = 4.0 / 3.0 * math.pi * A0**3


def test_undeformed_sphere():
    s = drop.compress(0.0, radius=A0, surface_tension=GAMMA)
    assert s.force == 0.0 and s.contact_radius == 0.0
    assert s.pressure == pytest.approx(2 * GAMMA / A0, rel=1e-15)
    np.testing.assert_allclose(np.hypot(s.profile_r, s.profile_z), A0, rtol=1e-15)


def test_small_approach_tends_to_the_sphere():
    s = drop.compress(1e-6 * A0, radius=A0, surface_tension=GAMMA)
    assert s.pressure == pytest.approx(2 * GAMMA / A0, rel=1e-6)
    assert 0 < s.force < 1e-6 * GAMMA * A0
    assert s.equatorial_radius == pytest.approx(A0, rel=1e-6)
    # the disc carries the Laplace pressure of the sphere; it is much smaller than the cut of a rigid
    # sphere (R3^2 = a0 delta): the liquid drop flattens globally (a logarithmic law)
    assert s.force == pytest.approx(math.pi * s.contact_radius**2 * 2 * GAMMA / A0, rel=1e-5)
    assert s.contact_radius < math.sqrt(A0 * 1e-6 * A0)


@pytest.mark.parametrize("x", [0.2, 1.0])
def test_volume_force_balance_and_profile(x):
    s = drop.compress(x * A0, radius=A0, surface_tension=GAMMA)
    assert s.volume == pytest.approx(V0, rel=1e-10)
    # the plate and the equator balances give one force (the first integral of Young-Laplace)
    assert s.force == pytest.approx(s.force_equator, rel=1e-9)
    # 180 deg: the classic formula F / (pi R3^2) = gamma (1/R1 + 1/R2) is exact
    assert s.force / (math.pi * s.contact_radius**2) == pytest.approx(
        GAMMA * (1 / s.meridional_radius + 1 / s.equatorial_radius), rel=1e-9
    )
    assert abs(s.profile_z[0]) < 1e-12 * A0 and s.profile_r[0] == pytest.approx(s.equatorial_radius, rel=1e-12)
    assert s.profile_z[-1] == pytest.approx(A0 - x * A0 / 2, rel=1e-10)
    assert s.profile_r[-1] == pytest.approx(s.contact_radius, rel=1e-10)
    # the volume of the profile (trapezoid in z) agrees with V0 to the sampling error
    r, z = s.profile_r, s.profile_z
    assert 2 * np.trapezoid(math.pi * r**2, z) == pytest.approx(V0, rel=1e-3)
    # a squeezed drop pushes the plates apart and bulges
    assert s.force > 0 and s.equatorial_radius > A0 and s.pressure > 2 * GAMMA / A0


def test_scaling():
    """F / (gamma a0) depends only on delta / a0 and theta."""
    s1 = drop.compress(0.6 * A0, radius=A0, surface_tension=GAMMA)
    s2 = drop.compress(0.6 * 2 * A0, radius=2 * A0, surface_tension=3 * GAMMA)
    assert s2.force == pytest.approx(6 * s1.force, rel=1e-9)
    assert s2.pressure == pytest.approx(1.5 * s1.pressure, rel=1e-9)


def test_force_increases_with_approach():
    F = drop.force(np.array([0.1, 0.4, 0.8]) * A0, radius=A0, surface_tension=GAMMA)
    assert np.all(np.diff(F) > 0) and F.shape == (3,)


def test_cylinder_at_right_angle():
    """theta = 90 deg: the cylinder of the drop's volume, F = -pi gamma R."""
    x = 0.5
    h = A0 * (1 - x / 2)
    s = drop.compress(x * A0, radius=A0, surface_tension=GAMMA, contact_angle=math.pi / 2)
    R = math.sqrt(V0 / (2 * math.pi * h))
    assert s.equatorial_radius == pytest.approx(R, rel=1e-10)
    assert s.contact_radius == pytest.approx(R, rel=1e-10)
    assert s.pressure == pytest.approx(GAMMA / R, rel=1e-10)
    assert s.force == pytest.approx(-math.pi * GAMMA * R, rel=1e-10)
    assert abs(A0 / s.meridional_radius) < 1e-9


def test_truncated_sphere():
    """A sphere of radius a cut at +-h meets the plates at theta = 90 deg + asin(h/a) with zero force."""
    x = 0.4
    h = 1 - x / 2  # scaled by a0

    def vol(a):
        c = a - h
        return 4 / 3 * math.pi * a**3 - 2 * math.pi * c**2 * (3 * a - c) / 3 - 4 / 3 * math.pi

    a = brentq(vol, h, 2.0, xtol=1e-15)
    theta = math.pi / 2 + math.asin(h / a)
    s = drop.compress(x * A0, radius=A0, surface_tension=GAMMA, contact_angle=theta)
    assert s.pressure == pytest.approx(2 * GAMMA / (a * A0), rel=1e-9)
    assert abs(s.force) < 1e-9 * GAMMA * A0
    assert s.equatorial_radius == pytest.approx(a * A0, rel=1e-9)
    assert s.meridional_radius == pytest.approx(a * A0, rel=1e-8)
    assert s.contact_radius == pytest.approx(math.sqrt(a * a - h * h) * A0, rel=1e-9)


def test_wetting_lowers_the_force():
    F = [
        drop.compress(0.5 * A0, radius=A0, surface_tension=GAMMA, contact_angle=math.radians(t)).force
        for t in (180, 150)
    ]
    assert F[1] < F[0]


@pytest.mark.slow
def test_thin_pancake_limit():
    """h << R2 at 180 deg: Delta_p -> gamma / h = 2 gamma / gap, F -> gamma V0 / (2 h^2)."""
    errs = []
    for x in (1.9, 1.98):
        s = drop.compress(x * A0, radius=A0, surface_tension=GAMMA)
        h = s.half_gap
        errs.append(abs(s.pressure * h / GAMMA - 1))
        assert s.meridional_radius == pytest.approx(h, rel=0.02)
        assert s.force == pytest.approx(GAMMA * V0 / (2 * h * h), rel=0.2)
        assert s.volume == pytest.approx(V0, rel=1e-10)
    # the error is O(h / R2): it falls ~ (h ratio)^1.5 = 10^1.5 (R2 ~ h^-1/2)
    assert errs[1] < errs[0] / 10 and errs[1] < 1e-3


@pytest.mark.parametrize(
    "kw",
    [
        dict(approach=-1e-6),
        dict(approach=2 * A0),
        dict(approach=float("nan")),
        dict(approach=1e-5, radius=-1.0),
        dict(approach=1e-5, surface_tension=0.0),
        dict(approach=1e-5, contact_angle=0.0),
        dict(approach=1e-5, contact_angle=4.0),
    ],
)
def test_bad_input(kw):
    args = dict(radius=A0, surface_tension=GAMMA) | kw
    d = args.pop("approach")
    with pytest.raises(ValueError, match="approach|radius|surface_tension|contact_angle"):
        drop.compress(d, **args)
