r"""FE spheroid: a Fung ball compressed between rigid frictionless plates, held, relaxing (seed Figs 6-10).

:func:`compress` (``SpheroidResult``, ``fem.output``). By symmetry a quarter section R >= 0, Z >= 0 of the
ball of radius a0 (u_r = 0 on the axis, u_z = 0 on the midplane) under one rigid flat plane
z = a0 - delta(t)/2 (exact unilateral contact, ``fem.contact``), mixed Q2/P1-discontinuous elements,
generalized Maxwell branches on S_iso (``fem.viscoelastic``), quasi-static time stepping
(``fem.timestepping``; inertia ~1e-6 of the stresses). Inside, lengths are scaled by a0, stresses by C,
forces by C a0^2 (``fem.problem.SceneProblem``). Contact-edge-fitted meshes: :func:`fitted_mesh`, ``LEVELS``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np

from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.contact import ContactError, RigidPlane
from tissuemech.fem.forms import Material
from tissuemech.fem.kinematics import invariants
from tissuemech.fem.mesh import AxiMesh, ball_section, graded_points
from tissuemech.fem.newton import KeptFactor, NewtonError, newton, symmetric_factor
from tissuemech.fem.output import SpheroidField, SpheroidResult
from tissuemech.fem.problem import SPHEROID_MARGIN, SceneProblem, check_mesh, mesh_spec, roundoff_floor, secant
from tissuemech.fem.timestepping import march, ramp_hold_schedule
from tissuemech.reduced.material import validate_branches, validate_material, validate_positive

log = logging.getLogger(__name__)

__all__ = ["compress", "make_mesh", "fitted_mesh", "MESHES", "LEVELS", "hertz_force"]

# level -> (n_core, n_radial, surface grading, n_contact, n_equator) of ``fitted_mesh``: the surface nodes of
# the pole block are placed so that node n_contact sits exactly on the contact edge (n_contact elements across
# the contact zone, n_core - n_contact beyond it, graded toward the edge; radial layers thin enough for the
# contact size; n_equator divisions of the equator block). The edge is found per state from the Signorini
# condition N_edge = 0 (see ``compress``); the force is then a smooth function of delta and of h (no
# node-to-node jitter). Levels 1..4 are one self-similar sequence (h ~ 1/n_core): compare.bench fem-spheroid.
LEVELS = {
    0: (8, 3, 2.0, 4, 3),
    1: (16, 6, 2.0, 7, 6),
    2: (32, 12, 2.0, 14, 12),
    3: (48, 18, 2.0, 21, 18),
    4: (64, 24, 2.0, 28, 24),
}
MESHES = {"coarse": 0, "default": 1, "fine": 2}
FORCE_CHECK = 1e-6  # |F_contact - F_reaction| / F
EDGE_TOL = 1e-6  # |N_edge| / F at the fitted contact edge (F is stationary in the edge position there; a
# tolerance of 1e-4 left force errors up to 7e-6 on levels 1-3; 1e-6 leaves <= 5.2e-8 for 4-19 % more Newton
# iterations: python notes/issue14_edge.py)
SPLIT = np.radians(55.0)  # the pole block's arc: 0..55 deg from the pole (holds the edge to delta/(2 a0) ~ 0.45)
EDGE_MAX = 0.92  # largest edge position, as a fraction of the pole block's arc
EDGE_MIN = 1e-4  # smallest edge position tried (an approach delta/(2 a0) of ~4e-9)
# smallest final approach delta/(2 a0) of a run (issue 14 audit): the first static state (1/8 of it) is then
# x >= 1.25e-7, which every level converges at; at 1e-7 the coarse level's first state did not (its residual stuck
# at round-off), and at x = 1e-6 F_FE / F_table is already 1.43 / 1.016 (coarse / default, notes/fe_small_approach.py)
X_MIN = 1e-6
_INNER_GRADING = 1.5  # contact-zone elements: first / last (finer at the edge)
_DEPTH = 2.0  # outermost radial layer <= _DEPTH x the mean contact-zone element length


def _geometric(n: int, length: float, first: float) -> np.ndarray:
    """n + 1 points on [0, length]: n geometric intervals, the first one ``first`` long."""
    if n == 1:
        return np.array([0.0, length])
    if abs(first * n - length) <= 1e-14 * length:
        return np.linspace(0.0, length, n + 1)
    from scipy.optimize import brentq

    q = brentq(lambda q: first * (q**n - 1) / (q - 1) - length, 1e-3, 1e3) if first * n != length else 1.0
    iv = first * q ** np.arange(n)
    return np.r_[0.0, np.cumsum(iv)] * (length / iv.sum())


def fitted_mesh(radius: float, level: int, edge: float) -> AxiMesh:
    """The level's ball_section mesh with a surface node on the contact edge.

    ``edge``: reference position of the edge node as a fraction of the pole block's arc (the surface angle
    from the pole is SPLIT * edge, SPLIT = 55 deg), in (0, EDGE_MAX]. Every edge gives the same topology and node numbering.
    """
    if level not in LEVELS:
        raise ValueError(f"mesh level must be an integer 0..4 (0 coarse, 1 default, 2 fine), got {level!r}")
    if not (0 < edge <= EDGE_MAX):
        raise ValueError(
            f"the contact edge at {np.degrees(SPLIT) * edge:.3g} deg from the pole is outside the meshable range "
            f"(0, {np.degrees(SPLIT) * EDGE_MAX:.3g}] deg; reduce the approach"
        )
    nc, nr, gr, k = LEVELS[level][:4]
    neq = LEVELS[level][4] if len(LEVELS[level]) > 4 else None
    inner = edge * graded_points(k, 1.0 / _INNER_GRADING)
    he = inner[-1] - inner[-2]
    outer = edge + _geometric(nc - k, 1.0 - edge, min(he, (1.0 - edge) / (nc - k)))
    v = graded_points(nr, 1.0 / gr)
    c_thick = 1.0 - 0.55 * np.sqrt(2) * np.cos(SPLIT)  # pole-block thickness at the axis (ball_section)
    hc = _DEPTH * edge * SPLIT / k
    if hc < c_thick * (v[-1] - v[-2]):
        v = 1.0 - _geometric(nr, 1.0, hc / c_thick)[::-1]
    return ball_section(
        radius, nc, nr, pole_points=np.r_[inner, outer[1:]], radial_points=v, n_equator=neq, split_angle=SPLIT,
        intorder=4,
    )  # fmt: skip


def hertz_force(approach, radius: float, C: float):
    """Hertz force (N) of a ball between two plates, total approach delta (m): (4/3) E* sqrt(a0) (delta/2)^1.5, E* = 8 C."""
    return 4.0 / 3.0 * 8.0 * C * np.sqrt(radius) * (np.asarray(approach, float) / 2) ** 1.5


def _level(mesh):
    """The mesh level (int) of a ``mesh`` argument, or None for an AxiMesh (validated)."""
    if isinstance(mesh, AxiMesh):
        return None
    mesh = mesh_spec(mesh, MESHES, "a level 0..4 or a ball_section mesh")
    if isinstance(mesh, (bool, np.bool_)) or not isinstance(mesh, (int, np.integer)) or int(mesh) not in LEVELS:
        raise ValueError(f"mesh level must be an integer 0..4 (0 coarse, 1 default, 2 fine), got {mesh!r}")
    return int(mesh)


def make_mesh(mesh, radius: float) -> AxiMesh:
    """Resolve the ``mesh`` argument to an AxiMesh of the quarter ball (see :func:`compress`); a level
    gives its mesh with the contact edge node half-way along the pole block (``fitted_mesh(radius, level, 0.5)``)."""
    if isinstance(mesh, AxiMesh):
        msg = "the mesh object must come from fem.mesh.ball_section(radius, ...) with the same radius"
        return check_mesh(mesh, radius, msg, tags=("outer",))
    # 3 x 3 Gauss points (exact enough for Q2: forces change < 1e-5 relative vs 4 x 4), 1.8x cheaper
    return fitted_mesh(radius, _level(mesh), 0.5)


class _Solved(NamedTuple):
    """A converged step of ``compress`` before its observables are taken."""

    time: float  # s (static runs: the load fraction)
    problem: _Problem  # the mesh's problem the state belongs to
    state: _State
    newton_iterations: int
    contact_passes: int
    wall_time: float  # s


class _Row(NamedTuple):
    """One step's entry of ``SpheroidResult`` (SI: s, m, N, Pa)."""

    time: float
    approach: float  # m, the total plate approach delta
    force: float  # N
    reaction_force: float  # N
    midplane_radius: float  # m
    contact_radius: float  # m
    mean_von_mises: float  # Pa
    newton_iterations: int
    contact_passes: int
    wall_time: float  # s
    contact_radius_node: float  # m
    min_gap: float  # m
    min_contact_force: float  # N


