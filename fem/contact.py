r"""Rigid, flat, frictionless plane z = h: exact unilateral contact by an active set.

The plane lies above the body (outward normal of the body at contact: +z) and moves down. Candidate
nodes are boundary nodes (scalar node indices into the interleaved displacement, dof ``2 i + 1`` is
u_z). With the nodal gap

    g_i = h - (Z_i + u_z,i)  >= 0,

the Signorini conditions g_i >= 0, N_i >= 0, g_i N_i = 0 are enforced node by node: on the ACTIVE
nodes u_z,i = h - Z_i is prescribed (a Dirichlet condition; the Lagrange multiplier is the reaction,
no penalty factor), u_r stays free (frictionless). With the residual r = f_int (no other loads on
those dofs) the contact force the plate exerts on node i is -N_i e_z with

    N_i = -r_i(u_z)  (>= 0 when the plate pushes; nodal reactions include the 2 pi R of dV).

Active-set iteration (inside one load/time step): solve equilibrium for the current set; activate
inactive nodes that penetrate (g_i < -tol), release active nodes whose multiplier is tensile
(N_i < -tol); repeat until the set is a fixed point. At the fixed point g >= 0 and N >= 0 to round-off
(the tolerances, ``gap_tol`` and ``force_tol`` relative to the total force). A set that repeats
(cycling) raises ``ContactError`` so the caller can cut the step.

API: ``RigidPlane(X, nodes)`` with ``.gap(x, h)``, ``.impose(x, h, active)``, ``.normal_force(r)``
(N per candidate), ``.constrained(active)`` (dof indices), ``.solve(fun, x0, h, active0, free, ...)``
-> ``ContactSolution(x, active, iterations, sets)``; ``ContactError``.
All quantities are in the solver's scaled units (length / a0, force / (C a0^2)).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from tissuemech.fem.newton import NewtonError, newton

__all__ = ["RigidPlane", "ContactSolution", "ContactError"]


class ContactError(NewtonError):
    """The active set did not settle (cycling or too many updates) at this load level."""


class ContactSolution(NamedTuple):
    x: np.ndarray
    active: np.ndarray  # bool per candidate node
    iterations: int  # Newton iterations summed over active-set passes
    sets: int  # active-set passes (1 = the initial guess of the set was right)
    residual: np.ndarray  # full residual at x (reactions on the constrained dofs)


class RigidPlane:
    """Frictionless rigid plane z = h above the body, acting on the candidate boundary ``nodes``."""

    def __init__(self, X: np.ndarray, nodes: np.ndarray):
        nodes = np.asarray(nodes, dtype=int)
        if nodes.ndim != 1 or nodes.size == 0:
            raise ValueError("contact needs a non-empty 1D array of candidate boundary nodes")
        order = np.argsort(np.arctan2(X[0, nodes], X[1, nodes]))  # from the top pole outward
        self.nodes = nodes[order]
        self.R, self.Z = X[0, self.nodes].copy(), X[1, self.nodes].copy()
        self.dofs = 2 * self.nodes + 1

    def gap(self, x: np.ndarray, h: float) -> np.ndarray:
        """g_i = h - z_i for every candidate (scaled length)."""
        return h - (self.Z + x[self.dofs])

    def impose(self, x: np.ndarray, h: float, active: np.ndarray) -> np.ndarray:
        """Copy of x with u_z = h - Z on the active nodes (they touch the plane exactly)."""
        x = np.array(x, dtype=float)
        x[self.dofs[active]] = h - self.Z[active]
        return x

    def normal_force(self, r: np.ndarray) -> np.ndarray:
        """Compressive nodal contact force N_i = -r(u_z,i) (meaningful on active nodes)."""
        return -r[self.dofs]

    def constrained(self, active: np.ndarray) -> np.ndarray:
        return self.dofs[active]

    def solve(
        self,
        fun: Callable,
        x0: np.ndarray,
        h: float,
        active0: np.ndarray,
        free: np.ndarray,
        *,
        gap_tol: float = 1e-10,
        force_tol: float = 1e-9,
        max_sets: int = 12,
        load=None,
        residual: Callable | None = None,
        **newton_kw,
    ) -> ContactSolution:
        """Equilibrium with the exact contact conditions at plane height h.

        ``fun(x) -> (r, K)`` the residual/tangent without contact; ``free`` the unknowns without
        contact (Dirichlet dofs excluded); the active set starts from ``active0`` plus every node that
        penetrates in x0. ``residual(x) -> r`` (optional) skips the tangent when only the reactions are
        needed. ``newton_kw`` go to :func:`fem.newton.newton`.
        """
        active = np.asarray(active0, bool) | (self.gap(x0, h) < -gap_tol)
        x = np.asarray(x0, float)
        seen, its = set(), 0
        for k in range(1, max_sets + 1):
            key = active.tobytes()
            if key in seen:
                raise ContactError(
                    "the contact active set cycles", load=load, hint="reduce the load/time step near the contact edge"
                )
            seen.add(key)
            x = self.impose(x, h, active)
            fr = np.setdiff1d(free, self.dofs[active], assume_unique=True)
            res = newton(fun, x, free=fr, load=load, **newton_kw)
            x, its = res.x, its + res.iterations
            r = residual(x) if residual is not None else fun(x)[0]
            N, g = self.normal_force(r), self.gap(x, h)
            scale = max(float(np.sum(N[active])), 1e-300)
            release = active & (N < -force_tol * scale)
            enter = ~active & (g < -gap_tol)
            if not release.any() and not enter.any():
                return ContactSolution(x, active, its, k, r)
            # release first (the most tensile only when several: avoids losing contact at once)
            new = active.copy()
            new[enter] = True
            if release.any():
                new[np.flatnonzero(release)[np.argmin(N[release])]] = False
            active = new
        raise ContactError(
            f"the contact active set did not settle in {max_sets} passes", load=load, hint="reduce the load/time step"
        )
