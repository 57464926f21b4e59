"""FE engine physics/consistency checks: meshes, kinematics, Fung tangent, assembly, Newton."""

import numpy as np
import pytest
import scipy.sparse as sp

from tissuemech.fem import constitutive as cm
from tissuemech.fem.forms import Assembler, Material
from tissuemech.fem.kinematics import IDENTITY5, first_from_second, invariants, second_from_first
from tissuemech.fem.mesh import ball_section, graded_points, shell_section
from tissuemech.fem.newton import NewtonError, newton

RNG = np.random.default_rng(7)


def _fd(fun, x, dx, h=1e-6):
    return (fun(x + h * dx) - fun(x - h * dx)) / (2 * h)


def test_shell_section_volume_and_tags():
    m = shell_section(50e-6, 75e-6, 4, 8)
    a = Assembler(m)
    exact = 2 * np.pi / 3 * (1.5**3 - 1)  # half of the hollow ball, scaled by A
    err8 = abs(a.volume() / exact - 1)
    err16 = abs(Assembler(shell_section(50e-6, 75e-6, 4, 16)).volume() / exact - 1)
    assert err8 < 1e-5 and err16 < err8 / 12  # quadratic geometry: O(h^4) volume error
    X = m.X
    assert np.allclose(np.hypot(*X[:, m.nodes["inner"]]), 1.0)
    assert np.allclose(np.hypot(*X[:, m.nodes["outer"]]), 1.5)
    assert np.allclose(X[0, m.nodes["axis"]], 0.0) and np.allclose(X[1, m.nodes["symmetry"]], 0.0)
    assert m.edges["inner"].shape == (8, 3)


def test_ball_section_volume_tags_grading():
    m = ball_section(500e-6, 6, 4, grading=3.0, pole_grading=3.0)
    a = Assembler(m)
    assert np.all(m.basis.dx > 0)
    assert abs(a.volume() / (2 * np.pi / 3) - 1) < 1e-5
    X = m.X
    assert np.allclose(X[0, m.nodes["axis"]], 0) and np.allclose(X[1, m.nodes["symmetry"]], 0)
    assert np.allclose(np.hypot(*X[:, m.nodes["outer"]]), 1.0)
    # surface tag covers the whole quarter arc: its edges' chord lengths add up to ~ pi/2
    e = m.edges["outer"]
    assert abs(np.sum(np.hypot(*(X[:, e[:, 2]] - X[:, e[:, 0]]))) - np.pi / 2) < 1e-2
    # graded toward the pole: the outer edge at the axis is shorter than at the equator
    L = np.hypot(*(X[:, e[:, 2]] - X[:, e[:, 0]]))
    top = np.argmax(np.max(X[1, e], axis=1))
    bottom = np.argmin(np.max(X[1, e], axis=1))
    assert L[top] < 0.7 * L[bottom]


def test_graded_points_ratio():
    p = graded_points(5, 4.0)
    h = np.diff(p)
    assert p[0] == 0 and abs(p[-1] - 1) < 1e-15 and abs(h[-1] / h[0] - 4) < 1e-12
    with pytest.raises(ValueError, match="at least one division"):
        graded_points(0)


@pytest.mark.parametrize("alpha", [0.0, 0.3])
def test_fung_stress_and_tangent_finite_differences(alpha):
    f = IDENTITY5 + 0.2 * RNG.standard_normal((6, 5))
    P, A = cm.iso_stress(f, 1.3, alpha)
    for k in range(5):
        e = np.eye(5)[k]
        Pn = _fd(lambda g: cm.iso_energy(g, 1.3, alpha), f, e)
        An = _fd(lambda g: cm.iso_stress(g, 1.3, alpha)[0], f, e)
        assert np.abs(P[:, k] - Pn).max() < 1e-7
        assert np.abs(A[:, :, k] - An).max() < 1e-6


def test_total_stress_lazy_tangent_is_the_eager_one_bitwise():
    """tangent="lazy" returns the stress pass's P and J and a callable giving the same w A as tangent=True,
    bit for bit, for the mixed (q), penalty (kappa) and extra-stress variants; tangent=False gives no A."""
    f = IDENTITY5 + 0.2 * RNG.standard_normal((4, 3, 5))
    w, q, S0 = RNG.uniform(0.5, 1.5, (4, 3)), RNG.standard_normal((4, 3)), 0.1 * RNG.standard_normal((4, 3, 5))
    for kw in (dict(q=q), dict(kappa=50.0), dict(q=q, extra_S=S0, iso_scale=1.3), dict(kappa=50.0, extra_S=S0)):
        P, A, J = cm.total_stress(f, 1.3, 0.3, weight=w, **kw)
        Pl, Al, Jl = cm.total_stress(f, 1.3, 0.3, weight=w, tangent="lazy", **kw)
        assert callable(Al) and np.array_equal(Pl, P) and np.array_equal(Jl, J) and np.array_equal(Al(), A)
        assert cm.total_stress(f, 1.3, 0.3, weight=w, tangent=False, **kw)[1] is None


def test_assembler_stress_without_tangent_is_the_stress_with_it():
    """``Assembler.stress(..., tangent=False)`` (the fused kernel, no 5 x 5 tangent; what the output fields use)
    gives the P and q of the separate iso + volumetric + extra-stress path to round-off, mixed and penalty."""
    from tissuemech.fem.forms import Assembler, Material
    from tissuemech.fem.mesh import shell_section

    S0 = 0.1 * RNG.standard_normal((32, 9, 5))
    for form in ("mixed", "displacement"):
        asm = Assembler(shell_section(50e-6, 75e-6, 4, 8, intorder=4), form)
        u = 0.003 * RNG.standard_normal(asm.ndof)
        for extra, scale in ((None, 1.0), (S0, 1.3)):
            f, P, A, q = asm.stress(u, Material(1.0, 0.2, 100.0), extra, scale)
            f2, P2, A2, q2 = asm.stress(u, Material(1.0, 0.2, 100.0), extra, scale, tangent=False)
            assert A2 is None and A.shape == P.shape + (5,) and np.array_equal(f, f2)
            assert np.abs(P2 - P).max() <= 1e-13 * np.abs(P).max()
            assert np.abs(q2 - q).max() <= 1e-13 * max(np.abs(q).max(), 1.0)


