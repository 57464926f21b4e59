"""fem.constitutive / kinematics / forms: Fung stress and tangent, assembly, follower pressure, patterns."""

import numpy as np
import pytest
import scipy.sparse as sp
import skfem

from tissuemech.fem import constitutive as cm
from tissuemech.fem.forms import Assembler, Material
from tissuemech.fem.kinematics import IDENTITY5, first_from_second, invariants, second_from_first
from tissuemech.fem.mesh import ball_section, shell_section
from tissuemech.fem.newton import newton

RNG = np.random.default_rng(7)


def _fd(fun, x, dx, h=1e-6):
    return (fun(x + h * dx) - fun(x - h * dx)) / (2 * h)


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
        r0, K0 = a.internal_reference(x, mat, **kw)
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


def test_meshes_with_one_connectivity_share_the_pattern():
    """Two assemblers on meshes with the same connectivity (different node positions) share one element
    pattern, and their tangents equal a fresh assembly of the reference path."""
    m1 = shell_section(50e-6, 75e-6, 3, 6)
    m2 = shell_section(50e-6, 80e-6, 3, 6)
    a1, a2 = Assembler(m1), Assembler(m2)
    assert a1.pattern is a2.pattern
    mat = Material(1.0, 0.2, 1e4)
    x = np.zeros(a2.ndof)
    x[: a2.n_u] = 1e-3 * np.sin(np.arange(a2.n_u))
    _, K = a2.internal(x, mat)
    _, K0 = a2.internal_reference(x, mat)
    K0 = K0.tocsr()
    K0.sum_duplicates()
    assert abs(K - K0).max() <= 1e-14 * abs(K0).max()
    assert Assembler(shell_section(50e-6, 75e-6, 4, 6)).pattern is not a1.pattern


def test_moved_assembler_is_the_assembler_of_the_moved_mesh():
    """``Assembler.moved(V, eps)``: the geometry of the mesh whose nodes are X + eps V is exact for the isoparametric
    map (weights, points, B against the assembler of the moved mesh itself, to round-off), and the central difference
    of the residual on X -+ h V, V the fitted mesh's nodal motion with its contact edge (``fitted_nodes``), equals
    that on the fitted meshes at e (1 -+ h) to O(h^2) (asserted here: 1e-9 of its largest)."""
    from tissuemech.fem.mesh import AxiMesh, fitted_mesh, fitted_nodes

    e, h = 0.3, 1e-4
    m = fitted_mesh(1.0, 1, e)
    A = Assembler(m)
    V = (fitted_nodes(1.0, 1, e * (1 + h)) - fitted_nodes(1.0, 1, e * (1 - h))) / (2 * h)
    np.testing.assert_array_equal(fitted_nodes(1.0, 1, e), m.X)
    # the moved mesh itself: the same connectivity, nodes X + eps V
    eps = 0.05
    mm = skfem.MeshQuad2(m.X + eps * V, m.mesh.t)
    moved_mesh = AxiMesh(mm, skfem.CellBasis(mm, skfem.ElementQuad2(), intorder=4), m.order, m.length_scale)
    B, Am = Assembler(moved_mesh), A.moved(V, eps)
    for name in ("w", "B", "M"):
        np.testing.assert_allclose(
            getattr(Am, name), getattr(B, name), rtol=1e-10, atol=1e-12 * np.abs(getattr(B, name)).max()
        )
    np.testing.assert_allclose(Am.xq, moved_mesh.quadrature_points, atol=1e-13)
    # the residual's derivative in the edge
    mat = Material(1.0, 0.8, 1e3)
    x = 2e-3 * np.random.default_rng(1).standard_normal(A.ndof)
    lo, hi = Assembler(fitted_mesh(1.0, 1, e * (1 - h))), Assembler(fitted_mesh(1.0, 1, e * (1 + h)))
    fd = (hi.internal(x, mat, tangent=False)[0] - lo.internal(x, mat, tangent=False)[0]) / (2 * h)
    mv = (A.moved(V, h).internal(x, mat, tangent=False)[0] - A.moved(V, -h).internal(x, mat, tangent=False)[0]) / (
        2 * h
    )
    assert np.max(np.abs(mv - fd)) <= 1e-9 * np.max(np.abs(fd))