class _State(NamedTuple):
    """A converged state of the scaled ball (lengths / a0, stresses / C, forces / (C a0^2))."""

    x: np.ndarray  # full unknown vector (u, q)
    active: np.ndarray  # bool per contact candidate (``plane.nodes``): on the plate
    visco: ve.MaxwellState  # branch stresses and S_iso after the step (None on _EdgeFit's static states)
    delta: float  # scaled plate displacement (= approach / 2 / a0)
    residual: np.ndarray  # full internal residual at x: the reactions on the constrained dofs
    iso_scale: float  # the step's algorithmic factors (for its stresses)
    extra_S: object
    passes: int  # contact active-set passes of the step


class Observation(NamedTuple):
    """Observables of one converged state (scaled: lengths / a0, forces / (C a0^2), stresses / C)."""

    plate_force: float  # sum of the active nodes' contact multipliers N_i [C a0^2]
    reaction_force: float  # reaction of the midplane constraint u_z = 0 [C a0^2]
    midplane_radius: float  # deformed equator radius [a0]
    contact_radius: float  # edge estimate between the outermost active node and the next [a0]
    contact_radius_node: float  # the outermost active node [a0]
    mean_von_mises: float  # von Mises averaged over the deformed volume [C]
    von_mises: np.ndarray  # at the quadrature points (n_el, n_qp) [C]
    pressure: np.ndarray  # the mixed field q = mean Cauchy stress at the points (n_el, n_qp) [C]; hydrostatic = -q
    normal_force: np.ndarray  # compressive nodal contact force per candidate node, 0 off contact [C a0^2]
    min_gap: float  # smallest plate gap of the candidates [a0]
    min_normal_force: float  # smallest contact force of the active nodes (0 without contact) [C a0^2]


class _Problem(SceneProblem):
    """The scaled ball between rigid plates: f_int(x) = 0 with u_z = h - Z on the active contact nodes.

    ``_Problem(m, mat, beta, tau, rtol)``: the mesh (scaled by a0), the scaled material, the Maxwell
    branches (beta_m, tau_m [s]) and Newton's relative tolerance. ``plane`` is the rigid plate over the
    surface nodes off the midplane, ``equator`` the node at (R, Z) = (a0, 0), ``floor`` the round-off
    floor of the residual (``fem.problem.roundoff_floor``, unit force scale)."""

    def __init__(self, m: AxiMesh, mat: Material, beta, tau, rtol: float):
        super().__init__(m, mat, "mixed", beta, tau)
        self.sym = m.nodes["symmetry"]
        cand = np.setdiff1d(m.nodes["outer"], self.sym)
        self.plane = RigidPlane(m.X, cand)
        X = m.X
        eq = np.flatnonzero((np.abs(X[1]) < 1e-12) & (np.abs(X[0] - 1) < 1e-9))
        if eq.size != 1:
            raise ValueError("the ball mesh has no node at the equator (R = a0, Z = 0)")
        self.equator = int(eq[0])
        self.rtol = rtol
        self.floor = roundoff_floor(mat.kappa, 1.0, SPHEROID_MARGIN)
        self.keep = KeptFactor()  # the factorisation kept across this mesh's solves (quasi-Newton first)

    def solve(self, s0: _State, d1: float, iso_scale, extra, guess, load):
        """Equilibrium with exact contact under the plate at h = 1 - d1 (scaled), from ``guess``, with the
        step's branch stresses; the active set starts from ``s0.active``. Returns ``ContactSolution``."""
        h = 1.0 - d1
        fun = lambda x: self.asm.internal(x, self.mat, extra_S=extra, iso_scale=iso_scale, tangent="lazy")
        ref = max(32.0 / 3.0 * max(d1, 1e-6) ** 1.5 * iso_scale, 1e-12)
        res = lambda x: self.asm.internal(x, self.mat, extra_S=extra, iso_scale=iso_scale, tangent=False)[0]
        sol = self.plane.solve(
            fun,
            guess,
            h,
            s0.active,
            self.free,
            load=load,
            ref_norm=ref,
            rtol=self.rtol,
            residual=res,
            xtol=1e-9,
            atol=self.floor,
            admissible=self.admissible,
            max_iter=25,
            factor=symmetric_factor,
            keep=self.keep,
        )
        return sol

    def step(self, s0: _State, d1: float, dt: float | None, prev, load):
        """(state, Newton iterations): equilibrium at plate displacement d1 (scaled) after a time step
        dt [s] (None: static), predicted by the secant through ``prev`` (a ``_State`` or None)."""
        iso_scale, extra = self.maxwell_factors(s0.visco, dt)
        guess = s0.x
        if prev is not None and abs(s0.delta - prev.delta) > 1e-14:
            guess = secant(s0.x, prev.x, d1 - s0.delta, s0.delta - prev.delta)
        sol = self.solve(s0, d1, iso_scale, extra, guess, load)
        visco = self.maxwell_update(s0.visco, dt, sol.x)
        return _State(sol.x, sol.active, visco, d1, sol.residual, iso_scale, extra, sol.sets), sol.iterations

    # ---- observables (scaled) --------------------------------------------------------------
    def observe(self, s: _State) -> Observation:
        """The observables of state ``s`` (see ``Observation``)."""
        r, pl = s.residual, self.plane
        N = np.where(s.active, pl.normal_force(r), 0.0)
        x = s.x
        rc, rc_node = _contact_radius(pl, x, s.active, 1.0 - s.delta)
        f, vm, q = self.point_stresses(x, s.extra_S, s.iso_scale)
        _, J = invariants(f)
        wJ = self.asm.w * J
        return Observation(
            plate_force=float(N.sum()),
            reaction_force=float(r[2 * self.sym + 1].sum()),
            midplane_radius=1.0 + x[2 * self.equator],
            contact_radius=rc,
            contact_radius_node=rc_node,
            mean_von_mises=float(np.sum(vm * wJ) / np.sum(wJ)),
            von_mises=vm,
            pressure=q,
            normal_force=N,
            min_gap=float(np.min(pl.gap(x, 1.0 - s.delta))),
            min_normal_force=float(np.min(N[s.active])) if s.active.any() else 0.0,
        )


