r"""One Newton-Raphson solver for every FE scene.

``newton(fun, x0, *, free=None, ref_norm=1.0, rtol=1e-9, xtol=1e-9, max_iter=30, admissible=None,
load=None, max_backtracks=8, growth=1e3, atol=0.0, solver=None, factor=None, keep=None, diverging_after=8)`` solves r(x) = 0
with ``fun(x) -> (r, K)`` (r ndarray, K scipy sparse). Hooks:

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
  sweeps to 1 kPa in 1-5 steps: 22-34 % fewer factorisations, the same cuts: ``python
  notes/issue14_predictor.py``).

Sparse direct solves (SuperLU via ``scipy.sparse.linalg.splu``); ``solver(K, b) -> x`` replaces it
(e.g. :func:`symmetric_solve`, fast for the symmetric saddle-point systems of the mixed u-p form).
``factor(K) -> solve`` (e.g. :func:`symmetric_factor`) instead of ``solver`` lets newton keep the last
factorisation: once the residual has converged (only the step test |dx| <= xtol (1 + |x|) is pending) the
remaining corrections use it (a chord step with the tangent one iterate back, whose error is the product of
two converged increments) instead of a new tangent and factorisation; a correction that fails (not at
most half the step before, residual up 10-fold, inadmissible state, a failed solve) falls back to a full
iteration. The convergence test is the same.

``keep`` (a :class:`KeptFactor`, one per run, with ``factor``) keeps the factorisation ACROSS solves
(modified / quasi-Newton between load or time steps): a solve starts with Broyden steps (Kelley's inverse
form, H0 = the kept factorisation without refinement, full steps) and factors a new tangent only when a
step does not contract (the first must cut the residual to ``keep.rate`` of the guess's, the others must not
raise it and be at most half the step before); after the first full iteration of a solve, one more Broyden
phase runs on that new factorisation. Each Broyden step costs one residual and one solve (no tangent, no
factorisation): the 4x8 blastula sweep 115 -> 28 factorisations, Fig. 10 58 -> 13 (``python
notes/ab_commits.py``). ``iterations`` counts both kinds. On failure ``NewtonError`` carries
``load`` (the load level being solved), ``residuals`` (history) and a ``hint``; no NaN is returned.
Returns ``NewtonResult(x, iterations, residuals)``.

Close to the machine (issue 14): the reduction ``K[free][:, free]`` is one gather ``K.data[map]`` with the
map built once per (sparsity pattern, free set) (``free=None``: no copy at all); :func:`symmetric_solve`
computes its fill-reducing ordering once per pattern and then factors the pre-permuted matrix (one gather
again, straight into CSC, no format conversion). Backends of :func:`symmetric_solve` (chosen by measurement,
``python -m tissuemech.compare.bench fem-perf``): ``"superlu"`` (scipy, the default: SuperLU in symmetric
mode, MMD ordering of K + K^T reused) and ``"qdldl"`` (optional, ``pip install qdldl``: sparse LDL^T of the
quasi-definite saddle-point matrix with AMD, numeric refactorisation on the stored symbolic analysis; 2-5x
faster factorisations here). ``set_backend("auto" | "superlu" | "qdldl")`` or the environment variable
``TISSUEMECH_SPARSE`` selects it; "auto" (default) takes qdldl when it imports. Every backend ends with
iterative refinement against the true K (|b - K x| <= 1e-13 |b|) and falls back to pivoted SuperLU (COLAMD),
so the answers do not depend on the backend beyond round-off.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = [
    "NewtonError",
    "NewtonResult",
    "newton",
    "sparse_solve",
    "symmetric_solve",
    "symmetric_factor",
    "KeptFactor",
    "set_backend",
    "backend",
    "available_backends",
]

try:  # optional sparse LDL^T (wheel on the package index; no compiler needed)
    import qdldl as _qdldl
except ImportError:  # pragma: no cover - depends on the environment
    _qdldl = None

_BACKEND = ["auto"]


def available_backends() -> list[str]:
    """The symmetric-solve backends that import here ("superlu" always)."""
    return ["superlu"] + (["qdldl"] if _qdldl is not None else [])


def set_backend(name: str) -> None:
    """Select the backend of :func:`symmetric_solve`: "auto", "superlu" or "qdldl" (raises ValueError)."""
    if name not in ("auto", "superlu", "qdldl"):
        raise ValueError(f"sparse backend must be 'auto', 'superlu' or 'qdldl', got {name!r}")
    if name == "qdldl" and _qdldl is None:
        raise ValueError("sparse backend 'qdldl' is not installed (pip install qdldl)")
    _BACKEND[0] = name


def backend() -> str:
    """The backend :func:`symmetric_solve` uses now ("superlu" or "qdldl")."""
    name = _BACKEND[0]
    if name == "auto":
        env = os.environ.get("TISSUEMECH_SPARSE", "auto")
        name = env if env in ("superlu", "qdldl") else "auto"
    if name == "qdldl" and _qdldl is None:
        name = "superlu"
    if name == "auto":
        name = "qdldl" if _qdldl is not None else "superlu"
    return name


class _Cache:
    """Small LRU of per-pattern plans keyed by (format, shape, nnz, extra) and checked against the
    stored ``indptr``/``indices`` (identity first, then equality: O(nnz), far below a factorisation)."""

    def __init__(self, size: int = 8):
        self.size = size
        self.items: list[tuple] = []

    def get(self, K, extra, build):
        key = (K.format, K.shape, K.nnz, extra)
        for i, (k, ptr, ind, plan) in enumerate(self.items):
            if k == key and (
                (ptr is K.indptr and ind is K.indices)
                or (np.array_equal(ptr, K.indptr) and np.array_equal(ind, K.indices))
            ):
                if i:
                    self.items.insert(0, self.items.pop(i))
                return plan
        plan = build()
        self.items.insert(0, (key, K.indptr, K.indices, plan))
        del self.items[self.size :]
        return plan


def _canonical(K) -> sp.spmatrix:
    """K as CSR or CSC without duplicate entries, sorted indices (no copy when it already is)."""
    if K.format not in ("csr", "csc"):
        K = sp.csr_matrix(K)
    if not K.has_canonical_format:
        K = K.copy()
        K.sum_duplicates()
    return K


def _gather_plan(K, rows: np.ndarray, cols: np.ndarray, fmt: str = "csc", upper: bool = False):
    """(src, indices, indptr): M = K[rows][:, cols] in format ``fmt`` (triu if ``upper``) is
    ``M.data = K.data[src]`` with the returned pattern."""
    tag = K.copy()
    tag.data = np.arange(1, K.nnz + 1, dtype=float)
    M = tag[rows][:, cols]
    if upper:
        M = sp.triu(M)
    M = M.asformat(fmt)
    M.sum_duplicates()
    M.sort_indices()
    return M.data.astype(np.int64) - 1, M.indices.copy(), M.indptr.copy()


_TLS = threading.local()  # plans are per thread: a qdldl plan holds mutable factors


def _sub_cache() -> _Cache:
    c = getattr(_TLS, "sub", None)
    if c is None:
        c = _TLS.sub = _Cache()
    return c


def _sym_cache() -> list:
    c = getattr(_TLS, "sym", None)
    if c is None:
        c = _TLS.sym = []
    return c


def _submatrix(K, free: np.ndarray | None):
    """K[free][:, free] (CSR) by one cached gather; K itself when ``free`` is None."""
    if free is None:
        return K
    K = _canonical(K)
    n = free.size
    if n == K.shape[0] and n == K.shape[1] and np.array_equal(free, np.arange(n)):
        return K
    plan = _sub_cache().get(K, free.tobytes(), lambda: _gather_plan(K, free, free, "csr"))
    src, ind, ptr = plan
    return sp.csr_matrix((K.data[src], ind, ptr), shape=(n, n))


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
    x: np.ndarray
    iterations: int
    residuals: list


def sparse_solve(K: sp.spmatrix, b: np.ndarray) -> np.ndarray:
    """Direct sparse solve; raises np.linalg.LinAlgError on a singular matrix."""
    try:
        # (factoring K^T, the CSR arrays read as CSC, and solving trans="T" saves the conversion but loses
        # 5 digits of the residual with COLAMD's row pivots here: measured, not used)
        x = spla.splu(sp.csc_matrix(K)).solve(b)
    except RuntimeError as e:  # SuperLU: "Factor is exactly singular"
        raise np.linalg.LinAlgError(str(e)) from e
    return x


ORDERINGS = ("mmd", "supervariable")

# The relative linear residual |b - K x| <= NEWTON_STEP_RTOL |b| a Newton step's solve is refined to (the
# forcing term of an inexact Newton method: the next nonlinear residual is ~1e-6 of this one's plus the
# quadratic term, so the iteration converges as with an exact solve, to the same tolerances); ``solve``
# itself refines to 1e-13. The unpivoted symmetric factorisation leaves 1e-10 - 1e-5 before refinement, so a
# step saves one or two refinement sweeps (a solve and a matvec each): issue 14.
NEWTON_STEP_RTOL = 1e-6


def _mmd(K) -> np.ndarray:
    """p such that K[p][:, p] has SuperLU's minimum-degree ordering of K + K^T (pattern only: a regular
    stand-in with K's pattern is factored)."""
    n = K.shape[0]
    A = sp.csc_matrix(K, copy=True)
    A.data[:] = 1.0
    A = A + sp.identity(n, format="csc") * (n + 1.0)
    lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))
    return np.argsort(lu.perm_c)