def test_neo_hookean_exact_and_stress_free_reference():
    f = IDENTITY5 + 0.1 * RNG.standard_normal((3, 5))
    # the invariants written out here (f = (F_rr, F_rz, F_zr, F_zz, F_tt)), not taken from the package
    I1 = (f**2).sum(-1)
    J = f[:, 4] * (f[:, 0] * f[:, 3] - f[:, 1] * f[:, 2])
    Ib = J ** (-2 / 3) * I1
    assert np.allclose(invariants(f), (I1, J), rtol=1e-15, atol=0)
    assert np.allclose(cm.iso_energy(f, 2.0, 0.0), 2.0 * (Ib - 3), rtol=0, atol=1e-14)
    assert np.allclose(cm.iso_energy(f, 2.0, 0.2), 2.0 / 0.2 * np.expm1(0.2 * (Ib - 3)), rtol=1e-13, atol=0)
    P, _ = cm.iso_stress(IDENTITY5[None], 1.0, 0.3)
    assert np.abs(P).max() < 1e-15
    # S = F^-1 P is symmetric; F S returns P
    S = second_from_first(f, cm.iso_stress(f, 1.0, 0.3)[0])
    assert np.allclose(S[:, 1], S[:, 2])
    assert np.allclose(first_from_second(f, S), cm.iso_stress(f, 1.0, 0.3)[0])


def test_simple_shear_cauchy_matches_closed_form():
    # simple shear gamma in (r, z): incompressible, sigma_rz = 2 W'(I1) gamma with I1 = 3 + gamma^2
    g, C, alpha = 0.4, 1.0, 0.25
    f = np.array([[1.0, g, 0.0, 1.0, 1.0]])
    P, _ = cm.iso_stress(f, C, alpha)
    sig = cm.cauchy(f, P)
    assert abs(sig[0, 0, 1] - 2 * C * np.exp(alpha * g**2) * g) < 1e-13


@pytest.mark.parametrize("formulation", ["mixed", "displacement"])
def test_assembly_tangent_with_extra_stress_matches_finite_differences(formulation):
    m = shell_section(1.0, 1.5, 2, 3)
    a = Assembler(m, formulation)
    mat = Material(1.0, 0.2, 1e3)
    x = 0.005 * RNG.standard_normal(a.ndof)
    S0 = 0.3 * RNG.standard_normal(a.B.shape[:2] + (5,))
    S0[..., 2] = S0[..., 1]
    r, K = a.internal(x, mat, extra_S=S0, iso_scale=1.7)
    assert abs(K - K.T).max() < 1e-8 * abs(K).max()
    dx = RNG.standard_normal(a.ndof)
    Kn = _fd(lambda y: a.internal(y, mat, S0, 1.7, tangent=False)[0], x, dx, 1e-7)
    assert np.abs(Kn - K @ dx).max() < 1e-7 * np.abs(K @ dx).max()


def test_follower_pressure_tangent_and_resultant():
    m = shell_section(1.0, 1.5, 2, 4)
    a = Assembler(m)
    x = 0.01 * RNG.standard_normal(a.ndof)
    F, K = a.follower_pressure(x, 0.7, m.edges["inner"])
    dx = RNG.standard_normal(a.ndof)
    Kn = _fd(lambda y: a.follower_pressure(y, 0.7, m.edges["inner"], tangent=False)[0], x, dx)
    assert np.abs(Kn - K @ dx).max() < 1e-8
    # uniform expansion by (1 + e): axial resultant on the quarter sphere = p pi a^2 exactly
    e = 0.3
    u = np.zeros(a.ndof)
    u[: a.n_u] = e * m.X.T.ravel()
    F, _ = a.follower_pressure(u, 0.7, m.edges["inner"], tangent=False)
    assert abs(F[1 : a.n_u : 2].sum() - 0.7 * np.pi * (1 + e) ** 2) < 1e-12


def test_newton_cuts_an_overflowing_trial_step_without_runtime_warnings():
    """r(x) = exp(x) - e from x = -10: the first Newton step lands at x ~ 6e4, where exp overflows; the line
    search halves it (12 times) and Newton converges to x = 1. The overflow is handled, so it is not
    reported as a RuntimeWarning."""
    import warnings

    fun = lambda x: (np.exp(x) - np.e, sp.csr_matrix([[float(np.exp(x[0]))]]))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        res = newton(fun, np.array([-10.0]), rtol=1e-14, xtol=1e-14, max_backtracks=20)
    assert abs(res.x[0] - 1.0) < 1e-13


def test_newton_quadratic_convergence_and_clear_error():
    fun = lambda x: (np.array([x[0] ** 3 - 8.0]), sp.csr_matrix([[3 * x[0] ** 2]]))
    res = newton(fun, np.array([3.0]), rtol=1e-14, xtol=1e-14)
    assert abs(res.x[0] - 2.0) < 1e-14
    h = res.residuals
    assert h[-2] < 1e-3 and h[-1] < 10 * h[-2] ** 2 + 1e-15  # quadratic
    sing = lambda x: (np.array([1.0]), sp.csr_matrix([[0.0]]))
    with pytest.raises(NewtonError) as ei:
        newton(sing, np.array([0.0]), load="p = 5 Pa")
    assert "p = 5 Pa" in str(ei.value) and ei.value.residuals and ei.value.hint
    bad = lambda x: (np.array([x[0] - 1.0]), sp.csr_matrix([[1.0]]))
    with pytest.raises(NewtonError, match="line search"):
        newton(bad, np.array([0.0]), admissible=lambda x: "J <= 0" if x[0] > 0.001 else None)