def _contact_radius(pl: RigidPlane, x: np.ndarray, active: np.ndarray, h: float):
    """(edge estimate, outermost active node) of the deformed contact radius (scaled).

    Between the outermost active node (r_k) and the next node (r_1) the edge a is estimated from the
    gaps g_1, g_2 of the next two free nodes with the Hertz-like law g ~ (r - a)^(3/2):
    (g_1/g_2)^(2/3) = (r_1 - a)/(r_2 - a), clamped to [r_k, r_1]."""
    if not active.any():
        return 0.0, 0.0
    r = pl.R + x[2 * pl.nodes]
    k = int(np.max(np.flatnonzero(active)))  # candidates are ordered from the pole outward
    rk = float(r[k])
    if k + 2 >= r.size:
        return rk, rk
    g = pl.gap(x, h)
    g1, g2, r1, r2 = g[k + 1], g[k + 2], r[k + 1], r[k + 2]
    if not (g2 > g1 > 0 and r2 > r1 > rk):
        return rk, rk
    rho = (g1 / g2) ** (2.0 / 3.0)
    a = (r1 - rho * r2) / (1.0 - rho)
    return float(np.clip(a, rk, r1)), rk


class _EdgeFit:
    """Static equilibrium states whose contact edge sits on a surface node (one fitted mesh per state).

    With the first 2 n_contact + 1 surface nodes of the pole block on the plate (the edge node
    ``n_contact`` on ``fitted_mesh(..., edge)``) and the rest free, the nodal multiplier of the edge node
    N_e(edge) falls through zero as the edge moves out: the root of phi(edge) = N_e / F (secant iteration)
    is the state where both Signorini conditions hold at the edge (N_e = 0, next gaps > 0) and the force is
    stationary in the edge position, so the force is a smooth function of the approach and of the mesh."""

    def __init__(self, radius: float, level: int, mat: Material, rtol: float):
        self.a0, self.level, self.mat, self.rtol = radius, level, mat, rtol
        self.k = int(LEVELS[level][3])
        self.slope = 0.0
        self._cache: dict = {}
        self.keep = KeptFactor()  # one factorisation kept across the fitted meshes (same size and pattern)

    def problem(self, edge: float) -> _Problem:
        key = float(edge)
        if key not in self._cache:
            if len(self._cache) > 6:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = _Problem(fitted_mesh(self.a0, self.level, key), self.mat, [], [], self.rtol)
        return self._cache[key]

    def _state(self, prob: _Problem, d: float, guesses, load, visc=None):
        pl, n_act = prob.plane, 2 * self.k + 1
        act = np.zeros(pl.nodes.size, bool)
        act[:n_act] = True
        fr = np.setdiff1d(prob.free, pl.dofs[act], assume_unique=True)
        iso_scale, extra = (1.0, None) if visc is None else visc(prob)
        fun = lambda x: prob.asm.internal(x, prob.mat, extra_S=extra, iso_scale=iso_scale, tangent="lazy")
        X = prob.m.X
        affine = np.zeros(prob.asm.ndof)  # a uniform squeeze: always admissible
        affine[0 : prob.asm.n_u : 2], affine[1 : prob.asm.n_u : 2] = 0.5 * d * X[0], -d * X[1]
        err = None
        for g in [*guesses, affine]:
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
                    factor=symmetric_factor,
                    keep=self.keep,
                )
            except NewtonError as e:
                err = e
                continue
            r = prob.asm.internal(res.x, prob.mat, extra_S=extra, iso_scale=iso_scale, tangent=False)[0]
            N = pl.normal_force(r)
            F = float(N[act].sum())
            st = _State(res.x, act, None, d, r, iso_scale, extra, 1)
            phi = float(N[n_act - 1]) / max(F, 1e-300)
            # a tensile node inside the last contact element: the zone is too large (a spurious root of
            # N_edge = 0 with the element lifting off in its middle): report it as negative
            inner = float(np.min(N[max(n_act - 3, 0) : n_act - 1])) / max(F, 1e-300)
            if inner < 0:
                phi = min(phi, inner)
            # a free node beyond the edge below the plate: the zone is too small (report it as positive)
            g = pl.gap(res.x, 1.0 - d)[n_act : n_act + 6]
            if g.size and g.min() < -1e-9 * d:
                phi = max(phi, -float(g.min()) / d)
            return st, res.iterations, phi
        raise err if err is not None else NewtonError("no admissible initial guess", load=load, hint="reduce the step")

    def solve(self, d: float, edge0: float, x0, load, tol: float = EDGE_TOL, visc=None):
        """(problem, state, edge, Newton iterations, solves) at plate displacement d (scaled).

        Safeguarded secant on phi(edge): phi > 0 (edge node pressed) means the zone is too small, phi < 0
        (edge node or its element pulled) too large; the root is kept inside that bracket (bisection when a
        secant step leaves it). ``visc(problem) -> (iso_scale, extra_S)``: the algorithmic viscoelastic stress of a
        time step on that problem's mesh (``fem.viscoelastic.algorithmic`` of the history mapped onto its Gauss
        points); None: elastic."""
        lo, hi = EDGE_MIN, EDGE_MAX  # phi(lo) > 0 > phi(hi) (bounds until evaluated)
        e_a = float(np.clip(edge0, lo, hi))
        st_a, its, phi_a = self._state(self.problem(e_a), d, [x0], load, visc)
        n = 1
        if abs(phi_a) < tol:
            return self.problem(e_a), st_a, e_a, its, n
        lo, hi = (e_a, hi) if phi_a > 0 else (lo, e_a)
        # first secant point: a step along the slope dphi/dln(edge) of the previous state (about -2)
        step = float(np.clip(-phi_a / self.slope, -0.1, 0.1)) if self.slope < 0 else 0.03 * np.sign(phi_a)
        e_b = float(np.clip(e_a * (1.0 + step), lo, hi))
        best = [abs(phi_a)]  # |phi| per pass: a search whose best |phi| stalls is stuck (see below)
        for _ in range(30):
            st_b, it, phi_b = self._state(self.problem(e_b), d, [st_a.x, x0], load, visc)
            its, n = its + it, n + 1
            best.append(abs(phi_b))
            if abs(phi_b) < tol:
                if phi_b != phi_a and e_b != e_a:
                    self.slope = (phi_b - phi_a) / np.log(e_b / e_a)
                return self.problem(e_b), st_b, e_b, its, n
            if phi_b > 0:
                lo = max(lo, e_b)
            else:
                hi = min(hi, e_b)
            e_new = e_b - phi_b * (e_b - e_a) / (phi_b - phi_a) if phi_b != phi_a and e_b != e_a else np.nan
            if e_b != e_a and phi_b != phi_a:
                self.slope = (phi_b - phi_a) / np.log(e_b / e_a)
            if not (lo < e_new < hi):  # outside the bracket: bisect (or expand toward the open bound)
                e_new = 0.5 * (lo + hi) if hi < EDGE_MAX or lo > EDGE_MIN else e_b * (1.2 if phi_b > 0 else 0.8)
                e_new = float(np.clip(e_new, EDGE_MIN, EDGE_MAX))
            if hi - lo < 1e-12 * hi:
                break
            if n >= 6 and min(best[-3:]) > 0.5 * min(best[:-3]):
                # stalled (issue 14): the best |phi| of the last 3 passes is not half the earlier best. phi
                # jumps across the bracket (a spurious state on one side), so the secant only creeps; the
                # caller cuts the step, as it would after the 30 passes (3 of 4 passes of the fine level 3
                # static curve were spent here before)
                break
            e_a, st_a, phi_a, e_b = e_b, st_b, phi_b, float(e_new)
        raise ContactError(
            "the contact edge did not settle (the edge node multiplier does not vanish)",
            load=load,
            hint="the approach may be beyond the meshable range; use a ball_section mesh",
        )


