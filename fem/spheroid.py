r"""FE spheroid: a Fung ball compressed between rigid frictionless plates, held, relaxing (seed Figs 6-10).

``compress(*, radius, C, alpha, branches, displacement, ramp_time, end_time, kappa=2.2e9,
mesh="default", static=False, field_times=(), n_ramp=None, n_hold=None, n_static=None, rtol=1e-10)
-> SpheroidResult`` (``fem.output``).

Model (physics.md, scene 2): by symmetry a quarter section R >= 0, Z >= 0 of the ball of radius a0
(u_r = 0 on the axis, u_z = 0 on the midplane Z = 0) and one rigid flat plane z = a0 - delta(t)/2 at
the top (``fem.contact``: exact unilateral contact by an active set, no penalty), mixed
Q2/P1-discontinuous elements (``fem.forms``), generalized Maxwell branches on S_iso
(``fem.viscoelastic``), quasi-static time stepping (``fem.timestepping``, inertia ~1e-6 of the stresses).
Inside, lengths are scaled by a0, stresses by C, forces by C a0^2.

* ``displacement``: the total approach delta (m) of the two plates reached at ``ramp_time`` by a
  linear ramp and then held to ``end_time``; or a callable delta(t) (m, t in s, delta(0) = 0), then
  ``ramp_time`` is the time scale of the fine initial steps and each step moves the plate by at most
  the ramp's step (steps are halved until it does).
* ``branches``: sequence of (beta_m, tau_m [s]); empty for elastic.
* ``static=True``: branches and times are ignored; the steps are equilibrium states from delta = 0 to
  ``displacement`` (``n_static`` equal steps, cut back on failure): the F_eq(delta) curve; ``time`` then
  holds the load fraction delta/displacement.
* ``mesh``: "coarse", "default", "fine", a level 0..4 (0 = coarse, 1 = default, 2 = fine; ``LEVELS``
  gives (n_core, n_radial, surface grading, pole grading) of ``fem.mesh.ball_section``; 3 x 3 Gauss
  points) or an ``AxiMesh`` from ``fem.mesh.ball_section`` (built with length_scale = radius; refine it
  toward the pole, e.g. pole_grading = 30, for Hertz-scale approaches delta < 1 % of the radius).
* ``field_times``: times (s) at which the deformed mesh, von Mises and pressure fields are stored
  (they become step times; static runs: load fractions delta/displacement in (0, 1], the stored field is
  the closest step); the last step is always stored. ``field_times="all"``: every converged step
  (for ``SpheroidResult.to_pvd``).

Outputs per converged step: plate force from the contact multipliers (sum of the nodal reactions of the
active nodes; they include the 2 pi R of the axisymmetric volume element, so this is the force on the
whole plate), the midplane reaction (must be equal: checked to 1e-6 relative, else RuntimeError),
midplane radius (deformed equator), nominal stress F / (pi r_mid^2), volume-averaged von Mises stress
(deformed volume), contact radius (edge estimate between the outermost active node and the next one,
from the gaps of the first free nodes; ``contact_radius_node``: the outermost active node itself).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
import skfem

from tissuemech.fem import constitutive as cm
from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.contact import RigidPlane
from tissuemech.fem.forms import Assembler, Material
from tissuemech.fem.kinematics import invariants
from tissuemech.fem.mesh import AxiMesh, ball_section
from tissuemech.fem.newton import symmetric_solve
from tissuemech.fem.output import SpheroidField, SpheroidResult
from tissuemech.fem.timestepping import march, ramp_hold_schedule
from tissuemech.reduced.material import validate_branches, validate_material, validate_positive

__all__ = ["compress", "make_mesh", "MESHES", "LEVELS", "hertz_force"]

# level -> (n_core, n_radial, surface grading, pole grading). Nodal contact quantizes the contact edge:
# the force carries a ~0.3 % jitter that falls slowly with the surface node spacing. Default (level 1):
# static F(delta) within ~0.6 % of levels 2-3 for delta/(2 a0) in [0.005, 0.3] (compare.bench fem-spheroid).
LEVELS = {0: (4, 3, 2.0, 3.0), 1: (12, 4, 2.0, 3.0), 2: (16, 8, 2.0, 4.0), 3: (24, 10, 2.0, 4.0), 4: (32, 12, 2.0, 4.0)}
MESHES = {"coarse": 0, "default": 1, "fine": 2}
FORCE_CHECK = 1e-6  # |F_contact - F_reaction| / F


def hertz_force(approach, radius: float, C: float):
    """Hertz force (N) of a ball between two plates, total approach delta (m): (4/3) E* sqrt(a0) (delta/2)^1.5, E* = 8 C."""
    return 4.0 / 3.0 * 8.0 * C * np.sqrt(radius) * (np.asarray(approach, float) / 2) ** 1.5


def make_mesh(mesh, radius: float) -> AxiMesh:
    """Resolve the ``mesh`` argument to an AxiMesh of the quarter ball (see the module docstring)."""
    if isinstance(mesh, AxiMesh):
        if abs(mesh.length_scale - radius) > 1e-12 * radius or "outer" not in mesh.nodes:
            raise ValueError("the mesh object must come from fem.mesh.ball_section(radius, ...) with the same radius")
        return mesh
    if isinstance(mesh, str):
        if mesh not in MESHES:
            raise ValueError(
                f"mesh must be 'coarse', 'default', 'fine', a level 0..4 or a ball_section mesh, got {mesh!r}"
            )
        mesh = MESHES[mesh]
    if isinstance(mesh, (bool, np.bool_)) or not isinstance(mesh, (int, np.integer)) or int(mesh) not in LEVELS:
        raise ValueError(f"mesh level must be an integer 0..4 (0 coarse, 1 default, 2 fine), got {mesh!r}")
    nc, nr, gr, pg = LEVELS[int(mesh)]
    m = ball_section(radius, nc, nr, grading=gr, pole_grading=pg)
    # 3 x 3 Gauss points (exact enough for Q2: forces change < 1e-5 relative vs 4 x 4), 1.8x cheaper
    return AxiMesh(
        m.mesh, skfem.CellBasis(m.mesh, skfem.ElementQuad2(), intorder=4), 2, m.length_scale, m.nodes, m.edges
    )


class _State(NamedTuple):
    x: np.ndarray
    active: np.ndarray
    visco: ve.MaxwellState
    delta: float  # scaled plate displacement (= approach / 2 / a0)
    residual: np.ndarray
    iso_scale: float
    extra_S: object
    passes: int


class _Problem:
    def __init__(self, m: AxiMesh, mat: Material, beta, tau, rtol: float):
        self.m, self.mat = m, mat
        self.asm = Assembler(m, "mixed")
        self.beta, self.tau = np.asarray(beta, float), np.asarray(tau, float)
        self.sym = m.nodes["symmetry"]
        fixed = np.concatenate([2 * m.nodes["axis"], 2 * self.sym + 1])
        self.free = np.setdiff1d(np.arange(self.asm.ndof), fixed)
        cand = np.setdiff1d(m.nodes["outer"], self.sym)
        self.plane = RigidPlane(m.X, cand)
        X = m.X
        eq = np.flatnonzero((np.abs(X[1]) < 1e-12) & (np.abs(X[0] - 1) < 1e-9))
        if eq.size != 1:
            raise ValueError("the ball mesh has no node at the equator (R = a0, Z = 0)")
        self.equator = int(eq[0])
        self.rtol = rtol
        # the round-off floor of the residual grows with kappa/C (q carries kappa (J - 1))
        self.floor = 1e2 * np.finfo(float).eps * max(mat.kappa, 1.0)

    def admissible(self, x):
        f = self.asm.f_at(x)
        _, J = invariants(f)
        if not np.all(J > 0):
            return "J <= 0 (an element turned inside out)"
        if not np.all(f[..., 4] > 0):
            return "hoop stretch <= 0"
        return None

    def solve(self, s0: _State, d1: float, iso_scale, extra, guess, load):
        h = 1.0 - d1
        fun = lambda x: self.asm.internal(x, self.mat, extra_S=extra, iso_scale=iso_scale)
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
            solver=symmetric_solve,
        )
        return sol

    def step(self, s0: _State, d1: float, dt: float | None, prev, load):
        """Equilibrium at plate displacement d1 after a time step dt (None: static)."""
        if dt is None:
            iso_scale, extra = 1.0, None
        else:
            iso_scale, extra = ve.algorithmic(s0.visco, self.beta, self.tau, dt)
        guess = s0.x
        if prev is not None and abs(s0.delta - prev.delta) > 1e-14:
            guess = s0.x + (s0.x - prev.x) * (d1 - s0.delta) / (s0.delta - prev.delta)
        sol = self.solve(s0, d1, iso_scale, extra, guess, load)
        S_new = self.asm.iso_S(sol.x, self.mat)
        visco = (
            ve.update(s0.visco, self.beta, self.tau, dt, S_new) if dt is not None else s0.visco._replace(S_iso=S_new)
        )
        return _State(sol.x, sol.active, visco, d1, sol.residual, iso_scale, extra, sol.sets), sol.iterations

    # ---- observables (scaled) --------------------------------------------------------------
    def observe(self, s: _State):
        r, pl = s.residual, self.plane
        N = np.where(s.active, pl.normal_force(r), 0.0)
        F = float(N.sum())
        Fr = float(r[2 * self.sym + 1].sum())
        x = s.x
        r_mid = 1.0 + x[2 * self.equator]
        rc, rc_node = _contact_radius(pl, x, s.active, 1.0 - s.delta)
        f, P, _, q = self.asm.stress(x, self.mat, s.extra_S, s.iso_scale)
        vm = cm.von_mises(cm.cauchy(f, P))
        _, J = invariants(f)
        wJ = self.asm.w * J
        gmin = float(np.min(pl.gap(x, 1.0 - s.delta)))
        nmin = float(np.min(N[s.active])) if s.active.any() else 0.0
        return F, Fr, r_mid, rc, rc_node, float(np.sum(vm * wJ) / np.sum(wJ)), vm, q, N, gmin, nmin


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
    mesh="default",
    static: bool = False,
    field_times: Sequence[float] | str = (),
    n_ramp: int | None = None,
    n_hold: int | None = None,
    n_static: int | None = None,
    rtol: float = 1e-10,
) -> SpheroidResult:
    """Compress the Fung ball between frictionless plates; see the module docstring. SI units (m, Pa, s, N)."""
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

    m = make_mesh(mesh, a0)
    prob = _Problem(m, Material(1.0, float(alpha), float(kappa) / C), beta, tau, rtol)
    n0 = prob.asm.ndof
    pole = np.argmin(np.hypot(prob.plane.R, prob.plane.Z - 1.0))
    active0 = np.zeros(prob.plane.nodes.size, bool)
    active0[pole] = True
    s0 = _State(
        np.zeros(n0), active0, ve.initial_state(beta.size, prob.asm.w.shape + (5,)), 0.0, np.zeros(n0), 1.0, None, 0
    )

    if static:
        n = n_static or max(8, int(np.ceil(d_max / a0 / 0.02)))
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

    def step(t0, s_old, t1, prev):
        load = f"delta = {dfun(t1) * 1e6:.4g} um" if static else f"t = {t1:.6g} s, delta = {dfun(t1) * 1e6:.4g} um"
        return prob.step(s_old, dscaled(t1), None if static else t1 - t0, prev[1] if prev is not None else None, load)

    steps = march(step, s0, times, too_large=too_large)

    L2 = C * a0**2
    rows, fields = [], []
    want = set()
    for tf in ft:
        want.add(int(np.argmin([abs(s.t - tf) for s in steps])))
    want.add(len(steps) - 1)
    if store_all:
        want = set(range(len(steps)))
    for k, st in enumerate(steps):
        s = st.state
        F, Fr, rm, rc, rcn, vmm, vm, q, N, gmin, nmin = prob.observe(s)
        if F > 0 and abs(F - Fr) > FORCE_CHECK * abs(F) + 1e3 * prob.floor:
            raise RuntimeError(
                f"contact force {F * L2:.6g} N and midplane reaction {Fr * L2:.6g} N differ by "
                f"{abs(F - Fr) / F:.2e} (relative) at t = {st.t:.6g} s: equilibrium not reached. "
                "Hint: tighten rtol"
            )
        rows.append(
            (
                st.t,
                2 * a0 * s.delta,
                F * L2,
                Fr * L2,
                rm * a0,
                rc * a0,
                vmm * C,
                st.iterations,
                s.passes,
                st.wall_s,
                rcn * a0,
                gmin * a0,
                nmin * L2,
            )
        )
        if k in want:
            w = prob.asm.w
            u = s.x[: prob.asm.n_u].reshape(-1, 2) * a0
            fields.append(
                SpheroidField(
                    time=st.t,
                    displacement=u,
                    deformed_nodes=m.X.T * a0 + u,
                    von_mises=(vm * w).sum(1) / w.sum(1) * C,
                    hydrostatic_pressure=-(q * w).sum(1) / w.sum(1) * C,
                    contact_nodal_force=N * L2,
                    contact_nodes=prob.plane.nodes,
                )
            )
    a = np.array(rows, float)
    area = np.pi * a[:, 4] ** 2
    return SpheroidResult(
        time=a[:, 0],
        approach=a[:, 1],
        force=a[:, 2],
        reaction_force=a[:, 3],
        midplane_radius=a[:, 4],
        midplane_area=area,
        nominal_stress=a[:, 2] / area,
        mean_von_mises=a[:, 6],
        contact_radius=a[:, 5],
        contact_radius_node=a[:, 10],
        min_gap=a[:, 11],
        min_contact_force=a[:, 12],
        newton_iterations=a[:, 7].astype(int),
        contact_passes=a[:, 8].astype(int),
        wall_time=a[:, 9],
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
        ),
    )
