r"""FE blastula: a hollow Fung sphere inflated by a follower pressure (seed Figs 1-5).

``inflate(*, inner_radius, outer_radius, C, alpha, pressures, kappa=2.2e9, mesh="default",
method="load", max_inner_stretch=None, rtol=1e-10, store_fields=False) -> BlastulaResult``

Quarter wall section A <= rho <= B, 0 <= theta <= 90 deg (u_z = 0 on Z = 0, u_r = 0 on the axis),
mixed Q2/P1-discontinuous elements (perturbed Lagrangian, condensed), follower pressure on the
deformed inner surface. Lengths scaled by A and stresses by C inside. ``pressures`` (Pa) must be
finite, >= 0 and non-decreasing; ``method="load"`` returns one entry per requested pressure
(steps are subdivided internally when Newton struggles); ``method="arclength"`` traces from p = 0
until the inner stretch reaches ``max_inner_stretch`` (``pressures`` then only sets the first
step: its first positive entry; None for an automatic step raising the stretch by ~0.02; steps
adapt up to twice the first), through limit points. Stretch = mean deformed /
reference radius over the inner (outer) surface. Mesh: "coarse", "default", "fine", a tuple
(n_radial, n_circ) or an ``AxiMesh`` from ``fem.mesh.shell_section``.

``creep(*, inner_radius, outer_radius, C, alpha, branches, pressure, ramp_time, end_time, kappa=2.2e9,
mesh="default", times=(), n_ramp=8, n_hold=60, first_hold=None, rtol=1e-10, store_fields=False) -> BlastulaResult``

The same shell with generalized Maxwell branches (beta_m, tau_m [s]) on the isochoric stress
(``fem.viscoelastic``: dQ_m/dt + Q_m/tau_m = beta_m dS_iso/dt, exact exponential update for S_iso
linear over a step) under a pressure ramp-and-hold: p(t) = pressure * min(t / ramp_time, 1) (Pa),
held to ``end_time`` (s). Quasi-static time marching (``fem.timestepping``: ``n_ramp`` equal ramp
steps, ``n_hold`` geometrically growing hold steps from ``first_hold`` (default ramp_time / 2),
``times`` merged in as step times; a failed step is halved). The result has one entry per converged
step in ``time`` [s], ``pressure``, ``inner_stretch``, ``outer_stretch``, ``newton_iterations``,
``wall_time`` and the fields at ``end_time``. A hold pressure above the relaxed limit point makes the
shell creep past it (it bursts): the step that cannot find equilibrium raises ``NewtonError`` naming
the time. No branches (or beta = 0) is the elastic shell at every step.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from tissuemech.fem import constitutive as cm
from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.continuation import LimitPointError, arc_length, load_control
from tissuemech.fem.forms import Assembler, Material
from tissuemech.fem.kinematics import invariants
from tissuemech.fem.mesh import AxiMesh, shell_section
from tissuemech.fem.newton import NewtonError, newton, sparse_solve, symmetric_solve
from tissuemech.fem.output import BlastulaField, BlastulaResult
from tissuemech.fem.timestepping import march, ramp_hold_schedule
from tissuemech.reduced.material import validate_branches, validate_material, validate_positive, validate_radii
from tissuemech.reduced.validation import validate_choice, validate_finite

__all__ = ["inflate", "creep", "MESHES", "LimitPointError", "NewtonError", "LockingWarning"]

MESHES = {"coarse": (2, 4), "default": (4, 8), "fine": (8, 16)}
LOCKING_RATIO = 100.0  # displacement-only elements lock (overly stiff) beyond kappa/C ~ 1e2


class LockingWarning(UserWarning):
    """formulation='displacement' with a nearly incompressible material: the answer is locked (too stiff)."""


def _make_mesh(mesh, A: float, B: float) -> AxiMesh:
    if isinstance(mesh, AxiMesh):
        if abs(mesh.length_scale - A) > 1e-12 * A:
            raise ValueError("the mesh object must be built with length_scale = inner_radius")
        return mesh
    if isinstance(mesh, str):
        if mesh not in MESHES:
            raise ValueError(
                f"mesh must be 'coarse', 'default', 'fine', a tuple (n_radial, n_circ) or a mesh object, got {mesh!r}"
            )
        mesh = MESHES[mesh]
    if (
        not isinstance(mesh, (tuple, list))
        or len(mesh) != 2
        or not all(isinstance(n, (int, np.integer)) and n >= 1 for n in mesh)
    ):
        raise ValueError(f"mesh divisions must be two positive integers (n_radial, n_circ), got {mesh!r}")
    return shell_section(A, B, int(mesh[0]), int(mesh[1]))


class _Problem:
    """The scaled blastula equations r(u, p) = f_int(u) - p f_p(u) on the free dofs.

    ``iso_scale``/``extra_S`` (``fem.viscoelastic.algorithmic``) add the Maxwell branch stresses of a
    time step; the defaults are the elastic shell. ``ref`` = |f_p| at unit pressure (the force scale),
    ``floor`` = the round-off floor of the residual (kappa/C times eps times the force scale)."""

    def __init__(self, m: AxiMesh, mat: Material, formulation: str = "mixed"):
        self.m, self.mat = m, mat
        self.asm = Assembler(m, formulation)
        fixed = np.concatenate([2 * m.nodes["axis"], 2 * m.nodes["symmetry"] + 1])
        self.free = np.setdiff1d(np.arange(self.asm.ndof), fixed)
        self.inner = m.edges["inner"]
        self.ref = float(np.linalg.norm(self.rk(np.zeros(self.free.size), 0.0, tangent=False)[2]))
        self.floor = 1e3 * np.finfo(float).eps * max(mat.kappa, 1.0) * self.ref

    def full(self, uf):
        u = np.zeros(self.asm.ndof)
        u[self.free] = uf
        return u

    def rk(self, uf, p, tangent=True, iso_scale: float = 1.0, extra_S=None):
        u = self.full(uf)
        ri, fp, K = self.asm.internal_follower(
            u, self.mat, p, self.inner, free=self.free, extra_S=extra_S, iso_scale=iso_scale, tangent=tangent
        )  # K_int - p K_p on one pattern, restricted to the free dofs by a cached gather (issue 14)
        return (ri - p * fp)[self.free], K, -fp[self.free]

    def solve(self, lam, guess, rtol, load, iso_scale: float = 1.0, extra_S=None):
        """Newton for the equilibrium at scaled pressure lam (raises NewtonError naming ``load``)."""
        return newton(
            lambda x: self.rk(x, lam, tangent="lazy", iso_scale=iso_scale, extra_S=extra_S)[:2],
            guess,
            ref_norm=self.ref * max(lam, 1e-3),
            rtol=rtol,
            xtol=1e-9,
            atol=self.floor * (1 + lam),
            admissible=self.admissible,
            load=load,
            solver=symmetric_solve,  # symmetric ordering (issue 14: 2x fewer fill-ins than COLAMD, same answer)
        )

    def admissible(self, uf):
        f = self.asm.f_at(self.full(uf))
        _, J = invariants(f)
        if not np.all(J > 0):
            return "J <= 0 (element turned inside out)"
        if not np.all(f[..., 4] > 0):
            return "hoop stretch <= 0"
        return None

    def stretches(self, uf):
        u = self.full(uf)
        return (
            self.asm.surface_mean_stretch(u, self.m.edges["inner"]),
            self.asm.surface_mean_stretch(u, self.m.edges["outer"]),
        )

    def field(self, x, C, iso_scale: float = 1.0, extra_S=None):
        """(displacement (N, 2) [m], element von Mises [Pa], element hydrostatic pressure [Pa]) of the
        scaled state ``x`` (free dofs), with its step's branch stresses."""
        A = self.m.length_scale
        xf = self.full(x)
        u = xf[: self.asm.n_u].reshape(-1, 2) * A
        f, P, _, q = self.asm.stress(xf, self.mat, extra_S, iso_scale)
        vm = cm.von_mises(cm.cauchy(f, P)) * C
        wq = self.asm.w
        return u, (vm * wq).sum(1) / wq.sum(1), -(q * wq).sum(1) / wq.sum(1) * C

    def result(
        self, lam, xs, its, wall, C, method, iso_scale: float = 1.0, extra_S=None, all_fields=None, **extra
    ) -> BlastulaResult:
        """BlastulaResult (SI) from the scaled states ``xs`` (free dofs) at scaled pressures ``lam``;
        the fields are those of the last state (with its step's branch stresses). ``all_fields``: None,
        or one (time [s] or None, iso_scale, extra_S) per state to keep the fields of every step."""
        A = self.m.length_scale
        st = np.array([self.stretches(x) for x in xs])
        u, vm, ph = self.field(xs[-1], C, iso_scale, extra_S)
        fields = None
        if all_fields is not None:
            fields = []
            for x, l, (t, isc, ex) in zip(xs, lam, all_fields):
                uk, vmk, phk = self.field(x, C, isc, ex)
                fields.append(BlastulaField(float(l) * C, t, uk, self.m.X.T * A + uk, vmk, phk))
        return BlastulaResult(
            pressure=np.asarray(lam, float) * C,
            inner_stretch=st[:, 0],
            outer_stretch=st[:, 1],
            newton_iterations=np.asarray(its, int),
            wall_time=np.asarray(wall, float),
            mesh=self.m,
            displacement=u,
            deformed_nodes=self.m.X.T * A + u,
            hydrostatic_pressure=ph,
            von_mises=vm,
            method=method,
            fields=fields,
            **extra,
        )