def supervariables(K) -> tuple[sp.csr_matrix, np.ndarray]:
    """(Q, sv): the quotient graph of the structure of K + K^T over its supervariables (unknowns whose rows,
    diagonal included, have the same column set: the 2 displacement dofs of a node, the 3 q-dofs of an
    element) and the supervariable of each unknown, sv (n,). Rows are told apart by two random-weighted sums of
    their column indices (fixed seed: deterministic); a collision only merges two rows in the ordering, the
    permutation stays valid."""
    n = K.shape[0]
    G = sp.csr_matrix(K, copy=True)
    G.data[:] = 1.0
    G = ((G + G.T + sp.identity(n, format="csr")) != 0).astype(float).tocsr()
    G.sort_indices()
    w = np.random.default_rng(14).random((2, n))
    starts = G.indptr[:-1]
    key = np.stack([np.diff(G.indptr).astype(float)] + [np.add.reduceat(wi[G.indices], starts) for wi in w], 1)
    _, sv = np.unique(key, axis=0, return_inverse=True)
    sv = sv.ravel()
    S = sp.csr_matrix((np.ones(n), (np.arange(n), sv)), shape=(n, int(sv.max()) + 1))
    Q = (S.T @ G @ S).tocsr()
    return Q, sv


def _supervariable_mmd(K) -> np.ndarray:
    """p: the minimum-degree ordering of the supervariable quotient graph, each supervariable's unknowns
    kept together (in index order)."""
    Q, sv = supervariables(K)
    pq = _mmd(Q)
    rank = np.empty(pq.size, dtype=np.int64)
    rank[pq] = np.arange(pq.size)
    return np.argsort(rank[sv], kind="stable")