def test_ball_under_outer_follower_pressure_compresses_uniformly():
    """Solid ball, pressure p on its surface: sigma = -p I, q = -p, J = 1 - p/kappa, u = (J^(1/3) - 1) X."""
    m = ball_section(500e-6, 3, 2, grading=2.0, pole_grading=2.0)
    a = Assembler(m)
    mat = Material(1.0, 0.2, 10.0)
    fixed = np.concatenate([2 * m.nodes["axis"], 2 * m.nodes["symmetry"] + 1])
    free = np.setdiff1d(np.arange(a.ndof), fixed)
    p = 1.0

    def fun(x):
        ri, Ki = a.internal(x, mat)
        fp, Kp = a.follower_pressure(x, p, m.edges["outer"])
        return ri - fp, (Ki - Kp).tocsr()

    res = newton(fun, np.zeros(a.ndof), free=free, rtol=1e-12, xtol=1e-12)
    lam = (1 - p / mat.kappa) ** (1 / 3)
    u = res.x[: a.n_u].reshape(-1, 2)
    assert np.abs(u - (lam - 1) * m.X.T).max() < 1e-10
    _, _, _, q = a.stress(res.x, mat)
    assert np.abs(q + p).max() < 1e-9
    assert abs(a.volume(res.x) / a.volume() - lam**3) < 1e-10


def test_arc_length_passes_a_limit_point_and_load_control_stops_there():
    """lam(x) = x exp(-x) has a maximum 1/e at x = 1: Riks passes it, load control reports it."""
    from tissuemech.fem.continuation import LimitPointError, arc_length, load_control

    def fun(x, lam):
        return (np.array([x[0] * np.exp(-x[0]) - lam]), sp.csr_matrix([[(1 - x[0]) * np.exp(-x[0])]]), np.array([-1.0]))

    path = arc_length(fun, np.array([0.0]), 0.0, 0.05, stop=lambda x, lam: x[0] >= 2.0, rtol=1e-12)
    xs = np.array([p[1][0] for p in path])
    lams = np.array([p[0] for p in path])
    assert np.allclose(lams, xs * np.exp(-xs), atol=1e-12)  # every point is an equilibrium
    assert xs[-1] >= 2.0 and lams[-1] < lams.max()  # on the falling branch
    assert abs(lams.max() - np.exp(-1)) < 2e-3

    def solve(lam, guess):
        return newton(
            lambda x: fun(x, lam)[:2],
            guess,
            rtol=1e-12,
            xtol=1e-12,
            load=lam,
            admissible=lambda x: "past the maximum" if x[0] > 1.5 else None,
        )

    with pytest.raises(LimitPointError) as ei:
        load_control(solve, np.linspace(0.05, 0.5, 10), np.array([0.0]), monitor=lambda x: x[0])
    assert np.exp(-1) - 0.05 < ei.value.last_converged <= np.exp(-1) < ei.value.load


@pytest.mark.parametrize("formulation", ["mixed", "displacement"])
@pytest.mark.parametrize("which", ["shell", "ball"])
def test_fast_assembly_equals_reference(formulation, which):
    """Issue 14: the fused, pattern-reusing assembly equals the straightforward one (values and pattern)."""
    m = shell_section(50e-6, 75e-6, 3, 5) if which == "shell" else ball_section(500e-6, 4, 3)
    a = Assembler(m, formulation)
    rng = np.random.default_rng(3)
    X = m.X
    x = np.zeros(a.ndof)
    x[0 : a.n_u : 2] = 0.05 * X[0] + 0.02 * X[0] * X[1]
    x[1 : a.n_u : 2] = -0.04 * X[1] + 0.01 * X[0] ** 2
    x[: a.n_u] += 1e-3 * rng.standard_normal(a.n_u)
    x[a.n_u :] = rng.standard_normal(a.ndof - a.n_u)
    mat = Material(1.0, 0.2, 1e4)
    S0 = rng.standard_normal(a.w.shape + (5,))
    S0[..., 2] = S0[..., 1]
    for kw in ({}, dict(extra_S=S0, iso_scale=1.3)):
        r, K = a.internal(x, mat, **kw)
        r0, K0 = a._internal_reference(x, mat, **kw)
        K0 = K0.tocsr()
        K0.sum_duplicates()
        assert np.abs(r - r0).max() <= 1e-14 * np.abs(r0).max()
        assert np.abs(a.internal(x, mat, tangent=False, **kw)[0] - r0).max() <= 1e-14 * np.abs(r0).max()
        assert sp.isspmatrix_csr(K) and np.array_equal(K.indptr, K0.indptr) and np.array_equal(K.indices, K0.indices)
        assert np.abs(K.data - K0.data).max() <= 1e-14 * np.abs(K0.data).max()


def test_deformation_gradient_is_kept_only_for_an_equal_state_and_is_read_only():
    """Assembler.f_at keeps the last (u, F): an equal u (another array, same values) gets the kept F, a
    changed u (also changed in place) a new one equal to a fresh assembler's, and nobody can write into it."""
    m = shell_section(50e-6, 75e-6, 2, 4)
    a, fresh = Assembler(m), Assembler(m)
    rng = np.random.default_rng(5)
    u = 1e-2 * rng.standard_normal(a.ndof)
    f1 = a.f_at(u)
    assert a.f_at(u.copy()) is f1
    np.testing.assert_array_equal(f1, fresh.f_at(u.copy()))
    with pytest.raises(ValueError, match="read-only"):
        f1[0, 0, 0] = 2.0
    u[a.edofs[0, 0]] += 1e-3  # in place: the kept copy must not follow
    f2 = a.f_at(u)
    assert f2 is not f1 and not np.array_equal(f2, f1)
    np.testing.assert_array_equal(f2, Assembler(m).f_at(u))
    np.testing.assert_array_equal(a.f_at(u[: a.n_u].copy()), f2)  # the displacement dofs alone: the same F
    _, J = invariants(f2)
    np.testing.assert_allclose(J, f2[..., 4] * (f2[..., 0] * f2[..., 3] - f2[..., 1] * f2[..., 2]), rtol=0, atol=0)


