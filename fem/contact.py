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
(N per candidate), ``.constrained(active)`` (dof indices), ``.contact_radius(x, active, h)``,
``.solve(fun, x0, h, active0, free, ...)`` -> ``ContactSolution(x, active, iterations, sets, residual)``;
``ContactError``. All quantities are in the solver's scaled units (length / a0, force / (C a0^2)).

Contact treatments (strategies, ``contact_treatment("fitted" | "nodal" | object)``): ``NodalContact()`` is the
active set above on one fixed mesh (the force carries the edge quantisation); ``FittedEdge(tol=EDGE_TOL)`` puts
the contact edge on a node of a contact-edge-fitted mesh (``fem.mesh.fitted_mesh``): :class:`EdgeSearch` finds,
per state, the mesh whose edge node's multiplier vanishes (a safeguarded secant on phi(edge) = N_edge / F), so
the force is a smooth function of the approach and of the mesh. Paths of a body under the plate (one
``fem.stepping.Step`` per state, its state a :class:`PlateStep`): :func:`static_fitted` (static states, each
on its own fitted mesh), :func:`timed_fitted` (time steps with Maxwell branches; the history at a new mesh's
Gauss points is rebuilt from every past step's solution, :func:`replayed_history`), :func:`nodal_step` (node
by node, a fixed mesh or beyond the fitted range).

Curved obstacles (``fem.indentation``): :class:`RigidSphere` (a sphere, or a plane with ``radius=inf``, above or
below the body) and :func:`solve_obstacles` (exact contact on several of them at once: an active node slides on
its obstacle, its u_z following its u_r; the tangent transformed by :func:`congruence`, which keeps the FE
pattern). The plane code above is unchanged.
"""

from __future__ import annotations

import copy
import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Generic, NamedTuple, Protocol, TypeVar

import numpy as np
import scipy.sparse as sp

from tissuemech.fem import constitutive as cm
from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.forms import Assembler, Material
from tissuemech.fem.linalg import Reuse, Symmetric
from tissuemech.fem.mesh import FITTED_EDGE_MAX, FITTED_LEVELS, FITTED_SPLIT, AxiMesh, fitted_mesh
from tissuemech.fem.newton import NewtonError, newton
from tissuemech.fem.stepping import Step, TimedState
from tissuemech.fem.timestepping import march
from tissuemech.fem.transfer import deformation_at, gauss_transfer, gauss_transfers, own_points

log = logging.getLogger(__name__)

__all__ = [
    "RigidPlane",
    "PlateState",
    "PlateStep",
    "first_state",
    "nodal_step",
    "static_fitted",
    "timed_fitted",
    "fitted_stepper",
    "without_contact",
    "contact_lost",
    "plate_force",
    "top_approach",
    "replayed_history",
    "ContactSolution",
    "ContactError",
    "FittedEdge",
    "NodalContact",
    "contact_treatment",
    "EdgeSearch",
    "EdgeState",
    "EdgeSolution",
    "edge_guess",
    "beyond_fit",
    "EDGE_TOL",
    "EDGE_MIN",
    "AFFINE_MAX_ITER",
    "RigidSphere",
    "ObstacleSolution",
    "solve_obstacles",
    "edge_estimate",
    "congruence",
]


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

    def moved(self, dX: np.ndarray) -> RigidPlane:
        """This plane's candidates on the section whose nodes moved by dX (2, n_nodes) (same nodes, same order)."""
        out = copy.copy(self)
        out.R, out.Z = self.R + dX[0, self.nodes], self.Z + dX[1, self.nodes]
        return out

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

    def contact_radius(self, x: np.ndarray, active: np.ndarray, h: float) -> tuple[float, float]:
        """(edge estimate, outermost active node) of the deformed contact radius (scaled).

        Between the outermost active node (r_k) and the next node (r_1) the edge a is estimated from the
        gaps g_1, g_2 of the next two free nodes with the Hertz-like law g ~ (r - a)^(3/2):
        (g_1/g_2)^(2/3) = (r_1 - a)/(r_2 - a), clamped to [r_k, r_1]."""
        if not active.any():
            return 0.0, 0.0
        r = self.R + x[2 * self.nodes]
        k = int(np.max(np.flatnonzero(active)))  # candidates are ordered from the pole outward
        return edge_estimate(r, self.gap(x, h), k)

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


# ---- the contact edge on a node of a fitted mesh (fem.mesh.fitted_mesh) --------------------------------------
EDGE_TOL = 1e-6  # |N_edge| / F at the fitted contact edge (F is NOT stationary in the edge position on a finite
# mesh: d ln F / d ln edge = -0.13 on level 0 at delta = 0.4 a0, so the edge must be found accurately; a
# tolerance of 1e-4 left force errors up to 7e-6 on levels 1-3; 1e-6 leaves <= 5.2e-8 for 4-19 % more Newton
# iterations)
EDGE_MIN = 1e-4  # smallest edge position tried (an approach delta/(2 a0) of ~4e-9)
EDGE_MAX = FITTED_EDGE_MAX


HISTORIES = ("replay", "points", "transfer", "chain")
REMESH = 1.25  # the history moves onto the step's mesh when the contact edge has moved by this factor


@dataclass(frozen=True)
class FittedEdge:
    """Contact treatment: every state on its own contact-edge-fitted mesh (``fem.mesh.fitted_mesh``), whose
    surface node n_contact sits on the contact edge, found by a secant iteration on the Signorini condition
    there (its multiplier N_edge = 0 to ``tol`` of the force). ``history`` (time runs with Maxwell branches,
    :func:`timed_fitted`): "replay" (default) rebuilds it at every new mesh's Gauss points by running the Maxwell
    recursion from t = 0 on the stress of every past step's own solution (no interpolated history, so nothing
    accumulates from mesh to mesh); "transfer" (release 0.1) interpolates it onto every step's new mesh (the
    error accumulates with the number of ramp steps); "chain" does the same with the continuous interpolant
    for Q_m and S_iso^n evaluated from the old solution (10x less drift); "points" keeps it on fixed material
    points while the mesh moves, moved onto the step's mesh only when the edge has moved by the factor
    ``remesh`` (no drift, but a step-to-step scatter of ~1e-4 of the force). Measured: ``python -m
    tissuemech.compare.bench.fem_time``."""

    tol: float = EDGE_TOL
    history: str = "replay"
    remesh: float = REMESH

    def __post_init__(self) -> None:
        if not (isinstance(self.tol, (int, float)) and 0 < self.tol < 1):
            raise ValueError(f"FittedEdge tol (|N_edge| / F, dimensionless) must lie in (0, 1), got {self.tol!r}")
        if not (isinstance(self.remesh, (int, float)) and self.remesh > 1):
            raise ValueError(f"FittedEdge remesh (a ratio of contact edges) must be > 1, got {self.remesh!r}")
        if self.history not in HISTORIES:
            raise ValueError(f"FittedEdge history must be one of {HISTORIES}, got {self.history!r}")


@dataclass(frozen=True)
class NodalContact:
    """Contact treatment: one fixed mesh, node-by-node exact contact (``RigidPlane.solve``); the force carries
    the edge quantisation (~0.2 % on a graded ball_section mesh)."""


CONTACTS = {"fitted": FittedEdge, "nodal": NodalContact}


def contact_treatment(contact) -> FittedEdge | NodalContact:
    """The strategy of a ``contact`` argument: "fitted", "nodal" or a ``FittedEdge`` / ``NodalContact``."""
    if isinstance(contact, (FittedEdge, NodalContact)):
        return contact
    if isinstance(contact, str) and contact in CONTACTS:
        return CONTACTS[contact]()
    raise ValueError(f"contact must be 'fitted', 'nodal', FittedEdge(...) or NodalContact(), got {contact!r}")


class PlateState(NamedTuple):
    """A converged state of a body under the plate (scaled: lengths / a0, stresses / C, forces / (C a0^2))."""

    x: np.ndarray  # full unknown vector (u, q)
    active: np.ndarray  # bool per contact candidate (``plane.nodes``): on the plate
    visco: ve.MaxwellState  # branch stresses and S_iso after the step (no branches: only S_iso)
    delta: float  # scaled plate displacement (= approach / 2 / a0)
    residual: np.ndarray  # full internal residual at x: the reactions on the constrained dofs
    iso_scale: float  # the step's algorithmic factors (for its stresses)
    extra_S: np.ndarray | None
    passes: int  # contact active-set passes of the step


