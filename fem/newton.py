r"""One Newton-Raphson solver for every FE scene.

``newton(fun, x0, *, free=None, ref_norm=1.0, rtol=1e-9, xtol=1e-9, max_iter=30, admissible=None,
load=None, max_backtracks=8, growth=1e3, atol=0.0, linear=None, diverging_after=8)`` solves r(x) = 0
with ``fun(x) -> (r, K)`` (r ndarray, K scipy sparse) and returns a :class:`NewtonResult`. Hooks:

* ``free``: indices of the unknowns (condensation of Dirichlet dofs: the others keep x0's values).
  Contact with Lagrange multipliers or any constraint is added by the caller by returning an
  augmented (r, K) from ``fun`` (x then holds the multipliers too).
* Lazy tangent: ``fun`` may return K as a zero-argument callable; it is called only when a solve needs
  that state's tangent (an accepted trial state that converges never assembles its tangent).
* ``admissible(x) -> None | str``: a reason string rejects the state (J <= 0, inside-out...);
  the step is cut back (halved) like a step whose residual is not finite or grows > ``growth``-fold.
* Convergence needs BOTH |r_free| <= rtol * ref_norm + atol AND |dx| <= xtol * (1 + |x|)
  (``atol``: the round-off floor of the residual, e.g. ~10 eps kappa/C for nearly incompressible).
* ``diverging_after`` (default 8; None: off): a solve that has taken more iterations than this while its
  last three residuals all exceed its initial one is abandoned (``NewtonError``) instead of running on to
  ``max_iter``, so a load-stepping caller cuts the step ~20 iterations and factorisations sooner (blastula
  sweeps to 1 kPa in 1-5 steps: 22-34 % fewer factorisations, the same cuts).

The linear solver is ONE strategy object, ``linear`` (``tissuemech.fem.linalg``):

* ``Pivoted()`` (default): a pivoted sparse direct solve (SuperLU, COLAMD) per iteration.
* ``Symmetric(ordering=..., backend_name=...)`` (a factorisation newton keeps): once the residual has converged
  (only the step test |dx| <= xtol (1 + |x|) is pending) the remaining corrections use the last factorisation
  (a chord step with the tangent one iterate back, whose error is the product of two converged increments)
  instead of a new tangent and factorisation; a correction that fails (not at most half the step before,
  residual up 10-fold, inadmissible state, a failed solve) falls back to a full iteration. The convergence
  test is the same.
* ``Reuse(Symmetric(...))`` (one per run) also keeps the factorisation ACROSS solves (modified /
  quasi-Newton between load or time steps): a solve starts with Broyden steps (Kelley's inverse form, H0 =
  the kept factorisation without refinement, full steps) and factors a new tangent only when a step does not
  contract (the first must cut the residual to ``rate`` of the guess's, the others must not raise it and be
  at most half the step before); after the first full iteration of a solve, one more Broyden phase runs on
  that new factorisation. Each Broyden step costs one residual and one solve (no tangent, no factorisation):
  the 4x8 blastula sweep 115 -> 28 factorisations, Fig. 10 58 -> 13. ``iterations`` counts both kinds.
* The old keywords still work: ``solver=`` (a one-shot ``solve(K, b)``), ``factor=`` (``factor(K) -> solve``)
  and ``keep=`` (a ``KeptFactor``, with ``factor``) are ``linear=Custom(solve=solver, factor=factor,
  kept=keep)``; they cannot be combined with ``linear``.

On failure ``NewtonError`` carries ``load`` (the load level being solved), ``residuals`` (history) and a
``hint``; no NaN is returned. The sparse linear algebra (backends, orderings, cached plans) lives in
``tissuemech.fem.linalg``; its public names are re-exported here for the callers of release 0.1.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from tissuemech.fem import linalg as _linalg
from tissuemech.fem.linalg import (
    NEWTON_STEP_RTOL,
    ORDERINGS,
    Custom,
    KeptFactor,
    LinearSolver,
    Pivoted,
    Reuse,
    Symmetric,
    available_backends,
    backend,
    mmd_ordering,
    set_backend,
    sparse_solve,
    submatrix,
    supervariable_ordering,
    supervariables,
    symmetric_factor,
    symmetric_solve,
)

__all__ = [
    "NewtonError",
    "NewtonResult",
    "newton",
    "linear_solver",
    # re-exported from fem.linalg (release 0.1 names)
    "sparse_solve",
    "symmetric_solve",
    "symmetric_factor",
    "KeptFactor",
    "set_backend",
    "backend",
    "available_backends",
    "supervariables",
    "NEWTON_STEP_RTOL",
    "ORDERINGS",
    "LinearSolver",
    "Pivoted",
    "Symmetric",
    "Reuse",
    "Custom",
]


def _tangent(K):
    """K itself, or the matrix of a lazy tangent (a zero-argument callable returned by ``fun``)."""
    return K() if callable(K) and not sp.issparse(K) else K


class NewtonError(RuntimeError):
    """Newton failed: ``load`` (load level), ``residuals`` (history), ``hint`` (what to try)."""

    def __init__(self, message: str, *, load=None, residuals: Sequence[float] = (), hint: str = "", unit: str = ""):
        self.load, self.residuals, self.hint = load, list(residuals), hint
        hist = ", ".join(f"{r:.3e}" for r in self.residuals[-8:])
        where = f"{load:.6g}{unit}" if isinstance(load, (int, float)) and not isinstance(load, bool) else f"{load}"
        if isinstance(load, (int, float)) and not unit:
            where += " (scaled load, no unit given)"
        super().__init__(f"{message} (load level {where}; residual history [{hist}]). Hint: {hint}")


class _Astray(NewtonError):
    """Internal: Newton diverges from a state quasi-Newton steps led to (``newton`` retries without them)."""


class NewtonResult(NamedTuple):
    """A converged Newton solve."""

    x: np.ndarray  # the solution (the full unknown vector; fixed dofs keep x0's values)
    iterations: int  # iterations taken (full Newton, chord and Broyden steps alike)
    residuals: list  # |r_free| of the guess and after each iteration (scaled like ref_norm)


def linear_solver(
    linear: LinearSolver | None = None,
    solver: Callable | None = None,
    factor: Callable | None = None,
    keep: KeptFactor | None = None,
) -> LinearSolver:
    """The strategy of newton's ``linear`` argument or of the old keywords (``solver``, ``factor``, ``keep``);
    ``Pivoted()`` when none is given. Raises ValueError for ``linear`` with an old keyword, both ``solver``
    and ``factor``, or ``keep`` without ``factor``."""
    if linear is not None:
        if solver is not None or factor is not None or keep is not None:
            raise ValueError("give newton a linear strategy or the old solver/factor/keep keywords, not both")
        if not isinstance(linear, LinearSolver):
            raise ValueError(
                f"linear must be a fem.linalg strategy (Pivoted, Symmetric, Reuse, Custom), got {linear!r}"
            )
        return linear
    if solver is None and factor is None and keep is None:
        return Pivoted()
    return Custom(solve=solver, factor=factor, kept=keep)


def _broyden(fun, x, r, free, h0, admissible, res: list, tol: float, xtol: float, rate: float, max_iter: int):
    """Broyden's method with H0 = a kept factorisation (Kelley's inverse form with full steps: only the
    steps s_j are stored, H_n v from H0 v and the s_j in O(n k)): (x, r, K, iterations, converged) from
    the last accepted state. A step must reduce the residual by ``rate`` (the first) or not increase it
    and be at most half the step before (the others); an inadmissible or non-finite state, a failed
    solve or max_iter steps end the phase unconverged (newton continues with full iterations there)."""
    steps: list[np.ndarray] = []
    K = None
    for k in range(1, max_iter + 1):
        try:
            z = h0(-r[free])
        except (np.linalg.LinAlgError, RuntimeError, ValueError):
            return x, r, K, k - 1, False
        for j in range(len(steps) - 1):
            z += steps[j + 1] * (float(steps[j] @ z) / float(steps[j] @ steps[j]))
        if steps:
            sn = steps[-1]
            denom = 1.0 - float(sn @ z) / float(sn @ sn)
            if not abs(denom) > 1e-8:
                return x, r, K, k - 1, False
            z = z / denom
        dxn = float(np.linalg.norm(z))
        if not np.isfinite(dxn) or (steps and dxn > 0.5 * float(np.linalg.norm(steps[-1]))):
            return x, r, K, k - 1, False
        t = _trial(fun, x, z, free, admissible, max((rate if k == 1 else 1.0) * res[-1], tol))
        if t is None:
            return x, r, K, k - 1, False
        x, r, K, rn = t
        res.append(rn)
        steps.append(z)
        if rn <= tol and dxn <= xtol * (1.0 + np.linalg.norm(x[free])):
            return x, r, K, k, True
    return x, r, K, max_iter, False


def _trial(fun, x, dx, free, admissible, max_rn: float):
    """The state x + dx (on ``free``) as (x, r, K, |r|), or None when it is inadmissible or its residual is
    not finite or above ``max_rn`` (the acceptance test of a correction on a kept factorisation)."""
    xt = x.copy()
    xt[free] += dx
    if admissible is not None and admissible(xt) is not None:
        return None
    with np.errstate(over="ignore", invalid="ignore"):
        rt, Kt = fun(xt)
        rn = float(np.linalg.norm(rt[free]))
    if not (np.isfinite(rn) and rn <= max_rn):
        return None
    return xt, rt, Kt, rn


def _chord_step(fun, x, r, free, solve, admissible, rn0: float, tol: float, max_dx: float):
    """One correction x + dx with dx = -K_kept^-1 r (a kept factorisation): (x, r, K, |r|, |dx|) of the
    new state, or None when the solve fails, |dx| > ``max_dx`` (no contraction), the state is
    inadmissible or its residual is not finite or no longer within max(10 |r0|, tol) (newton then takes a
    full iteration instead)."""
    try:
        dx = getattr(solve, "inexact", solve)(-r[free])
    except (np.linalg.LinAlgError, ValueError):
        return None
    if not float(np.linalg.norm(dx)) <= max_dx:
        return None
    t = _trial(fun, x, dx, free, admissible, max(10.0 * rn0, tol))
    return None if t is None else (*t, float(np.linalg.norm(dx)))


def newton(
    fun: Callable,
    x0: np.ndarray,
    *,
    free: np.ndarray | None = None,
    ref_norm: float = 1.0,
    rtol: float = 1e-9,
    xtol: float = 1e-9,
    max_iter: int = 30,
    admissible: Callable | None = None,
    load=None,
    max_backtracks: int = 8,
    growth: float = 1e3,
    atol: float = 0.0,
    linear: LinearSolver | None = None,
    diverging_after: int | None = 8,
    solver: Callable | None = None,
    factor: Callable | None = None,
    keep: KeptFactor | None = None,
    stagnation: bool = False,
) -> NewtonResult:
    """Solve fun(x)[0] = 0 from x0 (see the module docstring); returns a :class:`NewtonResult`.

    ``stagnation``: also accept a state whose residual met the tolerance in two successive full Newton steps while
    the correction stopped shrinking (not below half the previous one): the corrections are then round-off of an
    ill-conditioned tangent (a very thin shell), not progress, and the step test on them could never pass.

    Raises:
        NewtonError: no convergence (the message names ``load`` and gives the residual history and a hint).
        ValueError: a bad ``diverging_after`` or an inconsistent choice of the linear solver."""
    if diverging_after is not None and (
        isinstance(diverging_after, bool) or not isinstance(diverging_after, (int, np.integer)) or diverging_after < 3
    ):
        raise ValueError(f"diverging_after must be a whole number >= 3 or None, got {diverging_after!r}")
    lin = linear_solver(linear, solver, factor, keep)
    solver, factor, keep = lin.solve, lin.factor, lin.kept
    opts = dict(free=free, ref_norm=ref_norm, rtol=rtol, xtol=xtol, max_iter=max_iter, admissible=admissible)
    opts.update(load=load, max_backtracks=max_backtracks, growth=growth, atol=atol, solver=solver, factor=factor)
    opts.update(diverging_after=diverging_after, stagnation=stagnation)
    if keep is None:
        return _newton(fun, x0, keep=None, **opts)
    keep.age += 1
    steps = keep.broyden_steps
    try:
        return _newton(fun, x0, keep=keep, **opts)
    except NewtonError:
        keep.age = max(keep.age, 1)  # what a failed solve factored is no tangent of a converged state
        if keep.broyden_steps == steps:
            raise
        # the quasi-Newton steps may have led it astray: Newton alone from x0 (no worse than without keep)
        keep.retried += 1
        res = _newton(fun, x0, keep=None, **opts)
        keep.store(None, -1)
        return res


def _newton(fun, x0, *, free, ref_norm, rtol, xtol, max_iter, admissible, load, max_backtracks, growth, atol,
            solver, factor, keep, diverging_after, stagnation=False) -> NewtonResult:  # fmt: skip
    x = np.array(x0, dtype=float)
    sub = None if free is None else np.asarray(free)
    free = np.arange(x.size) if free is None else np.asarray(free)
    ref = max(float(ref_norm), 1e-300)
    why = admissible(x) if admissible is not None else None
    if why is not None:
        raise NewtonError(
            f"inadmissible initial guess ({why})",
            load=load,
            residuals=[],
            hint="reduce the load step (the predictor overshot)",
        )
    r, K = fun(x)
    with np.errstate(over="ignore", invalid="ignore"):  # a non-finite residual is handled below
        res = [float(np.linalg.norm(r[free]))]
    if not np.isfinite(res[0]):
        raise NewtonError(
            "the residual of the initial guess is not finite",
            load=load,
            residuals=res,
            hint="check the inputs and the initial state",
        )
    kept = None  # factor's solve of the last factored tangent
    tol = rtol * ref + atol
    last_dx = np.inf  # |x_k - x_(k-1)|: a kept correction must be at most half of it (contraction)
    it0 = 0
    if keep is not None and keep.solve is not None and keep.n == free.size:
        # quasi-Newton (Broyden) steps on the factorisation of an earlier step, while they contract
        h0 = getattr(keep.solve, "unrefined", keep.solve)
        x1, r1, K1, it0, done = _broyden(fun, x, r, free, h0, admissible, res, tol, xtol, keep.rate, max_iter)
        keep.broyden_steps += it0
        if it0:
            x, r, K = x1, r1, K1
        if done:
            return NewtonResult(x, it0, res)
        keep.refused += 1
    astray = it0 > 0  # Broyden steps were taken: a full Newton step that raises the residual ends this try
    fresh = keep is not None  # one quasi-Newton phase on the first new factorisation of this solve
    it = it0
    while it < max_iter:
        it += 1
        if kept is not None and res[-1] <= tol:
            # the residual has converged, only the step test is pending: a correction with the kept
            # factorisation (the tangent one iterate back) instead of a new tangent + factorisation
            chord = _chord_step(fun, x, r, free, kept, admissible, res[-1], tol, 0.5 * last_dx)
            if chord is not None:
                x, r, K, rn, last_dx = chord
                res.append(rn)
                if rn <= tol and last_dx <= xtol * (1.0 + np.linalg.norm(x[free])):
                    return NewtonResult(x, it, res)
                continue
            kept = None
        try:
            Kf = submatrix(_tangent(K), sub)
            if factor is not None:
                kept = factor(Kf)
                if keep is not None:
                    keep.store(kept, free.size)
                dx = getattr(kept, "inexact", kept)(-r[free])
            else:
                dx = (solver or sparse_solve)(Kf, -r[free])
        except np.linalg.LinAlgError:
            raise NewtonError(
                "singular tangent matrix",
                load=load,
                residuals=res,
                hint="a limit point or a missing constraint (rigid-body motion); "
                "use arc-length continuation or smaller load steps",
            ) from None
        step, why = 1.0, None
        for _ in range(max_backtracks + 1):
            xt = x.copy()
            xt[free] += step * dx
            why = admissible(xt) if admissible is not None else None
            if why is None:
                # a trial state that overflows is an exploding step: it is cut below, so no warning for it
                with np.errstate(over="ignore", invalid="ignore"):
                    rt, Kt = fun(xt)
                    rn = float(np.linalg.norm(rt[free]))
                if np.isfinite(rn) and rn <= growth * max(res[-1], rtol * ref):
                    break
                why = "non-finite or exploding residual"
            step *= 0.5
        else:
            raise NewtonError(
                f"line search failed ({why})",
                load=load,
                residuals=res,
                hint="reduce the load step; the state may be beyond a limit point",
            )
        if astray and rn > res[-1]:
            raise _Astray("the residual rose after quasi-Newton steps", load=load, residuals=res + [rn])
        x, r, K = xt, rt, Kt
        res.append(rn)
        prev_dx, last_dx = last_dx, step * float(np.linalg.norm(dx))
        if step != 1.0:
            kept = None  # a cut step: keep full Newton iterations until the residual has converged again
        if rn <= tol and last_dx <= xtol * (1.0 + np.linalg.norm(x[free])):
            return NewtonResult(x, it, res)
        if stagnation and step == 1.0 and rn <= tol and res[-2] <= tol and last_dx >= 0.5 * prev_dx:
            return NewtonResult(x, it, res)  # the residual is converged; the corrections are round-off
        if diverging_after is not None and len(res) > diverging_after and min(res[-3:]) > res[0]:
            raise NewtonError(
                f"diverging: after {len(res) - 1} iterations the last three residuals all exceed the initial one",
                load=load,
                residuals=res,
                hint="reduce the load step (a better guess); the state may be beyond a limit point",
            )
        if fresh and kept is not None and keep is not None and rn > tol and step == 1.0 and rn <= 0.5 * res[-2]:
            # (only in Newton's convergent regime: a full step that halved the residual)
            fresh = False
            h0 = getattr(kept, "unrefined", kept)
            x1, r1, K1, k, done = _broyden(fun, x, r, free, h0, admissible, res, tol, xtol, keep.rate, max_iter - it)
            keep.broyden_steps += k
            it += k
            if k:
                x, r, K = x1, r1, K1
                last_dx = np.inf
                astray = True
            if done:
                return NewtonResult(x, it, res)
    raise NewtonError(
        f"no convergence in {max_iter} iterations",
        load=load,
        residuals=res,
        hint="reduce the load step or loosen rtol/xtol",
    )


# Release 0.1 internals that ``compare.bench.fem_perf`` still reaches into; the public names are
# ``fem.linalg.mmd_ordering``, ``supervariable_ordering``, ``set_backend`` / ``backend``.
_mmd = mmd_ordering
_supervariable_mmd = supervariable_ordering
_BACKEND = _linalg._BACKEND  # the same list: restoring it restores the selection