def test_ball_section_gauss_rule_degree():
    """ball_section(intorder=4) gives the 3 x 3 rule the fitted meshes use; a rule too low for Q2 is refused."""
    assert ball_section(500e-6, 4, 3, intorder=4).basis.X.shape[1] == 9
    assert ball_section(500e-6, 4, 3).basis.X.shape[1] == 16  # default 2 order + 2 = 6: 4 x 4 points
    for bad in (-1, 0, 3, 2.5, "4", True):
        with pytest.raises(ValueError, match="intorder"):
            ball_section(500e-6, 4, 3, intorder=bad)


def test_ball_section_on_a_known_topology_is_the_full_construction():
    """A second ball_section with the same divisions only moves the nodes (issue 14: fitted meshes): the same
    node positions bit for bit, element dofs, quadrature weights, tags and edges as building it from scratch."""
    from tissuemech.fem import mesh as fm

    rng = np.random.default_rng(7)
    for n_core, n_radial in ((4, 3), (6, 5)):
        for _ in range(2):
            pole = np.r_[0.0, np.sort(rng.uniform(0.05, 0.95, n_core - 1)), 1.0]
            radial = np.r_[0.0, np.sort(rng.uniform(0.05, 0.95, n_radial - 1)), 1.0]
            kw = dict(pole_points=pole, radial_points=radial, split_angle=0.96, intorder=4)
            fm._BALL_TOPOLOGY.clear()
            full = ball_section(500e-6, n_core, n_radial, **kw)
            ball_section(500e-6, n_core, n_radial, split_angle=0.96, intorder=4)  # the topology, other nodes
            moved = ball_section(500e-6, n_core, n_radial, **kw)
            assert moved.mesh is not full.mesh and np.array_equal(moved.X, full.X)
            assert np.array_equal(moved.basis.element_dofs, full.basis.element_dofs)
            assert np.array_equal(moved.basis.dx, full.basis.dx) and moved.length_scale == full.length_scale
            for tags in ("nodes", "edges"):
                a, b = getattr(moved, tags), getattr(full, tags)
                assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


def test_solver_backends_and_submatrix_cache():
    """Every symmetric_solve backend and the cached K[free][:, free] gather give the same answer."""
    from tissuemech.fem import newton as nw

    m = shell_section(50e-6, 75e-6, 3, 6)
    a = Assembler(m)
    x = np.zeros(a.ndof)
    x[: a.n_u] = 1e-3 * np.sin(np.arange(a.n_u))
    _, K = a.internal(x, Material(1.0, 0.2, 1e7))
    fp, Kp = a.follower_pressure(x, 1.0, m.edges["inner"])
    K = (K - 0.7 * Kp).tocsr()  # slightly unsymmetric, and exact zeros dropped from the pattern
    free = np.setdiff1d(np.arange(a.ndof), np.concatenate([2 * m.nodes["axis"], 2 * m.nodes["symmetry"] + 1]))
    Kf = K[free][:, free]
    assert (nw._submatrix(K, free) != Kf).nnz == 0 and (nw._submatrix(K, free) != Kf).nnz == 0  # built, reused
    b = np.cos(np.arange(free.size))
    ref = nw.sparse_solve(Kf, b)
    old = nw.backend()
    try:
        for name in nw.available_backends():
            nw.set_backend(name)
            for _ in range(2):  # plan built, then reused
                xs = nw.symmetric_solve(Kf, b)
                assert np.linalg.norm(Kf @ xs - b) <= 1e-12 * np.linalg.norm(b)
                assert np.allclose(xs, ref, rtol=1e-7, atol=1e-12 * np.abs(ref).max())
        with pytest.raises(ValueError, match="sparse backend"):
            nw.set_backend("umfpack")
    finally:
        nw.set_backend("auto" if old == "auto" else old)


def test_internal_follower_one_pattern_equals_separate_assembly():
    """K_int - p K_p assembled on the element pattern and gathered to the free dofs equals the sparse sum and
    fancy slice it replaces (to round-off); the lazy tangent is the eager one; the pattern never changes (explicit zeros kept)."""
    m = shell_section(50e-6, 75e-6, 3, 6)
    a = Assembler(m)
    mat = Material(1.0, 0.2, 1e7)
    x = np.zeros(a.ndof)
    x[: a.n_u] = 2e-3 * np.sin(np.arange(a.n_u))
    x[a.n_u :] = 0.1 * np.cos(np.arange(a.ndof - a.n_u))
    inner = m.edges["inner"]
    free = np.setdiff1d(np.arange(a.ndof), np.concatenate([2 * m.nodes["axis"], 2 * m.nodes["symmetry"] + 1]))
    S0 = 0.05 * np.ones(a.w.shape + (5,))
    pats = []
    for p, kw in ((0.0, {}), (0.7, {}), (1.3, dict(extra_S=S0, iso_scale=1.2))):
        ri, Ki = a.internal(x, mat, **kw)
        fp, Kp = a.follower_pressure(x, 1.0, inner)
        K0 = (Ki - p * Kp).tocsr()[free][:, free]
        r, f1, K = a.internal_follower(x, mat, p, inner, free=free, **kw)
        assert np.array_equal(r, ri) and np.array_equal(f1, fp)
        assert sp.isspmatrix_csr(K) and K.has_canonical_format and K.shape == (free.size, free.size)
        assert abs(K - K0).max() <= 1e-14 * abs(K0).max()
        _, _, lazy = a.internal_follower(x, mat, p, inner, free=free, tangent="lazy", **kw)
        assert callable(lazy) and np.array_equal(lazy().data, K.data)
        full = a.internal_follower(x, mat, p, inner, **kw)[2]
        assert abs(full - (Ki - p * Kp)).max() <= 1e-14 * abs(K0).max()
        assert a.internal_follower(x, mat, p, inner, tangent=False)[2] is None
        r2, lazy_int = a.internal(x, mat, tangent="lazy", **kw)
        assert np.array_equal(r2, ri) and np.array_equal(lazy_int().data, Ki.data)
        pats.append((K.indptr, K.indices))
    assert all(np.array_equal(ptr, pats[0][0]) and np.array_equal(ind, pats[0][1]) for ptr, ind in pats)  # one plan
    with pytest.raises(ValueError, match="tangent"):
        a.internal_follower(x, mat, 1.0, inner, tangent="yes")


