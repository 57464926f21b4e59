r"""FE indentation: a rigid frictionless sphere pressed on the top of a Fung ball that rests on a rigid plate.

:func:`indent` (``IndentationResult``). The ball of radius a0 sits on a rigid frictionless plate z = -a0; a
rigid frictionless sphere of radius R_p (the AFM colloidal probe), centred on the axis at z = a0 + R_p -
delta(t), moves down by the approach delta (the probe travel since first contact; the plate stays put). The
scene is NOT symmetric about the midplane, so the whole meridian section R >= 0, -a0 <= Z <= a0 is meshed
(``fem.mesh.full_ball_section``: an O-grid whose two pole blocks are refined independently, each with
equal elements over its own contact zone and geometric growth beyond), u_r = 0 on the axis, nothing else
fixed: the ball is held by its two contacts alone. Mixed Q2/P1-discontinuous elements, generalized Maxwell
branches on S_iso (``fem.viscoelastic``), quasi-static time stepping (``fem.timestepping.march``).

Contact is exact on both obstacles (no penalty): ``fem.contact.RigidSphere`` for the probe (its lower cap)
and for the plate (a sphere of infinite radius below the body), solved together by
``fem.contact.solve_obstacles`` (an active node lies on its obstacle, u_z following u_r along the surface;
Signorini: gap >= 0, contact force >= 0, their product 0). ``contact="nodal"`` (default; time runs): node by
node on one fixed mesh per run, sized from the largest approach of the run (its two Hertz contact radii) so that
every level puts the same number of elements across each contact; the force carries the edge quantisation (a
sawtooth in the approach: 3.3e-3 of F on level 1, 1.0e-3 on level 2). ``contact="fitted"`` (static states):
every state on its own mesh whose two contact edges sit on nodes (:class:`FittedEdges`): smooth to 1e-6, observed
order 3.5 under refinement (F at approach / (2 a0) = 0.005, R_p = a0: level 2 within 7e-5 of the Richardson
limit, level 4 within 7e-6). Measured by ``python -m tissuemech.compare.bench.fem_indentation`` (``docs/afm.md``,
"FE indentation").

Loading (time runs, node-by-node contact): the approach as a ramp and hold, a callable or a measured history
``(times, approaches)``, or the probe force (``force=``: a number, a callable or ``(times, forces)``, > 0 N) by the
outer iteration of ``fem.protocols.force_controlled`` around the displacement-controlled step (records and their
step times: ``fem.protocols.Record`` / ``record_schedule``). :func:`fitted_states` gives static fitted-edge states
over a grid of approaches and alphas, continued in both (the indentation table's generator,
``compare.calibrate_indentation``).

``kinematics="small"`` (static, elastic; ``SmallStrainAssembler``, ``ReferenceSphere``): the geometrically linear
counterpart, linear strain, Hooke's law with the Fung law's small-strain shear modulus 2 C, tr(eps) for J - 1, the
Hertz contact gap (vertical, at the reference radius): what the two-contact Hertz law approximates but for the
half-spaces. At x = approach / (2 a0) = 0.005, R_p = a0 it is 2.20 % above Hertz (the ball's finite size, 1 + 0.311
sqrt(x)), the finite-strain FE 0.54 % below it (``python -m tissuemech.compare.bench.fem_indentation --hertz``).

Inside, lengths are scaled by a0, stresses by C, forces by C a0^2 (``fem.problem.SceneProblem``).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
import scipy.sparse as sp

from tissuemech.fem import sensitivity as sens
from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.constitutive import TRACE5, small_strain_stress
from tissuemech.fem.contact import ContactError, ObstacleSolution, RigidSphere, congruence, solve_obstacles
from tissuemech.fem.forms import Assembler, Material
from tissuemech.fem.linalg import Symmetric
from tissuemech.fem.mesh import AxiMesh, full_ball_section, surface_layers, zone_points
from tissuemech.fem.newton import NewtonError
from tissuemech.fem.problem import SPHEROID_MARGIN, SceneProblem, mesh_spec, roundoff_floor, secant
from tissuemech.fem.protocols import FORCE_TOL, Record, force_controlled, record_schedule
from tissuemech.fem.stepping import TimedState
from tissuemech.fem.timestepping import march, ramp_hold_schedule
from tissuemech.reduced.material import probe_share, validate_branches, validate_material, validate_positive

log = logging.getLogger(__name__)

__all__ = [
    "indent",
    "IndentationResult",
    "IndentProblem",
    "FittedEdges",
    "fitted_states",
    "make_mesh",
    "zone_mesh",
    "hertz_split",
    "LEVELS",
    "MESHES",
    "X_MIN",
    "X_MAX",
    "EDGE_TOL",
    "KINEMATICS",
    "SmallStrainAssembler",
    "ReferenceSphere",
]

KINEMATICS = ("finite", "small")

# level -> (n_zone, n_out, n_radial, n_equator): n_zone equal elements over each pole's contact zone (ZONE times
# its Hertz contact radius at the largest approach), n_out growing ones to the end of the pole block (SPLIT),
# n_radial layers in the curved blocks (the outermost DEPTH zone elements thick), 2 n_equator divisions of the
# equator block. Levels 1..4 refine every count by about the same factor.
LEVELS = {
    0: (6, 5, 5, 4),
    1: (10, 7, 7, 6),
    2: (16, 10, 10, 8),
    3: (24, 14, 14, 11),
    4: (32, 18, 18, 14),
}
MESHES = {"coarse": 0, "default": 1, "fine": 2}
SPLIT = np.radians(55.0)  # each pole block's arc, from its pole
ZONE = 1.5  # the refined zone, in Hertz contact radii (the finite-strain contact is a few % larger)
DEPTH = 2.0  # outermost radial layer, in zone elements
FORCE_CHECK = 1e-6  # |F_probe - F_plate| / F
X_MIN = 1e-5  # smallest final approach / (2 a0)
X_MAX = 0.25  # largest approach / (2 a0)


def hertz_split(delta: float, probe_radius: float) -> tuple[float, float, float, float]:
    """(d_1, d_2, a_1, a_2): the small-strain two-Hertz-contacts split of the scaled approach ``delta`` (lengths /
    a0) of a probe of scaled radius ``probe_radius`` on the unit ball resting on a plate: the probe-ball depth d_1
    (effective radius R_1 = R_p / (1 + R_p)) and the ball-plate depth d_2 (radius 1) in proportion R_i^(-1/3)
    (``reduced.material.probe_share``), and the contact radii a_i = sqrt(R_i d_i)."""
    r1 = probe_radius / (1.0 + probe_radius)
    d1 = delta * float(probe_share(1.0, probe_radius))
    d2 = delta - d1
    return d1, d2, float(np.sqrt(r1 * d1)), float(np.sqrt(d2))


def make_mesh(mesh, radius: float, probe_radius: float, approach: float) -> AxiMesh:
    """The full-section mesh of a level (``LEVELS``, or "coarse", "default", "fine") for the largest ``approach``
    (m) of a probe of ``probe_radius`` (m) on a ball of ``radius`` (m): each pole block with ``n_zone`` equal
    elements over ZONE times its Hertz contact radius (``hertz_split``)."""
    level = mesh_spec(mesh, MESHES, "or a level 0..4")
    if isinstance(level, (bool, np.bool_)) or not isinstance(level, (int, np.integer)) or int(level) not in LEVELS:
        raise ValueError(f"mesh level must be an integer 0..4 (0 coarse, 1 default, 2 fine), got {mesh!r}")
    _, _, a1, a2 = hertz_split(approach / radius, probe_radius / radius)
    return zone_mesh(radius, int(level), min(ZONE * a1 / SPLIT, 0.8), min(ZONE * a2 / SPLIT, 0.8))


def zone_mesh(radius: float, level: int, z_top: float, z_bot: float) -> AxiMesh:
    """The level's full-section mesh (``LEVELS``) with its top / bottom pole block refined uniformly over the
    fractions ``z_top`` / ``z_bot`` of its arc (``fem.mesh.zone_points``); every zone gives the same topology
    and numbering."""
    nz, no, nr, neq = LEVELS[level]
    thick = 1.0 - 0.55 * np.sqrt(2) * np.cos(SPLIT)  # the pole blocks' thickness at the axis
    depth = DEPTH * SPLIT * min(z_top, z_bot) / nz
    return full_ball_section(
        radius,
        zone_points(nz, no, z_top),
        zone_points(nz, no, z_bot),
        surface_layers(nr, depth, thick),
        n_equator=neq,
        split_angle=SPLIT,
        intorder=4,
    )


class SmallStrainAssembler(Assembler):
    """The mixed Q2/P1 assembly of the geometrically linear Fung law (``kinematics="small"``; static, elastic).

    ``constitutive.small_strain_stress``: eps = sym(grad u) incl. the hoop term u_r/R, Hooke's deviatoric law with
    the small-strain shear modulus 2 C, the constraint tr(eps) - q / kappa = 0 in place of J - 1 - q / kappa. The
    tangent is constant; only the contact makes the problem nonlinear. Branch stresses are not supported; ``stress``
    and ``iso_S`` stay the finite-strain ones (a static indentation reads forces from ``internal`` only)."""

    def __init__(self, mesh: AxiMesh):
        super().__init__(mesh, "mixed")

    def internal(self, u: np.ndarray, mat: Material, extra_S=None, iso_scale: float = 1.0, tangent: bool | str = True):
        """(r, K) of the linear law at x = (u, q) (as ``Assembler.internal``; ``extra_S`` must be None)."""
        if extra_S is not None or iso_scale != 1.0:
            raise ValueError("kinematics='small' is elastic: no Maxwell branch stresses (static=True)")
        ne, nq = self.w.shape
        f = self.f_at(u)
        q = np.einsum("eqa,ea->eq", self.psi, u[self.qdofs])
        P, A, tr = small_strain_stress(f, mat.C, q=q, weight=self.w)
        B2 = self.B.reshape(ne, nq * 5, -1)
        re = np.matmul(P.reshape(ne, 1, nq * 5), B2)[:, 0]
        r = np.bincount(self.edofs.ravel(), weights=re.ravel(), minlength=self.ndof)
        rq = np.einsum("eqa,eq->ea", self.psi, tr * self.w) - np.einsum("eab,eb->ea", self.M, u[self.qdofs]) / mat.kappa
        r[self.n_u :] = rq.ravel()

        def assemble():
            nd = self.B.shape[-1]
            Ke = np.empty((ne, nd + 3, nd + 3))
            AB = np.matmul(A, self.B).reshape(ne, nq * 5, nd)
            Ke[:, :nd, :nd] = np.matmul(B2.transpose(0, 2, 1), AB)
            tB = np.einsum("i,eqin->eqn", TRACE5, self.B) * self.w[..., None]
            G = np.einsum("eqa,eqn->ean", self.psi, tB)
            Ke[:, nd:, :nd] = G
            Ke[:, :nd, nd:] = G.transpose(0, 2, 1)
            Ke[:, nd:, nd:] = -self.M / mat.kappa
            return self.pattern.matrix(Ke)

        if tangent == "lazy":
            return r, assemble
        return r, (assemble() if tangent else None)


class ReferenceSphere(RigidSphere):
    """``fem.contact.RigidSphere`` with the linearised (Hertz) contact of ``kinematics="small"``: the gap is
    vertical and evaluated at the reference radius, g = z_s(R) - (Z + u_z) above the body (Z + u_z - z_s(R) below),
    the contact traction vertical; an active node's u_z = z_s(R) - Z does not depend on its u_r (slope and
    curvature 0 for ``fem.contact.solve_obstacles``), its u_r stays free (frictionless)."""

    def positions(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(reference r, deformed z) of the candidates."""
        return self.R.copy(), self.Z + x[self.dofs]

    def surface(self, r: np.ndarray, height: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        z = super().surface(r, height)[0]
        return z, np.zeros_like(r), np.zeros_like(r)

    def gap(self, x: np.ndarray, height: float) -> np.ndarray:
        r, z = self.positions(x)
        zs = self.surface(r, height)[0]
        return zs - z if self.above else z - zs

    def normals(self, x: np.ndarray, height: float) -> np.ndarray:
        n = self.R.size
        return np.stack([np.zeros(n), np.full(n, -1.0 if self.above else 1.0)])


class IndentState(NamedTuple):
    """A converged state (scaled: lengths / a0, stresses / C, forces / (C a0^2))."""

    x: np.ndarray  # full unknown vector (u, q)
    active: tuple[np.ndarray, ...]  # bool per candidate of (probe, plate)
    visco: ve.MaxwellState  # branch stresses and S_iso after the step
    delta: float  # scaled approach (probe travel / a0)
    residual: np.ndarray  # full internal residual at x (the contact reactions)
    passes: int  # active-set passes of the step


class IndentProblem(SceneProblem):
    """The scaled ball between the probe (above) and the plate (below) on one mesh.

    ``IndentProblem(m, mat, probe_radius, beta, tau, rtol)``: the full-section mesh (scaled by a0), the scaled
    material, the probe radius / a0, the Maxwell branches (beta_m, tau_m [s]) and Newton's relative tolerance.
    ``probe`` and ``plate`` are ``fem.contact.RigidSphere`` obstacles on the surface nodes of the upper and the
    lower half; ``centre`` the node at the ball's centre. ``kinematics="small"``: the geometrically linear law
    (``SmallStrainAssembler``) and the linearised contact (``ReferenceSphere``)."""

    def __init__(self, m: AxiMesh, mat: Material, probe_radius: float, beta, tau, rtol: float,
                 kinematics: str = "finite"):  # fmt: skip
        super().__init__(m, mat, "mixed", beta, tau)
        if kinematics not in KINEMATICS:
            raise ValueError(f"kinematics must be 'finite' or 'small', got {kinematics!r}")
        sphere = RigidSphere
        if kinematics == "small":
            self.asm = SmallStrainAssembler(m)
            sphere = ReferenceSphere
        X = m.X
        outer = m.nodes["outer"]
        self.rp = float(probe_radius)
        self.probe = sphere(X, outer[X[1, outer] > 1e-12], self.rp, above=True)
        self.plate = sphere(X, outer[X[1, outer] < -1e-12], np.inf, above=False)
        self.centre = int(np.argmin(np.hypot(X[0], X[1])))
        self.rtol = rtol
        self.floor = roundoff_floor(mat.kappa, 1.0, SPHEROID_MARGIN)
        r1 = self.rp / (1.0 + self.rp)
        self.r_series = (r1 ** (-1.0 / 3.0) + 1.0) ** -3.0

    def heights(self, delta: float) -> tuple[float, float]:
        """(probe centre, plate) heights at the scaled approach delta."""
        return 1.0 + self.rp - delta, -1.0

    def initial(self) -> IndentState:
        """The reference state: x = 0, the two poles touching."""
        n = self.asm.ndof
        a_p = np.zeros(self.probe.nodes.size, bool)
        a_b = np.zeros(self.plate.nodes.size, bool)
        a_p[0] = a_b[0] = True  # candidates are ordered from their pole outward
        return IndentState(np.zeros(n), (a_p, a_b), self.maxwell_initial(), 0.0, np.zeros(n), 0)

    def solve(self, s0: IndentState, d1: float, iso_scale, extra, guess, load, fixed: bool = False) -> ObstacleSolution:
        """Equilibrium with exact contact at the scaled approach d1 from ``guess`` with the step's branch stresses."""
        hp, hb = self.heights(d1)
        fun = lambda x: self.asm.internal(x, self.mat, extra_S=extra, iso_scale=iso_scale, tangent="lazy")
        res = lambda x: self.asm.internal(x, self.mat, extra_S=extra, iso_scale=iso_scale, tangent=False)[0]
        ref = max(32.0 / 3.0 * np.sqrt(self.r_series) * max(d1, 1e-6) ** 1.5 * iso_scale, 1e-12)
        return solve_obstacles(
            fun,
            guess,
            [(self.probe, hp), (self.plate, hb)],
            s0.active,
            self.free,
            load=load,
            residual=res,
            admissible=self.admissible,
            ref_norm=ref,
            rtol=self.rtol,
            xtol=1e-9,
            atol=self.floor,
            max_iter=25,
            linear=Symmetric(),
            fixed=fixed,
        )

    def step(self, s0: IndentState, d1: float, dt: float | None, prev: IndentState | None, load: str):
        """(state, Newton iterations) at the scaled approach d1 after a time step dt [s] (None: static)."""
        iso_scale, extra = self.maxwell_factors(s0.visco, dt)
        guess = s0.x
        if prev is not None and abs(s0.delta - prev.delta) > 1e-14:
            guess = secant(s0.x, prev.x, d1 - s0.delta, s0.delta - prev.delta)
        sol = self.solve(s0, d1, iso_scale, extra, guess, load)
        visco = self.maxwell_update(s0.visco, dt, sol.x)
        return IndentState(sol.x, sol.active, visco, d1, sol.residual, sol.sets), sol.iterations

    def observe(self, s: IndentState) -> dict[str, float]:
        """Scaled observables of state s: probe and plate forces, contact radii (edge estimates and outermost
        active nodes), the downward displacement of the ball's centre, the smallest gaps."""
        hp, hb = self.heights(s.delta)
        r = s.residual
        rc_p, rn_p = self.probe.contact_radius(s.x, s.active[0], hp)
        rc_b, rn_b = self.plate.contact_radius(s.x, s.active[1], hb)
        return dict(
            force=self.probe.axial_force(r, s.active[0]),
            plate_force=self.plate.axial_force(r, s.active[1]),
            contact_radius_probe=rc_p,
            contact_radius_plate=rc_b,
            contact_radius_probe_node=rn_p,
            contact_radius_plate_node=rn_b,
            centre_drop=-float(s.x[2 * self.centre + 1]),
            min_gap=float(min(self.probe.gap(s.x, hp).min(), self.plate.gap(s.x, hb).min())),
        )


class _IndentSensing:
    """Forward sensitivities of a node-by-node indentation run (scaled: probe force, centre drop and, under force
    control, the approach) to ln C (at fixed SI kappa), alpha and each branch's beta_m and tau_m, taken as the march
    accepts each state, with the active sets held and the probe held (displacement control) or moved so that the
    probe force stays the prescribed one (force control: the probe's motion is one more column, its active nodes'
    u_z moving by -1 with the approach, and d delta = (d F_target - dF) / dF_delta).

    The active nodes lie on their obstacles, u_z = z_s(R + u_r) - Z (``fem.contact.solve_obstacles``): with x =
    Phi(y) and T = dPhi/dy the equations are T^T r(Phi(y); theta) = 0, so (T^T K T + D) dy = -T^T dr/dtheta, D =
    diag(r_z z_s'') on the active nodes' u_r (Newton's exact reduced tangent), and dx = T dy. The probe force is
    -sum of the active probe nodes' r_z: dF = -sum (K dx + dr/dtheta)_z there. The explicit dr/dtheta and the Maxwell
    history's sensitivity are those of the plates' node-by-node runs (``fem.sensitivity.explicit_residuals``,
    ``history_update_tangent``). ``out``: per accepted state {name: (dF, d centre_drop, d delta)} (scaled; d delta
    = 0 under displacement control)."""

    def __init__(self, prob: IndentProblem, target: Callable[[float], float] | None = None) -> None:
        self.prob = prob
        self.target = target  # force control: the scaled probe force prescribed at t (s); None: the approach
        self.names, self.which = sens.sensing_names(prob.beta.size, False)
        P = len(self.names)
        visco0 = prob.maxwell_initial()
        self.dQ = np.zeros((P,) + visco0.Q.shape)
        self.dS = np.zeros((P,) + visco0.S_iso.shape)
        self.prev = visco0
        self.kept: tuple[bytes, Callable] | None = None  # (the unknowns, a solve with a recent factorisation)
        self.out: list[dict] = []

    def wrap(self, step: Callable, static: bool) -> Callable:
        def sensed(t0, old, t1, prev):
            new, its = step(t0, old, t1, prev)
            f1 = None if self.target is None else float(self.target(float(t1)))
            self.add(new, None if static else float(t1) - float(t0), f"t = {float(t1):.6g} s", f1)
            return new, its

        return sensed

    def add(self, s: IndentState, dt: float | None, what: str, target: float | None = None) -> None:
        """The sensitivities of the accepted state s (a step of dt seconds; None: static). ``target``: the scaled
        probe force prescribed there (force control: the probe's approach is then solved for, one more column: the
        active probe nodes moved with the probe)."""
        prob, names, which = self.prob, self.names, self.which
        asm, mat, x, prev = prob.asm, prob.mat, s.x, self.prev
        n, P = asm.ndof, len(names)
        iso, extra = prob.maxwell_factors(prev, dt)
        hp, hb = prob.heights(s.delta)
        rows, cols, vals, curv = [], [], [], []
        for ob, h, a in ((prob.probe, hp, s.active[0]), (prob.plate, hb, s.active[1])):
            r, _ = ob.positions(x)
            _, slope, c = ob.surface(r[a], h)
            rows.append(ob.dofs[a])
            cols.append(2 * ob.nodes[a])
            vals.append(slope)
            curv.append(c)
        rr, cc, vv, dc = (np.concatenate(v) for v in (rows, cols, vals, curv))
        f = asm.f_at(x)
        lin = sens.IsoLinearisation(f, mat.C, mat.alpha)
        coef = sens.maxwell_coefficients(prob.beta, prob.tau, dt) if (prob.beta.size and dt is not None) else None
        R = sens.explicit_residuals(prob, x, f, lin, float(iso), names, which, coef, self.dQ, self.dS, prev)
        _, K = asm.internal(x, mat, extra_S=extra, iso_scale=iso, tangent=True)
        K = sp.csr_matrix(K)
        M = congruence(K, rr, cc, vv)
        D = sp.csr_matrix((dc * s.residual[cc + 1], (cc, cc)), shape=(n, n))
        if M is None:
            T = sp.identity(n, format="csr") + sp.csr_matrix((vv, (rr, cc)), shape=(n, n))
            M = (T.T @ K @ T).tocsr()
        M = (M + D).tocsr()
        RT = R.copy()
        RT[cc] += vv[:, None] * R[rr]  # T^T dr/dtheta
        probe_dofs = prob.probe.dofs[s.active[0]]
        if target is not None:  # the probe moved (its centre at 1 + r_p - delta): its active nodes' u_z by -1
            if not s.active[0].any():
                raise ValueError(
                    f"gradient=True under force control: the probe does not touch the ball at {what} (a prescribed "
                    "force <= 0 N): no approach to solve for"
                )
            v = np.zeros(n)
            v[probe_dofs] = -1.0
            Kv = K @ v
            R = np.column_stack([R, np.zeros(n)])
            RT = np.column_stack([RT, Kv])
            RT[cc, -1] += vv * Kv[rr]  # T^T K v
        fr = np.setdiff1d(prob.free, rr)
        key = fr.tobytes()  # the last factorisation is kept for the same unknowns (active sets) only
        approx = self.kept[1] if self.kept is not None and self.kept[0] == key else None
        dY, solve, _ = sens.solve_block(M[fr][:, fr], approx, -RT[fr], what, tol=1e-10, max_iter=6)
        self.kept = (key, solve)
        dx = np.zeros((n, RT.shape[1]))
        dx[fr] = dY
        dx[rr] += vv[:, None] * dx[cc]  # T dy: the active u_z follow their u_r on the obstacle
        if target is not None:
            dx[:, -1] += v
        dr = K @ dx + R
        dF = -np.sum(dr[probe_dofs], axis=0)
        dd = np.zeros(P)
        if target is not None:  # F(theta, delta) = target(theta): d delta = (d target - dF) / dF_delta
            dtarget = np.zeros(P)
            dtarget[0] = -target  # the scaled target F / (C a0^2): d / d ln C = -itself
            dd = (dtarget - dF[:P]) / dF[P]
            dx = dx[:, :P] + dx[:, P:] * dd[None, :]
            dF = dtarget
        dc_drop = -dx[2 * prob.centre + 1]
        self.out.append({nm: (float(dF[j]), float(dc_drop[j]), float(dd[j])) for j, nm in enumerate(names)})
        dS_new = lin.dS(sens.point_increments(asm, dx))
        dS_new[1] += lin.d_alpha[..., None] * lin.S
        if coef is not None:
            self.dQ = sens.history_update_tangent(
                names, which, coef, prev.Q, prev.S_iso, s.visco.S_iso, self.dQ, self.dS, dS_new
            )
        self.dS, self.prev = dS_new, s.visco


def _indent_gradients(
    out: list[dict], F: np.ndarray, a0: float, C: float, names: list[str], force_control: bool = False
) -> dict:
    """SI gradients of the probe force (N per unit parameter), the centre drop and (``force_control``) the approach
    (m per unit parameter) from the scaled ones: F = C a0^2 F~ (dF/dC = F / C + a0^2 dF~/dln C), centre drop = a0 c~,
    approach = a0 delta~."""
    g = {}
    for nm in ["C"] + names[1:]:
        key = "lnC" if nm == "C" else nm
        dF = np.array([o[key][0] for o in out]) * C * a0**2
        dc = np.array([o[key][1] for o in out]) * a0
        dd = np.array([o[key][2] for o in out]) * a0
        if nm == "C":
            dF, dc, dd = dF / C + F / C, dc / C, dd / C
        if force_control:
            dF = np.zeros_like(F)  # the force is prescribed
        g[nm] = {"force": dF, "centre_drop": dc} | ({"approach": dd} if force_control else {})
    return g


EDGE_TOL = 1e-6  # |N_edge| / F at a fitted contact edge (as the plates, fem.contact.EDGE_TOL)


class FittedEdges:
    """Static states whose two contact edges sit on surface nodes (one mesh per state, ``zone_mesh``).

    On level L the edge node of each pole is the end of element k = round(n_zone / ZONE) of its zone; with the
    surface nodes up to it on their obstacle and the rest free (a fixed active set), the edge node's multiplier
    N_e falls through zero as the edge (its reference arc fraction e) moves out. A safeguarded secant per pole on
    phi(e) = N_e / F (the poles couple weakly; both are updated from each joint solve) finds the state where the
    Signorini conditions hold at both edges (N_e = 0 to ``tol``, the next gaps > 0): the force is then stationary
    in the edge positions, a smooth function of the approach and of the mesh (no node-to-node jitter), as the
    plates' ``fem.contact.EdgeSearch``."""

    def __init__(self, radius: float, probe_radius: float, level: int, make: Callable[[AxiMesh], IndentProblem],
                 tol: float = EDGE_TOL):  # fmt: skip
        self.a0, self.level, self.make, self.tol = radius, level, make, tol
        self.nz = LEVELS[level][0]
        self.k = max(1, int(round(self.nz / ZONE)))
        self.rp = probe_radius / radius
        self.cache: dict[tuple[float, float], IndentProblem] = {}

    def problem(self, e: tuple[float, float]) -> IndentProblem:
        if e not in self.cache:
            if len(self.cache) > 4:
                self.cache.pop(next(iter(self.cache)))
            zt, zb = (min(v * self.nz / self.k, 0.95) for v in e)
            self.cache[e] = self.make(zone_mesh(self.a0, self.level, zt, zb))
        return self.cache[e]

    def state(self, prob: IndentProblem, d: float, guess: np.ndarray | None, load: str):
        """(state, Newton iterations, (phi_top, phi_bot)) with the edge nodes as the last active ones."""
        n_act = 2 * self.k + 1
        acts = []
        for ob in (prob.probe, prob.plate):
            a = np.zeros(ob.nodes.size, bool)
            a[:n_act] = True
            acts.append(a)
        s0 = prob.initial()._replace(active=tuple(acts))
        X, n_u = prob.m.X, prob.asm.n_u
        squeeze = np.zeros_like(s0.x)  # a uniform squeeze: admissible whatever the mesh
        squeeze[0:n_u:2], squeeze[1:n_u:2] = 0.25 * d * X[0], -0.5 * d * (1.0 + X[1])
        err: NewtonError | None = None
        for x0 in (guess, squeeze):
            if x0 is None or x0.shape != s0.x.shape:
                continue
            xi = x0
            for ob, h, a in zip((prob.probe, prob.plate), prob.heights(d), acts):
                xi = ob.impose(xi, h, a)
            if prob.admissible(xi) is not None:
                continue
            try:
                sol = prob.solve(s0, d, 1.0, None, x0, load, fixed=True)
                break
            except NewtonError as e:
                err = e
        else:
            raise err if err is not None else NewtonError("no admissible initial guess", load=load)
        phis = []
        for ob, h, a in zip((prob.probe, prob.plate), prob.heights(d), sol.active):
            N = ob.normal_force(sol.x, sol.residual, h)
            F = max(float(N[a].sum()), 1e-300)
            phi = float(N[n_act - 1]) / F
            inner = float(np.min(N[max(n_act - 3, 0) : n_act - 1])) / F
            if inner < 0:  # the last contact element lifts off in its middle: the zone is too large
                phi = min(phi, inner)
            g = ob.gap(sol.x, h)[n_act : n_act + 6]
            if g.size and g.min() < -1e-9 * d:  # a free node beyond the edge penetrates: too small
                phi = max(phi, -float(g.min()) / d)
            phis.append(phi)
        st = IndentState(sol.x, sol.active, prob.maxwell_initial(), d, sol.residual, 1)
        return st, sol.iterations, phis

    def solve(self, d: float, e0: tuple[float, float] | None, x0: np.ndarray | None, load: str):
        """(problem, state, edges, Newton iterations, solves) at the scaled approach d."""
        if e0 is None:
            _, _, a1, a2 = hertz_split(d, self.rp)
            e0 = (a1 / SPLIT, a2 / SPLIT)
        e = [float(v) for v in e0]
        lo, hi = [1e-5, 1e-5], [0.9, 0.9]
        last: list[tuple[float, float] | None] = [None, None]
        its, x = 0, x0
        for n in range(1, 31):
            prob = self.problem((e[0], e[1]))
            st, it, phi = self.state(prob, d, x, load)
            its, x = its + it, st.x
            if max(abs(p) for p in phi) < self.tol:
                return prob, st, (e[0], e[1]), its, n
            new = []
            for i in range(2):
                if phi[i] > 0:
                    lo[i] = max(lo[i], e[i])
                else:
                    hi[i] = min(hi[i], e[i])
                prev = last[i]
                if abs(phi[i]) < self.tol:
                    cand = e[i]
                elif prev is None or prev[1] == phi[i] or prev[0] == e[i]:
                    cand = e[i] * (1.0 + 0.03 * np.sign(phi[i]))
                else:  # secant in ln(e)
                    le, lp = np.log(e[i]), np.log(prev[0])
                    cand = float(np.exp(le - phi[i] * (le - lp) / (phi[i] - prev[1])))
                if not lo[i] < cand < hi[i] and abs(phi[i]) >= self.tol:
                    cand = float(np.sqrt(lo[i] * hi[i]))
                last[i] = (e[i], phi[i])
                new.append(cand)
            e = new
        raise ContactError(
            "the fitted contact edges did not settle in 30 solves", load=load, hint="use contact='nodal'"
        )


def fitted_states(
    *,
    radius: float,
    probe_radius: float,
    C: float,
    alphas: Sequence[float],
    approaches: Sequence[float] | np.ndarray,
    kappa: float = 2.2e9,
    mesh: str | int = 2,
    rtol: float = 1e-10,
) -> dict[str, np.ndarray]:
    """Static equilibria with fitted contact edges (``FittedEdges``) on a grid of approaches and Fung exponents.

    The states are continued in both directions: each alpha's state at an approach starts from its own state at the
    previous approach (edges grown like sqrt(delta)), the first one (or a retry after a failed solve) from the
    previous alpha's state at the same approach. A strain-stiffening ball (alpha ~ 1.5) under a small probe is
    solved on levels >= 2 only this way (started from the uniform squeeze, its Newton iteration diverges). An
    alpha whose state fails at some approach stops there: its later entries are NaN (a table generator keeps the
    approaches every alpha reached).

    Args:
        radius: the ball's radius a0 (m).
        probe_radius: the probe's radius R_p (m).
        C: Fung stiffness (Pa).
        alphas: Fung exponents (dimensionless, >= 0), in the order of the continuation (increasing is best).
        approaches: increasing approaches delta (m), X_MIN <= delta / (2 a0) <= X_MAX.
        kappa: bulk modulus (Pa).
        mesh: "coarse", "default", "fine" or a level 0..4 (default 2).
        rtol: Newton's relative residual tolerance.

    Returns:
        dict: ``approach`` (n_d,) m, ``alpha`` (n_a,), ``force`` (n_a, n_d) N (NaN: not reached),
        ``contact_radius_probe`` / ``contact_radius_plate`` (n_a, n_d) m, ``wall_time`` (n_a, n_d) s.

    Raises:
        ValueError: an input out of range (the message names the quantity and its unit).
    """
    validate_positive("radius (the ball radius a0)", radius, "m")
    validate_positive("probe_radius (the radius of the spherical probe)", probe_radius, "m")
    a0, rp, C = float(radius), float(probe_radius), float(C)
    al = [float(a) for a in alphas]
    for a in al:
        validate_material(C, a, kappa)
    d = np.asarray(approaches, dtype=float)
    if d.ndim != 1 or d.size == 0 or np.any(~np.isfinite(d)) or np.any(np.diff(d) <= 0):
        raise ValueError(f"approaches (m) must be a non-empty increasing 1-D list of finite values; got {approaches!r}")
    _check_approach(float(d[0]), a0, rp, smallest=True)
    _check_approach(float(d[-1]), a0, rp)
    level = int(mesh_spec(mesh, MESHES, "or a level 0..4"))
    if level not in LEVELS:
        raise ValueError(f"mesh level must be an integer 0..4 (0 coarse, 1 default, 2 fine), got {mesh!r}")
    fits = [
        FittedEdges(a0, rp, level, (lambda m: lambda mm: IndentProblem(mm, m, rp / a0, np.zeros(0), np.zeros(0), rtol))(
            Material(1.0, a, float(kappa) / C)))
        for a in al
    ]  # fmt: skip
    shape = (len(al), d.size)
    out = {k: np.full(shape, np.nan) for k in ("force", "contact_radius_probe", "contact_radius_plate", "wall_time")}
    last: list[tuple[tuple[float, float], np.ndarray, float] | None] = [None] * len(al)
    stopped = [False] * len(al)
    for j, dj in enumerate(d / a0):
        here: tuple[tuple[float, float], np.ndarray] | None = None  # the previous alpha's state at this approach
        for i, fit in enumerate(fits):
            if stopped[i]:
                here = None
                continue
            w0 = time.perf_counter()
            starts: list[tuple[Any, Any]] = []
            if last[i] is not None:
                e_old, x_old, d_old = last[i]  # type: ignore[misc]
                starts.append(((e_old[0] * np.sqrt(dj / d_old), e_old[1] * np.sqrt(dj / d_old)), x_old))
            if here is not None:
                starts.append(here)
            if not starts:
                starts.append((None, None))
            load = f"alpha = {al[i]:g}, delta = {dj * a0 * 1e6:.4g} um"
            res = None
            for e0, x0 in starts:
                try:
                    res = fit.solve(dj, e0, x0, load)
                    break
                except (NewtonError, ContactError) as err:
                    log.info("fitted state failed (%s): %s", load, err)
            if res is None:
                stopped[i], here = True, None
                log.warning(
                    "fitted_states: alpha = %g stops at delta = %.4g um (no converged state)", al[i], dj * a0 * 1e6
                )
                continue
            pb, st, e, _, _ = res
            ob = pb.observe(st)
            out["force"][i, j] = ob["force"] * C * a0**2
            out["contact_radius_probe"][i, j] = ob["contact_radius_probe"] * a0
            out["contact_radius_plate"][i, j] = ob["contact_radius_plate"] * a0
            out["wall_time"][i, j] = time.perf_counter() - w0
            last[i] = (e, st.x, dj)
            here = (e, st.x)
    return dict(approach=d, alpha=np.asarray(al), **out)


def _check_approach(d_max: float, a0: float, rp: float, smallest: bool = False) -> None:
    """The approach (m) inside what the scene resolves: X_MIN <= delta / (2 a0) <= X_MAX (only the upper bound for
    the largest of a run unless ``smallest``), the probe-ball depth below half its effective radius."""
    x = d_max / (2 * a0)
    if (smallest and x < X_MIN) or x > X_MAX or (not smallest and x < X_MIN):
        raise ValueError(
            f"the approach {d_max:g} m is {x:.3g} of the ball's diameter {2 * a0:g} m; the FE indentation "
            f"covers {X_MIN:g} to {X_MAX:g} of it (check the units: m)"
        )
    d1_max = hertz_split(d_max / a0, rp / a0)[0] * a0
    if d1_max > 0.5 * rp / (1 + rp / a0):
        raise ValueError(
            f"displacement {d_max:g} m pushes the probe (radius {rp:g} m) about {d1_max:g} m into the ball, more than "
            "half its effective radius R_p a0 / (R_p + a0): beyond the contacts this scene resolves"
        )


def _record_protocol(spec, name: str, ramp_time, end_time, n_ramp: int):
    """(record, step times, ramp time, end time) of a measured history ``(times, values)`` (``fem.protocols``)."""
    unit = "N" if name == "force" else "m"
    if len(spec) != 2:
        raise ValueError(f"a measured {name} history is a pair (times in s, {name}s in {unit})")
    rec = Record(spec[0], spec[1], name, unit)
    top = float(np.max(rec.values))
    if not top > 0:
        raise ValueError(f"the {name} history (times, {name}s) is 0 throughout: nothing presses the ball")
    if name == "force" and np.any(rec.values[1:] <= 0):
        raise ValueError(
            "the force history (N) must stay > 0 after its first sample: the probe scene has no unloaded state "
            "(the ball would be free); use displacement=(times, approaches) for unloading"
        )
    end = float(rec.times[-1]) if end_time is None else float(end_time)
    validate_positive("end_time", end, "s")
    first = None
    if ramp_time is not None:
        validate_positive("ramp_time (the time scale of the first steps)", ramp_time, "s")
        first = float(ramp_time) / n_ramp
    times = record_schedule(rec, end, cap=top / n_ramp, first=first, growth=1.25 if name == "force" else 1.5)
    tr = float(ramp_time) if ramp_time is not None else float(rec.times[int(np.argmax(rec.values))])
    return rec, times, min(tr, end), end


def _force_target(force, ramp_time: float) -> Callable[[float], float]:
    """The prescribed probe force F(t) (N) of ``force=`` a number (a ramp to it, then held) or a callable."""
    if callable(force):
        f0 = float(force(0.0))
        if f0 != 0.0:
            raise ValueError(f"the force history must start at 0 N at t = 0 (first contact); F(0) = {f0:g} N")

        def target(t: float) -> float:
            f = float(force(t))
            if not np.isfinite(f) or (t > 0 and f <= 0):
                raise ValueError(
                    f"the force F(t = {t:g} s) = {f!r} N must be finite and > 0 after t = 0 (the probe pushes; the "
                    "probe scene has no unloaded state)"
                )
            return f

        return target
    validate_positive("force (the held probe force)", force, "N")
    F = float(force)
    return lambda t: F * min(float(t) / ramp_time, 1.0)


@dataclass
class IndentationResult:
    """:func:`indent`'s result, one entry per converged step (SI: s, m, N).

    ``time`` (s; static runs: the load fraction), ``approach`` (probe travel since first contact, m), ``force``
    (the axial force on the probe, N), ``plate_force`` (on the plate, N; equal to ``force`` to 1e-6),
    ``contact_radius_probe`` / ``contact_radius_plate`` (deformed contact radii, m: edge estimates between the
    outermost active node and the next from the gaps of the next free nodes), ``..._node`` (the outermost active
    node, m), ``centre_drop`` (downward displacement of the ball's centre, m: the ball-plate share of the
    approach in the Hertz picture), ``min_gap`` (m), ``newton_iterations``, ``contact_passes``, ``wall_time``
    (s); ``mesh``, ``static``, ``parameters``; ``gradient`` (``indent(gradient=True)``): {"C" | "alpha" | "beta" |
    "tau" | "beta_1" ...: {"force": N per unit parameter, "centre_drop": m per unit parameter}} per step, else None."""

    time: np.ndarray
    approach: np.ndarray
    force: np.ndarray
    plate_force: np.ndarray
    contact_radius_probe: np.ndarray
    contact_radius_plate: np.ndarray
    contact_radius_probe_node: np.ndarray
    contact_radius_plate_node: np.ndarray
    centre_drop: np.ndarray
    min_gap: np.ndarray
    newton_iterations: np.ndarray
    contact_passes: np.ndarray
    wall_time: np.ndarray
    mesh: AxiMesh
    static: bool
    parameters: dict = field(default_factory=dict)
    gradient: dict | None = None


def indent(
    *,
    radius: float,
    probe_radius: float,
    C: float,
    alpha: float,
    branches: Sequence = (),
    displacement: float | Callable[[float], float] | tuple | None = None,
    force: float | Callable[[float], float] | tuple | None = None,
    ramp_time: float | None = None,
    end_time: float | None = None,
    kappa: float = 2.2e9,
    mesh: str | int = "default",
    contact: str = "nodal",
    static: bool = False,
    n_ramp: int | None = None,
    n_hold: int | None = None,
    n_static: int | None = None,
    rtol: float = 1e-10,
    sizing_approach: float | None = None,
    kinematics: str = "finite",
    gradient: bool = False,
) -> IndentationResult:
    """Press a rigid frictionless sphere on the top of the Fung ball resting on a rigid frictionless plate.

    Every converged step is an equilibrium with exact contact on the probe and on the plate (module doc) and the
    Maxwell branch stresses of its time step.

    Args:
        radius: the ball's radius a0 (m).
        probe_radius: the probe's radius R_p (m).
        C: Fung stiffness of the relaxed (long-time) material (Pa).
        alpha: Fung exponent (dimensionless).
        branches: [(beta_m, tau_m), ...]: energy factors (dimensionless) and relaxation times (s); () elastic.
        displacement: the approach delta (m; X_MIN <= delta / (2 a0) <= X_MAX) reached at ``ramp_time`` by a
            linear ramp and then held to ``end_time``; or a callable delta(t) (m, t in s, delta(0) = 0; each step
            then moves the probe by at most a sixth of the history's largest value, halving steps until it does);
            or a measured history ``(times, approaches)`` (s, m; times strictly increasing from 0, approaches >= 0
            from 0): linear between the samples, held after the last, its steps from ``fem.protocols.
            record_schedule`` (on the kinks that matter, moving the probe by at most max / n_ramp, growing by 1.5
            after every kink; ``end_time`` defaults to the last sample, ``ramp_time`` (optional) sets the first step
            ramp_time / n_ramp).
        force: instead of ``displacement`` (exactly one of them; N; time runs with node-by-node contact): probe
            force control. A number F ramped linearly to F at ``ramp_time`` and held to ``end_time`` (creep); a
            callable F(t) (N, F(0) = 0, > 0 after; ``ramp_hold_schedule`` steps, halved while a step changes the
            force by more than the ramp's largest step); or ``(times, forces)`` (a measured history as above, > 0
            after the first sample: the probe scene has no unloaded state, the ball would be free). Every step
            solves for the approach whose probe force is F(t) to 1e-7 (``fem.protocols.force_controlled``, around
            the displacement-controlled step); ``approach`` (m) is then the observable. The mesh is sized for the
            relaxed small-strain approach of the largest force (the Hertz series law with C) times 1.1, or
            ``sizing_approach``. ``n_hold`` defaults to 40 (the creep moves the probe through the hold).
        ramp_time: end of the ramp (s; ignored when ``static``).
        end_time: end of the hold (s; ignored when ``static``).
        kappa: bulk modulus (Pa).
        mesh: "coarse", "default", "fine" or a level 0..4 (``LEVELS``): one fixed mesh sized for the run's
            largest approach (``make_mesh``), node-by-node contact.
        contact: "nodal" (default: one mesh, node-by-node contact, the force carries the edge quantisation) or
            "fitted" (``static=True`` only: every state on its own mesh whose two contact edges sit on nodes,
            ``FittedEdges``; the force is then a smooth function of the approach and of the mesh).
        static: equilibrium states from 0 to ``displacement`` (F_eq(delta); branches and times ignored);
            ``time`` then holds the load fraction.
        n_ramp, n_hold, n_static: ramp steps (default 6), geometric hold steps (default 20), static states
            (default 8).
        rtol: Newton's relative residual tolerance.
        sizing_approach: the approach (m) the node-by-node mesh is sized for (default: the run's largest approach;
            under force control see ``force``): equal values give equal meshes, so a force-controlled run and a
            displacement run can be compared without the edge quantisation between them.
        kinematics: "finite" (default: the finite-strain Fung law, the contact on the deformed surface) or "small"
            (``static=True`` only, elastic: the geometrically linear law with the small-strain shear modulus 2 C,
            tr(eps) for J - 1, and the Hertz contact gap, vertical at the reference radius: ``SmallStrainAssembler``,
            ``ReferenceSphere``): the FE counterpart of the small-strain two-contact Hertz law, which separates
            the finite-strain part of F / F_Hertz - 1 from the ball's finite size.
        gradient: also return the exact sensitivities of the probe force and the centre drop at every step,
            ``result.gradient = {"C": {"force": N/Pa, "centre_drop": m/Pa}, "alpha": ..., "beta" / "tau" (or
            "beta_1", "tau_1", ...)}`` (node-by-node contact, finite kinematics: static or time runs; the Maxwell
            history's sensitivity carried through the steps; the active nodes held on their obstacles,
            ``_IndentSensing``). Under force control (``force=``) the probe force's gradient is 0 (it is
            prescribed) and the approach's ("approach", m per unit parameter) is solved for with the state's. Accuracy and cost: ``python -m
            tissuemech.compare.bench.fem_gradient --only-indent``.

    Returns:
        ``IndentationResult``.

    Raises:
        ValueError: an input out of range (the message names the quantity and its unit).
        NewtonError: a step did not converge after its cut-backs (``ContactError``: the active set did not
            settle); the message names the step.
        RuntimeError: the probe and plate forces differ by more than 1e-6 (relative): equilibrium not reached.
    """
    validate_positive("radius (the ball radius a0)", radius, "m")
    validate_positive("probe_radius (the radius of the spherical probe)", probe_radius, "m")
    validate_material(C, alpha, kappa)
    br = () if static else validate_branches(branches)
    beta = np.array([float(b) for b, _ in br])
    tau = np.array([float(t) for _, t in br])
    a0, rp, C = float(radius), float(probe_radius), float(C)
    if (displacement is None) == (force is None):
        raise ValueError("give exactly one of displacement (the approach, m) and force (the probe force, N)")
    if force is not None and (static or contact != "nodal"):
        raise ValueError(
            "force control (force=) is a time run with node-by-node contact: static=False, contact='nodal'"
        )
    n_r = n_ramp or 6
    record = displacement if displacement is not None else force
    if isinstance(record, (tuple, list)):
        if static:
            raise ValueError("static=True needs the final approach as a number (m), not a measured history")
        proto = _record_protocol(record, "force" if force is not None else "approach", ramp_time, end_time, n_r)
    else:
        proto = None
        if not static:
            if ramp_time is None or end_time is None:
                raise ValueError("ramp_time and end_time (s) are needed unless static=True")
            validate_positive("ramp_time", ramp_time, "s")
            validate_positive("end_time", end_time, "s")
            if end_time < ramp_time:
                raise ValueError(f"end_time ({end_time} s) must be >= ramp_time ({ramp_time} s)")
    target: Callable[[float], float] | None = None  # the prescribed probe force (N) of t
    too_large = None
    if force is not None:
        if proto is not None:
            target, times, tr, end = proto
        else:
            assert ramp_time is not None and end_time is not None
            tr, end = float(ramp_time), float(end_time)
            target = _force_target(force, tr)
            times = ramp_hold_schedule(tr, end, n_ramp=n_r, n_hold=n_hold or 40)
            if callable(force):
                cap = max(abs(target(b) - target(a)) for a, b in zip(times[:-1], times[1:]) if a < tr) * (1 + 1e-9)
                too_large = lambda t0, t1: abs(target(t1) - target(t0)) > cap  # type: ignore[misc]
        f_max = max(target(t) for t in np.r_[times, np.linspace(0.0, end, 201)])
        r_s = a0 * ((rp / (a0 + rp)) ** (-1.0 / 3.0) + 1.0) ** -3.0  # the series radius (m), reduced.indentation
        d_max = 1.1 * (f_max / (32.0 / 3.0 * C * np.sqrt(r_s))) ** (2.0 / 3.0)
        delta_fn: Callable[[float], float] = lambda t: 0.0
    elif proto is not None:
        delta_fn, times, tr, end = proto
        d_max = float(np.max(delta_fn.values))  # type: ignore[attr-defined]
    elif callable(displacement):
        if static:
            raise ValueError("static=True needs the final approach as a number (m), not a function of time")
        assert ramp_time is not None and end_time is not None
        d0 = float(displacement(0.0))
        if abs(d0) > 1e-9 * a0:
            raise ValueError(f"the displacement history must start at 0 (delta(0) = {d0:g} m)")
        d_max = max(float(displacement(t)) for t in np.linspace(0.0, float(end_time), 201))
        delta_fn = displacement
    else:
        validate_positive("displacement (the approach of the probe)", displacement, "m")
        d_max = float(displacement)  # type: ignore[arg-type]
        tr_ = float(ramp_time) if ramp_time is not None else 1.0
        delta_fn = lambda t: d_max * min(float(t) / tr_, 1.0)
    _check_approach(d_max, a0, rp)
    if sizing_approach is not None:
        validate_positive("sizing_approach (the approach the mesh is sized for)", sizing_approach, "m")
        _check_approach(float(sizing_approach), a0, rp)
    if kinematics not in KINEMATICS:
        raise ValueError(f"kinematics must be 'finite' or 'small', got {kinematics!r}")
    if kinematics == "small" and not static:
        raise ValueError("kinematics='small' (the geometrically linear elastic law) needs static=True")
    if contact not in ("nodal", "fitted"):
        raise ValueError(f"contact must be 'nodal' or 'fitted', got {contact!r}")
    if contact == "fitted" and not static:
        raise ValueError("contact='fitted' (a mesh per state, its edges on nodes) needs static=True")
    if gradient and (contact != "nodal" or kinematics != "finite"):
        raise ValueError(
            "gradient=True is carried for node-by-node contact (contact='nodal') with finite kinematics: not for "
            "contact='fitted' or kinematics='small'"
        )
    m = make_mesh(mesh, a0, rp, d_max if sizing_approach is None else float(sizing_approach))
    mat = Material(1.0, float(alpha), float(kappa) / C)
    prob = IndentProblem(m, mat, rp / a0, beta, tau, rtol, kinematics)
    too_large = None
    if static:
        n = n_static or 8
        times = np.linspace(0.0, 1.0, n + 1)[1:]
        dfun: Callable[[float], float] = lambda t: d_max * t
    elif force is None:
        dfun = delta_fn
        if proto is None:
            assert ramp_time is not None and end_time is not None
            times = ramp_hold_schedule(float(ramp_time), float(end_time), n_ramp=n_r, n_hold=n_hold or 20)
            if callable(displacement):
                dd = d_max / n_r
                too_large = lambda t0, t1: abs(float(delta_fn(t1)) - float(delta_fn(t0))) > dd * (1 + 1e-12)
    else:
        dfun = delta_fn

    def dscaled(t: float) -> float:
        d = float(dfun(t))
        if not np.isfinite(d) or d < 0 or d > 2 * X_MAX * a0:
            raise ValueError(f"the approach delta(t = {t:g} s) = {d!r} m must be finite, >= 0 and <= {2 * X_MAX} a0")
        return d / a0

    def load_of(t: float) -> str:
        if target is not None:
            return f"t = {t:.6g} s, F = {target(t):.6g} N"
        return f"delta = {dfun(t) * 1e6:.4g} um" if static else f"t = {t:.6g} s, delta = {dfun(t) * 1e6:.4g} um"

    def step(t0: float, old: IndentState, t1: float, prev: TimedState[IndentState] | None):
        p = prev.state if prev is not None else None
        return prob.step(old, dscaled(t1), None if static else t1 - t0, p, load_of(t1))

    runs: list[tuple[float, IndentProblem, IndentState, int, float]] = []  # (time, problem, state, its, wall)
    sensing: _IndentSensing | None = None
    if contact == "fitted":
        fit = FittedEdges(a0, rp, int(mesh_spec(mesh, MESHES, "or a level 0..4")), lambda mm: IndentProblem(
            mm, mat, rp / a0, beta, tau, rtol, kinematics))  # fmt: skip
        e_prev: tuple[float, float] | None = None
        d_prev, x_prev = 0.0, None
        for t in times:
            w0 = time.perf_counter()
            d = dscaled(t)
            e0: tuple[float, float] | None = None
            if e_prev is not None:  # the edges grow like sqrt(delta)
                e0 = (e_prev[0] * np.sqrt(d / d_prev), e_prev[1] * np.sqrt(d / d_prev))
            pb, st_f, e_prev, its, _ = fit.solve(d, e0, x_prev, load_of(t))
            d_prev, x_prev = d, st_f.x
            runs.append((float(t), pb, st_f, its, time.perf_counter() - w0))
        m = runs[-1][1].m
    else:
        stepper: Callable[[float, IndentState, float, TimedState[IndentState] | None], tuple[IndentState, int]]
        stepper = step
        if target is not None:
            ftarget = target
            k_s = 32.0 / 3.0 * np.sqrt(prob.r_series)  # scaled: F / (C a0^2) = k_s (delta / a0)^1.5 (Hertz)

            def step_to(t0: float, old: IndentState, t1: float, prev, d1: float | None):
                if d1 is None:  # a target <= 0: refused by the force checks before
                    raise ValueError("the probe scene has no unloaded state (probe force 0 N)")
                return prob.step(old, float(d1), t1 - t0, prev.state if prev is not None else None, load_of(t1))

            stepper = force_controlled(
                step_to,
                lambda st: prob.observe(st)["force"] * 32.0 / (3.0 * k_s),  # in the Hertz form (32/3) u^1.5
                lambda st: st.delta,
                lambda st: 0.0,
                lambda t: ftarget(t) / (C * a0**2) * 32.0 / (3.0 * k_s),
                load_of,
                stiffness=1.0 + float(np.sum(beta)),
                tol=min(FORCE_TOL, 1e3 * rtol),  # as the plates': a tight rtol tightens the force too
            )
        if gradient:
            sensing = _IndentSensing(prob, None if target is None else lambda t: ftarget(t) / (C * a0**2))
        if sensing is not None:
            stepper = sensing.wrap(stepper, static)
        for st in march(stepper, prob.initial(), times, too_large=too_large):
            runs.append((st.time, prob, st.state, st.newton_iterations, st.wall_time))
    L2 = C * a0**2
    cols: dict[str, list] = {}
    for t_k, pb, state, its, wall in runs:
        ob = pb.observe(state)
        F, Fb = ob["force"], ob["plate_force"]
        if F > 0 and abs(F - Fb) > FORCE_CHECK * abs(F) + 1e3 * pb.floor:
            raise RuntimeError(
                f"probe force {F * L2:.6g} N and plate force {Fb * L2:.6g} N differ by {abs(F - Fb) / F:.2e} "
                f"(relative) at t = {t_k:.6g} s: equilibrium not reached. Hint: tighten rtol"
            )
        row = dict(
            time=t_k,
            approach=state.delta * a0,
            newton_iterations=its,
            contact_passes=state.passes,
            wall_time=wall,
        )
        for k, v in ob.items():
            row[k] = v * (L2 if k.endswith("force") else a0)
        for k, v in row.items():
            cols.setdefault(k, []).append(v)
    arrays = {k: np.array(v) for k, v in cols.items()}
    grad = None
    if gradient:
        assert sensing is not None
        grad = _indent_gradients(sensing.out, arrays["force"], a0, C, sensing.names, target is not None)
    return IndentationResult(
        **arrays,
        gradient=grad,
        mesh=m,
        static=bool(static),
        parameters=dict(
            radius=a0,
            probe_radius=rp,
            C=C,
            alpha=float(alpha),
            kappa=float(kappa),
            branches=tuple((float(b), float(t)) for b, t in br),
            ramp_time=None if static else float(tr if (proto is not None or force is not None) else ramp_time),  # type: ignore[arg-type]
            end_time=None if static else float(end if (proto is not None or force is not None) else end_time),  # type: ignore[arg-type]
            control="force" if force is not None else "displacement",
            mesh=mesh,
            contact=contact,
            kinematics=kinematics,
        ),
    )
