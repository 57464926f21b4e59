"""Physics tests of reduced.blastula: the exact thick incompressible Fung shell."""

from decimal import Decimal, getcontext

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

import tissuemech.reduced  # noqa: F401  (x64)
from tissuemech.compare.reference import shell_pressure
from tissuemech.reduced import blastula as bl

A = 50e-6
C = 200.0
GEO = dict(inner_radius=A, outer_radius=75e-6)


def nh_closed(la, A, B, C):
    """Neo-Hookean closed form p = 4C[1/lb + 1/(4 lb^4) - 1/la - 1/(4 la^4)] (float)."""
    lb = (1.0 + (la**3 - 1.0) * (A / B) ** 3) ** (1.0 / 3.0)
    return 4 * C * (1 / lb + 1 / (4 * lb**4) - 1 / la - 1 / (4 * la**4))


def nh_closed_decimal(la: float, A: float, B: float, C: float) -> float:
    """The same closed form in 50-digit decimal arithmetic (reference free of cancellation)."""
    getcontext().prec = 50
    la, A, B, C = (Decimal(float(v)) for v in (la, A, B, C))
    lb = (1 + (la**3 - 1) * (A / B) ** 3) ** (Decimal(1) / 3)
    f = lambda l: 1 / l + 1 / (4 * l**4)
    return float(4 * C * (f(lb) - f(la)))


def fung_quad(la, A, B, C, alpha):
    """The independent scipy-quad reference (``compare.reference.shell_pressure``)."""
    return shell_pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=alpha)


# ------------------------------------------------------------------ forward pressure


def test_neo_hookean_closed_form():
    rng = np.random.default_rng(1)
    la = rng.uniform(0.5, 4.0, 400)
    la = la[np.abs(la - 1) > 0.05]
    B = rng.uniform(51e-6, 500e-6, la.size)
    p = np.asarray(bl.pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=0.0))
    ref = np.array([nh_closed_decimal(x, A, b, C) for x, b in zip(la, B)])
    np.testing.assert_allclose(p, ref, rtol=1e-12, atol=0)
    np.testing.assert_allclose(p, nh_closed(la, A, B, C), rtol=1e-11, atol=0)


def test_fung_against_scipy_quad():
    rng = np.random.default_rng(2)
    n = 150
    la = rng.uniform(0.5, 4.0, n)
    B = rng.uniform(52e-6, 500e-6, n)
    alpha = rng.uniform(0.0, 0.3, n)
    p = np.asarray(bl.pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=alpha))
    ref = np.array([fung_quad(x, A, b, C, al) for x, b, al in zip(la, B, alpha)])
    np.testing.assert_allclose(p, ref, rtol=1e-11, atol=0)


@pytest.mark.parametrize("alpha", [0.0, 1e-5, 0.1, 0.3])
def test_ode_path_matches_quadrature(alpha):
    la = jnp.linspace(0.6, 4.0, 23)
    for B in (52e-6, 75e-6):
        q = bl.pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=alpha)
        o = bl.pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=alpha, method="ode")
        np.testing.assert_allclose(np.asarray(o), np.asarray(q), rtol=1e-10, atol=0)
        assert type(o) is type(q) is np.ndarray  # eager results are NumPy arrays, whichever method


def test_near_one_no_cancellation():
    """p ~ 8 C (1 - (A/B)^3)(lambda_a - 1) for small strain, for every alpha (W'(3) = C)."""
    B = 75e-6
    k = (A / B) ** 3
    for eps in (1e-9, 1e-8, 1e-6):
        la = 1.0 + eps
        eps_exact = la - 1.0  # the float's own distance to 1
        for alpha in (0.0, 0.2):
            p = float(bl.pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=alpha))
            lin = 8 * C * (1 - k) * eps_exact
            assert abs(p / lin - 1) < 10 * eps  # next term is O(eps)
        p0 = float(bl.pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=0.0))
        assert p0 == pytest.approx(nh_closed_decimal(la, A, B, C), rel=1e-12, abs=0)
    assert float(bl.pressure(1.0, **GEO, C=C, alpha=0.3)) == 0.0


def test_deflation_is_negative_pressure_and_monotone():
    la = jnp.linspace(0.5, 1.0, 41)
    for alpha in (0.0, 0.3):
        p = np.asarray(bl.pressure(la, **GEO, C=C, alpha=alpha))
        assert np.all(p[:-1] < 0) and p[-1] == 0.0
        assert np.all(np.diff(p) > 0)


def test_outer_stretch_incompressibility():
    la = np.array([0.7, 1.0, 1.3, 3.0])
    lb = np.asarray(bl.outer_stretch(la, **GEO))
    B = GEO["outer_radius"]
    # the wall volume is conserved: b^3 - a^3 = B^3 - A^3
    np.testing.assert_allclose((lb * B) ** 3 - (la * A) ** 3, B**3 - A**3, rtol=1e-13)


def test_pressure_derivative_closed_form():
    la = np.linspace(0.6, 3.5, 30)
    for alpha in (0.0, 0.2):
        d = np.asarray(bl.pressure_derivative(la, **GEO, C=C, alpha=alpha))
        h = 1e-6
        fd = (
            np.asarray(bl.pressure(la + h, **GEO, C=C, alpha=alpha))
            - np.asarray(bl.pressure(la - h, **GEO, C=C, alpha=alpha))
        ) / (2 * h)
        np.testing.assert_allclose(d, fd, rtol=1e-7)


# ------------------------------------------------------------------ limit point


def nh_slope(la, A, B):
    k = (A / B) ** 3
    lb = (1.0 + (la**3 - 1.0) * k) ** (1.0 / 3.0)
    dlb = k * la**2 / lb**2
    return (-1 / lb**2 - 1 / lb**5) * dlb + 1 / la**2 + 1 / la**5