class _SymPlan:
    """Per-pattern plan of :func:`symmetric_solve`: the fill-reducing permutation p (computed once: MMD on
    K + K^T by SuperLU, or on its supervariable quotient graph), the gather map of P K P^T (CSC), and for
    qdldl the gather map of the upper triangle of K and the qdldl solver (its AMD ordering and symbolic
    analysis, kept for refactorisation)."""

    def __init__(self, K, ordering: str = "mmd"):
        n = K.shape[0]
        self.ordering = ordering
        self.p = _supervariable_mmd(K) if ordering == "supervariable" else _mmd(K)  # K[p][:, p]: ordered
        self.pinv = np.empty(n, dtype=np.int64)
        self.pinv[self.p] = np.arange(n)
        self.perm = _gather_plan(K, self.p, self.p, "csc")
        self.upper = None
        self.ldl = None
        self.generation = 0  # qdldl refactorisations so far (a kept solve checks its own is still current)
        self.n = n
        self.format, self.indptr, self.indices = K.format, K.indptr, K.indices
        self.keys = _keys(K)


def _keys(K) -> np.ndarray:
    """Sorted linear keys major * n + minor of the stored entries of a canonical CSR/CSC matrix."""
    major = np.repeat(np.arange(K.shape[0] if K.format == "csr" else K.shape[1]), np.diff(K.indptr))
    return major.astype(np.int64) * K.shape[0] + K.indices