# Newton iterations allowed from the uniform-squeeze guess (the first contact): where it converges it takes 5-8
# (levels 0-3, the static curves and Fig. 10 runs); on level 4 the first static step (20 um) wandered for 25
# iterations and factorisations (~4 s) before the step was cut, which converged in 8 (issue 14)
AFFINE_MAX_ITER = 12


def _edge_guess(ds: list, es: list, d: float) -> float:
    """Edge position extrapolated in sqrt(d) from the previous states (Hertz: contact radius ~ sqrt(d))."""
    if not ds:
        return 1.06 * np.sqrt(d) / SPLIT
    if len(ds) == 1:
        return es[-1] * np.sqrt(d / ds[-1])
    s0, s1, s = np.sqrt(ds[-2]), np.sqrt(ds[-1]), np.sqrt(d)
    return es[-1] + (es[-1] - es[-2]) * (s - s1) / (s1 - s0)


def _beyond_fit(es: list, e_next: float, err: Exception | None = None) -> bool:
    """Whether the contact edge leaves the fitted range (the pole block): the predicted next edge is past
    EDGE_MAX, or the edge iteration failed (``err``) with the last edge in the outer tenth of the range."""
    if e_next > EDGE_MAX:
        return True
    return isinstance(err, ContactError) and bool(es) and es[-1] > 0.9 * EDGE_MAX


def _warn_nodal(load: str) -> None:
    log.warning(
        "the contact edge leaves the fitted range of the pole block (%.3g deg) at %s: node-by-node contact on "
        "the last fitted mesh from here on (the force carries the edge quantisation, ~1e-3)",
        np.degrees(SPLIT * EDGE_MAX),
        load,
    )


def _static_fitted(fit: _EdgeFit, d_of_t, times, load_of_t, max_cuts: int = 6):
    """Static states on fitted meshes at the load fractions ``times``: [(t, problem, state, its, passes, wall,
    edge)]. Where the contact edge leaves the fitted range (``_beyond_fit``), the remaining states are solved with
    node-by-node contact on the last fitted mesh (a logged warning; their edge is NaN)."""
    import time as _time

    out: list[tuple] = []
    ds: list[float] = []
    es: list[float] = []
    xs: list[np.ndarray] = []
    t_done = 0.0
    nodal: tuple | None = None  # (problem, state, previous state) once the contact is node by node
    for t in times:
        targets, cuts = [t], 0
        while targets:
            tt = targets[-1]
            d = d_of_t(tt)
            w0 = _time.perf_counter()
            guess = None
            if xs:  # linear extrapolation in d from the last two states (the reference state x = 0 at d = 0
                # counting as one: the second step starts from the first one scaled, not from the first one)
                x_prev, d_prev = (xs[-2], ds[-2]) if len(xs) > 1 else (0.0 * xs[-1], 0.0)
                guess = xs[-1]
                if ds[-1] != d_prev:
                    guess = xs[-1] + (xs[-1] - x_prev) * (d - ds[-1]) / (ds[-1] - d_prev)
            e_next = _edge_guess(ds, es, d)
            try:
                if nodal is None and out and _beyond_fit(es, e_next):
                    raise ContactError("the contact edge leaves the fitted range", load=load_of_t(tt))
                if nodal is None:
                    prob, st, e, its, n = fit.solve(d, e_next, guess, load_of_t(tt))
                else:
                    prob, s_last, s_prev = nodal
                    st, its = prob.step(s_last, d, None, s_prev, load_of_t(tt))
                    e, n = float("nan"), st.passes
            except NewtonError as err:
                if nodal is None and out and _beyond_fit(es, e_next, err):
                    _warn_nodal(load_of_t(tt))
                    p_last, s_last = out[-1][1], out[-1][2]
                    shape = p_last.asm.w.shape + (5,)
                    s_last = s_last._replace(visco=ve.initial_state(0, shape))
                    nodal = (p_last, s_last, None)
                    continue
                cuts += 1
                if cuts > max_cuts:
                    raise
                targets.append(0.5 * (t_done + tt))
                continue
            targets.pop()
            t_done = tt
            if nodal is None:
                ds.append(d)
                es.append(e)
                xs.append(st.x)
            else:
                nodal = (nodal[0], st, nodal[1])
            if not targets:
                out.append((tt, prob, st, its, n, _time.perf_counter() - w0, e))
    return out