@pytest.mark.parametrize("B", [52e-6, 60e-6, 75e-6])
def test_limit_point_neo_hookean(B):
    lim = bl.limit_point(inner_radius=A, outer_radius=B, C=C, alpha=0.0)
    la_ref = brentq(nh_slope, 1.01, 5.0, args=(A, B), xtol=1e-15, rtol=1e-15)
    assert float(lim.inner_stretch) == pytest.approx(la_ref, rel=1e-10)
    assert float(lim.pressure) == pytest.approx(nh_closed_decimal(la_ref, A, B, C), rel=1e-12)
    # it is a maximum
    pm = float(lim.pressure)
    for d in (-1e-3, 1e-3):
        assert float(bl.pressure(la_ref + d, inner_radius=A, outer_radius=B, C=C, alpha=0.0)) < pm


def test_limit_point_seed_values():
    lim = bl.limit_point(**GEO, C=C, alpha=0.0)
    # A = 50 um, B = 75 um, C = 200 Pa: the shell bursts near 197 Pa (seed: "p > 0.1 kPa")
    assert 190 < float(lim.pressure) < 200
    lim5 = bl.limit_point(**GEO, C=C, alpha=1e-5)
    assert lim5 is not None and float(lim5.pressure) > float(lim.pressure)
    for alpha in (0.1, 0.2, 0.3):
        assert bl.limit_point(**GEO, C=C, alpha=alpha) is None
    # arrays: NaN where none
    arr = bl.limit_point(**GEO, C=C, alpha=jnp.array([0.0, 0.2]))
    assert np.isfinite(arr.pressure[0]) and np.isnan(arr.pressure[1])


# A shell whose slope dp/dlambda_a dips below zero (to ~-1.8e-3 Pa at lambda_a ~ 1.918) only between two nodes of
# the 256-node search grid: the scan alone saw no falling node and returned None (and inner_stretch said "beyond
# the largest inner stretch" just above p_max); about 1e-5 of random shells (B/A 1.03-1.6, alpha 0-0.3) are such.
NARROW_DIP = dict(inner_radius=50e-6, outer_radius=66.30e-6, C=100.0, alpha=0.064363)


def test_limit_point_narrow_dip_between_grid_nodes():
    g = NARROW_DIP
    grid = np.geomspace(1.0, bl.LIMIT_SEARCH_MAX_STRETCH, 257)[1:]
    assert np.all(np.asarray(bl.pressure_derivative(grid, **g)) > 0)  # no grid node falls: the case is real
    lim = bl.limit_point(**g)
    assert lim is not None
    la, pm = lim.inner_stretch, lim.pressure
    assert 1.91 < la < 1.92
    # a stationary point: |dp/dlambda| ~ 0 (relative to the slope's two terms, ~ p_max / lambda_a)
    assert abs(float(bl.pressure_derivative(la, **g))) <= 1e-8 * pm / la
    # a maximum: above every grid node and dense stretch before it, and p falls just past it
    dense = np.linspace(1.0, la, 2001)
    assert pm >= np.max(np.asarray(bl.pressure(np.concatenate([grid[grid < la], dense]), **g)))
    assert float(bl.pressure(la + 5e-3, **g)) < pm
    # the other paths agree: an array call, a jit call
    arr = bl.limit_point(**{**g, "alpha": np.array([g["alpha"], 0.0])})
    assert arr.pressure[0] == pytest.approx(pm, rel=1e-15)
    assert arr.inner_stretch[0] == pytest.approx(la, rel=1e-13)
    jit = jax.jit(lambda al: bl.limit_point(**{**g, "alpha": al}))(g["alpha"])
    assert float(jit.pressure) == pytest.approx(pm, rel=1e-15)
    assert float(jit.inner_stretch) == pytest.approx(la, rel=1e-13)


def test_inner_stretch_at_a_narrow_dip_limit_point():
    g = NARROW_DIP
    lim = bl.limit_point(**g)
    below = lim.pressure * (1 - 1e-10)
    la = float(bl.inner_stretch(below, **g))
    assert la < lim.inner_stretch and float(bl.pressure(la, **g)) == pytest.approx(below, rel=1e-12)
    # just above p_max: the limit-pressure message (it said "beyond the largest inner stretch"), or a state on
    # the far branch past the dip (the solver may find it: see inner_stretch_solve), never a wrong message
    raised = 0
    for dp in (1e-7, 1e-6, 1e-5):
        try:
            far = float(bl.inner_stretch(lim.pressure + dp, **g))
        except ValueError as e:
            assert "exceeds the limit pressure" in str(e)
            raised += 1
        else:
            assert far > lim.inner_stretch
            assert float(bl.pressure(far, **g)) == pytest.approx(lim.pressure + dp, rel=1e-12)
    assert raised > 0


def test_limit_point_misses_no_maximum():
    """Random shells plus a family of narrow-dip shells: where the slope is negative at any of 2000 dense
    stretches in (1, 10] there is a limit point, before the first such stretch, and p_max is at least the
    pressure at every dense stretch before it; where there is none the slope is positive at all of them."""
    rng = np.random.default_rng(5)
    n = 300
    ratio = np.concatenate([rng.uniform(1.03, 1.6, n), np.full(6, 66.30 / 50)])
    alpha = np.concatenate([rng.uniform(0.0, 0.3, n), 0.064362 + 1e-6 * np.arange(6)])
    Bs = A * ratio
    lim = bl.limit_point(inner_radius=A, outer_radius=Bs, C=C, alpha=alpha)
    assert np.sum(np.isfinite(lim.pressure[n:])) == 6  # the narrow dips
    dense = np.geomspace(1.0, bl.LIMIT_SEARCH_MAX_STRETCH, 2001)[1:]
    slope = np.asarray(bl.pressure_derivative(dense[:, None], inner_radius=A, outer_radius=Bs, C=C, alpha=alpha))
    falls = np.any(slope <= 0, axis=0)
    has = np.isfinite(lim.pressure)
    assert np.all(has[falls])
    assert np.all(slope[:, ~has] > 0)
    first = dense[np.argmax(slope <= 0, axis=0)]
    assert np.all(lim.inner_stretch[falls] <= first[falls])
    p = np.asarray(bl.pressure(dense[:, None], inner_radius=A, outer_radius=Bs, C=C, alpha=alpha))
    before = dense[:, None] <= lim.inner_stretch[None, :]
    assert np.all(np.where(before, p, -np.inf).max(axis=0)[has] <= lim.pressure[has] * (1 + 1e-14))