def _sym_plan(K, ordering: str = "mmd"):
    """(plan, data): the plan of K's pattern and K's values in that pattern's storage order. A pattern that
    lost entries (exact zeros dropped by a sparse sum, e.g. K_int - p K_pressure) reuses the plan of the
    pattern that contains it (its values embedded, the missing ones zero) instead of a new ordering."""
    _SYM = _sym_cache()  # plans of this thread, most recent first
    for i, plan in enumerate(_SYM):
        if plan.n != K.shape[0] or plan.format != K.format or plan.ordering != ordering:
            continue
        if (plan.indptr is K.indptr and plan.indices is K.indices) or (
            plan.indices.size == K.nnz
            and np.array_equal(plan.indptr, K.indptr)
            and np.array_equal(plan.indices, K.indices)
        ):
            data = K.data
        elif K.nnz < plan.keys.size:
            kk = _keys(K)
            pos = np.searchsorted(plan.keys, kk)
            if pos[-1:].max(initial=0) >= plan.keys.size or not np.array_equal(plan.keys[pos], kk):
                continue
            data = np.zeros(plan.keys.size)
            data[pos] = K.data
        else:
            continue
        if i:
            _SYM.insert(0, _SYM.pop(i))
        return plan, data
    # a new pattern: plan for its union with the latest plan of the same shape (patterns that differ by
    # dropped zeros then converge to one plan after a few calls)
    same = [p for p in _SYM if p.n == K.shape[0] and p.format == K.format and p.ordering == ordering]
    data = K.data
    if same:
        kk = _keys(K)
        ku = np.union1d(same[0].keys, kk)
        n = K.shape[0]
        data = np.zeros(ku.size)
        data[np.searchsorted(ku, kk)] = K.data
        ptr = np.searchsorted(ku // n, np.arange(n + 1)).astype(K.indptr.dtype)
        K = (sp.csr_matrix if K.format == "csr" else sp.csc_matrix)(
            (data, (ku % n).astype(K.indices.dtype), ptr), shape=K.shape
        )
    plan = _SymPlan(K, ordering)
    _SYM.insert(0, plan)
    del _SYM[8:]
    return plan, data


def _refine(K, b, x, solve, refine: int, rtol: float):
    """Iterative refinement of K x = b with the approximate ``solve``; returns (x, |b - K x|)."""
    res = b - K @ x
    rn = np.linalg.norm(res)
    nb = np.linalg.norm(b)
    for _ in range(refine):
        if not np.isfinite(rn) or rn <= rtol * nb:
            break
        x2 = x + solve(res)
        res2 = b - K @ x2
        rn2 = np.linalg.norm(res2)
        if not rn2 < 0.5 * rn:  # stalled: keep the better one
            if rn2 < rn:
                x, rn = x2, rn2
            break
        x, res, rn = x2, res2, rn2
    return x, rn


def symmetric_solve(
    K: sp.spmatrix, b: np.ndarray, *, refine: int = 4, rtol: float = 1e-13, ordering: str = "mmd"
) -> np.ndarray:
    """Direct solve for structurally symmetric (saddle-point) matrices: ``symmetric_factor(K, ...)(b)``.

    Args:
        K: square sparse matrix (n, n), structurally symmetric (values may be slightly unsymmetric,
            e.g. a follower load: refinement against the true K corrects that).
        b: right-hand side (n,).
        refine: at most this many refinement corrections; rtol: target |b - K x| / |b|.
        ordering: the fill-reducing ordering of the "superlu" backend, computed once per pattern: "mmd"
            (minimum degree of K + K^T) or "supervariable" (minimum degree of the quotient graph of the
            supervariables: nodes and elements; 20-45 % fewer factorisation flops on the fine blastula
            tangents, 10-30 % more on the spheroid's: ``python -m tissuemech.compare.bench fem-perf``).
    Returns:
        x (n,).
    Raises:
        np.linalg.LinAlgError: singular K (from the pivoted fallback).
        ValueError: an unknown ``ordering``.

    Backend "superlu": SuperLU in symmetric mode (diagonal pivots, several times fewer fill-ins than COLAMD
    for the mixed u-p tangent) on P K P^T with the minimum-degree ordering of K + K^T computed once per
    pattern. Backend "qdldl": LDL^T of the upper triangle with refactorisation on the stored analysis.
    Both are followed by iterative refinement; when the diagonal pivots fail or refinement stalls above
    1e-8 |b|, the pivoted :func:`sparse_solve` (COLAMD) answers instead."""
    return symmetric_factor(K, refine=refine, rtol=rtol, ordering=ordering)(b)


def symmetric_factor(
    K: sp.spmatrix, *, refine: int = 4, rtol: float = 1e-13, ordering: str = "mmd"
) -> Callable[[np.ndarray], np.ndarray]:
    """Factor K once (see :func:`symmetric_solve` for the arguments and backends); returns ``solve(b) -> x``,
    which can be called for many right-hand sides (``newton`` keeps it for the final corrections of a step).

    Raises:
        ValueError: an unknown ``ordering``.
    ``solve`` raises np.linalg.LinAlgError for a singular K (the pivoted fallback). The qdldl backend keeps
    one solver per pattern and refactors it in place: a ``solve`` whose factors were overwritten by a later
    factorisation of another matrix with the same pattern refactors its own K first (correct, at the cost of
    one numeric factorisation)."""
    if ordering not in ORDERINGS:
        raise ValueError(f"ordering must be one of {ORDERINGS}, got {ordering!r}")
    K = _canonical(K)
    fallback: list = []

    def pivoted(b: np.ndarray) -> np.ndarray:
        if not fallback:
            try:
                fallback.append(spla.splu(sp.csc_matrix(K)))
            except RuntimeError as e:  # SuperLU: "Factor is exactly singular"
                raise np.linalg.LinAlgError(str(e)) from e
        return fallback[0].solve(b)

    pivoted.unrefined = pivoted  # type: ignore[attr-defined]
    try:
        plan, data = _sym_plan(K, ordering)
    except RuntimeError:
        return pivoted
    which = backend()
    solve_p = None
    try:
        if which == "qdldl":
            if plan.upper is None:
                ar = np.arange(plan.n)
                T = (sp.csr_matrix if plan.format == "csr" else sp.csc_matrix)(
                    (data, plan.indices, plan.indptr), shape=K.shape
                )
                plan.upper = _gather_plan(T, ar, ar, "csc", upper=True)
            src, ind, ptr = plan.upper
            U = sp.csc_matrix((data[src], ind, ptr), shape=K.shape)
            mine = [0]  # the plan's generation that holds this U's factors

            def refactor():
                if plan.ldl is None:
                    plan.ldl = _qdldl.Solver(U, upper=True)  # AMD ordering + symbolic analysis, kept
                else:
                    plan.ldl.update(U, upper=True)
                plan.generation += 1
                mine[0] = plan.generation

            refactor()

            def solve_p(v):
                if plan.ldl is None or plan.generation != mine[0]:  # overwritten since: factor U again
                    refactor()
                return plan.ldl.solve(v)
        else:
            src, ind, ptr = plan.perm
            Kp = sp.csc_matrix((data[src], ind, ptr), shape=K.shape)
            lu = spla.splu(Kp, permc_spec="NATURAL", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))
            solve_p = lambda v: lu.solve(v[plan.p])[plan.pinv]
    except (RuntimeError, ValueError):
        if which == "qdldl":
            plan.ldl = None
        return pivoted

    def solve(b: np.ndarray, tol: float = rtol) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        nb = np.linalg.norm(b)
        x = None
        try:
            x = solve_p(b)
            x, rn = _refine(K, b, x, solve_p, refine, tol)
        except (RuntimeError, ValueError):
            x = None
        if x is None or not (np.all(np.isfinite(x)) and rn <= max(tol, 1e-8) * max(float(nb), 1e-300)):
            return pivoted(b)
        return x

    solve.unrefined = solve_p  # type: ignore[attr-defined]  # a fixed linear map (quasi-Newton's H0)
    solve.inexact = lambda b: solve(b, NEWTON_STEP_RTOL)  # type: ignore[attr-defined]  # a Newton step's accuracy
    return solve