def test_newton_lazy_tangent_same_answer_fewer_assemblies():
    """A lazy tangent gives the same Newton iterates as the eager one, and the converged state's tangent is
    never assembled."""
    from tissuemech.fem import blastula as fb
    from tissuemech.fem.newton import symmetric_solve

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
    calls = {"eager": 0, "lazy": 0}

    def eager(x, lam):
        calls["eager"] += 1
        return prob.rk(x, lam)[:2]

    def lazy(x, lam):
        r, K, _ = prob.rk(x, lam, tangent="lazy")

        def K1():
            calls["lazy"] += 1
            return K()

        return r, K1

    x0 = np.zeros(prob.free.size)
    xe, xl = x0, x0
    opts = dict(ref_norm=prob.ref, rtol=1e-10, xtol=1e-9, atol=prob.floor * 2, admissible=prob.admissible)
    # (steps of at most 1.0 C from the last state, no predictor: the jump 1.0 -> 2.0 converged with the 4 x 4 Gauss
    # rule only after 18 wandering iterations, and wanders off with the scene's 3 x 3 rule: robustness of a bare
    # Newton far from the answer is not what this test is about)
    for lam in (0.5, 1.0, 1.5, 2.0):
        se = newton(lambda x: eager(x, lam), xe, solver=symmetric_solve, **opts)
        sl = newton(lambda x: lazy(x, lam), xl, solver=symmetric_solve, **opts)
        assert se.iterations == sl.iterations and np.allclose(se.residuals, sl.residuals, rtol=1e-12, atol=0)
        assert np.abs(sl.x - se.x).max() <= 1e-12 * np.abs(se.x).max()
        xe, xl = se.x, sl.x
    assert calls["lazy"] == calls["eager"] - 4  # one unused tangent per solve (the converged state's)


def test_supervariable_ordering_same_solution_less_fill():
    """The supervariable minimum-degree ordering of ``symmetric_solve`` gives the pivoted/dense answer to
    1e-12 and fewer fill-ins than MMD on K + K^T on a fine shell tangent; its supervariables are the nodes'
    dof pairs and the elements' interiors (fewer than nodes + elements)."""
    import scipy.sparse.linalg as spla

    from tissuemech.fem import blastula as fb
    from tissuemech.fem import newton as nw

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (12, 24))
    x = 1e-3 * np.sin(np.arange(prob.free.size))
    _, K, _ = prob.rk(x, 0.8)  # with the (unsymmetric) follower block
    b = np.cos(np.arange(K.shape[0]))
    ref = nw.sparse_solve(K, b)
    ref += nw.sparse_solve(K, b - K @ ref)  # one refinement of the pivoted LU: |b - K ref| ~ round-off
    for ordering in ("mmd", "supervariable"):
        for _ in range(2):  # the plan is built, then reused
            xs = nw.symmetric_solve(K, b, ordering=ordering)
            assert np.linalg.norm(K @ xs - b) <= 1e-12 * np.linalg.norm(b)
            assert np.abs(xs - ref).max() <= 1e-12 * np.abs(ref).max()
    fill = {}
    for name, order in (("mmd", nw._mmd), ("supervariable", nw._supervariable_mmd)):
        p = order(K)
        assert np.array_equal(np.sort(p), np.arange(K.shape[0]))
        lu = spla.splu(
            sp.csc_matrix(K[p][:, p]), permc_spec="NATURAL", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True)
        )
        fill[name] = lu.L.nnz + lu.U.nnz
    assert fill["supervariable"] < 0.95 * fill["mmd"]
    Q, sv = nw.supervariables(K)
    assert sv.shape == (K.shape[0],) and Q.shape[0] == sv.max() + 1 < prob.m.X.shape[1] + prob.asm.n_el
    with pytest.raises(ValueError, match="ordering"):
        nw.symmetric_solve(K, b, ordering="amd")


def test_meshes_with_one_connectivity_share_the_pattern():
    """Two assemblers on meshes with the same connectivity (different node positions) share one element
    pattern, and their tangents equal a fresh assembly of the reference path."""
    m1 = shell_section(50e-6, 75e-6, 3, 6)
    m2 = shell_section(50e-6, 80e-6, 3, 6)
    a1, a2 = Assembler(m1), Assembler(m2)
    assert a1._pattern is a2._pattern
    mat = Material(1.0, 0.2, 1e4)
    x = np.zeros(a2.ndof)
    x[: a2.n_u] = 1e-3 * np.sin(np.arange(a2.n_u))
    _, K = a2.internal(x, mat)
    _, K0 = a2._internal_reference(x, mat)
    K0 = K0.tocsr()
    K0.sum_duplicates()
    assert abs(K - K0).max() <= 1e-14 * abs(K0).max()
    assert Assembler(shell_section(50e-6, 75e-6, 4, 6))._pattern is not a1._pattern