# ------------------------------------------------------------------ inverse


def test_inverse_of_forward():
    rng = np.random.default_rng(3)
    lim = bl.limit_point(**GEO, C=C, alpha=0.0)
    la = rng.uniform(0.5, float(lim.inner_stretch) - 1e-3, 300)
    p = bl.pressure(la, **GEO, C=C, alpha=0.0)
    np.testing.assert_allclose(np.asarray(bl.inner_stretch(p, **GEO, C=C, alpha=0.0)), la, rtol=1e-11)
    la = rng.uniform(0.5, 4.0, 300)
    alpha = rng.uniform(0.1, 0.3, 300)
    p = bl.pressure(la, **GEO, C=C, alpha=alpha)
    np.testing.assert_allclose(np.asarray(bl.inner_stretch(p, **GEO, C=C, alpha=alpha)), la, rtol=1e-12)


def test_inverse_zero_and_tiny_pressure():
    assert float(bl.inner_stretch(0.0, **GEO, C=C, alpha=0.2)) == 1.0
    la = float(bl.inner_stretch(1e-6, **GEO, C=C, alpha=0.0))
    k = (2 / 3) ** 3
    assert (la - 1) == pytest.approx(1e-6 / (8 * C * (1 - k)), rel=1e-6)


def test_inverse_above_limit_point():
    lim = bl.limit_point(**GEO, C=C, alpha=0.0)
    with pytest.raises(ValueError, match="limit pressure 197"):
        bl.inner_stretch(200.0, **GEO, C=C, alpha=0.0)
    # just below the limit: the rising branch, not the falling one
    la = float(bl.inner_stretch(float(lim.pressure) * (1 - 1e-6), **GEO, C=C, alpha=0.0))
    assert la < float(lim.inner_stretch)
    f = jax.jit(lambda p: bl.inner_stretch(p, **GEO, C=C, alpha=0.0))
    out = np.asarray(f(jnp.array([100.0, 250.0])))
    assert np.isfinite(out[0]) and np.isnan(out[1])
    la, ok = bl.inner_stretch_solve(jnp.array([100.0, 250.0]), **GEO, C=C, alpha=0.0)
    assert bool(ok[0]) and not bool(ok[1])


def test_inverse_vmap_over_parameters():
    alphas = jnp.array([0.0, 0.1, 0.2, 0.3])
    f = jax.vmap(lambda a: bl.inner_stretch(150.0, **GEO, C=C, alpha=a))
    la = f(alphas)
    np.testing.assert_allclose(np.asarray(bl.pressure(la, **GEO, C=C, alpha=alphas)), 150.0, rtol=1e-12)
    assert np.all(np.diff(np.asarray(la)) < 0)  # stiffer (larger alpha) inflates less


# ------------------------------------------------------------------ derivatives


def _fd_check(f, args, rel=1e-6, rtol=1e-6, alpha_index=2):
    g = jax.grad(f, argnums=tuple(range(len(args))))(*args)
    for i, x in enumerate(args):
        h = rel * abs(x) if i != alpha_index else rel * max(abs(x), 0.1)  # absolute step for tiny alpha
        up = list(args)
        dn = list(args)
        up[i] += h
        dn[i] -= h
        fd = (float(f(*up)) - float(f(*dn))) / (2 * h)
        assert float(g[i]) == pytest.approx(fd, rel=rtol, abs=1e-9 * abs(fd) + 1e-300), i


def test_grad_pressure():
    f = lambda la, C_, al, A_, B_: bl.pressure(la, inner_radius=A_, outer_radius=B_, C=C_, alpha=al)
    _fd_check(f, (1.7, 200.0, 0.2, 50e-6, 75e-6))
    _fd_check(f, (1.2, 150.0, 1e-5, 50e-6, 60e-6))


def test_grad_inverse():
    f = lambda p, C_, al, A_, B_: bl.inner_stretch(p, inner_radius=A_, outer_radius=B_, C=C_, alpha=al)
    _fd_check(f, (150.0, 200.0, 0.05, 50e-6, 75e-6))
    _fd_check(f, (800.0, 200.0, 0.2, 50e-6, 75e-6))


def test_grad_limit_point():
    for j in (0, 1):
        f = lambda C_, al, A_, B_: bl.limit_point(inner_radius=A_, outer_radius=B_, C=C_, alpha=al)[j]
        _fd_check(f, (200.0, 0.01, 50e-6, 75e-6), rel=1e-5, rtol=1e-5, alpha_index=1)


# ------------------------------------------------------------------ profiles


