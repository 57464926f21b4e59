r"""FE blastula: a hollow Fung sphere inflated by a follower pressure (seed Figs 1-5).

:func:`inflate` (elastic, load control or arc-length through limit points) and :func:`creep` (generalized
Maxwell branches under a pressure ramp-and-hold). Quarter wall section A <= rho <= B, 0 <= theta <= 90 deg
(u_z = 0 on Z = 0, u_r = 0 on the axis), mixed Q2/P1-discontinuous elements, follower pressure on the
deformed inner surface; lengths scaled by A and stresses by C inside (``fem.problem.SceneProblem``).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from tissuemech.fem import sensitivity as sens
from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.continuation import LimitPointError, arc_length, load_control
from tissuemech.fem.forms import Material
from tissuemech.fem.linalg import Reuse, Symmetric, sparse_solve
from tissuemech.fem.mesh import AxiMesh, shell_section
from tissuemech.fem.newton import NewtonError, newton
from tissuemech.fem.output import BlastulaField, BlastulaResult
from tissuemech.fem.problem import BLASTULA_MARGIN, SceneProblem, check_mesh, mesh_spec, roundoff_floor, secant
from tissuemech.fem.timestepping import march, ramp_hold_schedule
from tissuemech.reduced.material import validate_branches, validate_material, validate_positive, validate_radii
from tissuemech.reduced.validation import validate_choice, validate_finite

__all__ = [
    "inflate",
    "creep",
    "shell_problem",
    "ThickWallWarning",
    "warn_thick_wall",
    "ShellProblem",
    "MESHES",
    "SHELL_ORDERING",
    "LimitPointError",
    "NewtonError",
    "LockingWarning",
]

MESHES = {"coarse": (2, 4), "default": (4, 8), "fine": (8, 16)}
LOCKING_RATIO = 100.0  # displacement-only elements lock (overly stiff) beyond kappa/C ~ 1e2


class LockingWarning(UserWarning):
    """formulation='displacement' with a nearly incompressible material: the answer is locked (too stiff)."""


# The blastula's linear solver: SuperLU in symmetric mode (issue 14: 2x fewer fill-ins than COLAMD) with the
# supervariable minimum-degree ordering (20-45 % fewer factorisation flops than MMD on the fine shells:
# ``python -m tissuemech.compare.bench fem-perf``), the same answer to round-off; kept across the steps of a run.
SHELL_ORDERING = "supervariable"


# The Gauss rule of the scene's Q2 shell meshes: 3 x 3 points (degree 4), as FElupe's biquadratic quads. Against the
# 4 x 4 rule (degree 6, the mesh builder's default), on the seed's six sets: 4x8 off a 24x48 reference by 3.2e-6 -
# 4.8e-5 (4 x 4: 3.2e-6 - 5.3e-5), 8x16 by 1.8e-7 - 3.8e-6 (4 x 4: 1.8e-7 - 3.9e-6), 10-30 % less time per sweep
# (measured in issue 14); the Richardson limit of 8x16 / 16x32 / 32x64 moves by 1.3e-10
# (`python -m tissuemech.compare.bench felupe --blastula-reference`).
SHELL_GAUSS_DEGREE = 4


def _make_mesh(mesh, A: float, B: float) -> AxiMesh:
    """The shell mesh of a ``mesh`` argument: a name of ``MESHES``, divisions (n_radial, n_circ) or an
    ``AxiMesh`` built with length_scale = A (m); B (m) the outer radius. Raises ValueError otherwise."""
    if isinstance(mesh, AxiMesh):
        return check_mesh(mesh, A, "the mesh object must be built with length_scale = inner_radius")
    mesh = mesh_spec(mesh, MESHES, "a tuple (n_radial, n_circ) or a mesh object")
    if (
        not isinstance(mesh, (tuple, list))
        or len(mesh) != 2
        or not all(isinstance(n, (int, np.integer)) and n >= 1 for n in mesh)
    ):
        raise ValueError(f"mesh divisions must be two positive integers (n_radial, n_circ), got {mesh!r}")
    return shell_section(A, B, int(mesh[0]), int(mesh[1]), intorder=SHELL_GAUSS_DEGREE)


class _Stretches(NamedTuple):
    inner: float  # a/A
    outer: float  # b/B


class ShellProblem(SceneProblem):
    """The scaled blastula equations r(u, p) = f_int(u) - p f_p(u) on the free dofs.

    ``iso_scale``/``extra_S`` (``fem.viscoelastic.algorithmic``) add the Maxwell branch stresses of a
    time step; the defaults are the elastic shell. ``ref`` = |f_p| at unit pressure (the force scale),
    ``floor`` = the round-off floor of the residual (``fem.problem.roundoff_floor`` over ``ref``).
    Unlike :class:`SceneProblem`, states here are vectors of the FREE dofs (``full`` expands them)."""

    def __init__(self, m: AxiMesh, mat: Material, formulation: str = "mixed", beta=(), tau=()):
        super().__init__(m, mat, formulation, beta, tau)
        self.inner = m.edges["inner"]
        self.ref = float(np.linalg.norm(self.rk(np.zeros(self.free.size), 0.0, tangent=False)[2]))
        self.floor = roundoff_floor(mat.kappa, self.ref, BLASTULA_MARGIN)
        # the factorisation kept across the steps of a run (quasi-Newton steps first)
        self.linear = Reuse(Symmetric(ordering=SHELL_ORDERING))
        self.keep = self.linear.kept

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
            linear=self.linear,
            stagnation=True,  # thin walls (B ~ 1.001 A): the tangent's round-off keeps the corrections above xtol
        )

    def load_tangent(self, lam, uf):
        """dx/dlam at the converged state ``uf`` (free dofs; lam unused: f_p is the follower force at unit
        pressure): K dx/dlam = f_p with the factorisation kept from the solve that just ended (the tangent of a
        state on its Newton path: ``load_control``'s Euler predictor); None when that solve factored nothing
        (Broyden steps on an older factorisation, whose slope predicts worse than the secant)."""
        kept = self.linear.kept
        solve = kept.solve if kept is not None else None
        if kept is None or solve is None or kept.n != uf.size or kept.age != 0:
            return None
        fp, _ = self.asm._follower_values(self.full(uf), 1.0, self.inner, tangent=False)
        try:
            t = getattr(solve, "unrefined", solve)(fp[self.free])
        except (np.linalg.LinAlgError, RuntimeError, ValueError):  # a failed solve predicts nothing: the secant does
            return None
        return t if np.all(np.isfinite(t)) else None

    def residual_at(self, uf, lam: float, mat: Material) -> np.ndarray:
        """The scaled residual r(u, lam) on the free dofs with the material ``mat`` (no tangent)."""
        ri, fp, _ = self.asm.internal_follower(self.full(uf), mat, lam, self.inner, free=self.free, tangent=False)
        return (ri - lam * fp)[self.free]

    def sensitivities(self, uf, lam: float, C: float) -> dict[str, float]:
        """d inner_stretch / d C (1/Pa) and / d alpha of the converged state ``uf`` at the fixed pressure
        p = lam C (``fem.sensitivity``: one factorisation of the converged tangent; lam = p / C and the scaled
        bulk modulus k = kappa / C both move with C)."""
        mat = self.mat
        kept = self.linear.kept
        factored = None  # the factorisation Newton holds (of this state or a nearby one: refined against K)
        if kept is not None and kept.solve is not None and kept.n == uf.size:
            factored = getattr(kept.solve, "unrefined", kept.solve)
        _, K, dr_dlam = self.rk(uf, lam, tangent=True)
        dr_dk = sens.residual_derivative(lambda k: self.residual_at(uf, lam, mat._replace(kappa=k)), mat.kappa)
        dr_da = sens.residual_derivative(lambda a: self.residual_at(uf, lam, mat._replace(alpha=a)), mat.alpha)
        rhs = {"C": (dr_dlam * (-lam) + dr_dk * (-mat.kappa)) / C, "alpha": dr_da}
        dx = sens.solve_all(K, rhs, f"p = {lam * C:.6g} Pa", factored)
        return {name: sens.directional(self.inner_stretch, uf, v) for name, v in dx.items()}

    def admissible(self, uf):
        """:meth:`SceneProblem.admissible` of the free dofs ``uf`` (J > 0 and hoop stretch > 0)."""
        return super().admissible(self.full(uf))

    def inner_stretch(self, uf) -> float:
        """a/A: the mean deformed / reference radius over the inner surface (area weights 2 pi R ds)."""
        return self.asm.surface_mean_stretch(self.full(uf), self.inner)

    def stretches(self, uf) -> _Stretches:
        """Mean deformed / reference radius over the inner and the outer surface (dimensionless)."""
        u = self.full(uf)
        return _Stretches(
            self.asm.surface_mean_stretch(u, self.inner), self.asm.surface_mean_stretch(u, self.m.edges["outer"])
        )

    def field(self, x, C, iso_scale: float = 1.0, extra_S=None):
        """(displacement (N, 2) [m], element von Mises [Pa], element hydrostatic pressure [Pa]) of the
        scaled state ``x`` (free dofs), with its step's branch stresses."""
        xf = self.full(x)
        _, vm, q = self.point_stresses(xf, extra_S, iso_scale)
        return (self.displacement(xf), *self.element_fields(vm, q, C))

    def result(
        self, lam, xs, its, wall, C, method, iso_scale: float = 1.0, extra_S=None, all_fields=None, **extra
    ) -> BlastulaResult:
        """BlastulaResult (SI) from the scaled states ``xs`` (free dofs) at scaled pressures ``lam``;
        the fields are those of the last state (with its step's branch stresses). ``all_fields``: None,
        or one ``_StepStress`` (time [s] or None, iso_scale, extra_S) per state to keep the fields of every step."""
        st = [self.stretches(x) for x in xs]
        inner, outer = np.array([s.inner for s in st]), np.array([s.outer for s in st])
        u, vm, ph = self.field(xs[-1], C, iso_scale, extra_S)
        fields = None
        if all_fields is not None:
            fields = []
            for x, l, st in zip(xs, lam, all_fields):
                uk, vmk, phk = self.field(x, C, st.iso_scale, st.extra_S)
                fields.append(BlastulaField(float(l) * C, st.time, uk, self.deformed_nodes(uk), vmk, phk))
        return BlastulaResult(
            pressure=np.asarray(lam, float) * C,
            inner_stretch=inner,
            outer_stretch=outer,
            newton_iterations=np.asarray(its, int),
            wall_time=np.asarray(wall, float),
            mesh=self.m,
            displacement=u,
            deformed_nodes=self.deformed_nodes(u),
            hydrostatic_pressure=ph,
            von_mises=vm,
            method=method,
            fields=fields,
            **extra,
        )


class _StepStress(NamedTuple):
    """The branch stresses a stored state was solved with (for its fields)."""

    time: float | None  # s (creep runs; None for load-controlled and arc-length runs)
    iso_scale: float
    extra_S: object


_ELASTIC = _StepStress(None, 1.0, None)


def shell_problem(
    inner_radius, outer_radius, C, alpha, kappa=2.2e9, mesh="default", formulation: str = "mixed", beta=(), tau=()
) -> ShellProblem:
    """The scaled shell problem (lengths / A, stresses / C) of :func:`inflate`'s arguments (validated: radii [m],
    C [Pa], alpha, kappa [Pa], mesh, formulation; Maxwell branches ``beta``, ``tau`` [s] for creep)."""
    validate_radii(inner_radius, outer_radius)
    validate_material(C, alpha, kappa)
    A, B = float(inner_radius), float(outer_radius)
    m = _make_mesh(mesh, A, B)
    return ShellProblem(m, Material(1.0, float(alpha), float(kappa) / float(C)), formulation, beta, tau)


THICK_WALL = 3.0  # B/A beyond which the uniform shell meshes lose accuracy (measured below)


class ThickWallWarning(UserWarning):
    """The wall is thicker than the shell meshes are made for (B/A <= 1.5, accurate to B/A ~ 3)."""


def warn_thick_wall(inner_radius: float, outer_radius: float, mesh) -> None:
    """Warn where B/A > THICK_WALL on the built-in meshes (uniform through the wall, made for the seed's walls):
    at an inner stretch of 1.5 the error of lambda_a - 1 is 1.1e-5 (default mesh) at B/A = 1.5, 4.9e-5 (fine) at
    3, 1.4e-2 at 10 and 67 % at 100 (``tissuemech bench acceptance thick-shell``). A mesh object passed in is
    the caller's choice: no warning."""
    ratio = float(outer_radius) / float(inner_radius)
    if ratio > THICK_WALL and not isinstance(mesh, AxiMesh):
        warnings.warn(
            f"outer_radius / inner_radius = {ratio:.3g}: the built-in shell meshes are uniform through the wall and "
            "made for B/A <= 1.5; the inner stretch error grows to ~1e-2 at B/A = 10 and 67 % at 100. Pass a mesh "
            "graded toward the cavity (mesh=AxiMesh) or use the exact shell, tissuemech.reduced.blastula",
            ThickWallWarning,
            stacklevel=3,
        )


def inflate(
    *,
    inner_radius: float,
    outer_radius: float,
    C: float,
    alpha: float,
    pressures: Sequence[float] | np.ndarray | None,
    kappa: float = 2.2e9,
    mesh: str | Sequence[int] | AxiMesh = "default",
    method: str = "load",
    max_inner_stretch: float | None = None,
    rtol: float = 1e-10,
    formulation: str = "mixed",
    store_fields: bool = False,
    gradient: bool = False,
) -> BlastulaResult:
    """Inflate the hollow sphere by a cavity pressure p acting on its deformed inner surface.

    Solves f_int(u) = p f_p(u) on the quarter wall section (the exact incompressible shell is
    ``tissuemech.reduced.blastula``). The stretches are surface means of deformed / reference radius.

    Args:
        inner_radius: reference radius A of the wall's inner surface (m).
        outer_radius: reference radius B > A of its outer surface (m).
        C: Fung stiffness (Pa).
        alpha: Fung exponent (dimensionless).
        kappa: bulk modulus (Pa).
        pressures: the pressures to reach (Pa): finite, >= 0, non-decreasing. ``method="load"``: one
            result entry per value (steps are subdivided internally when Newton struggles).
            ``method="arclength"``: only its first positive entry is used, as the first step; None for an
            automatic first step that raises the inner stretch by ~0.02.
        mesh: "coarse", "default", "fine" (``MESHES``: (n_radial, n_circ) = (2, 4), (4, 8), (8, 16)), a
            tuple (n_radial, n_circ) or an ``AxiMesh`` from ``fem.mesh.shell_section`` built with
            length_scale = inner_radius.
        method: "load" (load control to every pressure) or "arclength" (Riks from p = 0 until the inner
            stretch reaches ``max_inner_stretch``, through limit points; steps adapt up to twice the first).
        max_inner_stretch: where the arc-length trace stops (a/A > 1, dimensionless; "arclength" only).
        rtol: Newton's relative residual tolerance (dimensionless).
        formulation: "mixed" (default) or "displacement" (locks for kappa/C >> 100: a warning says so).
        store_fields: keep the fields of every converged step in ``result.fields`` (``BlastulaField``, for
            ``result.to_pvd``); by default only the final fields are kept.
        gradient: also return the exact sensitivities of the inner stretch at each step's pressure,
            ``result.gradient = {"C": d lambda_a / d C (1/Pa), "alpha": d lambda_a / d alpha}`` (arrays over the
            steps; ``fem.sensitivity``: one extra solve with each converged tangent, the pressure held fixed).
            Undefined at a limit point (the tangent is singular there: RuntimeError naming the pressure).

    Returns:
        ``BlastulaResult`` (SI): per converged step ``pressure`` (Pa), ``inner_stretch``,
        ``outer_stretch``, ``newton_iterations``, ``wall_time`` (s); the final ``displacement`` and
        ``deformed_nodes`` (N, 2) (m), element ``von_mises`` and ``hydrostatic_pressure`` (Pa); ``method``.
        An arc-length result starts with the reference state p = 0.

    Raises:
        ValueError: an input out of range (the message names the quantity and its unit).
        LimitPointError: load control cannot pass the maximum of the pressure (use method="arclength";
            ``last_converged`` holds the last pressure reached, Pa).
        NewtonError: a step did not converge after its cut-backs (the message names the pressure).
    Warns:
        LockingWarning: formulation="displacement" with kappa/C > 100.
    """
    validate_choice("method", method, ("load", "arclength"))
    if pressures is not None:
        checked = validate_finite("pressures (the pressure levels to reach)", pressures, "Pa")
        p = np.atleast_1d(np.asarray(pressures if checked is None else checked, float))
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
    warn_thick_wall(inner_radius, outer_radius, mesh)
    validate_material(C, alpha, kappa)
    if formulation == "displacement" and float(kappa) / float(C) > LOCKING_RATIO:
        warnings.warn(
            f"formulation='displacement' locks at kappa/C = {float(kappa) / float(C):.3g} (kappa = {float(kappa):g} Pa, "
            f"C = {float(C):g} Pa): the shell comes out far too stiff (e.g. inner stretch 1.002 instead of 1.116 "
            "at 100 Pa for the seed's kappa = 2.2 GPa). Use formulation='mixed' (the default)",
            LockingWarning,
            stacklevel=2,
        )
    prob = shell_problem(inner_radius, outer_radius, C, alpha, kappa, mesh, formulation)
    u0 = np.zeros(prob.free.size)
    ref, floor = prob.ref, prob.floor

    sensitivity: dict[float, dict[str, float]] = {}  # per converged pressure (scaled), while its factor is kept

    def solve(lam, guess):
        sol = prob.solve(lam, guess, rtol, load=f"p = {lam * C:.6g} Pa")
        if gradient:
            sensitivity[float(lam)] = prob.sensitivities(sol.x, float(lam), float(C))
        return sol

    if method == "load":
        steps = load_control(
            solve, p / C, u0, monitor=prob.inner_stretch, unit=" Pa", scale=C, tangent=prob.load_tangent
        )
        lam = np.array([s.load for s in steps])
        xs = [s.x for s in steps]
        its = np.array([s.newton_iterations for s in steps])
        wall = np.array([s.wall_time for s in steps])
    else:
        pos = p[p > 0] if pressures is not None else np.array([])
        if pos.size:
            dp = pos[0] / C
        else:  # automatic: a first step that raises the inner stretch by ~ 0.02 (linear estimate)
            _, K0, rl0 = prob.rk(u0, 0.0)
            t = sparse_solve(K0, -rl0)
            dp = 0.02 / max((prob.inner_stretch(1e-6 * t) - 1.0) / 1e-6, 1e-12)
        ds = np.sqrt(2.0) * dp  # the first tangent has equal parts in |x|/c and the load
        stop_at = float(max_inner_stretch)  # type: ignore[arg-type]  # checked > 1 above
        steps = arc_length(
            lambda x, l: prob.rk(x, l),
            u0,
            0.0,
            ds,
            stop=lambda x, l: prob.inner_stretch(x) >= stop_at,
            admissible=prob.admissible,
            ref_norm=ref,
            rtol=rtol,
            atol=floor,
            ds_max=2 * ds,
        )
        lam = np.array([0.0] + [s.load for s in steps])
        xs = [u0] + [s.x for s in steps]
        its = np.array([0] + [s.newton_iterations for s in steps])
        wall = np.array([0.0] + [s.wall_time for s in steps])
    grad = None
    if gradient:
        per_step = [
            sensitivity[float(lk)] if float(lk) in sensitivity else prob.sensitivities(x, float(lk), float(C))
            for x, lk in zip(xs, lam)
        ]
        grad = {name: np.array([g[name] for g in per_step]) for name in ("C", "alpha")}
    res = prob.result(lam, xs, its, wall, C, method, all_fields=[_ELASTIC] * len(xs) if store_fields else None)
    res.gradient = grad
    return res


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
    mesh: str | Sequence[int] | AxiMesh = "default",
    times: Sequence[float] = (),
    n_ramp: int = 8,
    n_hold: int = 60,
    first_hold: float | None = None,
    rtol: float = 1e-10,
    store_fields: bool = False,
) -> BlastulaResult:
    r"""Creep of the viscoelastic shell under the ramp-and-hold pressure p(t) = pressure min(t / ramp_time, 1).

    Generalized Maxwell branches on the isochoric stress (``fem.viscoelastic``: dQ_m/dt + Q_m/tau_m =
    beta_m dS_iso/dt, exact exponential update for S_iso linear over a step). Every step solves
    r(u, t_{n+1}) = f_int(u; iso_scale, extra_S) - p(t_{n+1}) f_p(u) = 0 with the algorithmic stress
    S = S_vol + (1 + sum_m beta_m g_m) S_iso + sum_m (e^{-h_m} Q_m^n - beta_m g_m S_iso^n), then updates
    the Q_m; quasi-static (``fem.timestepping``; a failed step is halved). No branches (or beta = 0) is
    the elastic shell at every step.

    Args:
        inner_radius: reference radius A of the wall's inner surface (m).
        outer_radius: reference radius B > A of its outer surface (m).
        C: Fung stiffness (Pa) of the relaxed (long-time) shell.
        alpha: Fung exponent (dimensionless).
        kappa: bulk modulus (Pa).
        branches: [(beta_m, tau_m), ...]: energy factors beta_m >= 0 (dimensionless) and relaxation
            times tau_m > 0 (s).
        pressure: the held cavity pressure (Pa, > 0).
        ramp_time: the ramp's duration (s, > 0).
        end_time: the end of the hold (s, >= ramp_time).
        mesh: as for :func:`inflate`.
        times: extra step times (s, in (0, end_time]), merged into the schedule.
        n_ramp: equal steps on the ramp.
        n_hold: geometrically growing steps through the hold, the first ``first_hold`` long.
        first_hold: the first hold step (s; default ramp_time / 2).
        rtol: Newton's relative residual tolerance.
        store_fields: keep the fields of every converged step (``BlastulaField`` with its time).

    Returns:
        ``BlastulaResult`` with ``method="creep"``: per converged step ``time`` (s), ``pressure`` (Pa),
        ``inner_stretch``, ``outer_stretch``, ``newton_iterations``, ``wall_time`` (s); the fields at
        ``end_time``; ``parameters`` records the inputs.

    Raises:
        ValueError: an input out of range (the message names the quantity and its unit).
        NewtonError: no equilibrium at some step: on the ramp the shell passes its instantaneous limit
            point, in the hold a pressure above the relaxed limit point makes it creep past it (it bursts);
            the message names the time.
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
    beta = np.array([float(b) for b, _ in br])
    tau = np.array([float(t) for _, t in br])
    prob = shell_problem(inner_radius, outer_radius, C, alpha, kappa, mesh, beta=beta, tau=tau)
    warn_thick_wall(inner_radius, outer_radius, mesh)
    C, p0, tr = float(C), float(pressure), float(ramp_time)
    schedule = ramp_hold_schedule(
        tr, float(end_time), n_ramp=int(n_ramp), n_hold=int(n_hold), first_hold=first_hold, breakpoints=list(ts)
    )
    lam_at = lambda t: p0 / C * min(t / tr, 1.0)
    on_ramp = lambda t: t <= tr * (1 + 1e-12)

    tried = [0.0]  # the last time a step was tried (for the failure message)

    def step(t0, s: _CreepState, t1, prev):
        tried[0] = t1
        dt = t1 - t0
        iso_scale, extra = prob.maxwell_factors(s.visco, dt)
        lam = lam_at(t1)
        guess = s.x
        if prev is not None and on_ramp(t1) == on_ramp(t0) and on_ramp(prev.time) == on_ramp(t0):
            # secant predictor in time, within one segment (ramp or hold) of the history
            cand = secant(s.x, prev.state.x, dt, t0 - prev.time)
            if prob.admissible(cand) is None:
                guess = cand
        load = f"t = {t1:.6g} s, p = {lam * C:.6g} Pa"
        sol = prob.solve(lam, guess, rtol, load, iso_scale, extra)
        visco = prob.maxwell_update(s.visco, dt, prob.full(sol.x))
        return _CreepState(sol.x, visco, lam, iso_scale, extra), sol.iterations

    s0 = _CreepState(np.zeros(prob.free.size), prob.maxwell_initial(), 0.0, 1.0, None)
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
        [st.newton_iterations for st in steps],
        [st.wall_time for st in steps],
        C,
        "creep",
        last.iso_scale,
        last.extra_S,
        all_fields=[_StepStress(float(st.time), st.state.iso_scale, st.state.extra_S) for st in steps]
        if store_fields
        else None,
        time=np.array([st.time for st in steps]),
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


# the names of release 0.1 (compare.bench.fem_perf reaches into them)
_Problem = ShellProblem
_setup = shell_problem