def test_newton_keeps_the_factorisation_once_the_residual_has_converged():
    """With ``factor`` newton corrects a converged residual with the kept factorisation (no new tangent or
    factorisation) until the step test passes: the same states to 1e-12 as full Newton with ``solver``, about
    one factorisation fewer per solve, the convergence test unchanged."""
    from tissuemech.fem import blastula as fb
    from tissuemech.fem.newton import symmetric_factor, symmetric_solve

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
    counts = {"solver": 0, "factor": 0}

    def solver(K, b):
        counts["solver"] += 1
        return symmetric_solve(K, b, ordering="supervariable")

    def factor(K):
        counts["factor"] += 1
        return symmetric_factor(K, ordering="supervariable")

    opts = dict(ref_norm=prob.ref, rtol=1e-10, xtol=1e-9, atol=prob.floor * 2, admissible=prob.admissible)
    x_s = x_f = np.zeros(prob.free.size)
    for lam in (0.5, 1.0, 1.5, 2.0, 3.0):  # (load steps a bare Newton from the last state converges from)
        fun = lambda x, lam=lam: prob.rk(x, lam, tangent="lazy")[:2]
        s = newton(fun, x_s, solver=solver, **opts)
        f = newton(fun, x_f, factor=factor, **opts)
        assert np.abs(f.x - s.x).max() <= 1e-12 * np.abs(s.x).max()
        assert f.residuals[-1] <= opts["rtol"] * prob.ref + opts["atol"]
        x_s, x_f = s.x, f.x
    assert counts["factor"] <= counts["solver"] - 5  # at least one factorisation saved per solve
    with pytest.raises(ValueError, match="not both"):
        newton(fun, x_f, solver=solver, factor=factor, **opts)


def test_newton_falls_back_to_full_iterations_when_a_kept_factorisation_fails():
    """A kept factorisation whose solve fails (singular) or gives a bad correction is not used: newton takes
    full iterations instead and converges to the same state."""
    from tissuemech.fem import blastula as fb
    from tissuemech.fem.newton import symmetric_factor

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
    opts = dict(ref_norm=prob.ref, rtol=1e-10, xtol=1e-9, atol=prob.floor * 2, admissible=prob.admissible)
    fun = lambda x: prob.rk(x, 1.0, tangent="lazy")[:2]
    ref = newton(fun, np.zeros(prob.free.size), factor=symmetric_factor, **opts)
    for bad in ("singular", "wild"):
        n = {"factor": 0}

        def factor(K, bad=bad):
            n["factor"] += 1
            solve, used = symmetric_factor(K), [0]

            def once(b):  # the first call is the full iteration's; later ones are the kept corrections
                used[0] += 1
                if used[0] > 1:
                    if bad == "singular":
                        raise np.linalg.LinAlgError("singular")
                    return solve(b) + 1e-2  # a correction far larger than the converging increments
                return solve(b)

            return once

        res = newton(fun, np.zeros(prob.free.size), factor=factor, **opts)
        assert np.abs(res.x - ref.x).max() <= 1e-12 * np.abs(ref.x).max()
        assert n["factor"] == res.iterations  # every iteration factored: no kept correction was accepted


def test_symmetric_factor_solves_many_right_hand_sides():
    """One factorisation answers several right-hand sides as symmetric_solve does (to round-off)."""
    from tissuemech.fem import blastula as fb
    from tissuemech.fem.newton import NEWTON_STEP_RTOL, symmetric_factor, symmetric_solve

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
    x = prob.solve(1.0, np.zeros(prob.free.size), 1e-10, "test").x
    _, K, _ = prob.rk(x, 1.0)
    solve = symmetric_factor(K, ordering="supervariable")
    for k in range(3):
        b = np.cos((k + 1) * np.arange(K.shape[0]))
        x = solve(b)
        assert np.linalg.norm(K @ x - b) <= 1e-12 * np.linalg.norm(b)
        assert np.abs(x - symmetric_solve(K, b, ordering="supervariable")).max() <= 1e-12 * np.abs(x).max()
        assert np.linalg.norm(K @ solve.inexact(b) - b) <= NEWTON_STEP_RTOL * np.linalg.norm(b)
    with pytest.raises(ValueError, match="ordering"):
        symmetric_factor(K, ordering="amd")


def test_newton_steps_solved_to_the_inexact_tolerance_converge_to_the_same_states(monkeypatch):
    """Newton's steps take the factorisation's ``inexact`` solve (refined to 1e-6 |b|, not 1e-13): on a 10-step
    sweep to 5 C of the 8x16 shell the same states as with fully refined solves (a factor without ``inexact``) to
    1e-11 of |x|, in the same number of iterations, with fewer refinement sweeps."""
    from tissuemech.fem import blastula as fb
    from tissuemech.fem import newton as nw

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (8, 16))
    opts = dict(ref_norm=prob.ref, rtol=1e-10, xtol=1e-9, atol=prob.floor * 2, admissible=prob.admissible)
    sweeps = [0]
    refine = nw._refine

    def counted(K, b, x, solve, n, rtol):
        def one(v):
            sweeps[0] += 1
            return solve(v)

        return refine(K, b, x, one, n, rtol)

    monkeypatch.setattr(nw, "_refine", counted)

    def strict(K):
        solve = nw.symmetric_factor(K, ordering="supervariable")
        return lambda b: solve(b)  # a plain function: no ``inexact``, every solve refined to 1e-13

    factors = {"inexact": lambda K: nw.symmetric_factor(K, ordering="supervariable"), "strict": strict}
    x = {k: np.zeros(prob.free.size) for k in factors}
    n_sweeps = dict.fromkeys(factors, 0)
    for lam in np.linspace(0.5, 5.0, 10):
        fun = lambda v, lam=lam: prob.rk(v, lam, tangent="lazy")[:2]
        out = {}
        for k in factors:
            sweeps[0] = 0
            out[k] = nw.newton(fun, x[k], factor=factors[k], **opts)
            n_sweeps[k] += sweeps[0]
        assert out["inexact"].iterations == out["strict"].iterations
        assert np.abs(out["inexact"].x - out["strict"].x).max() <= 1e-11 * np.abs(out["strict"].x).max()
        x = {k: out[k].x for k in x}
    assert n_sweeps["inexact"] < n_sweeps["strict"]


class _FakeLDL:
    """A stand-in for ``qdldl.Solver`` (upper triangle in, refactored in place by ``update``): SuperLU of
    the symmetric matrix it describes. qdldl itself is an optional extra that CI does not install."""

    def __init__(self, U, upper=True):
        self.update(U, upper=upper)

    def update(self, U, upper=True):
        import scipy.sparse as sp
        import scipy.sparse.linalg as spla

        A = (U + sp.triu(U, 1).T).tocsc()
        self.lu = spla.splu(A)

    def solve(self, b):
        return self.lu.solve(b)