def test_profiles_boundary_conditions_and_equilibrium():
    la, alpha = 1.8, 0.2
    pr = bl.profiles(la, **GEO, C=C, alpha=alpha, n=401)
    p = float(bl.pressure(la, **GEO, C=C, alpha=alpha))
    assert float(pr.sigma_r[0]) == pytest.approx(-p, rel=1e-13)
    assert abs(float(pr.sigma_r[-1])) < 1e-12 * p
    r, sr, st = (np.asarray(v) for v in (pr.r, pr.sigma_r, pr.sigma_theta))
    # incompressibility: r^3 - R^3 constant
    R = np.asarray(pr.R)
    np.testing.assert_allclose(r**3 - R**3, (la * A) ** 3 - A**3, rtol=1e-12)
    # radial equilibrium d sigma_r/dr = 2 (sigma_theta - sigma_r)/r (second-order FD on the grid)
    dsr = np.gradient(sr, r, edge_order=2)
    rhs = 2 * (st - sr) / r
    np.testing.assert_allclose(dsr[1:-1], rhs[1:-1], rtol=2e-4)
    np.testing.assert_allclose(np.asarray(pr.von_mises), np.abs(st - sr), rtol=1e-14)


# ------------------------------------------------------------------ validation


@pytest.mark.parametrize(
    "kw, message",
    [
        (dict(inner_radius=-1e-6, outer_radius=75e-6, C=C, alpha=0.0), r"^inner_radius must be positive \(in m\)"),
        (
            dict(inner_radius=75e-6, outer_radius=75e-6, C=C, alpha=0.0),
            r"^inner_radius must be smaller than outer_radius",
        ),
        (
            dict(inner_radius=80e-6, outer_radius=75e-6, C=C, alpha=0.0),
            r"^inner_radius must be smaller than outer_radius",
        ),
        (
            dict(inner_radius=A, outer_radius=75e-6, C=0.0, alpha=0.0),
            r"^C \(the Fung stiffness.*must be positive \(in Pa\)",
        ),
        (
            dict(inner_radius=A, outer_radius=75e-6, C=-5.0, alpha=0.0),
            r"^C \(the Fung stiffness.*must be positive \(in Pa\)",
        ),
        (
            dict(inner_radius=A, outer_radius=75e-6, C=C, alpha=-0.1),
            r"^alpha \(the Fung stiffening exponent\) must be >= 0",
        ),
        (
            dict(inner_radius=A, outer_radius=75e-6, C=C, alpha=float("nan")),
            r"^alpha \(the Fung stiffening exponent\) must be finite",
        ),
    ],
)
def test_bad_parameters_raise(kw, message):
    """Each entry point names the bad parameter (numerics downstream would raise ValueErrors of their own, e.g.
    'exceeds the limit pressure -21.3 Pa' for swapped radii: a bare ``pytest.raises(ValueError)`` passed on those)."""
    with pytest.raises(ValueError, match=message):
        bl.pressure(1.5, **kw)
    with pytest.raises(ValueError, match=message):
        bl.inner_stretch(10.0, **kw)
    with pytest.raises(ValueError, match=message):
        bl.limit_point(**kw)
    with pytest.raises(ValueError, match=message):
        bl.profiles(1.5, **kw)


