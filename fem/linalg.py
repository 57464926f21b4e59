r"""Sparse linear algebra of the FE Newton solves: direct solvers, orderings, backends, kept factorisations.

Close to the machine (issue 14): the reduction ``K[free][:, free]`` is one gather ``K.data[map]`` with the
map built once per (sparsity pattern, free set) (:func:`submatrix`; ``free=None``: no copy at all);
:func:`symmetric_solve` computes its fill-reducing ordering once per pattern and then factors the
pre-permuted matrix (one gather again, straight into CSC, no format conversion). Backends of
:func:`symmetric_solve` (chosen by measurement, ``python -m tissuemech.compare.bench fem-perf``):
``"superlu"`` (scipy, the default: SuperLU in symmetric mode, MMD ordering of K + K^T reused) and
``"qdldl"`` (optional, ``pip install qdldl``: sparse LDL^T of the quasi-definite saddle-point matrix with
AMD, numeric refactorisation on the stored symbolic analysis; 2-5x faster factorisations here).
``set_backend("auto" | "superlu" | "qdldl")`` or the environment variable ``TISSUEMECH_SPARSE`` selects it
for the whole process; "auto" (default) takes qdldl when it imports; ``symmetric_factor(..., backend_name=)``
and :class:`Symmetric` choose one per call. Every backend ends with iterative refinement against the true K
(|b - K x| <= 1e-13 |b|) and falls back to pivoted SuperLU (COLAMD), so the answers do not depend on the
backend beyond round-off. Per-pattern plans are cached per thread (a qdldl plan holds mutable factors).

Linear-solver strategies of :func:`tissuemech.fem.newton.newton` (one object, its ``linear`` argument):

* :class:`Pivoted` (the default): SuperLU with partial pivoting (COLAMD), one factorisation per Newton
  iteration, nothing kept.
* :class:`Symmetric` (``ordering``, ``backend_name``): :func:`symmetric_factor`; newton keeps the last
  factorisation WITHIN a solve for the corrections after the residual has converged (chord steps).
* :class:`Reuse` (a :class:`Symmetric` or :class:`Custom` factor, ``rate``): also keeps the factorisation
  ACROSS solves (quasi-Newton between load or time steps) in its :class:`KeptFactor` ``kept``; one per run.
* :class:`Custom` (``solve=`` a one-shot ``solve(K, b) -> x``, or ``factor=`` a ``factor(K) -> solve(b)``,
  optionally ``kept=``): the old keywords ``newton(solver=, factor=, keep=)`` map to it.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = [
    "sparse_solve",
    "symmetric_solve",
    "symmetric_factor",
    "submatrix",
    "refine_solution",
    "supervariables",
    "mmd_ordering",
    "supervariable_ordering",
    "ORDERINGS",
    "NEWTON_STEP_RTOL",
    "KeptFactor",
    "set_backend",
    "backend",
    "available_backends",
    "LinearSolver",
    "Pivoted",
    "Symmetric",
    "Reuse",
    "Custom",
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


def submatrix(K, free: np.ndarray | None):
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


def _check_backend(name: str | None) -> None:
    if name is None:
        return
    if name not in ("superlu", "qdldl"):
        raise ValueError(f"sparse backend must be 'superlu' or 'qdldl' (or None: the selected one), got {name!r}")
    if name == "qdldl" and _qdldl is None:
        raise ValueError("sparse backend 'qdldl' is not installed (pip install qdldl)")


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


def mmd_ordering(K) -> np.ndarray:
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


def supervariable_ordering(K) -> np.ndarray:
    """p: the minimum-degree ordering of the supervariable quotient graph, each supervariable's unknowns
    kept together (in index order)."""
    Q, sv = supervariables(K)
    pq = mmd_ordering(Q)
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
        self.p = supervariable_ordering(K) if ordering == "supervariable" else mmd_ordering(K)  # K[p][:, p]: ordered
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


def refine_solution(K, b, x, solve, refine: int, rtol: float):
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
    K: sp.spmatrix, *, refine: int = 4, rtol: float = 1e-13, ordering: str = "mmd", backend_name: str | None = None
) -> Callable[[np.ndarray], np.ndarray]:
    """Factor K once (see :func:`symmetric_solve` for the arguments and backends); returns ``solve(b) -> x``,
    which can be called for many right-hand sides (``newton`` keeps it for the final corrections of a step).

    Raises:
        ValueError: an unknown ``ordering`` or ``backend_name`` (None: :func:`backend`; "superlu", "qdldl").
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
    _check_backend(backend_name)
    which = backend() if backend_name is None else backend_name
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
            x, rn = refine_solution(K, b, x, solve_p, refine, tol)
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


