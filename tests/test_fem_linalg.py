"""fem.linalg: sparse backends, orderings, cached gathers, factorisations and their refinement."""

import numpy as np
import pytest
import scipy.sparse as sp

from tissuemech.fem import linalg
from tissuemech.fem.blastula import shell_problem
from tissuemech.fem.forms import Assembler, Material
from tissuemech.fem.linalg import (
    NEWTON_STEP_RTOL,
    mmd_ordering,
    sparse_solve,
    submatrix,
    supervariable_ordering,
    symmetric_factor,
    symmetric_solve,
)
from tissuemech.fem.mesh import fitted_mesh, shell_section
from tissuemech.fem.newton import newton

A0 = 500e-6


def test_solver_backends_and_submatrix_cache():
    """Every symmetric_solve backend and the cached K[free][:, free] gather give the same answer."""

    m = shell_section(50e-6, 75e-6, 3, 6)
    a = Assembler(m)
    x = np.zeros(a.ndof)
    x[: a.n_u] = 1e-3 * np.sin(np.arange(a.n_u))
    _, K = a.internal(x, Material(1.0, 0.2, 1e7))
    fp, Kp = a.follower_pressure(x, 1.0, m.edges["inner"])
    K = (K - 0.7 * Kp).tocsr()  # slightly unsymmetric, and exact zeros dropped from the pattern
    free = np.setdiff1d(np.arange(a.ndof), np.concatenate([2 * m.nodes["axis"], 2 * m.nodes["symmetry"] + 1]))
    Kf = K[free][:, free]
    assert (submatrix(K, free) != Kf).nnz == 0 and (submatrix(K, free) != Kf).nnz == 0  # built, reused
    b = np.cos(np.arange(free.size))
    ref = linalg.sparse_solve(Kf, b)
    old = linalg.backend()
    try:
        for name in linalg.available_backends():
            linalg.set_backend(name)
            for _ in range(2):  # plan built, then reused
                xs = linalg.symmetric_solve(Kf, b)
                assert np.linalg.norm(Kf @ xs - b) <= 1e-12 * np.linalg.norm(b)
                assert np.allclose(xs, ref, rtol=1e-7, atol=1e-12 * np.abs(ref).max())
        with pytest.raises(ValueError, match="sparse backend"):
            linalg.set_backend("umfpack")
    finally:
        linalg.set_backend("auto" if old == "auto" else old)


def test_supervariable_ordering_same_solution_less_fill():
    """The supervariable minimum-degree ordering of ``symmetric_solve`` gives the pivoted/dense answer to
    1e-12 and fewer fill-ins than MMD on K + K^T on a fine shell tangent; its supervariables are the nodes'
    dof pairs and the elements' interiors (fewer than nodes + elements)."""
    import scipy.sparse.linalg as spla

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (12, 24))
    x = 1e-3 * np.sin(np.arange(prob.free.size))
    _, K, _ = prob.rk(x, 0.8)  # with the (unsymmetric) follower block
    b = np.cos(np.arange(K.shape[0]))
    ref = linalg.sparse_solve(K, b)
    ref += linalg.sparse_solve(K, b - K @ ref)  # one refinement of the pivoted LU: |b - K ref| ~ round-off
    for ordering in ("mmd", "supervariable"):
        for _ in range(2):  # the plan is built, then reused
            xs = linalg.symmetric_solve(K, b, ordering=ordering)
            assert np.linalg.norm(K @ xs - b) <= 1e-12 * np.linalg.norm(b)
            assert np.abs(xs - ref).max() <= 1e-12 * np.abs(ref).max()
    fill = {}
    for name, order in (("mmd", mmd_ordering), ("supervariable", supervariable_ordering)):
        p = order(K)
        assert np.array_equal(np.sort(p), np.arange(K.shape[0]))
        lu = spla.splu(
            sp.csc_matrix(K[p][:, p]), permc_spec="NATURAL", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True)
        )
        fill[name] = lu.L.nnz + lu.U.nnz
    assert fill["supervariable"] < 0.95 * fill["mmd"]
    Q, sv = linalg.supervariables(K)
    assert sv.shape == (K.shape[0],) and Q.shape[0] == sv.max() + 1 < prob.m.X.shape[1] + prob.asm.n_el
    with pytest.raises(ValueError, match="ordering"):
        linalg.symmetric_solve(K, b, ordering="amd")