def _setup(inner_radius, outer_radius, C, alpha, kappa, mesh, formulation: str = "mixed") -> _Problem:
    """Validate the shell inputs and build the scaled problem (lengths / A, stresses / C)."""
    validate_radii(inner_radius, outer_radius)
    validate_material(C, alpha, kappa)
    A, B = float(inner_radius), float(outer_radius)
    m = _make_mesh(mesh, A, B)
    return _Problem(m, Material(1.0, float(alpha), float(kappa) / float(C)), formulation)


def inflate(
    *,
    inner_radius: float,
    outer_radius: float,
    C: float,
    alpha: float,
    pressures: Sequence[float] | np.ndarray | None,
    kappa: float = 2.2e9,
    mesh="default",
    method: str = "load",
    max_inner_stretch: float | None = None,
    rtol: float = 1e-10,
    formulation: str = "mixed",
    store_fields: bool = False,
) -> BlastulaResult:
    """Inflate the hollow sphere; see the module docstring. SI units (m, Pa).

    ``store_fields=True`` keeps the fields (displacement, von Mises, pressure) of every converged step in
    ``result.fields`` (``BlastulaField``; for ``result.to_pvd``); by default only the final ones are kept.
    """
    validate_choice("method", method, ("load", "arclength"))
    if pressures is not None:
        p = np.atleast_1d(validate_finite("pressures (the pressure levels to reach)", pressures, "Pa"))
        if p.ndim != 1 or p.size == 0 or not np.all(np.isfinite(p)):
            raise ValueError("pressures must be a non-empty 1D list of finite values in Pa")
        if np.any(p < 0):
            raise ValueError("pressures must be >= 0 Pa (the cavity pressure inflates the shell)")
        if np.any(np.diff(p) < 0):
            raise ValueError("pressures must be sorted in increasing order (a loading sweep)")
    elif method == "load":
        raise ValueError("method='load' needs the list of pressures (Pa) to reach")
    if method == "arclength":
        if max_inner_stretch is not None:
            validate_finite("max_inner_stretch (a/A, dimensionless)", max_inner_stretch, "dimensionless")
        if max_inner_stretch is None or not np.isfinite(max_inner_stretch) or max_inner_stretch <= 1:
            raise ValueError("method='arclength' needs max_inner_stretch > 1 (where to stop the trace)")
    validate_choice("formulation", formulation, ("mixed", "displacement"))
    validate_radii(inner_radius, outer_radius)
    validate_material(C, alpha, kappa)
    if formulation == "displacement" and float(kappa) / float(C) > LOCKING_RATIO:
        warnings.warn(
            f"formulation='displacement' locks at kappa/C = {float(kappa) / float(C):.3g} (kappa = {float(kappa):g} Pa, "
            f"C = {float(C):g} Pa): the shell comes out far too stiff (e.g. inner stretch 1.002 instead of 1.116 "
            "at 100 Pa for the seed's kappa = 2.2 GPa). Use formulation='mixed' (the default)",
            LockingWarning,
            stacklevel=2,
        )
    prob = _setup(inner_radius, outer_radius, C, alpha, kappa, mesh, formulation)
    u0 = np.zeros(prob.free.size)
    ref, floor = prob.ref, prob.floor

    def solve(lam, guess):
        return prob.solve(lam, guess, rtol, load=f"p = {lam * C:.6g} Pa")

    if method == "load":
        steps = load_control(solve, p / C, u0, monitor=lambda x: prob.stretches(x)[0], unit=" Pa", scale=C)
        lam = np.array([s[0] for s in steps])
        xs = [s[1].x for s in steps]
        its = np.array([s[1].iterations for s in steps])
        wall = np.array([s[2] for s in steps])
    else:
        pos = p[p > 0] if pressures is not None else np.array([])
        if pos.size:
            dp = pos[0] / C
        else:  # automatic: a first step that raises the inner stretch by ~ 0.02 (linear estimate)
            _, K0, rl0 = prob.rk(u0, 0.0)
            t = sparse_solve(K0, -rl0)
            dp = 0.02 / max((prob.stretches(1e-6 * t)[0] - 1.0) / 1e-6, 1e-12)
        ds = np.sqrt(2.0) * dp  # the first tangent has equal parts in |x|/c and the load
        steps = arc_length(
            lambda x, l: prob.rk(x, l),
            u0,
            0.0,
            ds,
            stop=lambda x, l: prob.stretches(x)[0] >= max_inner_stretch,
            admissible=prob.admissible,
            ref_norm=ref,
            rtol=rtol,
            atol=floor,
            ds_max=2 * ds,
        )
        lam = np.array([0.0] + [s[0] for s in steps])
        xs = [u0] + [s[1] for s in steps]
        its = np.array([0] + [s[2] for s in steps])
        wall = np.array([0.0] + [s[3] for s in steps])
    return prob.result(
        lam, xs, its, wall, C, method, all_fields=[(None, 1.0, None)] * len(xs) if store_fields else None
    )