def _lagrange2(t: np.ndarray):
    """1D quadratic Lagrange basis on the nodes 0, 1/2, 1 of [0, 1] at t (n,): values and derivatives,
    (3, n) each, one row per node."""
    v = np.stack([2 * (t - 0.5) * (t - 1), -4 * t * (t - 1), 2 * t * (t - 0.5)])
    d = np.stack([4 * t - 3, -8 * t + 4, 4 * t - 1])
    return v, d


def _local_coordinates(xe: np.ndarray, ref: np.ndarray, x: np.ndarray, iters: int = 30, start=None) -> np.ndarray:
    """Reference coordinates (2, n) in [0, 1]^2 (outside it for points outside; Newton from ``start``, default
    the element centre, bounded to [-1, 2]) of the points x (2, n) in Q2 elements with node coordinates
    xe (2, 9, n), reference nodes ref (2, 9) (each coordinate 0, 1/2 or 1)."""
    X = np.full(x.shape, 0.5) if start is None else np.array(start, float)
    ia, ib = (np.rint(2.0 * r).astype(int) for r in ref)  # the row of each node's 1D factor
    # the points still iterating: each stops after its first step below 1e-13, or when it is clipped twice in a
    # row (a point far outside the element: its coordinates are meaningless and the caller looks elsewhere)
    act = np.arange(x.shape[1])
    Xa = X
    clipped = np.zeros(x.shape[1], bool)
    for _ in range(iters):
        (v0, d0), (v1, d1) = _lagrange2(Xa[0]), _lagrange2(Xa[1])
        va, da, vb, db = v0[ia], d0[ia], v1[ib], d1[ib]
        F = np.einsum("ikn,kn->in", xe, va * vb)
        J0 = np.einsum("ikn,kn->in", xe, da * vb)  # dx/dxi
        J1 = np.einsum("ikn,kn->in", xe, va * db)  # dx/deta
        det = J0[0] * J1[1] - J1[0] * J0[1]
        r = x - F
        dX = np.stack([J1[1] * r[0] - J1[0] * r[1], -J0[1] * r[0] + J0[0] * r[1]]) / det
        Xn = Xa + dX
        Xa = np.clip(Xn, -1.0, 2.0)
        X[:, act] = Xa
        now = np.any(Xn != Xa, axis=0)
        going = (np.max(np.abs(dX), axis=0) >= 1e-13) & ~(now & clipped)
        if not going.any():
            break
        if not going.all():
            act, Xa, xe, x = act[going], Xa[:, going], xe[:, :, going], x[:, going]
            now = now[going]
        clipped = now
    return X


def _search_trees(m: AxiMesh):
    """(tree of the quadrature points, tree of the element centres) of a mesh, built once per mesh (a step's old
    mesh sends its history to every fitted mesh the edge search tries)."""
    from scipy.spatial import cKDTree

    if "search_trees" not in m._cache:
        xe = m.basis.doflocs[:, m.basis.element_dofs]
        m._cache["search_trees"] = (cKDTree(m.quadrature_points.reshape(2, -1).T), cKDTree(xe.mean(axis=1).T))
    return m._cache["search_trees"]