def test_a_kept_qdldl_factorisation_refactored_for_another_matrix_refactors_its_own(monkeypatch):
    """qdldl refactors one solver per pattern in place: a solve kept from before refactors its own matrix
    (one numeric factorisation) instead of silently solving with the other matrix's factors."""
    import threading
    from types import SimpleNamespace

    from tissuemech.fem import blastula as fb
    from tissuemech.fem import newton as nw

    updates = [0]

    class Counting(_FakeLDL):
        def update(self, U, upper=True):
            updates[0] += 1
            super().update(U, upper=upper)

    monkeypatch.setattr(nw, "_qdldl", SimpleNamespace(Solver=Counting))
    monkeypatch.setattr(nw, "_BACKEND", ["qdldl"])
    monkeypatch.setattr(nw, "_TLS", threading.local())  # no plan (and no real qdldl solver) from other tests
    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
    x = prob.solve(1.0, np.zeros(prob.free.size), 1e-10, "test").x
    K1 = prob.rk(x, 1.0)[1]
    K2 = prob.rk(x, 2.0)[1]  # the same pattern, other values
    b = np.cos(np.arange(K1.shape[0]))
    s1 = nw.symmetric_factor(K1)
    s2 = nw.symmetric_factor(K2)
    n = updates[0]
    for s, K in ((s2, K2), (s1, K1), (s1, K1), (s2, K2)):
        assert np.linalg.norm(K @ s(b) - b) <= 1e-12 * np.linalg.norm(b)
    assert updates[0] == n + 2  # s1 refactored once (then current), s2 once when it was stale again


def test_newton_keeps_a_factorisation_across_solves_with_quasi_newton_steps():
    """``keep=KeptFactor()``: the solves of a load sweep start with Broyden steps on the factorisation of an
    earlier solve and factor a new tangent only when those do not contract: the same states as Newton that
    factors every tangent, to the convergence tolerance (xtol = 1e-9 of |x|), the residual converged, and
    fewer than half the factorisations."""
    from tissuemech.fem import blastula as fb
    from tissuemech.fem.newton import KeptFactor, symmetric_factor

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
    counts = {"full": 0, "keep": 0}

    def counted(which):
        def factor(K):
            counts[which] += 1
            return symmetric_factor(K, ordering="supervariable")

        return factor

    opts = dict(ref_norm=prob.ref, rtol=1e-10, xtol=1e-9, atol=prob.floor * 2, admissible=prob.admissible)
    keep = KeptFactor()
    x_s = x_k = x_old = np.zeros(prob.free.size)
    for lam in np.linspace(0.1, 2.0, 20):
        fun = lambda x, lam=lam: prob.rk(x, lam, tangent="lazy")[:2]
        s = newton(fun, 2 * x_s - x_old, factor=counted("full"), **opts)  # secant predictor (equal steps)
        k = newton(fun, 2 * x_k - x_old, factor=counted("keep"), keep=keep, **opts)
        assert np.abs(k.x - s.x).max() <= 1e-8 * np.abs(s.x).max()
        assert k.residuals[-1] <= opts["rtol"] * prob.ref + opts["atol"]
        x_old, x_s, x_k = x_s, s.x, k.x
    assert keep.broyden_steps > 0
    assert counts["keep"] < 0.5 * counts["full"]


def test_a_kept_factorisation_that_does_not_contract_or_does_not_fit_is_not_used():
    """A kept factorisation whose first quasi-Newton step does not reduce the residual is refused (newton
    factors anew and reaches the same state); one of another size is not tried; bad arguments raise."""
    from tissuemech.fem import blastula as fb
    from tissuemech.fem.newton import KeptFactor, symmetric_factor

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
    opts = dict(ref_norm=prob.ref, rtol=1e-10, xtol=1e-9, atol=prob.floor * 2, admissible=prob.admissible)
    fun = lambda x: prob.rk(x, 1.0, tangent="lazy")[:2]
    x0 = np.zeros(prob.free.size)
    ref = newton(fun, x0, factor=symmetric_factor, **opts)
    _, K0, _ = prob.rk(x0, 0.0)
    solve0 = symmetric_factor(K0)
    wild, small = KeptFactor(), KeptFactor()
    bad = lambda b: -30.0 * solve0(b)  # steps backwards, 30x too long
    wild.store(bad, prob.free.size)
    small.store(solve0, prob.free.size - 1)
    for keep in (wild, small):
        res = newton(fun, x0, factor=symmetric_factor, keep=keep, **opts)
        assert np.abs(res.x - ref.x).max() <= 1e-8 * np.abs(ref.x).max()
    assert wild.refused == 1 and wild.solve is not bad  # refused, replaced by this solve's factorisation
    assert small.refused == 0 and small.n == prob.free.size  # not tried; replaced by this solve's factor
    with pytest.raises(ValueError, match="rate"):
        KeptFactor(rate=1.0)
    with pytest.raises(ValueError, match="only with a factor"):
        newton(fun, x0, keep=KeptFactor(), **opts)