@pytest.mark.parametrize("la", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_stretch_raises(la):
    with pytest.raises(ValueError, match="inner_stretch"):
        bl.pressure(la, **GEO, C=C, alpha=0.1)
    with pytest.raises(ValueError, match="inner_stretch"):
        bl.outer_stretch(la, **GEO)


def test_other_bad_inputs_raise():
    with pytest.raises(ValueError, match="method"):
        bl.pressure(1.5, **GEO, C=C, alpha=0.1, method="simpson")
    with pytest.raises(ValueError, match="pressure"):
        bl.inner_stretch(float("nan"), **GEO, C=C, alpha=0.1)
    with pytest.raises(ValueError, match="smallest inner stretch"):
        bl.inner_stretch(-1e6, **GEO, C=C, alpha=0.1)
    with pytest.raises(ValueError, match="largest inner stretch"):
        bl.inner_stretch(1e30, **GEO, C=C, alpha=0.1)
    with pytest.raises(ValueError, match="at least 2"):
        bl.profiles(1.5, **GEO, C=C, alpha=0.1, n=1)


def test_bounded_inverse_stays_on_the_first_branch():
    """A Fung shell with a limit point re-stiffens far beyond it: past the limit pressure the unbounded
    inverse may return that far branch (lambda_a ~ 9); bounded by the limit stretch it says 'bursts'
    (NaN), and below the limit both agree with the forward map."""
    geo = dict(inner_radius=50e-6, outer_radius=52.84e-6, C=200.0, alpha=0.0357)
    lim = bl.limit_point(**geo)
    far, ok = bl.inner_stretch_solve(962.8, **geo)
    assert bool(ok) and float(far) > 3 * float(lim.inner_stretch)  # the far, re-stiffening branch
    la, ok = bl.inner_stretch_solve(962.8, **geo, max_inner_stretch=lim.inner_stretch)
    assert not bool(ok) and np.isnan(float(la))
    p = np.linspace(0.05, 0.99, 25) * float(lim.pressure)
    la, ok = bl.inner_stretch_solve(p, **geo, max_inner_stretch=lim.inner_stretch)
    assert np.all(np.asarray(ok)) and np.all(np.asarray(la) <= float(lim.inner_stretch))
    np.testing.assert_allclose(np.asarray(bl.pressure(np.asarray(la), **geo)), p, rtol=1e-10)


# ------------------------------------------------------------------ eager calls run the compiled cores (issue 14)


def _rel(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape
    assert np.array_equal(np.isnan(a), np.isnan(b))
    m = ~np.isnan(a)
    return float(np.max(np.abs(a[m] - b[m]) / np.maximum(np.abs(b[m]), 1e-300), initial=0.0))


@pytest.mark.parametrize("n", [1, 300, 1500])  # scalar-like, padded bucket, exact shape
def test_eager_equals_jit(n):
    rng = np.random.default_rng(10 + n)
    la = rng.uniform(0.6, 4.0, n)
    al = rng.uniform(0.0, 0.3, n)
    Bs = rng.uniform(52e-6, 100e-6, n)
    p = np.asarray(bl.pressure(la, **GEO, C=C, alpha=0.2))
    cases = [
        (lambda x, a: bl.pressure(x, **GEO, C=C, alpha=a), (la, al)),
        (lambda x, a: bl.pressure_derivative(x, **GEO, C=C, alpha=a), (la, al)),
        (lambda x, a: bl.outer_stretch(x, **GEO), (la, al)),
        (lambda q, a: bl.inner_stretch(q, **GEO, C=C, alpha=0.2), (p, al)),
        (lambda x, a: bl.profiles(x, **GEO, C=C, alpha=a, n=7), (la, al)),
        (lambda b, a: bl.limit_point(inner_radius=A, outer_radius=b, C=C, alpha=0.05 * a), (Bs, al)),
    ]
    for f, args in cases:
        eager, jitted = f(*args), jax.jit(f)(*args)
        for e, j in zip(jax.tree_util.tree_leaves(eager), jax.tree_util.tree_leaves(jitted)):
            assert _rel(e, j) <= 1e-14
    # scalar in, scalar out (0-d), equal to the array call
    assert np.shape(bl.pressure(1.5, **GEO, C=C, alpha=0.2)) == ()
    assert float(bl.pressure(1.5, **GEO, C=C, alpha=0.2)) == float(
        bl.pressure(np.array([1.5]), **GEO, C=C, alpha=0.2)[0]
    )


def test_eager_stiff_entries_still_error_controlled():
    """Entries the one-panel rule cannot resolve (NaN under jit) are redone eagerly with more panels."""
    la = np.array([1.5, 3.0, 6.0])
    eager = np.asarray(bl.pressure(la, **GEO, C=C, alpha=5.0))
    jitted = np.asarray(jax.jit(lambda x: bl.pressure(x, **GEO, C=C, alpha=5.0))(la))
    assert np.all(np.isfinite(eager)) and np.isnan(jitted[-1])
    ref = [fung_quad(x, A, 75e-6, C, 5.0) for x in la]
    np.testing.assert_allclose(eager, ref, rtol=1e-10)
    pr = bl.profiles(la, **GEO, C=C, alpha=5.0, n=9)  # the through-wall integral, redone the same way
    assert np.all(np.isfinite(np.asarray(pr.sigma_r)))
    np.testing.assert_allclose(np.asarray(pr.sigma_r[:, 0]), -eager, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(pr.sigma_r[:, -1]), 0.0, atol=1e-12 * eager.max())
    np.testing.assert_allclose(np.asarray(pr.von_mises), np.abs(np.asarray(pr.sigma_theta - pr.sigma_r)), rtol=1e-12)


def test_chunked_limit_point_equals_unchunked():
    rng = np.random.default_rng(11)
    n = 2 * bl._LIMIT_CHUNK + 37  # scanned in blocks inside the compiled core
    Bs = rng.uniform(52e-6, 100e-6, n)
    al = rng.uniform(0.0, 0.06, n)
    whole = bl.limit_point(inner_radius=A, outer_radius=Bs, C=C, alpha=al)
    assert 0 < np.mean(np.isnan(np.asarray(whole.pressure))) < 1
    for s in (slice(0, 500), slice(1990, 2110), slice(n - 300, n)):  # one block each
        part = bl.limit_point(inner_radius=A, outer_radius=Bs[s], C=C, alpha=al[s])
        assert _rel(whole.pressure[s], part.pressure) <= 1e-15
        assert _rel(whole.inner_stretch[s], part.inner_stretch) <= 1e-15
    for i in (0, 2100):  # scalar calls agree too
        one = bl.limit_point(inner_radius=A, outer_radius=float(Bs[i]), C=C, alpha=float(al[i]))
        if one is None:
            assert np.isnan(float(whole.pressure[i]))
        else:
            assert one.pressure == pytest.approx(float(whole.pressure[i]), rel=1e-15)


def test_limit_point_fields_are_floats_for_scalar_input():
    lim = bl.limit_point(**GEO, C=C, alpha=0.0)
    assert type(lim.pressure) is float and type(lim.inner_stretch) is float
    assert lim.pressure == lim[0] and lim.inner_stretch == lim[1]
    arr = bl.limit_point(**GEO, C=C, alpha=np.array([0.0, 0.01]))
    assert np.shape(arr.pressure) == (2,) and np.shape(arr.inner_stretch) == (2,)


def test_ode_rtol_reaches_the_integrator():
    la = np.linspace(1.1, 3.5, 9)
    q = np.asarray(bl.pressure(la, **GEO, C=C, alpha=0.2))
    loose = np.asarray(bl.pressure(la, **GEO, C=C, alpha=0.2, method="ode", rtol=1e-3))
    tight = np.asarray(bl.pressure(la, **GEO, C=C, alpha=0.2, method="ode", rtol=1e-12))
    assert np.max(np.abs(loose / q - 1)) > 1e-9  # a loose tolerance changes the answer
    np.testing.assert_allclose(tight, q, rtol=1e-12, atol=0)  # a tight one agrees with the quadrature
    under_jit = jax.jit(lambda x: bl.pressure(x, **GEO, C=C, alpha=0.2, method="ode", rtol=1e-3))(la)
    np.testing.assert_allclose(np.asarray(under_jit), loose, rtol=1e-14)
    for bad in (0.0, -1e-6, float("nan"), "tight"):
        with pytest.raises(ValueError, match="rtol"):
            bl.pressure(la, **GEO, C=C, alpha=0.2, method="ode", rtol=bad)


def _inverse_inputs(alpha, n, m, seed):
    """(stretches, pressures, limit point) for inverse tests: n stretches up to just below the limit point, the
    first m within 1e-9..1e-3 of 1 (both sides); then 10 pressures 0, 10 far below the deflation range
    (not converged) and, where there is a limit point, 10 just above it (not converged)."""
    rng = np.random.default_rng(seed)
    lim = bl.limit_point(**GEO, C=C, alpha=alpha)
    top = float(lim.inner_stretch) - 1e-3 if lim is not None else (4.0 if alpha < 1 else 2.5)
    la = rng.uniform(0.55, top, n)
    la[:m] = 1.0 + rng.choice([-1.0, 1.0], m) * 10 ** rng.uniform(-9, -3, m)
    p = np.array(bl.pressure(la, **GEO, C=C, alpha=alpha))
    p[m : m + 10] = 0.0
    p[m + 10 : m + 20] = -1e12 * C  # below the smallest covered stretch: not converged
    if lim is not None:
        p[m + 20 : m + 30] = 1.01 * float(lim.pressure)  # above the limit point
    return la, p, lim


@pytest.mark.parametrize("alpha", [0.0, 0.2, 1.0])
def test_large_one_shell_inverse_equals_per_lane_path(alpha):
    """A large call for one shell starts from a table of the curve (one 20-point Newton step per lane);
    the same pressures with per-lane shell parameters take the two-stage Newton path: same answers
    (1e-13), same converged pattern, including pressures near 0, exactly 0, negative, beyond the
    deflation range and (neo-Hookean) above the limit point."""
    n = 3 * 1024 + 17  # more than two chunks, not a multiple of the chunk
    la, p, lim = _inverse_inputs(alpha, n, 200, 20)
    one, ok1 = bl.inner_stretch_solve(p, **GEO, C=C, alpha=alpha)
    per, ok2 = bl.inner_stretch_solve(p, inner_radius=np.full(n, A), outer_radius=75e-6, C=C, alpha=alpha)
    one, per, ok1, ok2 = (np.asarray(v) for v in (one, per, ok1, ok2))
    assert np.array_equal(ok1, ok2)
    assert not ok1[210:220].any() and ok1[:210].all()
    if lim is not None:
        assert not ok1[220:230].any()
    np.testing.assert_array_equal(one[200:210], 1.0)
    # (2e-13: next to the neo-Hookean limit point, lambda_a ~ 1.602 of 1.603, dp/dlambda -> 0 and the two paths'
    # converged residuals map to stretches ~1e-13 apart)
    np.testing.assert_allclose(one[ok1], per[ok1], rtol=2e-13, atol=0)
    good = ok1.copy()
    good[:230] = False
    np.testing.assert_allclose(one[good], la[good], rtol=1e-11, atol=0)


@pytest.mark.parametrize("alpha", [0.0, 0.2, 1.0])
def test_small_inverse_calls_equal_the_two_stage_path(alpha):
    """Calls of up to 2048 points run the 20-point Newton from the small-strain guess (one loop to compile);
    larger calls with per-lane shells run a 6-point stage first: the same stretches (1e-13) and the same
    converged pattern, including p = 0, pressures beyond the deflation range and above the limit point."""
    n = 600
    la, p, lim = _inverse_inputs(alpha, n, 50, 21)
    small, ok_s = (np.asarray(v) for v in bl.inner_stretch_solve(p, **GEO, C=C, alpha=alpha))
    big, ok_b = bl.inner_stretch_solve(
        np.tile(p, 4), inner_radius=np.full(4 * n, A), outer_radius=75e-6, C=C, alpha=alpha
    )
    big, ok_b = np.asarray(big)[:n], np.asarray(ok_b)[:n]
    assert np.array_equal(ok_s, ok_b)
    assert not ok_s[60:70].any() and ok_s[:60].all()
    if lim is not None:
        assert not ok_s[70:80].any()
    np.testing.assert_allclose(small[ok_s], big[ok_s], rtol=1e-13, atol=0)
    good = ok_s.copy()
    good[:80] = False  # (beyond it: not converged only where the one-panel rule cannot resolve the state)
    assert good.sum() > 400
    np.testing.assert_allclose(small[good], la[good], rtol=1e-11, atol=0)


def test_one_point_fast_path_equals_array_path():
    """Python floats and size-1 arrays of any rank take the one-point path: the same values as the
    same point inside a larger call, the broadcast shape, and bad one-point input still raises."""
    kw = dict(**GEO, C=C, alpha=0.2)
    two = np.array([1.5, 2.5])
    ref = {
        "pressure": bl.pressure(two, **kw)[0],
        "pressure_derivative": bl.pressure_derivative(two, **kw)[0],
        "outer_stretch": bl.outer_stretch(two, **GEO)[0],
        "inner_stretch": bl.inner_stretch(np.array([150.0, 100.0]), **kw)[0],
        "profiles": bl.profiles(two, **kw).sigma_theta[0],
    }
    for x, shape in ((1.5, ()), (np.float64(1.5), ()), (np.array([1.5]), (1,)), (np.array([[1.5]]), (1, 1))):
        got = {
            "pressure": bl.pressure(x, **kw),
            "pressure_derivative": bl.pressure_derivative(x, **kw),
            "outer_stretch": bl.outer_stretch(x, **GEO),
            "inner_stretch": bl.inner_stretch(x * 100.0, **kw),
            "profiles": bl.profiles(x, **kw).sigma_theta,
        }
        for name, v in got.items():
            assert isinstance(v, np.ndarray)
            assert v.shape == (shape + (50,) if name == "profiles" else shape), name
            np.testing.assert_allclose(v.reshape(np.shape(ref[name])), ref[name], rtol=1e-14, atol=0)
    lim = bl.limit_point(inner_radius=A, outer_radius=75e-6, C=C, alpha=0.01)
    lim1 = bl.limit_point(inner_radius=A, outer_radius=np.array([75e-6]), C=C, alpha=0.01)
    assert isinstance(lim.pressure, float) and lim1.pressure.shape == (1,)
    assert lim.pressure == pytest.approx(float(lim1.pressure[0]), rel=1e-14)
    assert bl.limit_point(inner_radius=A, outer_radius=75e-6, C=C, alpha=0.2) is None
    with pytest.raises(ValueError, match="inner_stretch must be positive"):
        bl.pressure(-1.0, **kw)
    with pytest.raises(ValueError, match="inner_radius must be smaller than outer_radius"):
        bl.pressure(1.5, inner_radius=1e-4, outer_radius=5e-5, C=C, alpha=0.2)
    with pytest.raises(ValueError, match="alpha"):
        bl.inner_stretch(10.0, **GEO, C=C, alpha=-0.1)
    with pytest.raises(ValueError, match="limit pressure"):
        bl.inner_stretch(250.0, **GEO, C=C, alpha=0.0)


@pytest.mark.parametrize("la", [0.7, 1e-2, 1e-3, 1e-5, 1e-8])
def test_strong_deflation_against_the_neo_hookean_closed_form(la):
    """p = C [4 (1/lb - 1/la) + (1/lb^4 - 1/la^4)] for W = C (I1 - 3), down to the collapse (both methods, profiles):
    the width log(la / lb) was formed from 1 + e (1 - k)/(1 + e k) -> 0 and lost digits (2e-8 at 1e-3, 2 % at 1e-5,
    an error at 1e-6), and the profile's hoop stretch was 0 at 1e-10."""
    import warnings

    lb = (1 + (la**3 - 1) * (A / 75e-6) ** 3) ** (1 / 3)
    exact = C * (4 * (1 / lb - 1 / la) + (1 / lb**4 - 1 / la**4))
    geo = dict(inner_radius=A, outer_radius=75e-6, C=C, alpha=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for method in ("quadrature", "ode"):
            assert float(bl.pressure(la, **geo, method=method)) == pytest.approx(exact, rel=1e-12)
        pr = bl.profiles(la, **geo, n=5)
        assert float(np.asarray(pr.sigma_r)[0]) == pytest.approx(-exact, rel=1e-12)
        assert np.asarray(pr.stretch)[0] == pytest.approx(la, rel=1e-14)


@pytest.mark.parametrize("scale", [1e-105, 1e-30, 1e30, 1e200])
def test_the_shell_is_scale_free(scale):
    """Only A/B enters: radii of 1e-105 m or 1e200 m give the same pressure and inverse as 50 / 100 um (1 - k was
    formed with B^3, which under/overflowed there and gave messages blaming the quadrature)."""
    ref = dict(inner_radius=50e-6, outer_radius=100e-6, C=C, alpha=0.2)
    geo = dict(ref, inner_radius=scale, outer_radius=2 * scale)
    assert float(bl.pressure(2.0, **geo)) == pytest.approx(float(bl.pressure(2.0, **ref)), rel=1e-14)
    assert float(bl.inner_stretch(100.0, **geo)) == pytest.approx(float(bl.inner_stretch(100.0, **ref)), rel=1e-13)


def test_concrete_parameters_inside_a_users_jit():
    """Every public function called with plain-number parameters INSIDE a user's jit (only another value traced):
    the compiled cores are staged into the user's program and their outputs are tracers; the functions return them
    (the traced conventions: NaN where there is no state or no maximum) instead of converting them to NumPy, which
    raised TracerArrayConversionError (`tissuemech scan blastula` with its defaults crashed on it)."""
    g = dict(inner_radius=A, outer_radius=75e-6, C=C, alpha=0.0)
    q = jnp.float64(0.0)
    cases = {
        "limit_point": (lambda: bl.limit_point(**g).pressure, bl.limit_point(**g).pressure),
        "inner_stretch": (lambda: bl.inner_stretch(100.0, **g), bl.inner_stretch(100.0, **g)),
        "pressure": (lambda: bl.pressure(1.5, **g), bl.pressure(1.5, **g)),
        "pressure arrays": (lambda: bl.pressure(np.array([1.5, 2.0]), **g), bl.pressure(np.array([1.5, 2.0]), **g)),
        "pressure_derivative": (lambda: bl.pressure_derivative(1.5, **g), bl.pressure_derivative(1.5, **g)),
        "outer_stretch": (
            lambda: bl.outer_stretch(1.5, inner_radius=A, outer_radius=75e-6),
            bl.outer_stretch(1.5, inner_radius=A, outer_radius=75e-6),
        ),
        "profiles": (lambda: bl.profiles(1.5, **g, n=3).sigma_r, bl.profiles(1.5, **g, n=3).sigma_r),
    }
    for name, (traced, eager) in cases.items():
        out = jax.jit(lambda q, f=traced: f() + q)(q)
        np.testing.assert_allclose(np.asarray(out), np.asarray(eager), rtol=1e-13, atol=1e-12, err_msg=name)
    past = jax.jit(lambda q: bl.inner_stretch(np.array([100.0, 300.0]), **g) + q)(q)  # 300 Pa: past the limit
    assert np.isfinite(past[0]) and np.isnan(past[1])


def test_regrouped_inverse_takes_the_per_block_loops_steps():
    """Large calls with per-lane shells run each Newton stage in two phases: a few steps for every lane, then the
    unfinished lanes (near-flat curves of small alpha that converge linearly) regrouped into the first blocks for
    the rest. Lane by lane the same steps as the loops per block of 1024 (``_solve_block``): the same stretches
    (to the last bits) and the same converged and rule flags, on random shells and lanes near and above the limit
    point, at p = 0 and beyond the deflation range."""
    import jax

    from tissuemech.compare.bench.reduced_blastula import random_shells

    n = 4 * bl._CHUNK
    sh = random_shells(n, seed=3)
    pt = np.asarray(sh["pressure"] / sh["C"], dtype=float)
    pt[:8] = 0.0
    pt[8:16] = -1e12
    k, omk = bl._geometry(sh["A"], sh["B"])
    args = [np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy() for v in (pt, k, omk, sh["alpha"])]
    B, al = (np.broadcast_to(np.asarray(v, dtype=float), (n,))[16:24] for v in (sh["B"], sh["alpha"]))
    lim = bl.limit_point(inner_radius=sh["A"], outer_radius=B, C=1.0, alpha=al)
    args[0][16:24] = np.where(np.isnan(lim.pressure), 1e3, 1.001 * np.nan_to_num(lim.pressure))  # above the limit
    mx = np.full(n, bl.INVERSE_STRETCH_RANGE[1])
    new = [np.asarray(v) for v in bl._solve_stretch(*args, mx)]
    blocks = tuple(v.reshape(-1, bl._CHUNK) for v in (*args, mx))
    old = [np.asarray(v).ravel() for v in jax.jit(lambda b: jax.lax.map(lambda c: bl._solve_block(*c), b))(blocks)]
    for a, b in zip(new[1:], old[1:]):
        assert np.array_equal(a, b)
    ok = new[1]
    assert ok[8:].sum() > 0.97 * (n - 8) and not ok[8:16].any()
    np.testing.assert_allclose(new[0][ok], old[0][ok], rtol=1e-14, atol=0)
    np.testing.assert_allclose(new[0][24:][ok[24:]], np.asarray(sh["stretch"])[24:][ok[24:]], rtol=1e-11)


@pytest.mark.parametrize("n", [8, 3 * 1024 + 5])
def test_inverse_solve_of_non_finite_pressure_is_nan(n):
    """``inner_stretch_solve`` (no input check) gives NaN and converged False for a pressure of NaN, +inf or -inf,
    eager and under jit, in small calls and in large per-lane calls (the search would otherwise stop at its
    bracket's end, lambda_a = 0.5 for -inf: a number that is no state)."""
    import jax

    p = np.full(n, 100.0)
    p[:3] = [np.nan, np.inf, -np.inf]
    B = np.full(n, 75e-6)
    kw = dict(inner_radius=A, outer_radius=B, C=C, alpha=0.2)
    for fn in (bl.inner_stretch_solve, jax.jit(lambda q: bl.inner_stretch_solve(q, **kw))):
        la, ok = (np.asarray(v) for v in (fn(p, **kw) if fn is bl.inner_stretch_solve else fn(p)))
        assert np.isnan(la[:3]).all() and not ok[:3].any()
        assert ok[3:].all()
        np.testing.assert_allclose(la[3:], float(bl.inner_stretch(100.0, **{**kw, "outer_radius": 75e-6})), rtol=1e-12)


def test_small_call_programs_equal_the_default_programs():
    """Eager calls of up to ~1000 points run the cores compiled with XLA options that favour compile time
    (``reduced.programs``): the same values as the cores with XLA's defaults, to rounding, at one point and at 64
    points; inside a user's trace the core itself is staged (a nested program cannot take compiler options)."""
    from tissuemech.reduced.programs import small_call

    rng = np.random.default_rng(3)
    one = np.array([A, 75e-6, C, 0.01])
    n = 64
    many = (np.full(n, A), A * rng.uniform(1.05, 1.6, n), np.full(n, C), rng.uniform(0.0, 0.3, n))
    la = rng.uniform(1.01, 1.4, n)
    p = np.asarray(bl.pressure(la, inner_radius=many[0], outer_radius=many[1], C=C, alpha=many[3]))
    cases = [
        (bl._limit_core, (one,), True),
        (bl._inverse_core, (np.array(100.0), one), True),
        (bl._pressure_core, (np.array(1.5), one), True),
        (bl._limit_core, (many,), False),
        (bl._inverse_core, (p, many), False),
        (bl._pressure_core, (la, many), False),
    ]
    for core, args, one_point in cases:
        program = small_call(core, one_point=one_point)
        assert program is not core
        for got, want in zip(jax.tree_util.tree_leaves(program(*args)), jax.tree_util.tree_leaves(core(*args))):
            got, want = np.asarray(got), np.asarray(want)
            if want.dtype == bool:
                np.testing.assert_array_equal(got, want)
            else:
                np.testing.assert_allclose(got, want, rtol=4e-15, atol=0, err_msg=core.__name__)
    staged = []
    jax.jit(lambda q: staged.append(small_call(bl._pressure_core, one_point=True)) or q)(1.0)
    assert staged == [bl._pressure_core]


def test_large_pressure_calls_sum_the_rule_node_by_node_to_the_same_values():
    """Calls of at least ``_NODE_LOOP_MIN`` points sum the 20-point rule one node at a time (one fused pass over the
    points), smaller ones with the nodes as a trailing axis: the same pressures to rounding, on random shells."""
    rng = np.random.default_rng(11)
    n = bl._NODE_LOOP_MIN + 7
    B = A * rng.uniform(1.03, 1.6, n)
    alpha = rng.uniform(0.0, 0.3, n)
    la = rng.uniform(0.8, 2.0, n)
    large = np.asarray(bl.pressure(la, inner_radius=A, outer_radius=B, C=C, alpha=alpha))
    small = np.concatenate(
        [
            np.asarray(
                bl.pressure(
                    la[i : i + 1000], inner_radius=A, outer_radius=B[i : i + 1000], C=C, alpha=alpha[i : i + 1000]
                )
            )
            for i in range(0, n, 1000)
        ]
    )
    np.testing.assert_allclose(large, small, rtol=1e-14, atol=1e-300)