class ContactProblem(Protocol):
    """What :class:`EdgeSearch` needs of a scene's problem on one mesh (``fem.spheroid``)."""

    m: AxiMesh
    mat: Material
    asm: Assembler
    free: np.ndarray
    plane: RigidPlane
    floor: float
    long_time: float  # weight of the long-time Fung term in the algorithmic stress (0: a Maxwell liquid)

    def admissible(self, x: np.ndarray) -> str | None: ...

    def step(
        self, s0: PlateState, d1: float, dt: float | None, prev: PlateState | None, load: str
    ) -> tuple[PlateState, int]: ...

    def solve(
        self, s0: PlateState, d1: float, iso_scale: float, extra, guess: np.ndarray, load: str
    ) -> ContactSolution: ...


P = TypeVar("P", bound=ContactProblem)


class EdgeState(NamedTuple):
    """A converged state of a fitted mesh (scaled units)."""

    x: np.ndarray  # full unknown vector (u, q)
    active: np.ndarray  # bool per candidate node: on the plate
    residual: np.ndarray  # full internal residual at x (the reactions)
    iso_scale: float  # the step's algorithmic factors (1, None: elastic)
    extra_S: np.ndarray | None


class EdgeSolution(NamedTuple, Generic[P]):
    """:meth:`EdgeSearch.solve`: the fitted mesh's problem, its state, the edge, Newton iterations, solves."""

    problem: P
    state: EdgeState
    edge: float  # the edge node's position, fraction of the pole block's arc
    iterations: int
    solves: int