class LinearSolver:
    """How :func:`tissuemech.fem.newton.newton` solves its linear systems (the base of the strategies).

    Attributes newton reads: ``solve`` (a one-shot ``solve(K, b) -> x``, or None), ``factor`` (a
    ``factor(K) -> solve(b)`` whose last factorisation newton keeps for its chord corrections, or None) and
    ``kept`` (a :class:`KeptFactor` kept across solves, or None). At most one of ``solve``/``factor``;
    neither: :func:`sparse_solve`."""

    solve: Callable | None = None
    factor: Callable | None = None
    kept: KeptFactor | None = None


class Pivoted(LinearSolver):
    """SuperLU with partial pivoting (COLAMD), one factorisation per Newton iteration (:func:`sparse_solve`)."""

    def __init__(self) -> None:
        self.solve = sparse_solve

    def __repr__(self) -> str:
        return "Pivoted()"


class Symmetric(LinearSolver):
    """:func:`symmetric_factor` with ``ordering`` ("mmd" or "supervariable") and ``backend_name`` (None: the
    process-wide :func:`backend`; "superlu" or "qdldl"); newton keeps its factorisation within a solve.

    Raises:
        ValueError: an unknown ordering or backend name, or "qdldl" when it is not installed."""

    def __init__(self, ordering: str = "mmd", backend_name: str | None = None) -> None:
        if ordering not in ORDERINGS:
            raise ValueError(f"ordering must be one of {ORDERINGS}, got {ordering!r}")
        _check_backend(backend_name)
        self.ordering, self.backend_name = ordering, backend_name
        self.factor = self._factor

    def _factor(self, K):
        return symmetric_factor(K, ordering=self.ordering, backend_name=self.backend_name)

    def __repr__(self) -> str:
        return f"Symmetric(ordering={self.ordering!r}, backend_name={self.backend_name!r})"


class Reuse(LinearSolver):
    """A factorisation kept ACROSS newton calls (quasi-Newton between load or time steps; see
    :class:`KeptFactor`): ``Reuse(Symmetric(...), rate=0.25)``; one object per run (it holds ``kept``).

    Raises:
        ValueError: ``inner`` without a factor, or ``rate`` outside (0, 1)."""

    def __init__(self, inner: LinearSolver | None = None, rate: float = 0.25) -> None:
        inner = Symmetric() if inner is None else inner
        if inner.factor is None:
            raise ValueError("Reuse needs a factoring strategy (Symmetric or Custom(factor=...))")
        self.inner = inner
        self.factor = inner.factor
        self.kept = KeptFactor(rate)

    def __repr__(self) -> str:
        return f"Reuse({self.inner!r}, rate={self.kept.rate if self.kept else None})"


class Custom(LinearSolver):
    """User callables: ``solve(K, b) -> x`` (one shot) or ``factor(K) -> solve(b)``, with ``kept`` (a
    :class:`KeptFactor`, only with ``factor``). The old ``newton(solver=, factor=, keep=)`` keywords.

    Raises:
        ValueError: both ``solve`` and ``factor``, or ``kept`` without ``factor``."""

    def __init__(
        self, solve: Callable | None = None, factor: Callable | None = None, kept: KeptFactor | None = None
    ) -> None:
        if solve is not None and factor is not None:
            raise ValueError("give newton a solver or a factor, not both")
        if kept is not None and factor is None:
            raise ValueError("newton keeps a factorisation across calls (keep=) only with a factor")
        self.solve, self.factor, self.kept = solve, factor, kept