def _gauss_transfer(old: AxiMesh, new: AxiMesh) -> Callable[[np.ndarray], np.ndarray]:
    """Map Gauss-point fields (..., n_el, n_qp, c) of ``old`` to the Gauss points of ``new`` (same quadrature)
    by interpolation in the reference configuration: each new Gauss point is located in the old mesh (the
    element of the nearest old Gauss point first, then those of the next nearest Gauss points and element
    centres), and the old element's field is evaluated there from its tensor-product quadratic through the
    element's 3 x 3 Gauss values (exact for fields quadratic in the element's reference coordinates; slightly
    extrapolated for a point just outside the old discretised boundary)."""
    bo, bn = old.basis, new.basis
    xq = new.quadrature_points  # (2, n_el, n_qp)
    ne, nq = xq.shape[1:]
    pts = xq.reshape(2, -1)
    ref = np.asarray(bo.elem.doflocs, float).T  # (2, 9): the Q2 nodes in [0, 1]^2 (isoparametric geometry)
    xe = bo.doflocs[:, bo.element_dofs]  # (2, 9, n_el)
    G_ref = np.tile(np.asarray(bn.X, float), (1, ne))  # the reference coordinates of every Gauss point (2, n)
    excess_of = lambda lc: np.max(np.maximum(np.maximum(-lc, lc - 1.0), 0.0), axis=0)
    points, centres = _search_trees(old)
    # first the element of the nearest old Gauss point, from that point's reference coordinates (10 Newton
    # steps: a point inside converges in ~5, in one where the meshes coincide; most points that move are found
    # there too, issue 14); the others are looked for below
    _, near = points.query(pts.T)
    elem = near // nq
    loc = _local_coordinates(xe[:, :, elem], ref, pts, iters=10, start=G_ref[:, near])
    excess = excess_of(loc)
    out = np.flatnonzero(excess > 1e-10)
    if out.size:
        # the rest (near strongly graded elements, or just outside the old discretised boundary): the elements of
        # the 16 nearest old Gauss points (from their reference coordinates) and of the 8 nearest element centres
        # (from the centre), in one pass, taken in that order: the first that contains the point wins, else the
        # least excess (a point-by-point search's choice)
        _, near = points.query(pts[:, out].T, k=min(16, ne * nq))
        _, cen = centres.query(pts[:, out].T, k=min(8, ne))
        cand = np.concatenate([near // nq, cen.reshape(out.size, -1)], axis=1)
        start = np.concatenate([G_ref[:, near], np.full((2, out.size, cand.shape[1] - near.shape[1]), 0.5)], axis=2)
        nc = cand.shape[1]
        lc = _local_coordinates(
            xe[:, :, cand.ravel()], ref, np.repeat(pts[:, out], nc, axis=1), iters=10, start=start.reshape(2, -1)
        ).reshape(2, out.size, nc)
        ex = excess_of(lc.reshape(2, -1)).reshape(out.size, nc)
        best = excess[out]
        for j in range(nc):
            better = (best > 1e-10) & (ex[:, j] < best - 1e-14)
            k = out[better]
            best[better], elem[k], loc[:, k] = ex[better, j], cand[better, j], lc[:, better, j]
    G = np.asarray(bo.X)  # (2, n_qp) in [0, 1]^2
    powers = [(i, j) for i in range(3) for j in range(3)]
    V = np.stack([G[0] ** i * G[1] ** j for i, j in powers], axis=1)  # (n_qp, 9)
    P = np.stack([loc[0] ** i * loc[1] ** j for i, j in powers], axis=1)  # (n, 9)
    L = P @ np.linalg.inv(V)  # (n, n_qp): weights of the old element's Gauss values
    assert L.shape == (pts.shape[1], nq)

    def transfer(f: np.ndarray) -> np.ndarray:
        g = f[..., elem, :, :]  # (..., n, n_qp, c)
        return np.einsum("np,...npc->...nc", L, g).reshape(f.shape[:-3] + (ne, nq, f.shape[-1]))

    return transfer


class _Fitted(NamedTuple):
    """A converged time step on its own fitted mesh."""

    state: _State
    problem: _Problem
    edge: float


def _timed_fitted(fit: _EdgeFit, beta, tau, d_of_t, times, load_of_t, too_large=None):
    """Time steps on fitted meshes (one per step): [(t, problem, state, its, passes, wall)].

    Every step is an equilibrium state whose contact edge is a node of its own fitted mesh (``_EdgeFit``,
    with the step's algorithmic viscoelastic stress). The meshes of one level share topology and numbering,
    so the displacement guess is carried from step to step by index; the Maxwell variables (Q_m, S_iso^n per
    element and Gauss point) are interpolated to the new mesh's Gauss points in the reference configuration
    (:func:`_gauss_transfer`, exact for fields quadratic in an element) whenever the step's mesh is another
    than the last one's: in ramp steps, and for every trial mesh of the edge search. While the plate is held the
    edge stays where it is, the mesh with it, and the history is taken as it is.
    """
    p0 = fit.problem(0.5)
    n0 = p0.asm.ndof
    visco0 = ve.initial_state(beta.size, p0.asm.w.shape + (5,))
    s0 = _Fitted(
        _State(np.zeros(n0), np.zeros(p0.plane.nodes.size, bool), visco0, 0.0, np.zeros(n0), 1.0, None, 0), p0, 0.0
    )

    def step(t0, old: _Fitted, t1, prev):
        d1, dt = d_of_t(t1), t1 - t0
        s_old = old.state
        guess = s_old.x
        p_old = prev[1].state if prev is not None else None
        if p_old is not None and abs(s_old.delta - p_old.delta) > 1e-14:
            guess = s_old.x + (s_old.x - p_old.x) * (d1 - s_old.delta) / (s_old.delta - p_old.delta)
        if np.isnan(old.edge):  # node-by-node contact (beyond the fitted range)
            e0 = float("nan")
        elif old.edge <= 0.0:  # the first contact
            e0 = _edge_guess([], [], d1)
        elif p_old is not None and prev[1].edge > 0.0 and abs(s_old.delta - p_old.delta) > 1e-14:  # nan: False
            e0 = _edge_guess([p_old.delta, s_old.delta], [prev[1].edge, old.edge], d1)
        else:
            e0 = old.edge * np.sqrt(d1 / s_old.delta) if s_old.delta > 0 else old.edge
        history: dict = {}

        def on(prob: _Problem) -> ve.MaxwellState:
            """The Maxwell history of the old step at the Gauss points of prob's mesh."""
            key = id(prob)
            if key not in history:
                if prob is old.problem or beta.size == 0 or not np.any(s_old.visco.S_iso):
                    history[key] = s_old.visco
                else:
                    tr = _gauss_transfer(old.problem.m, prob.m)
                    history[key] = ve.MaxwellState(tr(s_old.visco.Q), tr(s_old.visco.S_iso))
            return history[key]

        def nodal() -> tuple[_Fitted, int]:
            """Node-by-node contact on the previous step's mesh (beyond the fitted range)."""
            prob = old.problem
            if not np.isnan(old.edge):
                _warn_nodal(load_of_t(t1))
            iso_scale, extra = ve.algorithmic(s_old.visco, beta, tau, dt)
            sol = prob.solve(s_old, d1, iso_scale, extra, guess, load_of_t(t1))
            visco = ve.update(s_old.visco, beta, tau, dt, prob.asm.iso_S(sol.x, fit.mat))
            st = _State(sol.x, sol.active, visco, d1, sol.residual, iso_scale, extra, sol.sets)
            return _Fitted(st, prob, float("nan")), sol.iterations

        if np.isnan(old.edge) or (old.edge > 0.0 and e0 > EDGE_MAX):
            return nodal()
        visc = lambda prob: ve.algorithmic(on(prob), beta, tau, dt)
        try:
            prob, st, e, its, n = fit.solve(d1, e0, guess, load_of_t(t1), visc=visc)
        except NewtonError as err:
            if old.edge > 0.0 and _beyond_fit([old.edge], e0, err):
                return nodal()
            raise
        S_new = prob.asm.iso_S(st.x, fit.mat)
        visco = ve.update(on(prob), beta, tau, dt, S_new)
        return _Fitted(st._replace(visco=visco, passes=n), prob, e), its

    return [
        (st.t, st.state.problem, st.state.state, st.iterations, st.state.state.passes, st.wall_s, st.state.edge)
        for st in march(step, s0, times, too_large=too_large)
    ]


def compress(
    *,
    radius: float,
    C: float,
    alpha: float,
    branches: Sequence = (),
    displacement: float | Callable[[float], float],
    ramp_time: float,
    end_time: float,
    kappa: float = 2.2e9,
    mesh: str | int | AxiMesh = "default",
    static: bool = False,
    field_times: Sequence[float] | str = (),
    n_ramp: int | None = None,
    n_hold: int | None = None,
    n_static: int | None = None,
    rtol: float = 1e-10,
) -> SpheroidResult:
    """Compress the Fung ball between rigid frictionless plates, hold, and let it relax.

    Every converged step is an equilibrium with exact contact (Signorini: gap >= 0, contact force >= 0,
    their product 0) and the Maxwell branch stresses of its time step.

    Args:
        radius: the ball's radius a0 (m).
        C: Fung stiffness of the relaxed (long-time) material (Pa).
        alpha: Fung exponent (dimensionless).
        kappa: bulk modulus (Pa).
        branches: [(beta_m, tau_m), ...]: energy factors beta_m >= 0 (dimensionless) and relaxation
            times tau_m > 0 (s); empty for elastic.
        displacement: the total approach delta (m, 2e-6 a0 <= delta < 1.6 a0: below ``X_MIN`` = 1e-6 of the
            diameter the contact force nears round-off) of the two plates, reached at ``ramp_time`` by a linear
            ramp and then held to ``end_time``; or a callable delta(t) (m, t in s, delta(0) = 0): ``ramp_time`` is
            then the time scale of the fine initial steps and each step moves the plate by at most the ramp's step
            (steps are halved until it does).
        ramp_time: end of the ramp (s, 0 < ramp_time <= end_time; ignored when ``static``).
        end_time: end of the hold (s; ignored when ``static``).
        mesh: "coarse", "default", "fine" or a level 0..4 (0 = coarse, 1 = default, 2 = fine; ``LEVELS``
            gives (n_core, n_radial, surface grading, n_contact, n_equator) of :func:`fitted_mesh`):
            CONTACT-EDGE-FITTED meshes. Static runs solve every state on its own mesh whose surface node
            ``n_contact`` sits on the contact edge, found by a secant iteration on the Signorini
            condition there (its nodal multiplier N_edge = 0 to ``EDGE_TOL`` of the force; the force is
            stationary in the edge position): the plate force is a smooth function of delta and converges
            smoothly under refinement (levels 1..4 are self-similar, h ~ 1/n_core). Time runs do the same
            at every step (the step's algorithmic viscoelastic stress in the edge condition); the Maxwell
            history (Q_m, S_iso per Gauss point) is interpolated onto each new mesh's Gauss points in the
            reference configuration, so it stays tied to material points; while the plate is held the
            edge and the mesh stay put. Beyond the fitted range (edge past 50.6 deg from the pole, about
            delta/(2 a0) = 0.49) the remaining states / steps use node-by-node contact on the last fitted
            mesh (a logged warning; ``parameters["contact"]`` says "fitted" or "nodal" per step).
            Or an ``AxiMesh`` from ``fem.mesh.ball_section`` built with length_scale = radius: a fixed
            mesh with node-by-node contact (its force carries the edge quantisation, ~0.2 %).
        static: equilibrium states from delta = 0 to ``displacement`` (the F_eq(delta) curve; branches and
            times are ignored); ``time`` then holds the load fraction delta / displacement. On a level every
            state has its own mesh (same topology and numbering); the result's ``mesh`` is the last state's.
        field_times: times (s; static runs: load fractions in (0, 1]) at which the fields are stored (they
            become step times; static runs store the closest step); the last step is always stored.
            ``"all"``: every converged step (for ``SpheroidResult.to_pvd``). A stored field is given on the
            result's ``mesh`` (the last state's): ``deformed_nodes`` are the state's deformed positions (m),
            ``displacement`` = deformed_nodes - the result mesh's reference positions.
        n_ramp: ramp steps (default 6).
        n_hold: geometrically growing hold steps (default 20).
        n_static: static steps (default: 0.04 in delta / a0 on a level, 0.02 on a mesh object, at least 8;
            failed steps are cut back).
        rtol: Newton's relative residual tolerance.

    Returns:
        ``SpheroidResult`` with one entry per converged step: ``time`` (s), ``approach`` (m), plate
        ``force`` (N: the sum of the active nodes' contact multipliers, which include the 2 pi R of the
        axisymmetric volume element, so it is the force on the whole plate), ``reaction_force`` of the
        midplane (N), ``midplane_radius`` (m), ``midplane_area`` (m^2), ``nominal_stress`` F / (pi
        r_mid^2) (Pa), ``mean_von_mises`` over the deformed volume (Pa), ``contact_radius`` (m: static
        runs on a level the edge node; else an edge estimate between the outermost active node and the
        next from the gaps of the first free nodes), ``contact_radius_node`` (the outermost active node,
        m), ``min_gap`` (m), ``min_contact_force`` (N), ``newton_iterations``, ``contact_passes``,
        ``wall_time`` (s); ``fields`` (``SpheroidField``), ``mesh``, ``static``, ``parameters``.

    Raises:
        ValueError: an input out of range (the message names the quantity and its unit).
        NewtonError: a step did not converge after its cut-backs (``ContactError``: the active set or the
            fitted contact edge did not settle); the message names the step's time or approach.
        RuntimeError: the plate force and the midplane reaction differ by more than 1e-6 (relative): the
            equilibrium was not reached (tighten rtol).
    """
    validate_positive("radius (the spheroid radius a0)", radius, "m")
    validate_material(C, alpha, kappa)
    br = validate_branches(branches)
    if static:
        br = ()
    beta = np.array([float(b) for b, _ in br])
    tau = np.array([float(t) for _, t in br])
    a0, C = float(radius), float(C)
    if callable(displacement):
        if static:
            raise ValueError("static=True needs the final approach as a number (m), not a function of time")
        delta_fn = displacement
        d_max = None
    else:
        validate_positive("displacement (the total approach of the plates)", displacement, "m")
        d_max = float(displacement)
        if d_max < X_MIN * 2 * a0:
            raise ValueError(
                f"displacement {d_max:g} m is delta/(2 a0) = {d_max / (2 * a0):.2g} of the diameter, below the "
                f"smallest approach the FE resolves ({X_MIN:g} of it, {X_MIN * 2 * a0:g} m here): the contact force, "
                "~ C a0^2 (delta/a0)^1.5, nears the round-off of the nearly incompressible residual there; use "
                "tissuemech.reduced.spheroid (its calibrated table tends to Hertz as delta -> 0)"
            )
        if d_max >= 1.6 * a0:
            raise ValueError(
                f"displacement {d_max:g} m would squeeze the ball (diameter {2 * a0:g} m) to less "
                "than 20 % of its height; the model is not meant for that"
            )
    if not static:
        validate_positive("ramp_time", ramp_time, "s")
        validate_positive("end_time", end_time, "s")
        if end_time < ramp_time:
            raise ValueError(f"end_time ({end_time} s) must be >= ramp_time ({ramp_time} s)")
        if d_max is not None:
            tr = float(ramp_time)
            delta_fn = lambda t: d_max * min(float(t) / tr, 1.0)
    store_all = isinstance(field_times, str) and field_times == "all"
    if isinstance(field_times, str) and not store_all:
        raise ValueError(f"field_times must be times in s or 'all', got {field_times!r}")
    ft = (
        np.array([])
        if store_all or not len(np.atleast_1d(field_times))
        else np.atleast_1d(np.asarray(field_times, float))
    )
    t_max = 1.0 if static else float(end_time)
    if ft.size and (not np.all(np.isfinite(ft)) or np.any(ft <= 0) or np.any(ft > t_max * (1 + 1e-12))):
        raise ValueError(
            "field_times must be finite times in (0, end_time] (s); for static=True load fractions in (0, 1]"
        )

    level = _level(mesh)
    mat = Material(1.0, float(alpha), float(kappa) / C)
    fit = _EdgeFit(a0, level, mat, rtol) if level is not None else None
    if static:
        assert d_max is not None  # static=True rejects a callable displacement above
        # fitted levels: every state is solved on its own mesh, states 0.02 apart in x suffice
        n = n_static or max(8, int(np.ceil(d_max / a0 / (0.04 if fit is not None else 0.02) - 1e-9)))
        times = np.linspace(0.0, 1.0, n + 1)[1:]
        dfun = lambda t: d_max * t
        too_large = None
    else:
        breaks = list(ft)
        times = ramp_hold_schedule(
            float(ramp_time), float(end_time), n_ramp=n_ramp or 6, n_hold=n_hold or 20, breakpoints=breaks
        )
        dfun = delta_fn
        too_large = None
        if d_max is None:
            d0 = float(delta_fn(0.0))
            if abs(d0) > 1e-9 * a0:
                raise ValueError(f"the displacement history must start at 0 (delta(0) = {d0:g} m)")
            dd = max(abs(float(delta_fn(t))) for t in np.linspace(0, ramp_time, 7)) / (n_ramp or 6)
            dd = max(dd, 1e-3 * a0)
            too_large = lambda t0, t1: abs(float(delta_fn(t1)) - float(delta_fn(t0))) > dd

    def dscaled(t):
        d = float(dfun(t))
        if not np.isfinite(d) or d < 0 or d >= 1.6 * a0:
            raise ValueError(f"the approach delta(t = {t:g} s) = {d!r} m must be finite, >= 0 and < 1.6 radius")
        return d / (2 * a0)

    def load_of(t1):
        return f"delta = {dfun(t1) * 1e6:.4g} um" if static else f"t = {t1:.6g} s, delta = {dfun(t1) * 1e6:.4g} um"

    if fit is not None:  # every state / step on its own fitted mesh
        if static:
            done = _static_fitted(fit, dscaled, times, load_of)
        else:  # the Maxwell history interpolated onto each step's mesh
            done = _timed_fitted(fit, beta, tau, dscaled, times, load_of, too_large)
        steps = [_Solved(t, pr, st, its, n_s, w) for t, pr, st, its, n_s, w, _ in done]
        modes = tuple("fitted" if np.isfinite(e) else "nodal" for *_, e in done)
        m = steps[-1].problem.m
    else:
        m = make_mesh(mesh, a0)
        prob = _Problem(m, mat, beta, tau, rtol)
        n0 = prob.asm.ndof
        pole = np.argmin(np.hypot(prob.plane.R, prob.plane.Z - 1.0))
        active0 = np.zeros(prob.plane.nodes.size, bool)
        active0[pole] = True
        s0 = _State(np.zeros(n0), active0, prob.maxwell_initial(), 0.0, np.zeros(n0), 1.0, None, 0)

        def step(t0, s_old, t1, prev):
            return prob.step(
                s_old, dscaled(t1), None if static else t1 - t0, prev.state if prev is not None else None, load_of(t1)
            )

        steps = [
            _Solved(st.time, prob, st.state, st.newton_iterations, st.state.passes, st.wall_time)
            for st in march(step, s0, times, too_large=too_large)
        ]
        modes = ("nodal",) * len(steps)

    L2 = C * a0**2
    rows: list[_Row] = []
    fields = []
    want = set()
    for tf in ft:
        want.add(int(np.argmin([abs(st.time - tf) for st in steps])))
    want.add(len(steps) - 1)
    if store_all:
        want = set(range(len(steps)))
    for k, st in enumerate(steps):
        prob, s = st.problem, st.state
        ob = prob.observe(s)
        F, Fr = ob.plate_force, ob.reaction_force
        # fitted states: the edge node is the contact edge
        rc = ob.contact_radius_node if modes[k] == "fitted" else ob.contact_radius
        if F > 0 and abs(F - Fr) > FORCE_CHECK * abs(F) + 1e3 * prob.floor:
            raise RuntimeError(
                f"contact force {F * L2:.6g} N and midplane reaction {Fr * L2:.6g} N differ by "
                f"{abs(F - Fr) / F:.2e} (relative) at t = {st.time:.6g} s: equilibrium not reached. "
                "Hint: tighten rtol"
            )
        rows.append(
            _Row(
                time=st.time,
                approach=2 * a0 * s.delta,
                force=F * L2,
                reaction_force=Fr * L2,
                midplane_radius=ob.midplane_radius * a0,
                contact_radius=rc * a0,
                mean_von_mises=ob.mean_von_mises * C,
                newton_iterations=st.newton_iterations,
                contact_passes=st.contact_passes,
                wall_time=st.wall_time,
                contact_radius_node=ob.contact_radius_node * a0,
                min_gap=ob.min_gap * a0,
                min_contact_force=ob.min_normal_force * L2,
            )
        )
        if k in want:
            u = prob.displacement(s.x)
            xd = prob.deformed_nodes(u)
            if prob.m is not m:  # an earlier state's own fitted mesh: same topology, given on the result's mesh
                u = xd - m.X.T * a0
            vm_el, ph_el = prob.element_fields(ob.von_mises, ob.pressure, C)
            fields.append(
                SpheroidField(
                    time=st.time,
                    displacement=u,
                    deformed_nodes=xd,
                    von_mises=vm_el,
                    hydrostatic_pressure=ph_el,
                    contact_nodal_force=ob.normal_force * L2,
                    contact_nodes=prob.plane.nodes,
                )
            )
    col = {name: np.array(values) for name, values in zip(_Row._fields, zip(*rows))}
    area = np.pi * col["midplane_radius"] ** 2
    return SpheroidResult(
        **col,
        midplane_area=area,
        nominal_stress=col["force"] / area,
        mesh=m,
        fields=fields,
        static=bool(static),
        parameters=dict(
            radius=a0,
            C=C,
            alpha=float(alpha),
            kappa=float(kappa),
            branches=tuple((float(b), float(t)) for b, t in br),
            ramp_time=None if static else float(ramp_time),
            end_time=None if static else float(end_time),
            contact=modes,
        ),
    )