class EdgeSearch(Generic[P]):
    """Equilibrium states whose contact edge sits on a surface node (one fitted mesh per state).

    With the first 2 n_contact + 1 surface nodes of the pole block on the plate (the edge node
    ``n_contact`` on ``fitted_mesh(..., edge)``) and the rest free, the nodal multiplier of the edge node
    N_e(edge) falls through zero as the edge moves out: the root of phi(edge) = N_e / F (secant iteration)
    is the state where both Signorini conditions hold at the edge (N_e = 0, next gaps > 0), so the force is a
    smooth function of the approach and of the mesh. (The force is not stationary in the edge position on a
    finite mesh, d ln F / d ln edge ~ -0.13 on level 0 at delta = 0.4 a0: parameter sensitivities carry the
    edge's motion, ``BallProblem.sensitivities``.)

    With a surface tension the edge condition is instead :func:`edge_slope` = 0 (the surface leaves the plate
    tangentially: the contact pressure jumps at the edge, so N_e does not vanish there), the first state starts
    from the free ball's Laplace state (:meth:`laplace_state`) and a failed first edge guess is halved. On a
    wetting plate (a problem with ``contact_angle`` theta < pi, ``fem.spheroid.BallProblem``) it is Young's angle,
    :func:`edge_angle` = 0, the first state comes from a continuation in the angle from pi (steps of
    ``ANGLE_STEP``), and tensile nodes near the edge are allowed (the plate adheres)."""

    def __init__(
        self, radius: float, level: int, make_problem: Callable[[AxiMesh], P], rtol: float, tol: float = EDGE_TOL
    ):
        self.a0, self.level, self.make_problem, self.rtol, self.tol = radius, level, make_problem, rtol, tol
        self.k = int(FITTED_LEVELS[level][3])
        self.slope = 0.0
        self._cache: dict[float, P] = {}
        self._laplace: np.ndarray | None = None
        self._no_laplace = False  # the free ball's Laplace state did not converge on this level (not retried)
        self.linear = Reuse(Symmetric())  # one factorisation kept across the fitted meshes (same size and pattern)
        self._angle: float | None = None  # the contact angle every problem is set to (None: its own)
        self._angle_started = False  # the first state of a wetting plate came from a continuation in the angle

    def problem(self, edge: float) -> P:
        """The problem on ``fitted_mesh(radius, level, edge)`` (the last 7 kept)."""
        prob = self._problem(edge)
        if self._angle is not None and getattr(prob, "contact_angle", np.pi) != self._angle:
            prob.set_contact_angle(self._angle)  # type: ignore[attr-defined]
        return prob

    def _problem(self, edge: float) -> P:
        key = float(edge)
        if key not in self._cache:
            if len(self._cache) > 6:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = self.make_problem(fitted_mesh(self.a0, self.level, key))
        return self._cache[key]

    def laplace_state(self, prob: P) -> np.ndarray:
        """The free ball's equilibrium under its surface tension (u = 0, the Laplace pressure 2 gamma / a0 in the
        mixed field: exact with the balanced reference of ``fem.surface``, where Newton starts at the solution),
        solved once on ``prob``'s mesh: every fitted mesh has the same dofs, and the state is the same on all."""
        if self._laplace is None or self._laplace.shape[0] != prob.asm.ndof:
            gam = prob.asm.surface.gamma if prob.asm.surface is not None else 0.0
            fun = lambda x: prob.asm.internal(x, prob.mat, tangent="lazy")
            res = newton(
                fun, prob.asm.rest_state(), free=prob.free, ref_norm=max(gam, 1e-12), rtol=self.rtol, xtol=1e-9,
                atol=prob.floor, admissible=prob.admissible, max_iter=25,
            )  # fmt: skip
            self._laplace = res.x
        return self._laplace

    def _state(self, prob: P, d: float, guesses, load, visc=None) -> tuple[EdgeState, int, float]:
        pl, n_act = prob.plane, 2 * self.k + 1
        act = np.zeros(pl.nodes.size, bool)
        act[:n_act] = True
        fr = np.setdiff1d(prob.free, pl.dofs[act], assume_unique=True)
        iso_scale, extra = (1.0, None) if visc is None else visc(prob)
        fun = lambda x: prob.asm.internal(x, prob.mat, extra_S=extra, iso_scale=iso_scale, tangent="lazy")
        X = prob.m.X
        affine = np.zeros(prob.asm.ndof)  # a uniform squeeze: always admissible
        if prob.asm.surface is not None and not any(g is not None and g.shape[0] == prob.asm.ndof for g in guesses):
            # with a tension the squeeze starts from the free ball under its Laplace pressure 2 gamma / a0 (from
            # q = 0 the first Newton steps of a fitted mesh's first state stall or diverge beyond gamma/(C a0) ~ 0.3)
            try:
                affine = newton(
                    lambda x: prob.asm.internal(x, prob.mat, tangent="lazy"), prob.asm.rest_state(), free=prob.free,
                    ref_norm=1.0,
                    rtol=1e-12, atol=prob.floor, admissible=prob.admissible,
                ).x  # fmt: skip
            except NewtonError:  # (its corrections may stall at round-off on a fine mesh: the squeeze from q = 0)
                affine = np.zeros(prob.asm.ndof)
        affine[0 : prob.asm.n_u : 2] += 0.5 * d * X[0]
        affine[1 : prob.asm.n_u : 2] += -d * X[1]
        err = None
        tension = prob.asm.surface is not None and prob.asm.surface.gamma > 0
        # with a tension the round ball at its Laplace pressure (the contact zone pressed onto the plate) is closer
        # than the squeeze (whose residual is the tension's, gamma / (C a0) times larger than the elastic one)
        laplace = []
        if tension and not self._no_laplace:
            try:
                laplace = [self.laplace_state(prob)]
            except NewtonError as e:  # (a fine mesh at strong tension: the continuation below starts without it)
                self._no_laplace, err = True, e
        for g in [*guesses, *laplace, affine, *([_TENSION_RAMP] if tension else [])]:
            if g is _TENSION_RAMP:  # every guess failed: continuation in the tension from a weak one
                try:
                    g = self._tension_ramp(prob, d, act, fr, load, fun)
                except NewtonError as e:
                    err = e
                    continue
            if g is None or g.shape[0] != prob.asm.ndof:
                continue  # none, or a state of a fitted mesh with other dofs (its numbers mean nothing here)
            xg = pl.impose(g, 1.0 - d, act)
            if prob.admissible(xg) is not None:
                continue
            try:
                res = newton(
                    fun,
                    xg,
                    free=fr,
                    load=load,
                    ref_norm=max(32.0 / 3.0 * d**1.5 * iso_scale, 1e-12),
                    rtol=self.rtol,
                    xtol=1e-9,
                    atol=prob.floor,
                    admissible=prob.admissible,
                    max_iter=AFFINE_MAX_ITER if g is affine else 25,
                    linear=self.linear,
                )
            except NewtonError as e:
                err = e
                continue
            r = prob.asm.internal(res.x, prob.mat, extra_S=extra, iso_scale=iso_scale, tangent=False)[0]
            N = pl.normal_force(r)
            F = float(N[act].sum())
            st = EdgeState(res.x, act, r, iso_scale, extra)
            phi = float(N[n_act - 1]) / max(F, 1e-300)
            if prob.asm.surface is not None and prob.asm.surface.gamma > 0:  # tension: the contact angle at the edge
                phi = edge_angle(pl, res.x, n_act, getattr(prob, "contact_angle", np.pi))
            # a tensile node inside the last contact element: the zone is too large (a spurious root of
            # N_edge = 0 with the element lifting off in its middle): report it as negative
            inner = float(np.min(N[max(n_act - 3, 0) : n_act - 1])) / max(F, 1e-300)
            if inner < 0 and getattr(prob, "contact_angle", np.pi) == np.pi:  # (not on a wetting plate: it adheres,
                phi = min(phi, inner)  # and tension near the edge is its physics, as in JKR)
            # a free node beyond the edge below the plate: the zone is too small (report it as positive)
            g = pl.gap(res.x, 1.0 - d)[n_act : n_act + 6]
            if g.size and g.min() < -1e-9 * d:
                phi = max(phi, -float(g.min()) / d)
            return st, res.iterations, phi
        raise err if err is not None else NewtonError("no admissible initial guess", load=load, hint="reduce the step")

    def _tension_ramp(self, prob: P, d: float, act: np.ndarray, fr: np.ndarray, load, fun) -> np.ndarray:
        """A guess for the state at approach d on ``prob``'s mesh under a strong tension: the elastic squeeze solved
        at the tension ``TENSION_START`` (gamma / (C a0)) and then at tensions doubled up to the problem's, each from
        the last (measured: on level 2 at gamma / (C a0) = 1.5 no state started from the Laplace state or the squeeze
        at any approach; the first contact's kinked surface pulled Newton astray). The problem's tension is
        restored on return."""
        surf = prob.asm.surface
        assert surf is not None
        full = surf.gamma
        steps = [full]
        while steps[-1] > TENSION_START:
            steps.append(0.5 * steps[-1])
        X = prob.m.X
        x = np.zeros(prob.asm.ndof)
        x[0 : prob.asm.n_u : 2] = 0.5 * d * X[0]
        x[1 : prob.asm.n_u : 2] = -d * X[1]
        x = prob.plane.impose(x, 1.0 - d, act)
        try:
            for g in reversed(steps):
                surf.gamma = g
                x = newton(
                    fun, x, free=fr, load=load, ref_norm=max(32.0 / 3.0 * d**1.5, 1e-12), rtol=self.rtol, xtol=1e-9,
                    atol=prob.floor, admissible=prob.admissible, max_iter=25, linear=self.linear,
                ).x  # fmt: skip
        finally:
            surf.gamma = full
        return x

    def solve(self, d: float, edge0: float, x0, load, visc=None) -> EdgeSolution:
        """The state at plate displacement d (scaled) whose edge node's multiplier vanishes (to ``tol``).

        Safeguarded secant on phi(edge): phi > 0 (edge node pressed) means the zone is too small, phi < 0
        (edge node or its element pulled) too large; the root is kept inside that bracket (bisection when a
        secant step leaves it). ``visc(problem) -> (iso_scale, extra_S)``: the algorithmic viscoelastic stress of a
        time step on that problem's mesh (``fem.viscoelastic.algorithmic`` of the history mapped onto its Gauss
        points); None: elastic."""
        tol = self.tol
        lo, hi = EDGE_MIN, FITTED_EDGE_MAX  # phi(lo) > 0 > phi(hi) (bounds until evaluated)
        e_a = float(np.clip(edge0, lo, hi))
        prob_a = self.problem(e_a)
        target = float(getattr(prob_a, "contact_angle", np.pi))
        if target < np.pi and not self._angle_started and self._angle is None:
            # a wetting plate adheres: the first contact is a finite disc (JKR-like), far from the Hertz guess;
            # reach it by a continuation in the contact angle from the non-wetting pi, each state from the last
            # (a failure propagates: the caller cuts the step, and the next first state continues again)
            m = int(np.ceil((np.pi - target) / ANGLE_STEP))
            x, e = x0, e_a
            try:
                for th in np.linspace(np.pi, target, m + 1):  # (the last one is the target)
                    self._angle = float(th)
                    sol = self.solve(d, e, x, load, visc)
                    x, e = sol.state.x, sol.edge
            finally:
                self._angle = None
                for p in self._cache.values():
                    p.set_contact_angle(target)  # type: ignore[attr-defined]
            self._angle_started = True
            return sol
        tension = prob_a.asm.surface is not None and prob_a.asm.surface.gamma > 0
        n = 1
        for shrink in range(SHRINK_TRIES + 1):
            try:
                st_a, its, phi_a = self._state(self.problem(e_a), d, [x0], load, visc)
                break
            except NewtonError:
                # with a surface tension the contact disc is smaller than the Hertz guess (the drop's is 0.24 of it
                # as delta -> 0) and Newton from a too-large flattened zone diverges (the tension pulls the kink): a
                # failed first edge counts as too large, the edge is halved
                if not tension or shrink == SHRINK_TRIES:
                    raise
                hi, e_a, n = e_a, max(0.5 * e_a, EDGE_MIN), n + 1
        if abs(phi_a) < tol:
            return EdgeSolution(self.problem(e_a), st_a, e_a, its, n)
        lo, hi = (e_a, hi) if phi_a > 0 else (lo, e_a)
        # first secant point: a step along the slope dphi/dln(edge) of the previous state (about -2)
        step = float(np.clip(-phi_a / self.slope, -0.1, 0.1)) if self.slope < 0 else 0.03 * np.sign(phi_a)
        e_b = float(np.clip(e_a * (1.0 + step), lo, hi))
        best = [abs(phi_a)]  # |phi| per pass: a search whose best |phi| stalls is stuck (see below)
        for _ in range(30):
            try:
                st_b, it, phi_b = self._state(self.problem(e_b), d, [st_a.x, x0], load, visc)
            except NewtonError:
                if not tension or e_b <= e_a or n >= 12:  # (tension: a failed trial beyond e_a counts as too large)
                    raise
                hi, e_b, n = min(hi, e_b), 0.5 * (e_a + min(hi, e_b)), n + 1
                continue
            its, n = its + it, n + 1
            best.append(abs(phi_b))
            if abs(phi_b) < tol:
                if phi_b != phi_a and e_b != e_a:
                    self.slope = (phi_b - phi_a) / np.log(e_b / e_a)
                return EdgeSolution(self.problem(e_b), st_b, e_b, its, n)
            if phi_b > 0:
                lo = max(lo, e_b)
            else:
                hi = min(hi, e_b)
            e_new = e_b - phi_b * (e_b - e_a) / (phi_b - phi_a) if phi_b != phi_a and e_b != e_a else np.nan
            if e_b != e_a and phi_b != phi_a:
                self.slope = (phi_b - phi_a) / np.log(e_b / e_a)
            if not (lo < e_new < hi):  # outside the bracket: bisect (or expand toward the open bound)
                e_new = 0.5 * (lo + hi) if hi < FITTED_EDGE_MAX or lo > EDGE_MIN else e_b * (1.2 if phi_b > 0 else 0.8)
                e_new = float(np.clip(e_new, EDGE_MIN, FITTED_EDGE_MAX))
            if hi - lo < 1e-12 * hi:
                break
            if len(best) >= 6 and min(best[-3:]) > 0.5 * min(best[:-3]):
                # stalled (issue 14): the best |phi| of the last 3 passes is not half the earlier best. phi
                # jumps across the bracket (a spurious state on one side), so the secant only creeps; the
                # caller cuts the step, as it would after the 30 passes (3 of 4 passes of the fine level 3
                # static curve were spent here before)
                break
            e_a, st_a, phi_a, e_b = e_b, st_b, phi_b, float(e_new)
        raise ContactError(
            "the contact edge did not settle (the edge node multiplier does not vanish)",
            load=load,
            hint="the approach may be beyond the meshable range; use contact='nodal' or a ball_section mesh",
        )


def edge_slope(plane: RigidPlane, x: np.ndarray, n_act: int) -> float:
    """dz/dr of the deformed boundary at the contact edge node (candidate ``n_act - 1``), on the first free quadratic
    edge (candidates n_act - 1, n_act, n_act + 1): the edge condition of a surface with tension.

    With a surface tension gamma the contact pressure jumps at the edge (the wetted surface is flat, the free one
    curved: on a liquid drop it falls from the Laplace pressure to 0), so the edge node's multiplier does not vanish
    there and N_edge = 0 puts the edge too far out (3.5 % of the contact radius on the drop at 10 % compression,
    level 0; from gamma / (C a0) ~ 5 on it found no root at all). The edge node carries no concentrated line force
    instead: the surface leaves the plate tangentially (the 180 deg contact angle of a non-wetting plate; for an
    elastic body without tension the same smooth contact as Hertz's), i.e. no kink between the flat wetted edge and
    the free one: dz/dr = 0 at the edge. Positive (the free surface rises into the plate): the zone is too small."""
    dr, dz = _edge_tangent(plane, x, n_act, True)
    return float(dz / dr)


