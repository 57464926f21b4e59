r"""One Newton-Raphson solver for every FE scene.

``newton(fun, x0, *, free=None, ref_norm=1.0, rtol=1e-9, xtol=1e-9, max_iter=30, admissible=None,
load=None, max_backtracks=8, growth=1e3, atol=0.0, solver=None)`` solves r(x) = 0 with ``fun(x) -> (r, K)`` (r ndarray, K scipy
sparse). Hooks:

* ``free``: indices of the unknowns (condensation of Dirichlet dofs: the others keep x0's values).
  Contact with Lagrange multipliers or any constraint is added by the caller by returning an
  augmented (r, K) from ``fun`` (x then holds the multipliers too).
* ``admissible(x) -> None | str``: a reason string rejects the state (J <= 0, inside-out...);
  the step is cut back (halved) like a step whose residual is not finite or grows > ``growth``-fold.
* Convergence needs BOTH |r_free| <= rtol * ref_norm + atol AND |dx| <= xtol * (1 + |x|)
  (``atol``: the round-off floor of the residual, e.g. ~10 eps kappa/C for nearly incompressible).

Sparse direct solves (SuperLU via ``scipy.sparse.linalg.splu``); ``solver(K, b) -> x`` replaces it
(e.g. :func:`symmetric_solve`, fast for the symmetric saddle-point systems of the mixed u-p form). On failure ``NewtonError`` carries
``load`` (the load level being solved), ``residuals`` (history) and a ``hint``; no NaN is returned.
Returns ``NewtonResult(x, iterations, residuals)``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["NewtonError", "NewtonResult", "newton", "sparse_solve", "symmetric_solve"]


class NewtonError(RuntimeError):
    """Newton failed: ``load`` (load level), ``residuals`` (history), ``hint`` (what to try)."""

    def __init__(self, message: str, *, load=None, residuals: Sequence[float] = (), hint: str = "", unit: str = ""):
        self.load, self.residuals, self.hint = load, list(residuals), hint
        hist = ", ".join(f"{r:.3e}" for r in self.residuals[-8:])
        where = f"{load:.6g}{unit}" if isinstance(load, (int, float)) and not isinstance(load, bool) else f"{load}"
        if isinstance(load, (int, float)) and not unit:
            where += " (scaled load, no unit given)"
        super().__init__(f"{message} (load level {where}; residual history [{hist}]). Hint: {hint}")


class NewtonResult(NamedTuple):
    x: np.ndarray
    iterations: int
    residuals: list


def sparse_solve(K: sp.spmatrix, b: np.ndarray) -> np.ndarray:
    """Direct sparse solve; raises np.linalg.LinAlgError on a singular matrix."""
    try:
        x = spla.splu(sp.csc_matrix(K)).solve(b)
    except RuntimeError as e:  # SuperLU: "Factor is exactly singular"
        raise np.linalg.LinAlgError(str(e)) from e
    return x


def symmetric_solve(K: sp.spmatrix, b: np.ndarray, *, refine: int = 4, rtol: float = 1e-13) -> np.ndarray:
    """Direct solve for structurally symmetric (saddle-point) matrices: SuperLU in symmetric mode
    (minimum-degree ordering of K + K^T, diagonal pivots, several times fewer fill-ins than the default
    COLAMD for the mixed u-p tangent) followed by iterative refinement (|b - K x| <= rtol |b|, at most
    ``refine`` corrections: the unpivoted saddle-point factor is accurate to ~1e-6 before refinement).
    Falls back to :func:`sparse_solve` when the diagonal pivots fail or refinement stalls."""
    Kc = sp.csc_matrix(K)
    try:
        lu = spla.splu(Kc, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))
    except RuntimeError:
        return sparse_solve(Kc, b)
    x = lu.solve(b)
    nb = np.linalg.norm(b)
    res = b - Kc @ x
    rn = np.linalg.norm(res)
    for _ in range(refine):
        if not np.isfinite(rn) or rn <= rtol * nb:
            break
        x2 = x + lu.solve(res)
        res2 = b - Kc @ x2
        rn2 = np.linalg.norm(res2)
        if not rn2 < 0.5 * rn:  # stalled: keep the better one
            if rn2 < rn:
                x, rn = x2, rn2
            break
        x, res, rn = x2, res2, rn2
    if not (np.all(np.isfinite(x)) and rn <= 1e-8 * max(float(nb), 1e-300)):
        return sparse_solve(Kc, b)
    return x


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
    solver: Callable | None = None,
) -> NewtonResult:
    """Solve fun(x)[0] = 0 from x0 (see the module docstring)."""
    x = np.array(x0, dtype=float)
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
    for it in range(1, max_iter + 1):
        try:
            dx = (solver or sparse_solve)(K[free][:, free], -r[free])
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
                rt, Kt = fun(xt)
                with np.errstate(over="ignore", invalid="ignore"):  # overflow = exploding: cut the step
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
        x, r, K = xt, rt, Kt
        res.append(rn)
        if rn <= rtol * ref + atol and step * np.linalg.norm(dx) <= xtol * (1.0 + np.linalg.norm(x[free])):
            return NewtonResult(x, it, res)
    raise NewtonError(
        f"no convergence in {max_iter} iterations",
        load=load,
        residuals=res,
        hint="reduce the load step or loosen rtol/xtol",
    )
