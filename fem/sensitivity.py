r"""Exact parameter sensitivities of a converged equilibrium (forward, tangent-linear).

A converged state x of the scaled equations r(x; theta) = 0 moves with a parameter theta as

    K dx/dtheta = -dr/dtheta,        K = dr/dx (the tangent Newton factors),

so one solve with the converged tangent per parameter gives dx/dtheta exactly (to the residual tolerance and
round-off), with no re-solve of the nonlinear problem. An observable g(x; theta) then has
dg/dtheta = dg/dx . dx/dtheta + dg/dtheta|_x. This module holds the pieces every scene shares:

* :func:`residual_derivative`: dr/dtheta at fixed x, a central difference of the residual ASSEMBLY only (no
  Newton inside: the residual is an explicit smooth function of theta, so the step h ~ 1e-4 theta leaves
  ~1e-8 relative truncation and ~1e-12 round-off; the nonlinear solve is never differenced);
* :func:`directional`: dg/dx . v of an observable along a direction, by the same central difference;
* :func:`solve_all`: one LU factorisation of the converged tangent reused for every parameter;
* time runs (``fem.spheroid.compress(..., gradient=True)``): :class:`IsoLinearisation` (the Fung stress and its exact
  directional derivative in closed form), :func:`point_increments` / :func:`stress_residuals` (B dx at the points
  and int B^T P dV for a block of directions), :func:`solve_block` (all parameters as one block of right-hand sides,
  minimal-residual refinement from a kept factorisation, else one new factorisation).

Used by ``fem.blastula.inflate(..., gradient=True)``; verified against central differences of whole runs at
tight Newton tolerance and against the exact shell's JAX gradient (``tests/test_fem_sensitivity.py``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.kinematics import first_from_second
from tissuemech.fem.linalg import symmetric_factor


def _factor(K: sp.spmatrix) -> Callable[[np.ndarray], np.ndarray]:
    """A solve with one factorisation of K: the symmetric-mode SuperLU Newton uses (``fem.linalg``), refined."""
    return symmetric_factor(K)


__all__ = [
    "residual_derivative",
    "directional",
    "directional_field",
    "solve_all",
    "refined",
    "KeptLU",
    "maxwell_coefficients",
    "REL_STEP",
    "IsoLinearisation",
    "point_increments",
    "stress_residuals",
    "solve_block",
    "branch_names",
    "sensing_names",
    "explicit_residuals",
    "history_update_tangent",
]

REL_STEP = 1e-4  # relative step of the residual's central difference in a parameter (truncation ~1e-8)


def residual_derivative(residual: Callable[[float], np.ndarray], value: float, step: float | None = None) -> np.ndarray:
    """d residual(theta) / d theta at ``value`` by a central difference of the assembly (x held fixed).

    ``residual(theta)`` assembles the scaled residual with the parameter set to theta; ``step`` defaults to
    ``REL_STEP * max(|value|, 1)``."""
    h = REL_STEP * max(abs(float(value)), 1.0) if step is None else float(step)
    return (residual(float(value) + h) - residual(float(value) - h)) / (2.0 * h)


def directional(g: Callable[[np.ndarray], float], x: np.ndarray, v: np.ndarray) -> float:
    """dg/dx . v at ``x`` (g a smooth scalar observable of the state): a central difference along v, step
    1e-6 / max|v| (g's curvature over that step leaves ~1e-12)."""
    vmax = float(np.max(np.abs(v))) if v.size else 0.0
    if vmax == 0.0:
        return 0.0
    h = 1e-6 / vmax
    return (g(x + h * v) - g(x - h * v)) / (2.0 * h)


class KeptLU:
    """One LU factorisation reused across consecutive states (the steps of a hold change the tangent little):
    ``solver(K, key)`` returns a solve with ``K``, refined from the kept factor while its dof set ``key`` is the
    same and refinement converges; otherwise ``K`` is factored and kept."""

    def __init__(self) -> None:
        self.key: bytes | None = None
        self.solve: Callable[[np.ndarray], np.ndarray] | None = None

    def solver(self, K: sp.spmatrix, key: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        k = np.asarray(key).tobytes()
        if self.solve is None or self.key != k:
            self.key, self.solve = k, _factor(K)
            return self.solve
        ref = refined(K, getattr(self.solve, "unrefined", self.solve), gmres=False)

        def solve(b: np.ndarray) -> np.ndarray:
            x = ref(b)
            if ref.exact:  # type: ignore[attr-defined]  # refinement failed: K was factored, keep it
                self.solve = ref.exact[0]  # type: ignore[attr-defined]
            return x

        return solve


def refined(
    K: sp.spmatrix,
    approx: Callable[[np.ndarray], np.ndarray],
    tol: float = 1e-12,
    max_iter: int = 12,
    gmres: bool = True,
):
    """A solve with ``K`` from an approximate inverse ``approx`` (a factorisation of a nearby state: Newton's
    last factor, made one iterate before convergence) by iterative refinement to ``tol`` (relative residual),
    then (``gmres``) GMRES preconditioned by it, then a new factorisation of K (kept in ``solve.exact``)."""

    exact: list = []

    def solve(b: np.ndarray) -> np.ndarray:
        if exact:
            return exact[0](b)
        x = approx(b)
        nb = float(np.linalg.norm(b)) or 1.0
        for _ in range(max_iter):
            r = b - K @ x
            if np.linalg.norm(r) <= tol * nb:
                return x
            x = x + approx(r)
        if gmres:
            M = spla.LinearOperator(K.shape, matvec=approx, dtype=float)  # a farther factor: GMRES preconditioned
            y, info = spla.gmres(K, b, x0=x, M=M, rtol=tol, atol=0.0, restart=40, maxiter=4)
            if info == 0 and np.linalg.norm(b - K @ y) <= 10 * tol * nb:
                return y
        exact.append(_factor(K))  # too far from the factored state: factor K itself
        return exact[0](b)

    solve.exact = exact  # type: ignore[attr-defined]
    return solve


def solve_all(
    K: sp.spmatrix | None,
    rhs: Mapping[str, np.ndarray],
    what: str,
    factored: Callable[[np.ndarray], np.ndarray] | None = None,
) -> dict[str, np.ndarray]:
    """dx/dtheta = -K^-1 dr/dtheta for every parameter, one LU of the converged tangent ``K`` (or ``factored``,
    a solve with a factorisation Newton made at this state, reused as it is).

    Raises RuntimeError naming ``what`` (the state, e.g. "p = 120 Pa") when the tangent is singular (a limit
    point: the state does not depend smoothly on the parameters there)."""
    if factored is None:
        if K is None:
            raise ValueError("solve_all needs the tangent K or a factored solve")
        try:
            factored = _factor(K)
        except (RuntimeError, np.linalg.LinAlgError) as exc:  # SuperLU: "Factor is exactly singular"
            raise RuntimeError(
                f"the tangent at {what} is singular ({exc}): no parameter sensitivity at a limit point"
            ) from exc
    elif K is not None:  # a factorisation of a nearby iterate: iterative refinement with the exact tangent
        factored = refined(K, factored)
    out = {}
    for name, r in rhs.items():
        try:
            dx = -factored(np.asarray(r, float))
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            raise RuntimeError(
                f"the tangent at {what} is singular ({exc}): no parameter sensitivity at a limit point"
            ) from exc
        if not np.all(np.isfinite(dx)):
            raise RuntimeError(f"the sensitivity d x / d {name} at {what} is not finite: the tangent is singular")
        out[name] = dx
    return out


def directional_field(g: Callable[[np.ndarray], np.ndarray], x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """dg/dx . v of an array-valued smooth function of the state (e.g. the isochoric stress at the points), by a
    central difference along v (step 1e-6 / max|v|)."""
    vmax = float(np.max(np.abs(v))) if v.size else 0.0
    if vmax == 0.0:
        return np.zeros_like(g(x))
    h = 1e-6 / vmax
    return (g(x + h * v) - g(x - h * v)) / (2.0 * h)


def maxwell_coefficients(beta: np.ndarray, tau: np.ndarray, dt: float):
    """The Maxwell update's coefficients and their derivatives (``fem.viscoelastic.coefficients``):
    (decay_m = e^{-h_m}, b_m = beta_m g_m with g_m = (1 - e^{-h_m}) / h_m, h_m = dt / tau_m), d decay_m / d tau_m
    (1/s), d b_m / d beta_m, d b_m / d tau_m (1/s). decay does not depend on beta."""
    beta, tau = np.asarray(beta, float), np.asarray(tau, float)
    h = dt / tau
    decay = np.exp(-h)
    small = h < 1e-6
    hs = np.where(small, 1.0, h)
    g = np.where(small, 1.0 - h / 2 + h * h / 6, -np.expm1(-h) / hs)
    dg_dh = np.where(small, -0.5 + h / 3, (decay * (h + 1.0) - 1.0) / hs**2)
    dh_dtau = -h / tau
    return decay, beta * g, decay * h / tau, g, beta * dg_dh * dh_dtau


# ---- closed-form linearisations for time runs (issue 38: the cost of a time run's gradients) ----------------------


class IsoLinearisation:
    """The isochoric Fung stress of the points and its exact directional derivatives, in closed form.

    ``IsoLinearisation(f, C, alpha)``: f the 5-component deformation gradients (..., 5) (``fem.kinematics``),
    W' = C exp(alpha (Ibar1 - 3)) (``reduced.material.dW_dI1``). Attributes: ``P`` the first Piola stress
    W' dIbar1/dF, ``S`` the second S = 2 W' J^(-2/3) (I - I1/3 C^-1) (both unweighted, (..., 5)), ``d_alpha`` =
    Ibar1 - 3 (dP/dalpha = d_alpha P and dS/dalpha = d_alpha S at fixed F). :meth:`dS` gives dS along
    deformation-gradient increments df (k, ..., 5) for k directions at once: with dI1 = 2 f.df, dJ = dJ/dF.df,
    dIbar = J^(-2/3) dI1 - 2/3 Ibar/J dJ, dW' = alpha W' dIbar, d(J^(-2/3)) = -2/3 J^(-2/3)/J dJ and
    dC^-1 = dF^-1 F^-T + F^-1 dF^-T (dF^-1 = -F^-1 dF F^-1; hoop 1/F_tt^2), the product rule on S. Replaces two
    stress evaluations per direction of a central difference (the time runs' former cost)."""

    def __init__(self, f: np.ndarray, C: float, alpha: float) -> None:
        a, b, c, d, e = (f[..., i] for i in range(5))
        det2 = a * d - b * c
        self.J = e * det2
        self.I1 = np.einsum("...i,...i->...", f, f)
        self.gJ = np.stack([e * d, -e * c, -e * b, e * a, det2], axis=-1)
        self.Jm23 = self.J ** (-2.0 / 3.0)
        Ib = self.Jm23 * self.I1
        self.alpha = float(alpha)
        self.w1 = C * np.exp(self.alpha * (Ib - 3.0))
        self.d_alpha = Ib - 3.0
        self.Ib, self.f = Ib, f
        # F^-1 in plane (rows r, z) and C^-1 = F^-1 F^-T (symmetric), hoop 1/e^2
        self.Fi = np.stack([d / det2, -b / det2, -c / det2, a / det2], axis=-1)
        fi = self.Fi
        cinv = np.stack(
            [
                fi[..., 0] ** 2 + fi[..., 1] ** 2,
                fi[..., 0] * fi[..., 2] + fi[..., 1] * fi[..., 3],
                fi[..., 0] * fi[..., 2] + fi[..., 1] * fi[..., 3],
                fi[..., 2] ** 2 + fi[..., 3] ** 2,
                1.0 / (e * e),
            ],
            axis=-1,
        )
        self.Cinv = cinv
        self.Idev = np.array([1.0, 0.0, 0.0, 1.0, 1.0]) - (self.I1 / 3.0)[..., None] * cinv
        s = 2.0 * self.w1 * self.Jm23
        self.S = s[..., None] * self.Idev
        self._planes: tuple | None = None  # (f, F^-1, dJ/dF) component first, and scalars: dS builds them once
        self._scalars: tuple = ()
        self.P = (self.w1 * 2.0 * self.Jm23)[..., None] * f - ((2.0 / 3.0) * self.w1 * self.Jm23 / self.J * self.I1)[
            ..., None
        ] * self.gJ

    def dS(self, df: np.ndarray) -> np.ndarray:
        """dS along df (k, ..., 5) (or (..., 5)): the exact derivative of ``S`` (same shape as df). Computed on
        contiguous component planes (the points are few thousand: numpy's per-operation cost dominates)."""
        if self._planes is None:  # the state's component planes, once
            self._planes = tuple(np.ascontiguousarray(np.moveaxis(a, -1, 0)) for a in (self.f, self.Fi, self.gJ))
            s = 2.0 * self.w1 * self.Jm23
            self._scalars = (s, (2.0 / 3.0) / self.J, s * self.I1 / 3.0, 2.0 / self.f[..., 4] ** 3)
        (f0, f1, f2, f3, f4), (i0, i1, i2, i3), (g0, g1, g2, g3, g4) = self._planes
        s, c23J, sI13, two_e3 = self._scalars
        d0, d1, d2, d3, d4 = np.ascontiguousarray(np.moveaxis(df, -1, 0))
        dI1 = 2.0 * (d0 * f0 + d1 * f1 + d2 * f2 + d3 * f3 + d4 * f4)
        c = (d0 * g0 + d1 * g1 + d2 * g2 + d3 * g3 + d4 * g4) * c23J  # 2/3 dJ / J
        # S = s Idev, s = 2 W' J^(-2/3): ds = s (alpha dIbar - 2/3 dJ / J), dIbar = J^(-2/3) dI1 - 2/3 Ibar dJ / J
        ds = s * (self.alpha * (self.Jm23 * dI1 - self.Ib * c) - c)
        # dF^-1 = -F^-1 dF F^-1 (2 x 2 in plane: rows / columns (r, z), entries (0, 1, 2, 3) row-major)
        m0, m1, m2, m3 = d0 * i0 + d1 * i2, d0 * i1 + d1 * i3, d2 * i0 + d3 * i2, d2 * i1 + d3 * i3  # dF F^-1
        h0, h1, h2, h3 = -(i0 * m0 + i1 * m2), -(i0 * m1 + i1 * m3), -(i2 * m0 + i3 * m2), -(i2 * m1 + i3 * m3)
        # dS = ds Idev - s dI1 / 3 C^-1 - s I1 / 3 dC^-1, dC^-1 = dF^-1 F^-T + F^-1 dF^-T (hoop -2 dF_tt / F_tt^3)
        a = s * dI1 / 3.0
        Id, Ci = self.Idev, self.Cinv
        out = np.empty(ds.shape + (5,))
        out[..., 0] = ds * Id[..., 0] - a * Ci[..., 0] - sI13 * 2.0 * (h0 * i0 + h1 * i1)
        out[..., 1] = ds * Id[..., 1] - a * Ci[..., 1] - sI13 * (h0 * i2 + h1 * i3 + i0 * h2 + i1 * h3)
        out[..., 2] = out[..., 1]
        out[..., 3] = ds * Id[..., 3] - a * Ci[..., 3] - sI13 * 2.0 * (h2 * i2 + h3 * i3)
        out[..., 4] = ds * Id[..., 4] - a * Ci[..., 4] + sI13 * two_e3 * d4
        return out


def point_increments(asm, dx: np.ndarray) -> np.ndarray:
    """The deformation-gradient increments df = B dx_e at the points (k, n_el, n_qp, 5) of k state increments dx
    (ndof, k) (``fem.forms.Assembler``: f is affine in the displacement dofs)."""
    ne, nq, _, nd = asm.B.shape
    B2 = asm.B.reshape(ne, nq * 5, nd)
    de = dx[asm.edofs]  # (ne, nd, k)
    return np.matmul(B2, de).reshape(ne, nq, 5, -1).transpose(3, 0, 1, 2)


def stress_residuals(asm, P: np.ndarray) -> np.ndarray:
    """The displacement rows of the internal residual of k first Piola stresses P (k, n_el, n_qp, 5) (unweighted):
    int B^T P dV for each, as columns (ndof, k) (zeros on the mixed field's rows)."""
    ne, nq, _, nd = asm.B.shape
    k = P.shape[0]
    Pw = (P * asm.w[None, :, :, None]).reshape(k, ne, nq * 5).transpose(1, 0, 2)  # (ne, k, nq 5)
    re = np.matmul(Pw, asm.B.reshape(ne, nq * 5, nd))  # (ne, k, nd)
    out = np.empty((asm.ndof, k))
    idx = asm.edofs.ravel()
    for j in range(k):
        out[:, j] = np.bincount(idx, weights=re[:, j, :].ravel(), minlength=asm.ndof)
    return out


def solve_block(
    K: sp.spmatrix,
    approx: Callable[[np.ndarray], np.ndarray] | None,
    rhs: np.ndarray,
    what: str,
    tol: float = 1e-10,
    max_iter: int = 8,
) -> tuple[np.ndarray, Callable[[np.ndarray], np.ndarray], int]:
    """K X = rhs for the columns of ``rhs`` (n, k) at once: iterative refinement from ``approx`` (a factorisation of a
    nearby tangent, e.g. the previous step's) to ``tol`` (relative residual per column), else one new factorisation
    of K. Returns (X, the solve used (to keep for the next state), refinement iterations; -1: K was factored).
    Raises RuntimeError naming ``what`` when K is singular or the solution is not finite."""
    nb = np.maximum(np.linalg.norm(rhs, axis=0), 1e-300)

    def refine(solve: Callable[[np.ndarray], np.ndarray]) -> tuple[np.ndarray | None, int]:
        # minimal-residual refinement: X = X0 + Z c over every correction Z_j = solve(R_j) so far, c minimising
        # |rhs - K X| per column (a block flexible GMRES with the factorisation as preconditioner): on Fig. 10 it
        # takes 2-3 iterations in the hold where plain refinement took 3-6
        X0 = _columns(solve, rhs)
        R0 = rhs - K @ X0
        R, Zs, KZs, X = R0, [], [], X0
        for it in range(max_iter + 1):
            open_ = np.linalg.norm(R, axis=0) > tol * nb
            if not open_.any():
                return (X, it) if np.all(np.isfinite(X)) else (None, it)
            if it == max_iter or not np.all(np.isfinite(R)):
                break
            Z = _columns(solve, R[:, open_])  # the columns not yet converged widen the space (all columns use it)
            Zs.append(Z)
            KZs.append(np.asarray(K @ Z))
            W = np.hstack(KZs)
            c = _least_squares(W, R0)
            X = X0 + np.hstack(Zs) @ c
            R = R0 - W @ c
        return None, max_iter

    if approx is not None:
        X, it = refine(approx)
        if X is not None:
            return X, approx, it
    try:
        exact = symmetric_factor(K)
        fresh = getattr(exact, "unrefined", exact)
        X, _ = refine(fresh)
        if X is None:
            X = _columns(exact, rhs)
    except (RuntimeError, np.linalg.LinAlgError) as exc:
        raise RuntimeError(f"the tangent at {what} is singular ({exc}): no parameter sensitivity there") from exc
    if not np.all(np.isfinite(X)):
        raise RuntimeError(f"the sensitivity at {what} is not finite: the tangent is singular")
    return X, fresh, -1


def _least_squares(W: np.ndarray, B: np.ndarray) -> np.ndarray:
    """argmin_c |B - W c| per column of B for a tall, thin W (n, m), m a few dozen at most: the normal equations of
    the column-scaled W (a ridge of 1e-13 on their unit diagonal bounds c where the columns are nearly dependent).
    Only the convergence of the refinement depends on c's accuracy: its residual is recomputed as B - W c. Not
    ``numpy.linalg.lstsq``: OpenBLAS's threaded LAPACK took 0.1-0.4 s per call for m = 8-16 on the loaded 2-core
    machine (its gelsd on one thread, or this, well under 10 ms), 90 % of a Fig. 10 run with gradients."""
    s = np.maximum(np.linalg.norm(W, axis=0), 1e-300)
    Ws = W / s
    G = Ws.T @ Ws + 1e-13 * np.eye(W.shape[1])
    return np.linalg.solve(G, Ws.T @ B) / s[:, None]


def _columns(solve: Callable[[np.ndarray], np.ndarray], B: np.ndarray) -> np.ndarray:
    """solve applied to the columns of B (n, k): one call with all of them where the solver takes a block."""
    try:
        X = np.asarray(solve(B))
        if X.shape == B.shape:
            return X
    except (ValueError, TypeError):
        pass
    return np.column_stack([solve(B[:, j]) for j in range(B.shape[1])])


# ---- a time step's explicit parameter derivatives and the Maxwell history's (every scene's time runs) ----------


def branch_names(n_branches: int) -> list[tuple[str, str, int]]:
    """(name of beta_m, name of tau_m, m) as ``compare.fit`` spells them: "beta", "tau" for one branch, else
    "beta_1", "tau_1", ..."""
    if n_branches == 1:
        return [("beta", "tau", 0)]
    return [(f"beta_{m + 1}", f"tau_{m + 1}", m) for m in range(n_branches)]


def sensing_names(n_branches: int, tension: bool) -> tuple[list[str], dict[str, tuple[str, int]]]:
    """(the scaled parameters of a time run's sensitivities: "lnC", "alpha", ["surface_tension",] then each branch's
    beta and tau as :func:`branch_names` spells them; {branch parameter name: ("beta" | "tau", branch index)})."""
    names = ["lnC", "alpha"] + ["surface_tension"] * bool(tension)
    names += [n for b, t, _ in branch_names(n_branches) for n in (b, t)]
    which = {b: ("beta", m) for b, _, m in branch_names(n_branches)} | {
        t: ("tau", m) for _, t, m in branch_names(n_branches)
    }
    return names, which


def explicit_residuals(
    prob,
    x: np.ndarray,
    f: np.ndarray,
    lin: IsoLinearisation,
    iso: float,
    names: list[str],
    which: dict[str, tuple[str, int]],
    coef,
    dQ: np.ndarray,
    dS: np.ndarray,
    prev: ve.MaxwellState,
    gamma: float = 0.0,
) -> np.ndarray:
    """The explicit derivatives dr/dtheta (ndof, P) of a time step's scaled residual at its state ``x`` (deformation
    gradients ``f``, ``lin`` their ``IsoLinearisation``, ``iso`` the step's iso_scale), the parameters ``names``
    (ln C, alpha, [surface_tension,] beta_m / tau_m as ``which`` maps them), with the history before the step
    ``prev`` on this mesh and its sensitivities dQ (P, n_branches, ...), dS (P, ...); ``coef`` the step's
    ``sens.maxwell_coefficients`` (None: no branches). The step's stress is S_vol + iso_scale S_iso + extra_S with
    iso_scale = long_time + sum_m b_m and extra_S = sum_m (decay_m Q_m - b_m S_iso^n); ln C moves k = kappa / C and
    g = gamma / (C a0) as -k, -g."""
    asm, mat = prob.asm, prob.mat
    P = len(names)
    Pst = np.zeros((P,) + f.shape)
    Pst[1] = iso * lin.d_alpha[..., None] * lin.P
    if coef is not None:
        decay, b, ddecay, db_dbeta, db_dtau = coef
        d_extra = np.einsum("m,pm...->p...", decay, dQ) - b.sum() * dS
        d_iso = np.zeros(P)
        for j, n in enumerate(names):
            if n in which:
                kind, m = which[n]
                if kind == "beta":
                    d_iso[j] = db_dbeta[m]
                    d_extra[j] -= db_dbeta[m] * prev.S_iso
                else:
                    d_iso[j] = db_dtau[m]
                    d_extra[j] += ddecay[m] * prev.Q[m] - db_dtau[m] * prev.S_iso
        Pst += d_iso[:, None, None, None] * lin.P[None]
        Pst += first_from_second(f, d_extra)
    R = stress_residuals(asm, Pst)
    # ln C: k and g scale as 1 / C; r_q = ... - M q / k, so dr_q / dln C = -M q / k (and -g dr/dg)
    q = x[asm.qdofs]
    q = q - np.asarray([asm.q_ref, 0.0, 0.0])  # the law q = q_ref + kappa (J - 1) (q_ref = -2 g: fem.surface)
    R[asm.n_u :, 0] = -(np.matmul(asm.M, q[:, :, None])[..., 0] / mat.kappa).ravel()
    if gamma:
        rg = prob.tension_derivative(x)
        R[:, 2] += rg
        R[:, 0] -= gamma * rg
    return R


def history_update_tangent(
    names: list[str], which: dict, coef, Q: np.ndarray, S: np.ndarray, S_new: np.ndarray, dQ, dS, dS_new
) -> np.ndarray:
    """dQ^{n+1} (P, n_branches, ...) of the Maxwell update Q^{n+1} = decay Q^n + b (S^{n+1} - S^n)
    (``fem.viscoelastic.update``) from the sensitivities of its inputs and of its coefficients."""
    decay, b, ddecay, db_dbeta, db_dtau = coef
    jump = S_new - S
    out = decay[None, :, None, None, None] * dQ + b[None, :, None, None, None] * (dS_new - dS)[:, None]
    for j, n in enumerate(names):
        if n in which:
            kind, m = which[n]
            out[j, m] += db_dbeta[m] * jump if kind == "beta" else ddecay[m] * Q[m] + db_dtau[m] * jump
    return out