def edge_angle(plane: RigidPlane, x: np.ndarray, n_act: int, contact_angle: float = np.pi) -> float:
    """The edge condition of a surface with tension on a plate of contact angle theta (rad, through the body):
    :func:`edge_slope` at theta = pi (the surface leaves the plate tangentially), else (pi - theta) - psi with psi
    = atan2(-dz, dr) the angle of the first free edge below the plate at the edge node (Young's angle: the free
    surface leaves the plate at pi - theta below it, the wetted part pulling the edge inward by -gamma cos(theta)
    per length, the free one along its tangent by gamma). Positive: the zone is too small (as edge_slope)."""
    if contact_angle == np.pi:
        return edge_slope(plane, x, n_act)
    dr, dz = _edge_tangent(plane, x, n_act, True)
    return float((np.pi - contact_angle) - np.arctan2(-dz, dr))


def _edge_tangent(plane: RigidPlane, x: np.ndarray, n_act: int, reference: bool) -> tuple[float, float]:
    """2 d(r, z)/dxi at xi = -1 of the first free edge (``reference``: of X + x, else of the increment x alone)."""
    nodes = plane.nodes[n_act - 1 : n_act + 2]
    r, z = x[2 * nodes], x[2 * nodes + 1]
    if reference:
        r, z = r + plane.R[n_act - 1 : n_act + 2], z + plane.Z[n_act - 1 : n_act + 2]
    return float(-3 * r[0] + 4 * r[1] - r[2]), float(-3 * z[0] + 4 * z[1] - z[2])


def edge_slope_change(plane: RigidPlane, x: np.ndarray, n_act: int, dx: np.ndarray) -> float:
    """The change of :func:`edge_slope` at the state x along the increment dx (its exact directional derivative)."""
    dr, dz = _edge_tangent(plane, x, n_act, True)
    ddr, ddz = _edge_tangent(plane, dx, n_act, False)
    return (ddz * dr - dz * ddr) / dr**2


ANGLE_STEP = np.radians(2.5)  # the continuation in the contact angle of a first wetting contact (EdgeSearch.solve)
TENSION_START = 0.02  # gamma / (C a0) of the first state of EdgeSearch._tension_ramp (level 3 at 0.25 starts from 0.02, not from 0.2)
_TENSION_RAMP = np.zeros(0)  # marker of the continuation guess in EdgeSearch._state

SHRINK_TRIES = 4  # halvings of a failed first edge guess with a surface tension (EdgeSearch.solve)

# Newton iterations allowed from the uniform-squeeze guess (the first contact): where it converges it takes 5-8
# (levels 0-3, the static curves and Fig. 10 runs); on level 4 the first static step (20 um) wandered for 25
# iterations and factorisations (~4 s) before the step was cut, which converged in 8 (issue 14)
AFFINE_MAX_ITER = 12


def edge_guess(ds: list, es: list, d: float) -> float:
    """Edge position extrapolated in sqrt(d) from the previous states (Hertz: contact radius ~ sqrt(d))."""
    if not ds:
        return 1.06 * np.sqrt(d) / FITTED_SPLIT
    if len(ds) == 1:
        return es[-1] * np.sqrt(d / ds[-1])
    s0, s1, s = np.sqrt(ds[-2]), np.sqrt(ds[-1]), np.sqrt(d)
    return es[-1] + (es[-1] - es[-2]) * (s - s1) / (s1 - s0)


def beyond_fit(es: list, e_next: float, err: Exception | None = None) -> bool:
    """Whether the contact edge leaves the fitted range (the pole block): the predicted next edge is past
    FITTED_EDGE_MAX, or the edge iteration failed (``err``) with the last edge in the outer tenth of the range."""
    if e_next > FITTED_EDGE_MAX:
        return True
    return isinstance(err, ContactError) and bool(es) and es[-1] > 0.9 * FITTED_EDGE_MAX


# ---- paths of a body under the plate: fitted edge (static, timed) and node by node ------------------------------
def _warn_nodal(load: str) -> None:
    log.warning(
        "the contact edge leaves the fitted range of the pole block (%.3g deg) at %s: node-by-node contact on "
        "the last fitted mesh from here on (the force carries the edge quantisation, ~1e-3)",
        np.degrees(FITTED_SPLIT * EDGE_MAX),
        load,
    )


class PlateStep(NamedTuple, Generic[P]):
    """A converged state with its mesh's problem and contact edge (NaN: node-by-node contact)."""

    state: PlateState
    problem: P
    edge: float  # the edge node's position on its fitted mesh (fraction of the pole block's arc), NaN: nodal
    history_mesh: AxiMesh | None = None  # where state.visco lives (its Gauss points); None: problem.m
    history_edge: float = float("nan")  # the contact edge of history_mesh
    path: tuple = ()  # history="replay": (mesh, x, S_iso, dt) of every converged step so far (dt in s, x the full vector)
    source: HistorySource | None = None  # history="replay", a fitted contact step: where its history came from
    before: ve.MaxwellState | None = None  # with ``source``: the history at problem.m's Gauss points before the step


class HistorySource(NamedTuple):
    """Where the Maxwell history before a fitted time step (history="replay") comes from, on any mesh of the level
    (:func:`history_before`): ``kind`` "none" (no history yet: ``state`` as it is, on every mesh alike), "replay"
    (rebuilt from ``path`` by :func:`replayed_history`) or "transfer" (the plate held: ``state``, living at the
    Gauss points of ``mesh``, interpolated element-wise, ``fem.transfer.gauss_transfer``). The exact gradients of
    fitted time runs linearise this map (``fem.fitted_sensitivity``)."""

    kind: str
    state: ve.MaxwellState
    mesh: AxiMesh | None = None
    path: tuple = ()


def history_before(src: HistorySource, m: AxiMesh, mat: Material, beta: np.ndarray, tau: np.ndarray) -> ve.MaxwellState:
    """The Maxwell history before a fitted step at the Gauss points of ``m`` (see :class:`HistorySource`)."""
    if src.kind == "none" or m is src.mesh:
        return src.state
    if src.kind == "replay":
        return replayed_history(src.path, m, mat, beta, tau)
    assert src.kind == "transfer" and src.mesh is not None
    # the plate held: m nearly coincides with the history's mesh (its points sought first in their own elements)
    tr = gauss_transfers([src.mesh], m, near=[own_points(m)])[0]
    return ve.MaxwellState(tr(src.state.Q), tr(src.state.S_iso))


def replayed_history(
    path, m: AxiMesh, mat: Material, beta: np.ndarray, tau: np.ndarray, smooth: bool = True
) -> ve.MaxwellState:
    """The Maxwell history at the Gauss points of ``m`` after the steps ``path`` ((mesh, x, S_iso, dt) per
    converged step from t = 0, the reference state; S_iso at that mesh's Gauss points): each step's S_iso^{n+1}
    is taken from that step's own FE solution at m's points and the recursion ``fem.viscoelastic.update`` is run
    from the undisturbed state. No history is ever interpolated, so nothing accumulates from mesh to mesh; on
    ``smooth`` (what ``timed_fitted`` uses) takes every step's S_iso field by the continuous interpolant
    (``gauss_transfer(..., continuous=True)``, its own mesh included): continuous in m's points, so the edge
    search over trial meshes sees no jumps (a spatial error of the order of one continuous transfer, the same
    for every step, which does not accumulate). ``smooth=False``: a step on m itself takes its S_iso as it is
    (on one mesh: the plain step-by-step update), one on another mesh S_iso of its deformation gradient
    evaluated at m's points (``fem.transfer.deformation_at``: the FE field itself, but discontinuous across
    that mesh's element boundaries, which stalls the edge search). Consecutive steps on one mesh share the
    point search."""
    shape = m.quadrature_points.shape[1:] + (5,)
    state = ve.initial_state(np.asarray(beta).size, shape)
    groups = []  # (k, j): consecutive steps on one mesh
    k = 0
    while k < len(path):
        j = k + 1
        while j < len(path) and path[j][0] is path[k][0]:
            j += 1
        groups.append((k, j))
        k = j
    # one point search of m's Gauss points in every step's mesh (fem.transfer.locate_many)
    transfers = gauss_transfers([path[k][0] for k, _ in groups], m, continuous=True) if smooth else []
    for g, (k, j) in enumerate(groups):
        mk = path[k][0]
        if smooth:
            S = transfers[g](np.stack([p[2] for p in path[k:j]]))
        elif mk is m:
            S = np.stack([p[2] for p in path[k:j]])
        else:
            f = deformation_at(mk, np.stack([p[1] for p in path[k:j]]), m)
            S = cm.iso_second_piola(f.reshape((-1,) + shape), mat.C, mat.alpha).reshape(f.shape)
        state = ve.replay(state, beta, tau, zip([p[3] for p in path[k:j]], S))
    return state


