"""compare.bench fem-perf: its floors count the work the FE does (the bench's own helpers)."""

import numpy as np
import pytest

from tissuemech.fem.blastula import shell_problem


def test_fem_perf_floor_counts_residuals_and_computes_the_assemblers_F():
    """``bench fem-perf``'s run floor: the residual counter counts one pass per residual evaluation (a Newton
    solve's residual history has one entry per accepted evaluation) and not the output fields' stress passes, and the
    residual's element matmuls of the floor compute the same F as the assembler (F = B u_e + I) and the same element
    residual (B^T P)."""
    from tissuemech.compare.bench.fem_perf import _count_residuals, _residual_flops
    from tissuemech.fem.forms import Assembler

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (2, 4))
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

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (2, 4))
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
