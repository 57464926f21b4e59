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
* :func:`solve_all`: one LU factorisation of the converged tangent reused for every parameter.

Used by ``fem.blastula.inflate(..., gradient=True)``; verified against central differences of whole runs at
tight Newton tolerance and against the exact shell's JAX gradient (``tests/test_fem_sensitivity.py``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

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