def first_state(search: EdgeSearch[P], n_branches: int) -> PlateStep[P]:
    """The reference state (x = 0, no contact) on the fitted mesh with its edge half-way (edge 0: not yet fitted)."""
    p0 = search.problem(0.5)
    n0 = p0.asm.ndof
    visco0 = ve.initial_state(n_branches, p0.asm.w.shape + (5,))
    return PlateStep(
        PlateState(np.zeros(n0), np.zeros(p0.plane.nodes.size, bool), visco0, 0.0, np.zeros(n0), 1.0, None, 0), p0, 0.0
    )


def nodal_step(
    old: PlateStep[P], prev: TimedState[PlateStep[P]] | None, d1: float | None, dt: float | None, load: str
) -> tuple[PlateStep[P], int]:
    """(state, iterations): node-by-node contact on ``old``'s mesh (beyond the fitted range, or a fixed mesh); the
    secant predictor uses ``prev`` when it is a state of the same mesh. Contact may be lost and regained
    (:func:`without_contact`, tried first where :func:`contact_lost` expects it or after a failed unloading step);
    ``d1=None``: the free ball, its approach the plate touching its top."""
    prob = old.problem

    def free() -> tuple[PlateStep[P], int] | None:
        got = without_contact(prob, old.state, d1, dt, load)
        return None if got is None else (PlateStep(got[0], prob, float("nan")), got[1])

    if d1 is None or contact_lost(old, d1):
        done = free()
        if done is not None:
            return done
        assert d1 is not None  # with no plate to touch the free ball is always admissible
    s_prev = prev.state.state if prev is not None and prev.state.problem is prob else None
    try:
        st, its = prob.step(old.state, d1, dt, s_prev, load)
    except NewtonError:
        done = free() if d1 < old.state.delta else None
        if done is None:
            raise
        return done
    return PlateStep(st, prob, float("nan")), its


# ---- contact lost and regained (unloading, force removed) ------------------------------------------------------
FAR = -1.0  # the scaled approach of a plate out of reach (h = 2 a0): the free ball
GAP_TOL = 1e-9  # a plate within this (scaled) distance of the free ball's top does not touch it


def plate_force(step: PlateStep) -> float:
    """The plate force of a converged state (scaled by C a0^2): the sum of the active nodes' multipliers."""
    s = step.state
    return float(step.problem.plane.normal_force(s.residual)[s.active].sum()) if s.active.any() else 0.0


def top_approach(step: PlateStep) -> float:
    """The scaled approach at which the plate touches the ball's top in this state (0 for the undeformed ball)."""
    return float(np.min(step.problem.plane.gap(step.state.x, 1.0)))


def regain_top(step: PlateStep) -> float:
    """The scaled approach at which the plate would just touch the ball of this state: its top without contact;
    in contact the approach less what the elastic (Hertz) unloading of its force would recover."""
    if not step.state.active.any():
        return top_approach(step)
    return max(step.state.delta - (3.0 * max(plate_force(step), 0.0) / 32.0) ** (2.0 / 3.0), 0.0)


def contact_lost(old: PlateStep, d1: float) -> bool:
    """Whether a step from ``old`` to the scaled approach d1 is likely free of contact (the free ball is then tried
    first): no contact before (except the reference state going on to press), or the plate moving up by more than
    half the approach the elastic (instantaneous, Hertz) unloading of the old force would recover."""
    s = old.state
    if not s.active.any():
        return s.delta > 0.0 or d1 <= 0.0
    if d1 >= s.delta:
        return False
    reach = (3.0 * max(plate_force(old), 0.0) / (32.0 * max(float(s.iso_scale), 1.0))) ** (2.0 / 3.0)
    return s.delta - d1 > 0.5 * reach


def without_contact(
    prob: P, s0: PlateState, d1: float | None, dt: float | None, load: str
) -> tuple[PlateState, int] | None:
    """(state, iterations) of the step from ``s0`` with the plate out of reach (the free ball, with its Maxwell
    history: it recovers), or None when the plate at the scaled approach d1 would touch it (the free ball's top
    above h = 1 - d1 by more than ``GAP_TOL``: the step has contact). ``d1=None``: the plate touching the free top
    (the state's approach is then that of the top). The state's active set is empty, its force 0."""
    st, its = prob.step(s0._replace(active=np.zeros_like(s0.active)), FAR, dt, None, load)
    if st.active.any():
        return None
    d_top = float(np.min(prob.plane.gap(st.x, 1.0)))  # h = 1: the gap of the top is 1 - z_top
    if d1 is None:
        d1 = d_top
    elif d1 > d_top + GAP_TOL:
        return None
    return st._replace(delta=float(d1)), its


def static_fitted(search: EdgeSearch[P], d_of_t, times, load_of_t, max_cuts: int = 6) -> list[Step[PlateStep[P]]]:
    """Static states on fitted meshes at the load fractions ``times`` (``march``: a failed state is approached in
    halved steps). Where the contact edge leaves the fitted range (``beyond_fit``), the remaining states are
    solved with node-by-node contact on the last fitted mesh (a logged warning; their edge is NaN)."""

    def step(
        t0: float, old: PlateStep[P], t1: float, prev: TimedState[PlateStep[P]] | None
    ) -> tuple[PlateStep[P], int]:
        d, load = d_of_t(t1), load_of_t(t1)
        if np.isnan(old.edge):
            return nodal_step(old, prev, d, None, load)
        first = old.edge == 0.0
        pv = prev.state if prev is not None and prev.state.edge > 0.0 else None  # the fitted state before
        ds = [] if first else ([pv.state.delta] if pv is not None else []) + [old.state.delta]
        es = [] if first else ([pv.edge] if pv is not None else []) + [old.edge]
        guess = None
        if not first:  # linear extrapolation in d from the last two states (the reference state x = 0, d = 0
            # counting as one: the second step starts from the first one scaled, not from the first one)
            x1, d1 = old.state.x, old.state.delta
            x0, d0 = (pv.state.x, pv.state.delta) if pv is not None else (0.0 * x1, 0.0)
            guess = x1 if d1 == d0 else x1 + (x1 - x0) * (d - d1) / (d1 - d0)
        e_next = edge_guess(ds, es, d)
        try:
            if not first and beyond_fit(es, e_next):
                raise ContactError("the contact edge leaves the fitted range", load=load)
            sol = search.solve(d, e_next, guess, load)
        except NewtonError as err:
            if not first and beyond_fit(es, e_next, err):
                _warn_nodal(load)
                return nodal_step(old, None, d, None, load)
            raise
        es_ = sol.state
        visco = ve.initial_state(0, sol.problem.asm.w.shape + (5,))
        st = PlateState(es_.x, es_.active, visco, d, es_.residual, es_.iso_scale, es_.extra_S, sol.solves)
        return PlateStep(st, sol.problem, sol.edge), sol.iterations

    return march(step, first_state(search, 0), times, max_cuts=max_cuts, substeps=False)


def timed_fitted(
    fit: EdgeSearch[P],
    beta,
    tau,
    d_of_t,
    times,
    load_of_t,
    too_large=None,
    history: str = "replay",
    remesh: float = REMESH,
    hold: float = 0.0,
    wrap: Callable[[Callable], Callable] | None = None,
) -> list[Step[PlateStep[P]]]:
    """Time steps on fitted meshes (one per step); ``wrap``: applied to the one-step function (the sensitivities of
    ``fem.fitted_sensitivity`` taken as each step is accepted).

    Every step is an equilibrium state whose contact edge is a node of its own fitted mesh (``EdgeSearch``,
    with the step's algorithmic viscoelastic stress). The meshes of one level share topology and numbering,
    so the displacement guess is carried from step to step by index. The Maxwell variables (Q_m, S_iso^n per
    Gauss point) while the mesh moves (``history``, see ``FittedEdge``):

    * "points": they stay on fixed material points, the Gauss points of the mesh of the step where
      they were last moved (``PlateStep.history_mesh``). Each trial mesh of a step gets the step's history
      stress from them (Q_m by the continuous interpolant ``gauss_transfer(..., continuous=True)``, on every
      trial mesh alike, so the edge condition has no jumps; S_iso^n of the old solution evaluated there,
      ``fem.transfer.deformation_at``), and the update evaluates the solution's S_iso^{n+1} AT the history's
      points: the recursion is exact on fixed points. The history moves (once) onto the step's own mesh only
      when the contact edge has moved by the factor ``remesh`` since the history's mesh, and when the plate
      stops (a step with the same approach): the number of moves is set by the motion, not by the step.
    * "replay" (default): every converged step's (mesh, solution, dt) is kept (``PlateStep.path``); on a new
      mesh the history at its Gauss points is rebuilt by :func:`replayed_history` (each past step's S_iso
      evaluated from its own FE solution there, the recursion run from t = 0). The only error is that of the FE
      solutions themselves. While the plate stands still (the hold) the edge moves by ~1e-6 of itself per step
      and the history is carried as by "transfer" (element-wise, between nearly coinciding meshes: nearly the
      identity), node-by-node steps run the plain update: the replays cost O(n^2) stress transfers over the n
      steps that move the plate (the ramp).
    * "transfer" (release 0.1): they are interpolated onto each step's new mesh; the interpolation
      error accumulates with the number of ramp steps (a chain of element-wise Gauss-point fits is not
      stable): with a fast branch refining the ramp makes the force worse (``compare.bench.fem_time``).
    * "chain": as "transfer", with Q_m carried by the continuous interpolant (stable when chained) and S_iso^n
      evaluated from the old solution on the new mesh (no interpolation of S_iso): on the fast two-branch case
      (level 1, t = 0.2 s) F moves by +5.5e-4 from 24 to 96 ramp steps against +5.2e-3 for "transfer", but the
      held force moves by +3.5e-4 (transfer: +3e-5).

    While the plate is held the edge stays where it is, the mesh with it, and the history is taken as it is.
    """
    step_to = fitted_stepper(fit, beta, tau, load_of_t, history=history, remesh=remesh, hold=hold)

    def step(
        t0: float, old: PlateStep[P], t1: float, prev: TimedState[PlateStep[P]] | None
    ) -> tuple[PlateStep[P], int]:
        return step_to(t0, old, t1, prev, d_of_t(t1))

    return march(step if wrap is None else wrap(step), first_state(fit, beta.size), times, too_large=too_large)