class _CreepState(NamedTuple):
    x: np.ndarray  # free dofs (scaled)
    visco: ve.MaxwellState  # branch stresses and S_iso after the step
    lam: float  # scaled pressure p / C
    iso_scale: float  # algorithmic factors of the step that produced this state (for its stresses)
    extra_S: object


def creep(
    *,
    inner_radius: float,
    outer_radius: float,
    C: float,
    alpha: float,
    branches: Sequence,
    pressure: float,
    ramp_time: float,
    end_time: float,
    kappa: float = 2.2e9,
    mesh="default",
    times: Sequence[float] = (),
    n_ramp: int = 8,
    n_hold: int = 60,
    first_hold: float | None = None,
    rtol: float = 1e-10,
    store_fields: bool = False,
) -> BlastulaResult:
    r"""Creep of the viscoelastic shell under p(t) = pressure min(t / ramp_time, 1); see the module docstring.

    SI units: radii (m), C, kappa, pressure (Pa), times (s); ``branches`` = [(beta_m, tau_m [s]), ...].
    Every step solves the equilibrium r(u, t_{n+1}) = f_int(u; iso_scale, extra_S) - p(t_{n+1}) f_p(u) = 0
    with the algorithmic Maxwell stress S = S_vol + (1 + sum beta_m g_m) S_iso + sum (e^{-h_m} Q_m^n -
    beta_m g_m S_iso^n) (``fem.viscoelastic``), then updates Q_m. Returns a BlastulaResult with ``time``
    and ``method="creep"`` (``parameters`` records the inputs). ``store_fields=True`` keeps the fields of
    every converged step in ``result.fields`` (``BlastulaField`` with its time; for ``result.to_pvd``).
    """
    br = validate_branches(branches)
    validate_positive("pressure (the held cavity pressure)", pressure, "Pa")
    validate_positive("ramp_time", ramp_time, "s")
    validate_positive("end_time", end_time, "s")
    if end_time < ramp_time:
        raise ValueError(
            f"end_time ({end_time} s) must be >= ramp_time ({ramp_time} s): the pressure is "
            "ramped up over ramp_time, then held until end_time"
        )
    for name, n in (("n_ramp", n_ramp), ("n_hold", n_hold)):
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"{name} (number of time steps) must be a positive integer, got {n!r}")
    if first_hold is not None:
        validate_positive("first_hold (the first step after the ramp)", first_hold, "s")
    ts = np.atleast_1d(np.asarray(times, float)) if len(np.atleast_1d(times)) else np.array([])
    if ts.size and (not np.all(np.isfinite(ts)) or np.any(ts <= 0) or np.any(ts > end_time * (1 + 1e-12))):
        raise ValueError(f"times (extra output times) must be finite and in (0, end_time = {end_time} s]")
    prob = _setup(inner_radius, outer_radius, C, alpha, kappa, mesh)
    C, p0, tr = float(C), float(pressure), float(ramp_time)
    beta = np.array([float(b) for b, _ in br])
    tau = np.array([float(t) for _, t in br])
    schedule = ramp_hold_schedule(
        tr, float(end_time), n_ramp=int(n_ramp), n_hold=int(n_hold), first_hold=first_hold, breakpoints=list(ts)
    )
    lam_at = lambda t: p0 / C * min(t / tr, 1.0)
    on_ramp = lambda t: t <= tr * (1 + 1e-12)

    tried = [0.0]  # the last time a step was tried (for the failure message)

    def step(t0, s: _CreepState, t1, prev):
        tried[0] = t1
        dt = t1 - t0
        iso_scale, extra = ve.algorithmic(s.visco, beta, tau, dt)
        lam = lam_at(t1)
        guess = s.x
        if prev is not None and on_ramp(t1) == on_ramp(t0) and on_ramp(prev[0]) == on_ramp(t0):
            # secant predictor in time, within one segment (ramp or hold) of the history
            cand = s.x + (s.x - prev[1].x) * dt / (t0 - prev[0])
            if prob.admissible(cand) is None:
                guess = cand
        load = f"t = {t1:.6g} s, p = {lam * C:.6g} Pa"
        sol = prob.solve(lam, guess, rtol, load, iso_scale, extra)
        S_new = prob.asm.iso_S(prob.full(sol.x), prob.mat)
        return _CreepState(sol.x, ve.update(s.visco, beta, tau, dt, S_new), lam, iso_scale, extra), sol.iterations

    s0 = _CreepState(np.zeros(prob.free.size), ve.initial_state(beta.size, prob.asm.w.shape + (5,)), 0.0, 1.0, None)
    try:
        steps = march(step, s0, schedule)
    except NewtonError as err:
        t_fail = tried[0]
        if t_fail > tr * (1 + 1e-12):
            why = (
                f"no equilibrium of the viscoelastic shell under the held pressure {p0:g} Pa near "
                f"t = {t_fail:.6g} s: it creeps past its limit point (bursts)"
            )
            hint = (
                "compare the held pressure with the limit point of the relaxed shell (C), e.g. "
                "reduced.blastula.limit_point; lower the pressure or end the hold earlier"
            )
        else:
            why = (
                f"no equilibrium on the pressure ramp near t = {t_fail:.6g} s (p = {lam_at(t_fail) * C:.6g} Pa): "
                "the shell passes its limit point while loading"
            )
            hint = (
                "compare the pressure with the limit point of the instantaneous shell ((1 + sum beta) C), "
                "e.g. reduced.blastula.limit_point; lower the pressure"
            )
        raise NewtonError(why, load=err.load, residuals=err.residuals, hint=hint) from err
    last = steps[-1].state
    return prob.result(
        [st.state.lam for st in steps],
        [st.state.x for st in steps],
        [st.iterations for st in steps],
        [st.wall_s for st in steps],
        C,
        "creep",
        last.iso_scale,
        last.extra_S,
        all_fields=[(float(st.t), st.state.iso_scale, st.state.extra_S) for st in steps] if store_fields else None,
        time=np.array([st.t for st in steps]),
        parameters=dict(
            inner_radius=float(inner_radius),
            outer_radius=float(outer_radius),
            C=C,
            alpha=float(alpha),
            kappa=float(kappa),
            branches=tuple((float(b), float(t)) for b, t in br),
            pressure=p0,
            ramp_time=tr,
            end_time=float(end_time),
        ),
    )