class KeptFactor:
    """A factorisation kept ACROSS ``newton`` calls (quasi-Newton between load or time steps).

    The caller makes one per run and passes it to every ``newton(..., factor=..., keep=...)`` of the run:
    a solve then starts with Broyden steps whose H0 is the factorisation of an earlier step, and newton
    factors a new tangent only when a step does not contract: |r_1| <= ``rate`` |r_0| for the first step;
    after it the residual must not grow and each step must be at most half the one before. The convergence
    test is newton's own. A kept factorisation of another size is not used; a solve that fails after
    Broyden steps is solved again by Newton alone from its guess.

    Args:
        rate: the residual reduction the first Broyden step of a solve must reach (0 < rate < 1; default 0.25).
    Attributes:
        solve: the kept ``solve(b) -> x`` (None: nothing kept yet); ``n``: its size; ``age``: newton solves begun
            since it was stored (0: the last solve converged and factored it on its way, e.g. for a predictor's
            slope; a failed solve leaves it >= 1).
        broyden_steps, refused, retried: Broyden steps accepted / phases ended by a step that did not
            contract / solves that failed after Broyden steps and were solved again by Newton alone.
    Raises:
        ValueError: ``rate`` outside (0, 1).
    """

    def __init__(self, rate: float = 0.25):
        if not 0.0 < rate < 1.0:
            raise ValueError(f"KeptFactor rate must lie in (0, 1), got {rate!r}")
        self.rate = float(rate)
        self.solve: Callable | None = None
        self.n = -1
        self.age = 0  # newton solves begun since the kept factorisation was stored
        self.broyden_steps = 0
        self.refused = 0
        self.retried = 0

    def store(self, solve: Callable | None, n: int) -> None:
        """Keep ``solve`` (a factorisation of size n) for the next newton call."""
        self.solve, self.n = solve, int(n)
        self.age = 0


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
    solver: Callable | None = None,
    factor: Callable | None = None,
    keep: KeptFactor | None = None,
    diverging_after: int | None = 8,
) -> NewtonResult:
    """Solve fun(x)[0] = 0 from x0 (see the module docstring)."""
    if diverging_after is not None and (
        isinstance(diverging_after, bool) or not isinstance(diverging_after, (int, np.integer)) or diverging_after < 3
    ):
        raise ValueError(f"diverging_after must be a whole number >= 3 or None, got {diverging_after!r}")
    if solver is not None and factor is not None:
        raise ValueError("give newton a solver or a factor, not both")
    if keep is not None and factor is None:
        raise ValueError("newton keeps a factorisation across calls (keep=) only with a factor")
    opts = dict(free=free, ref_norm=ref_norm, rtol=rtol, xtol=xtol, max_iter=max_iter, admissible=admissible)
    opts.update(load=load, max_backtracks=max_backtracks, growth=growth, atol=atol, solver=solver, factor=factor)
    opts.update(diverging_after=diverging_after)
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
            solver, factor, keep, diverging_after) -> NewtonResult:  # fmt: skip
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
            Kf = _submatrix(_tangent(K), sub)
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
        last_dx = step * float(np.linalg.norm(dx))
        if step != 1.0:
            kept = None  # a cut step: keep full Newton iterations until the residual has converged again
        if rn <= tol and last_dx <= xtol * (1.0 + np.linalg.norm(x[free])):
            return NewtonResult(x, it, res)
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