def fitted_stepper(
    fit: EdgeSearch[P], beta, tau, load_of_t, history: str = "replay", remesh: float = REMESH, hold: float = 0.0
) -> Callable[..., tuple[PlateStep[P], int]]:
    """The one-step function of :func:`timed_fitted`: ``step_to(t0, old, t1, prev, d1)`` -> (PlateStep, Newton
    iterations), the step from ``old`` at t0 to t1 (s) with the plate at the scaled approach ``d1`` (any value: the
    force control of ``fem.spheroid.compress`` calls it for several trial approaches from the same ``old``), or
    ``d1=None``: the ball without contact, its approach the plate touching its top (:func:`without_contact`).
    Contact may be lost (a free step on the last mesh, force 0, edge 0: the next contact is searched as a first
    contact) and regained (:func:`contact_lost` says when to try the free ball first). ``hold``: a step moving the
    plate by at most this fraction of the approach counts as held (the history then carried as by "transfer", not
    replayed; 0: only a plate standing still)."""
    if history not in HISTORIES:
        raise ValueError(f"history must be one of {HISTORIES}, got {history!r}")
    if not remesh > 1.0:
        raise ValueError(f"remesh (a factor of the contact edge) must be > 1, got {remesh!r}")

    def step_to(
        t0: float, old: PlateStep[P], t1: float, prev: TimedState[PlateStep[P]] | None, d1: float | None
    ) -> tuple[PlateStep[P], int]:
        if d1 is None or contact_lost(old, d1):  # try the free ball first
            got = attempt(t0, old, t1, prev, d1, free=True)
            if got is not None:
                return got
            assert d1 is not None  # with no plate to touch the free ball is always admissible
        try:
            got = attempt(t0, old, t1, prev, d1, free=False)
        except NewtonError:
            if d1 < old.state.delta or not old.state.active.any():  # unloading: the contact may have been lost
                got = attempt(t0, old, t1, prev, d1, free=True)
                if got is not None:
                    return got
            raise
        assert got is not None  # a contact step returns its state or raises
        return got

    def attempt(
        t0: float, old: PlateStep[P], t1: float, prev: TimedState[PlateStep[P]] | None, d1: float | None, free: bool
    ) -> tuple[PlateStep[P], int] | None:
        """The step with contact at d1, or (``free``) without contact (None: the ball would touch the plate)."""
        dt = t1 - t0
        s_old = old.state
        guess = s_old.x
        p_old = prev.state.state if prev is not None else None
        # extrapolate from the last two steps only where the last one moved the plate by at least a tenth of this one
        # (a creep step after a nearly held one would extrapolate by a huge factor)
        moved = (
            p_old is not None
            and d1 is not None
            and abs(s_old.delta - p_old.delta) > max(1e-14, 0.1 * abs(d1 - s_old.delta))
        )
        if free or d1 is None:  # the free ball's history only (on the previous step's mesh): no guess, no edge
            e0 = float("nan")
        elif p_old is not None and moved:
            guess = s_old.x + (s_old.x - p_old.x) * (d1 - s_old.delta) / (s_old.delta - p_old.delta)
        if free or d1 is None:
            pass
        elif np.isnan(old.edge):  # node-by-node contact (beyond the fitted range)
            e0 = float("nan")
        elif old.edge <= 0.0:  # the first contact (again, after a free step: from the ball's top)
            e0 = edge_guess([], [], d1 if s_old.delta == 0.0 else max(d1 - regain_top(old), 1e-3 * d1))
        elif prev is not None and p_old is not None and prev.state.edge > 0.0 and moved:  # nan: False
            e0 = edge_guess([p_old.delta, s_old.delta], [prev.state.edge, old.edge], d1)
        else:
            e0 = old.edge * np.sqrt(d1 / s_old.delta) if s_old.delta > 0 else old.edge
        H = old.history_mesh if old.history_mesh is not None else old.problem.m  # where s_old.visco lives
        H_edge = old.history_edge if old.history_mesh is not None else old.edge
        quiet = beta.size == 0 or not np.any(s_old.visco.S_iso)  # no history yet: it lives anywhere
        # the plate stands still (or, ``hold``, moves by at most that fraction of the approach): the edge hardly moves
        # (replay: as "transfer")
        holding = d1 == s_old.delta or (d1 is not None and abs(d1 - s_old.delta) <= hold * s_old.delta)
        cache: dict = {}
        src = None  # history="replay": where the step's history comes from (fem.contact.history_before)
        if history == "replay":
            src = (
                HistorySource("none", s_old.visco)
                if quiet
                else HistorySource("transfer", s_old.visco, H)
                if holding
                else HistorySource("replay", s_old.visco, None, old.path)  # every trial mesh alike (H included)
            )

        def on(prob: P) -> ve.MaxwellState:
            """The Maxwell history of the old step at the Gauss points of prob's mesh (interpolated)."""
            key = id(prob)
            if key not in cache:
                if src is not None:
                    cache[key] = history_before(src, prob.m, prob.mat, beta, tau)
                elif quiet:
                    cache[key] = s_old.visco
                elif prob.m is H:
                    cache[key] = s_old.visco
                elif history == "chain":  # Q_m by the continuous interpolant, S_iso^n evaluated on prob's mesh
                    f_old = deformation_at(H, s_old.x, prob.m)
                    S_n = cm.iso_second_piola(f_old, prob.mat.C, prob.mat.alpha)
                    cache[key] = ve.MaxwellState(gauss_transfer(H, prob.m, continuous=True)(s_old.visco.Q), S_n)
                else:
                    tr = gauss_transfer(H, prob.m)
                    cache[key] = ve.MaxwellState(tr(s_old.visco.Q), tr(s_old.visco.S_iso))
            return cache[key]

        def visc(prob: P):
            """The step's algorithmic terms (iso_scale, extra_S) at the Gauss points of prob's mesh."""
            if history in ("replay", "transfer", "chain"):
                return ve.algorithmic(on(prob), beta, tau, dt, prob.long_time)
            key = ("extra", id(prob))
            if key not in cache:
                here = s_old.visco
                if not quiet:  # Q_m by the continuous interpolant (on every trial mesh alike, H included: the edge
                    # condition has no jump where a trial mesh meets H), S_iso^n of the old solution evaluated here
                    m_old = old.problem.m
                    f_old = prob.asm.f_at(s_old.x) if prob.m is m_old else deformation_at(m_old, s_old.x, prob.m)
                    S_n = cm.iso_second_piola(f_old, prob.mat.C, prob.mat.alpha)
                    here = ve.MaxwellState(gauss_transfer(H, prob.m, continuous=True)(s_old.visco.Q), S_n)
                cache[key] = ve.algorithmic(here, beta, tau, dt, prob.long_time)
            return cache[key]

        def updated(prob: P, x: np.ndarray, e_new: float, held: bool) -> tuple[ve.MaxwellState, AxiMesh | None, float]:
            """(history after the step, the mesh it lives on (None: prob's), that mesh's edge) for the solution x on
            prob's mesh with contact edge e_new."""
            if history in ("replay", "transfer", "chain"):
                return ve.update(on(prob), beta, tau, dt, prob.asm.iso_S(x, prob.mat)), None, float("nan")
            mat = prob.mat

            def S_at(m: AxiMesh) -> np.ndarray:  # S_iso^{n+1} of the solution at m's Gauss points (material points)
                return (
                    prob.asm.iso_S(x, mat)
                    if m is prob.m
                    else cm.iso_second_piola(deformation_at(prob.m, x, m), mat.C, mat.alpha)
                )

            # the history moves (once) onto this step's mesh when the plate stops or the edge has moved by the
            # factor remesh since the history's mesh (whose edge node then lags too far behind the contact edge)
            target = prob.m if held or not (e_new <= H_edge * remesh and H_edge <= e_new * remesh) else H
            if quiet:  # no history yet: it starts on this mesh
                return ve.update(s_old.visco, beta, tau, dt, S_at(prob.m)), None, float("nan")
            visco = ve.update(s_old.visco, beta, tau, dt, S_at(H))  # the exact recursion on H's points
            if target is not H:  # moved once (Q_m interpolated, S_iso evaluated there)
                visco = ve.MaxwellState(gauss_transfer(H, target)(visco.Q), S_at(target))
            return visco, (None if target is prob.m else target), (float("nan") if target is prob.m else H_edge)

        def walked(prob: P, x: np.ndarray, S: np.ndarray) -> tuple:
            """The path after this step (history="replay"; empty otherwise)."""
            return (*old.path, (prob.m, x, S, dt)) if history == "replay" else ()

        def nodal(warn: bool = True) -> tuple[PlateStep[P], int]:
            """Node-by-node contact on the previous step's mesh (beyond the fitted range)."""
            assert d1 is not None  # a contact step
            prob = old.problem
            if warn and not np.isnan(old.edge):
                _warn_nodal(load_of_t(t1))
            visco0 = s_old.visco if history == "replay" else on(prob)  # replay: it lives on this mesh
            if visco0 is not s_old.visco:  # anchored elsewhere: S_iso^n evaluated on this mesh, Q_m interpolated
                visco0 = visco0._replace(S_iso=prob.asm.iso_S(s_old.x, prob.mat))
            iso_scale, extra = ve.algorithmic(visco0, beta, tau, dt, prob.long_time)
            sol = prob.solve(s_old, d1, iso_scale, extra, guess, load_of_t(t1))
            visco = ve.update(visco0, beta, tau, dt, prob.asm.iso_S(sol.x, prob.mat))
            st = PlateState(sol.x, sol.active, visco, d1, sol.residual, iso_scale, extra, sol.sets)
            return PlateStep(st, prob, float("nan"), path=walked(prob, sol.x, visco.S_iso)), sol.iterations

        if free:  # on the previous step's mesh, its history there (as nodal() below)
            prob = old.problem
            visco0 = s_old.visco if history == "replay" else on(prob)
            if visco0 is not s_old.visco:
                visco0 = visco0._replace(S_iso=prob.asm.iso_S(s_old.x, prob.mat))
            got = without_contact(prob, s_old._replace(visco=visco0), d1, dt, load_of_t(t1))
            if got is None:
                return None
            st_free, its_free = got
            edge_free = float("nan") if np.isnan(old.edge) else 0.0  # next contact: searched as a first one
            return PlateStep(st_free, prob, edge_free, path=walked(prob, st_free.x, st_free.visco.S_iso)), its_free
        assert d1 is not None  # a contact step has a plate position
        if np.isnan(old.edge) or (old.edge > 0.0 and e0 > EDGE_MAX):
            return nodal()
        try:
            sol = fit.solve(d1, e0, guess, load_of_t(t1), visc=visc)
        except NewtonError as err:
            if old.edge > 0.0 and beyond_fit([old.edge], e0, err):
                return nodal()
            if old.edge == 0.0 and s_old.delta > 0.0:  # contact regained, too small yet for a fitted edge: node by
                # node on the last mesh for this step (edge 0: the next step searches a fitted edge again)
                regained, its_regained = nodal(warn=False)
                return regained._replace(edge=0.0), its_regained
            raise
        prob, es_ = sol.problem, sol.state
        visco, where, where_edge = updated(prob, es_.x, sol.edge, held=d1 == s_old.delta)
        st = PlateState(es_.x, es_.active, visco, d1, es_.residual, es_.iso_scale, es_.extra_S, sol.solves)
        before = on(prob) if src is not None else None
        return (
            PlateStep(st, prob, sol.edge, where, where_edge, walked(prob, es_.x, visco.S_iso), src, before),
            sol.iterations,
        )

    return step_to


