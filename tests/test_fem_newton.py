"""fem.newton: convergence, line search, lazy tangents, the linear-solver strategies (kept factorisations)."""

import numpy as np
import pytest
import scipy.sparse as sp

from tissuemech.fem.blastula import SHELL_ORDERING, shell_problem
from tissuemech.fem.linalg import Custom, KeptFactor, Pivoted, Reuse, Symmetric, symmetric_factor, symmetric_solve
from tissuemech.fem.newton import NewtonError, newton


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


def test_newton_lazy_tangent_same_answer_fewer_assemblies():
    """A lazy tangent gives the same Newton iterates as the eager one, and the converged state's tangent is
    never assembled."""

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
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


def test_newton_keeps_the_factorisation_once_the_residual_has_converged():
    """With ``factor`` newton corrects a converged residual with the kept factorisation (no new tangent or
    factorisation) until the step test passes: the same states to 1e-12 as full Newton with ``solver``, about
    one factorisation fewer per solve, the convergence test unchanged."""

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
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

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
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


def test_newton_keeps_a_factorisation_across_solves_with_quasi_newton_steps():
    """``keep=KeptFactor()``: the solves of a load sweep start with Broyden steps on the factorisation of an
    earlier solve and factor a new tangent only when those do not contract: the same states as Newton that
    factors every tangent, to the convergence tolerance (xtol = 1e-9 of |x|), the residual converged, and
    fewer than half the factorisations."""

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
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

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
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

    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (4, 8))
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
        prob.linear = Symmetric(SHELL_ORDERING) if kept is None else Reuse(Symmetric(SHELL_ORDERING))
        x = np.zeros(prob.free.size)
        for lam in np.linspace(0.25, 2.5, 10):
            x = prob.solve(lam, x, 1e-10, f"lam = {lam}").x
        if kept is None:
            x_alone = x
    assert np.abs(x - x_alone).max() <= 1e-8 * np.abs(x_alone).max()


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


def test_linear_strategies_are_the_old_keywords():
    """``linear=`` takes one strategy object: Pivoted() is the default solve, Symmetric() the kept factorisation of
    ``factor=symmetric_factor``, Reuse(Symmetric()) that of ``factor=..., keep=KeptFactor()``, Custom the old
    callables: the same iterates and residuals bit for bit. Mixing the two spellings, or a strategy without a
    factor under Reuse, raises."""
    prob = shell_problem(50e-6, 75e-6, 200.0, 0.2, 2.2e9, (3, 6))
    opts = dict(ref_norm=prob.ref, rtol=1e-10, xtol=1e-9, atol=prob.floor * 2, admissible=prob.admissible)
    x0 = np.zeros(prob.free.size)
    pairs = [
        (dict(), dict(linear=Pivoted())),
        (dict(factor=symmetric_factor), dict(linear=Symmetric())),
        (dict(solver=symmetric_solve), dict(linear=Custom(solve=symmetric_solve))),
    ]
    for old, new in pairs:
        fun = lambda x: prob.rk(x, 1.0, tangent="lazy")[:2]
        a, b = newton(fun, x0, **old, **opts), newton(fun, x0, **new, **opts)
        assert a.iterations == b.iterations and a.residuals == b.residuals and np.array_equal(a.x, b.x)
    keep, reuse = KeptFactor(), Reuse(Symmetric())
    xa = xb = x0
    for lam in (0.5, 1.0, 1.5):
        fun = lambda x, lam=lam: prob.rk(x, lam, tangent="lazy")[:2]
        a = newton(fun, xa, factor=symmetric_factor, keep=keep, **opts)
        b = newton(fun, xb, linear=reuse, **opts)
        assert a.iterations == b.iterations and np.array_equal(a.x, b.x)
        xa, xb = a.x, b.x
    assert reuse.kept is not None and reuse.kept.broyden_steps == keep.broyden_steps > 0
    with pytest.raises(ValueError, match="not both"):
        newton(fun, x0, linear=Symmetric(), factor=symmetric_factor, **opts)
    with pytest.raises(ValueError, match="strategy"):
        newton(fun, x0, linear=symmetric_factor, **opts)
    with pytest.raises(ValueError, match="factoring"):
        Reuse(Pivoted())
    with pytest.raises(ValueError, match="ordering"):
        Symmetric(ordering="amd")
    with pytest.raises(ValueError, match="backend"):
        Symmetric(backend_name="umfpack")


def test_newton_stagnation_accepts_a_converged_residual_with_round_off_corrections():
    """An ill-conditioned tangent (a very thin shell) keeps the corrections of a converged state above xtol: with
    ``stagnation=True`` Newton accepts the state once two successive residuals met the tolerance and the correction
    stopped shrinking; without it the solve runs to max_iter and fails as before."""
    rng = np.random.default_rng(0)
    # r = 1e-9 (x - 1) + round-off: each correction moves x by ~1e-6 at random, the residual stays ~1e-15
    fun = lambda x: (np.array([1e-9 * (x[0] - 1.0) + 1e-15 * rng.standard_normal()]), sp.csr_matrix([[1e-9]]))
    with pytest.raises(NewtonError):  # "diverging" (the residuals wander above the first) or "no convergence"
        newton(fun, np.array([1.0]), rtol=1e-12, xtol=1e-9)
    res = newton(fun, np.array([1.0]), rtol=1e-12, xtol=1e-9, stagnation=True)
    assert res.iterations <= 4 and abs(res.x[0] - 1.0) < 1e-5 and max(res.residuals) < 1e-12
    # a contracting iteration is not stagnation: Newton still converges by its step test
    fun2 = lambda x: (np.array([x[0] ** 3 - 8.0]), sp.csr_matrix([[3 * x[0] ** 2]]))
    assert abs(newton(fun2, np.array([3.0]), rtol=1e-14, xtol=1e-14, stagnation=True).x[0] - 2.0) < 1e-14