def test_newton_with_a_kept_factorisation_converges_wherever_newton_alone_does():
    """A solve that fails after Broyden steps (here: they use up a tight ``max_iter``) is solved again by
    Newton alone from the guess: the same state, counted in ``keep.retried``; the 10-step blastula sweep
    without a predictor (large steps, Newton's residual rising 100-fold in the first iteration) converges
    with a kept factorisation as it does without."""
    from tissuemech.fem import blastula as fb
    from tissuemech.fem.newton import KeptFactor, symmetric_factor

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (4, 8))
    opts = dict(ref_norm=prob.ref, rtol=1e-10, xtol=1e-9, atol=prob.floor * 2, admissible=prob.admissible)
    fun = lambda lam: lambda x: prob.rk(x, lam, tangent="lazy")[:2]
    x1 = newton(fun(1.0), np.zeros(prob.free.size), factor=symmetric_factor, **opts).x
    alone = newton(fun(1.1), x1, factor=symmetric_factor, **opts)
    keep = KeptFactor()
    _, K0, _ = prob.rk(np.zeros(prob.free.size), 0.5)
    keep.store(symmetric_factor(K0), prob.free.size)  # an old tangent: slow but contracting Broyden steps
    res = newton(fun(1.1), x1, factor=symmetric_factor, keep=keep, **{**opts, "max_iter": alone.iterations})
    assert keep.retried == 1 and keep.broyden_steps > 0
    assert np.abs(res.x - alone.x).max() <= 1e-12 * np.abs(alone.x).max()
    for kept in (None, KeptFactor()):
        prob.keep, x = kept, np.zeros(prob.free.size)
        for lam in np.linspace(0.25, 2.5, 10):
            x = prob.solve(lam, x, 1e-10, f"lam = {lam}").x
        if kept is None:
            x_alone = x
    assert np.abs(x - x_alone).max() <= 1e-8 * np.abs(x_alone).max()


def test_fem_perf_floor_counts_residuals_and_computes_the_assemblers_F():
    """``bench fem-perf``'s run floor: the residual counter counts one pass per residual evaluation (a Newton
    solve's residual history has one entry per accepted evaluation) and not the output fields' stress passes, and the
    residual's element matmuls of the floor compute the same F as the assembler (F = B u_e + I) and the same element
    residual (B^T P)."""
    from tissuemech.compare.bench.fem_perf import _count_residuals, _residual_flops
    from tissuemech.fem import blastula as fb
    from tissuemech.fem.forms import Assembler

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (2, 4))
    with _count_residuals() as count:
        res = prob.solve(1.0, np.zeros(prob.free.size), 1e-10, "test")
        n = count.n
        prob.point_stresses(prob.full(res.x))  # output, not a residual
    assert 3 <= len(res.residuals) <= n == count.n <= len(res.residuals) + 2  # (+ trial states newton rejected)
    assert Assembler._residual is count._orig  # restored
    asm, x = prob.asm, prob.full(res.x)
    ne, nq = asm.w.shape
    f_floor, _ = _residual_flops(asm, x)()
    np.testing.assert_allclose(
        f_floor.reshape(ne, nq, 5) + np.array([1.0, 0.0, 0.0, 1.0, 1.0]), asm.f_at(x), rtol=0, atol=1e-14
    )
    P = np.cos(np.arange(ne * nq * 5, dtype=float)).reshape(ne, nq, 5)
    re = np.einsum("eqc,eqcd->ed", P, asm.B)
    np.testing.assert_allclose(_residual_flops(asm, x)()[1][:, 0], re, rtol=1e-13, atol=1e-13)


def test_fem_perf_run_floor_is_the_work_of_the_iterations_taken(monkeypatch):
    """``bench fem-perf``'s floor of a scaling run: LU x (best factorisation + the tangent's element matmuls) +
    iterations x a bare solve + residual evaluations x their element matmuls, with the fastest factorisation
    chosen (timings replaced by fixed numbers: each callable's name stands for its time)."""
    import tissuemech.compare.bench.fem_perf as fp
    from tissuemech.fem import blastula as fb

    prob = fb._setup(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (2, 4))
    x = prob.solve(1.0, np.zeros(prob.free.size), 1e-10, "test").x
    _, K, _ = prob.rk(x, 1.0)
    facs = fp._factorisations(K)
    assert {"SuperLU sym, MMD(K+K^T) kept", "SuperLU sym, supervariable MMD kept"} <= set(facs)
    times = {id(f): 1e-3 * (i + 2) for i, f in enumerate(facs.values())}
    fastest = min(facs, key=lambda k: times[id(facs[k])])
    monkeypatch.setattr(fp, "_factorisations", lambda K: facs)
    monkeypatch.setattr(fp, "_elem_flops", lambda *a: "elem")
    monkeypatch.setattr(fp, "_residual_flops", lambda *a: "res")
    monkeypatch.setattr(fp, "_bare_solve", lambda *a: "solve")
    fixed = {"elem": 5e-4, "res": 7e-5, "solve": 3e-5}
    monkeypatch.setattr(fp, "_med", lambda f, n: fixed[f] if isinstance(f, str) else times[id(f)])
    floor, best = fp._run_floor((K, prob.asm, prob.full(x), prob.mat), 4, 30, 40)
    assert best == fastest
    assert floor == pytest.approx(4 * (times[id(facs[fastest])] + 5e-4) + 30 * 3e-5 + 40 * 7e-5, rel=1e-12)


def test_newton_abandons_a_diverging_solve_after_diverging_after_iterations():
    """Newton on arctan(x) = 0 diverges from |x0| > 1.3917 (the iterates alternate in sign and grow): with the
    default ``diverging_after=8`` it stops after 8 iterations whose last three residuals all exceed the first
    (a caller cuts the step then), without it only at a singular tangent (the residual saturates at pi/2).
    A converging start is untouched; bad values are refused."""
    fun = lambda x: (np.arctan(x), sp.csr_matrix([[1.0 / (1.0 + x[0] ** 2)]]))
    with pytest.raises(NewtonError, match="diverging") as err:
        newton(fun, np.array([1.45]), load=2.0)
    assert len(err.value.residuals) == 9 and min(err.value.residuals[-3:]) > err.value.residuals[0]
    with np.errstate(over="ignore"), pytest.raises(NewtonError) as late:
        newton(fun, np.array([1.45]), diverging_after=None)
    assert "diverging" not in str(late.value) and len(late.value.residuals) > 9
    assert newton(fun, np.array([1.3])).iterations == newton(fun, np.array([1.3]), diverging_after=None).iterations
    for bad in (2, 0, 3.5, True, "8"):
        with pytest.raises(ValueError, match="diverging_after"):
            newton(fun, np.array([1.3]), diverging_after=bad)