# ---- a rigid sphere (or plane) above or below the body: exact contact on a curved obstacle (fem.indentation) --
class RigidSphere:
    """Frictionless rigid sphere of radius ``radius`` (scaled; ``np.inf``: a plane) centred on the axis, acting
    on the candidate boundary ``nodes`` from ``above`` the body (a probe pressed down) or from below (a plate the
    body rests on). ``height`` (per call) is the z of its centre (of the plane for ``radius=inf``).

    Its contact surface is the graph z = z_s(r) of the cap that faces the body (above: z_s = height -
    sqrt(rho^2 - r^2); below: height + sqrt(...)). An active node lies on it exactly: its u_r stays free and
    its u_z = z_s(R + u_r) - Z follows (:meth:`impose`), so the Newton unknown of an active node is u_r alone;
    :func:`solve_obstacles` writes the equations in these unknowns (chain rule, exact tangent incl. the
    surface's curvature). The gap is the normal distance |x - c| - rho (plane: the vertical one), the compressive
    normal force N_i = r_i . n_i with n the obstacle's unit normal into the body (nodal reactions include the
    2 pi R of dV). Scaled units as :class:`RigidPlane`."""

    def __init__(self, X: np.ndarray, nodes: np.ndarray, radius: float = np.inf, above: bool = True):
        nodes = np.asarray(nodes, dtype=int)
        if nodes.ndim != 1 or nodes.size == 0:
            raise ValueError("contact needs a non-empty 1D array of candidate boundary nodes")
        if not radius > 0:
            raise ValueError(f"the rigid sphere's radius must be positive (scaled length), got {radius!r}")
        self.radius, self.above = float(radius), bool(above)
        side = 1.0 if above else -1.0
        order = np.argsort(np.arctan2(X[0, nodes], side * X[1, nodes]))  # from the facing pole outward
        self.nodes = nodes[order]
        self.R, self.Z = X[0, self.nodes].copy(), X[1, self.nodes].copy()
        self.dofs = 2 * self.nodes + 1

    def surface(self, r: np.ndarray, height: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(z_s, dz_s/dr, d2z_s/dr2) of the facing cap at the radii r (scaled; r < radius)."""
        if not np.isfinite(self.radius):
            z = np.full_like(r, height)
            return z, np.zeros_like(r), np.zeros_like(r)
        rho = self.radius
        root = np.sqrt(np.maximum(rho**2 - r**2, 1e-12 * rho**2))  # only the facing cap (r < rho) is meant
        sgn = -1.0 if self.above else 1.0
        return height + sgn * root, -sgn * r / root, -sgn * rho**2 / root**3

    def positions(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Deformed (r, z) of the candidates."""
        return self.R + x[2 * self.nodes], self.Z + x[self.dofs]

    def gap(self, x: np.ndarray, height: float) -> np.ndarray:
        """Normal gap of every candidate (scaled length; < 0: penetration)."""
        r, z = self.positions(x)
        if not np.isfinite(self.radius):
            return (height - z) if self.above else (z - height)
        return np.hypot(r, z - height) - self.radius

    def impose(self, x: np.ndarray, height: float, active: np.ndarray) -> np.ndarray:
        """Copy of x with the active nodes on the surface: u_z = z_s(R + u_r) - Z."""
        x = np.array(x, dtype=float)
        r, _ = self.positions(x)
        zs, _, _ = self.surface(r[active], height)
        x[self.dofs[active]] = zs - self.Z[active]
        return x

    def normals(self, x: np.ndarray, height: float) -> np.ndarray:
        """(2, n) unit normals into the body: from the sphere's centre to the candidates (for the active nodes, on
        the sphere, the surface normal); a plane's is -e_z above the body, +e_z below."""
        r, z = self.positions(x)
        if not np.isfinite(self.radius):
            return np.stack([np.zeros_like(r), np.full_like(r, -1.0 if self.above else 1.0)])
        n = np.stack([r, z - height])
        return n / np.hypot(n[0], n[1])

    def normal_force(self, x: np.ndarray, r: np.ndarray, height: float) -> np.ndarray:
        """Compressive nodal contact force N_i = r_i . n_i (meaningful on active nodes)."""
        n = self.normals(x, height)
        return r[2 * self.nodes] * n[0] + r[self.dofs] * n[1]

    def axial_force(self, r: np.ndarray, active: np.ndarray) -> float:
        """The force the body exerts on the obstacle along the axis, positive pushing it away from the body
        (the sum of the active nodes' axial reactions)."""
        fz = r[self.dofs[active]].sum()
        return float(-fz if self.above else fz)

    def contact_radius(self, x: np.ndarray, active: np.ndarray, height: float) -> tuple[float, float]:
        """(edge estimate, outermost active node) of the deformed contact radius (scaled), as
        :meth:`RigidPlane.contact_radius` (the Hertz-like gap law between the outermost active node and the
        next)."""
        if not active.any():
            return 0.0, 0.0
        r, _ = self.positions(x)
        k = int(np.max(np.flatnonzero(active)))
        return edge_estimate(r, self.gap(x, height), k)


def edge_estimate(r: np.ndarray, g: np.ndarray, k: int) -> tuple[float, float]:
    """(edge estimate, r_k): the contact edge between the outermost active candidate k (radius r_k) and the next,
    from the gaps g_1, g_2 of the next two with the Hertz-like law g ~ (r - a)^(3/2), clamped to [r_k, r_1]."""
    rk = float(r[k])
    if k + 2 >= r.size:
        return rk, rk
    g1, g2, r1, r2 = g[k + 1], g[k + 2], r[k + 1], r[k + 2]
    if not (g2 > g1 > 0 and r2 > r1 > rk):
        return rk, rk
    rho = (g1 / g2) ** (2.0 / 3.0)
    a = (r1 - rho * r2) / (1.0 - rho)
    return float(np.clip(a, rk, r1)), rk


class ObstacleSolution(NamedTuple):
    x: np.ndarray  # full unknown vector, the active nodes on their obstacles
    active: tuple[np.ndarray, ...]  # bool per candidate node of each obstacle
    iterations: int  # Newton iterations summed over active-set passes
    sets: int  # active-set passes
    residual: np.ndarray  # full internal residual at x (the reactions on the active nodes)


def _add_rows(M: sp.csr_matrix, dst: np.ndarray, src: np.ndarray, s: np.ndarray) -> bool:
    """In place: row dst_k += s_k row src_k of a canonical CSR matrix whose rows dst_k and src_k have the same
    columns (False, nothing changed, if they do not)."""
    ptr = M.indptr
    n = ptr[src + 1] - ptr[src]
    if not np.array_equal(n, ptr[dst + 1] - ptr[dst]):
        return False
    off = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
    i_dst, i_src = np.repeat(ptr[dst], n) + off, np.repeat(ptr[src], n) + off
    if not np.array_equal(M.indices[i_dst], M.indices[i_src]):
        return False
    M.data[i_dst] += np.repeat(s, n) * M.data[i_src]
    return True


def congruence(K, rows: np.ndarray, cols: np.ndarray, s: np.ndarray) -> sp.csr_matrix | None:
    """T^T K T for T = I + sum_k s_k e_{rows_k} e_{cols_k}^T (the u_z of a node following its u_r) with K's own
    sparsity pattern (CSR, explicit zeros kept, so a factorisation's plan is reused across active sets and
    iterations): valid when the rows and columns of the two dofs of a node have the same pattern, as every FE
    matrix assembled node by node has; None when they do not."""
    M = sp.csr_matrix(K, copy=True)
    M.sum_duplicates()
    M.sort_indices()
    if not _add_rows(M, cols, rows, s):  # T^T K: row u_r += s row u_z
        return None
    Mt = M.T.tocsr()
    Mt.sort_indices()
    if not _add_rows(Mt, cols, rows, s):  # (T^T K T)^T = T^T (T^T K)^T
        return None
    out = Mt.T.tocsr()
    out.sort_indices()
    return out


def solve_obstacles(
    fun: Callable,
    x0: np.ndarray,
    obstacles: list[tuple[RigidSphere, float]],
    active0: tuple[np.ndarray, ...],
    free: np.ndarray,
    *,
    gap_tol: float = 1e-10,
    force_tol: float = 1e-9,
    max_sets: int = 12,
    load=None,
    residual: Callable | None = None,
    admissible: Callable | None = None,
    release_all: bool = True,
    fixed: bool = False,
    **newton_kw,
) -> ObstacleSolution:
    """Equilibrium with exact contact on several rigid obstacles (``(RigidSphere, height)`` pairs).

    As :meth:`RigidPlane.solve`, with curved obstacles: for each active set Newton solves in the unknowns
    ``free`` less the u_z of the active nodes, which follow their u_r on the surface (``RigidSphere.impose``).
    With x = Phi(y) (u_z = z_s(r) - Z on the active nodes) the equations are T^T r(Phi(y)) = 0 with T =
    dPhi/dy (u_z,i += z_s'(r_i) u_r,i) and the exact tangent T^T K T + diag(r_z,i z_s''(r_i)). Active-set
    updates: penetrating candidates (gap < -gap_tol) enter, tensile active nodes (N < -force_tol of their
    obstacle's total) leave (``release_all``: all of them at once; else the most tensile one, as ``RigidPlane``);
    a repeated set raises ``ContactError``. ``fixed``: one solve with the active sets as given, no updates (the
    contact edge on a node of a fitted mesh, ``fem.indentation``)."""
    n = x0.size
    active = [np.asarray(a, bool).copy() for a in active0]
    if not fixed:  # every candidate that penetrates in x0 starts active
        active = [a | (ob.gap(x0, h) < -gap_tol) for a, (ob, h) in zip(active, obstacles)]

    def phi(x):
        for (ob, h), a in zip(obstacles, active):
            x = ob.impose(x, h, a)
        return x

    def transformed(x):
        x = phi(x)
        rows, cols, vals, d_idx, d_val = [], [], [], [], []
        for (ob, h), a in zip(obstacles, active):
            r, _ = ob.positions(x)
            _, s, c = ob.surface(r[a], h)
            rows.append(ob.dofs[a])
            cols.append(2 * ob.nodes[a])
            vals.append(s)
            d_idx.append(2 * ob.nodes[a])
            d_val.append(c)
        rr, cc, vv = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
        di, dc = np.concatenate(d_idx), np.concatenate(d_val)
        T = sp.identity(n, format="csr") + sp.csr_matrix((vv, (rr, cc)), shape=(n, n))
        r_full, K = fun(x)
        r_t = r_full.copy()
        r_t[cc] += vv * r_full[rr]  # T^T r on the u_r of the active nodes

        def tangent():
            Km = K() if callable(K) and not sp.issparse(K) else K
            M = congruence(Km, rr, cc, vv)
            if M is None:  # not an FE pattern (the rows of a node's two dofs differ): sparse products
                D = sp.csr_matrix((dc * r_full[di + 1], (di, di)), shape=(n, n))
                return (T.T @ Km @ T + D).tocsr()
            for i, v in zip(di, dc * r_full[di + 1]):
                lo, hi = M.indptr[i], M.indptr[i + 1]
                M.data[lo + np.searchsorted(M.indices[lo:hi], i)] += v
            return M

        return r_t, tangent

    adm = (lambda x: admissible(phi(x))) if admissible is not None else None
    x = np.asarray(x0, float)
    seen, its = set(), 0
    for k in range(1, max_sets + 1):
        key = b"".join(a.tobytes() for a in active)
        if key in seen:
            raise ContactError(
                "the contact active set cycles", load=load, hint="reduce the load/time step near the contact edge"
            )
        seen.add(key)
        x = phi(x)
        pinned = np.concatenate([ob.dofs[a] for (ob, _), a in zip(obstacles, active)])
        fr = np.setdiff1d(free, pinned)
        res = newton(transformed, x, free=fr, load=load, admissible=adm, **newton_kw)
        x, its = phi(res.x), its + res.iterations
        r = residual(x) if residual is not None else fun(x)[0]
        if fixed:
            return ObstacleSolution(x, tuple(active), its, k, r)
        new, changed = [], False
        for (ob, h), a in zip(obstacles, active):
            N, g = ob.normal_force(x, r, h), ob.gap(x, h)
            scale = max(float(np.sum(N[a])), 1e-300)
            release = a & (N < -force_tol * scale)
            enter = ~a & (g < -gap_tol)
            b = a.copy()
            b[enter] = True
            if release_all:
                b[release] = False
            elif release.any():
                b[np.flatnonzero(release)[np.argmin(N[release])]] = False
            changed = changed or bool(release.any() or enter.any())
            new.append(b)
        if not changed:
            return ObstacleSolution(x, tuple(active), its, k, r)
        active = new
    raise ContactError(
        f"the contact active set did not settle in {max_sets} passes", load=load, hint="reduce the load/time step"
    )