def test_symmetric_factor_solves_many_right_hand_sides():
    """One factorisation answers several right-hand sides as symmetric_solve does (to round-off)."""

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
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

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (8, 16))
    opts = dict(ref_norm=prob.ref, rtol=1e-10, xtol=1e-9, atol=prob.floor * 2, admissible=prob.admissible)
    sweeps = [0]
    refine = linalg.refine_solution

    def counted(K, b, x, solve, n, rtol):
        def one(v):
            sweeps[0] += 1
            return solve(v)

        return refine(K, b, x, one, n, rtol)

    monkeypatch.setattr(linalg, "refine_solution", counted)

    def strict(K):
        solve = linalg.symmetric_factor(K, ordering="supervariable")
        return lambda b: solve(b)  # a plain function: no ``inexact``, every solve refined to 1e-13

    factors = {"inexact": lambda K: linalg.symmetric_factor(K, ordering="supervariable"), "strict": strict}
    x = {k: np.zeros(prob.free.size) for k in factors}
    n_sweeps = dict.fromkeys(factors, 0)
    for lam in np.linspace(0.5, 5.0, 10):
        fun = lambda v, lam=lam: prob.rk(v, lam, tangent="lazy")[:2]
        out = {}
        for k in factors:
            sweeps[0] = 0
            out[k] = newton(fun, x[k], factor=factors[k], **opts)
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

    updates = [0]

    class Counting(_FakeLDL):
        def update(self, U, upper=True):
            updates[0] += 1
            super().update(U, upper=upper)

    monkeypatch.setattr(linalg, "_qdldl", SimpleNamespace(Solver=Counting))
    monkeypatch.setattr(linalg, "_BACKEND", ["qdldl"])
    monkeypatch.setattr(linalg, "_TLS", threading.local())  # no plan (and no real qdldl solver) from other tests
    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
    x = prob.solve(1.0, np.zeros(prob.free.size), 1e-10, "test").x
    K1 = prob.rk(x, 1.0)[1]
    K2 = prob.rk(x, 2.0)[1]  # the same pattern, other values
    b = np.cos(np.arange(K1.shape[0]))
    s1 = linalg.symmetric_factor(K1)
    s2 = linalg.symmetric_factor(K2)
    n = updates[0]
    for s, K in ((s2, K2), (s1, K1), (s1, K1), (s2, K2)):
        assert np.linalg.norm(K @ s(b) - b) <= 1e-12 * np.linalg.norm(b)
    assert updates[0] == n + 2  # s1 refactored once (then current), s2 once when it was stale again


def test_symmetric_solve_matches_pivoted_lu():
    m = fitted_mesh(A0, 0, 0.5)
    from tissuemech.fem.forms import Assembler, Material

    asm = Assembler(m)
    x = np.zeros(asm.ndof)
    x[: asm.n_u] = 1e-3 * np.sin(np.arange(asm.n_u))
    _, K = asm.internal(x, Material(1.0, 0.2, 1e7))
    fixed = np.concatenate([2 * m.nodes["axis"], 2 * m.nodes["symmetry"] + 1, 2 * m.nodes["outer"] + 1])
    free = np.setdiff1d(np.arange(asm.ndof), fixed)
    Kf = K[free][:, free]
    b = np.cos(np.arange(free.size))
    assert np.allclose(symmetric_solve(Kf, b), sparse_solve(Kf, b), rtol=1e-8, atol=1e-12)


# ---- the spheroid ------------------------------------------------------------------------------
