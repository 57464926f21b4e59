r"""FE blastula: a hollow Fung sphere inflated by a follower pressure (seed Figs 1-5).

``inflate(*, inner_radius, outer_radius, C, alpha, pressures, kappa=2.2e9, mesh="default",
method="load", max_inner_stretch=None, rtol=1e-10) -> BlastulaResult``

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
"""

from __future__ import annotations

import time
from typing import Sequence, Union

import numpy as np

from reduced.material import validate_material, validate_radii
from fem import constitutive as cm
from fem.continuation import LimitPointError, arc_length, load_control
from fem.forms import Assembler, Material
from fem.kinematics import invariants
from fem.mesh import AxiMesh, shell_section
from fem.newton import newton, sparse_solve
from fem.output import BlastulaResult

__all__ = ["inflate", "MESHES", "LimitPointError"]

MESHES = {"coarse": (2, 4), "default": (4, 8), "fine": (8, 16)}


def _make_mesh(mesh, A: float, B: float) -> AxiMesh:
    if isinstance(mesh, AxiMesh):
        if abs(mesh.length_scale - A) > 1e-12 * A:
            raise ValueError("the mesh object must be built with length_scale = inner_radius")
        return mesh
    if isinstance(mesh, str):
        if mesh not in MESHES:
            raise ValueError(f"mesh must be 'coarse', 'default', 'fine', a tuple (n_radial, n_circ) or a mesh object, got {mesh!r}")
        mesh = MESHES[mesh]
    if (not isinstance(mesh, (tuple, list)) or len(mesh) != 2
            or not all(isinstance(n, (int, np.integer)) and n >= 1 for n in mesh)):
        raise ValueError(f"mesh divisions must be two positive integers (n_radial, n_circ), got {mesh!r}")
    return shell_section(A, B, int(mesh[0]), int(mesh[1]))


class _Problem:
    """The scaled blastula equations r(u, p) = f_int(u) - p f_p(u) on the free dofs."""

    def __init__(self, m: AxiMesh, mat: Material, formulation: str = "mixed"):
        self.m, self.mat = m, mat
        self.asm = Assembler(m, formulation)
        fixed = np.concatenate([2 * m.nodes["axis"], 2 * m.nodes["symmetry"] + 1])
        self.free = np.setdiff1d(np.arange(self.asm.ndof), fixed)
        self.inner = m.edges["inner"]

    def full(self, uf):
        u = np.zeros(self.asm.ndof)
        u[self.free] = uf
        return u

    def rk(self, uf, p, tangent=True):
        u = self.full(uf)
        ri, Ki = self.asm.internal(u, self.mat, tangent=tangent)
        fp, Kp = self.asm.follower_pressure(u, 1.0, self.inner, tangent=tangent)
        r = (ri - p * fp)[self.free]
        if not tangent:
            return r, None, -fp[self.free]
        K = (Ki - p * Kp).tocsr()[self.free][:, self.free]
        return r, K, -fp[self.free]

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
        return (self.asm.surface_mean_stretch(u, self.m.edges["inner"]),
                self.asm.surface_mean_stretch(u, self.m.edges["outer"]))


def inflate(*, inner_radius: float, outer_radius: float, C: float, alpha: float,
            pressures: Union[Sequence[float], np.ndarray, None], kappa: float = 2.2e9,
            mesh="default", method: str = "load", max_inner_stretch: float | None = None,
            rtol: float = 1e-10, formulation: str = "mixed") -> BlastulaResult:
    """Inflate the hollow sphere; see the module docstring. SI units (m, Pa)."""
    validate_radii(inner_radius, outer_radius)
    validate_material(C, alpha, kappa)
    if method not in ("load", "arclength"):
        raise ValueError(f"method must be 'load' or 'arclength', got {method!r}")
    if pressures is not None:
        p = np.atleast_1d(np.asarray(pressures, dtype=float))
        if p.ndim != 1 or p.size == 0 or not np.all(np.isfinite(p)):
            raise ValueError("pressures must be a non-empty 1D list of finite values in Pa")
        if np.any(p < 0):
            raise ValueError("pressures must be >= 0 Pa (the cavity pressure inflates the shell)")
        if np.any(np.diff(p) < 0):
            raise ValueError("pressures must be sorted in increasing order (a loading sweep)")
    elif method == "load":
        raise ValueError("method='load' needs the list of pressures (Pa) to reach")
    if method == "arclength":
        if max_inner_stretch is None or not np.isfinite(max_inner_stretch) or max_inner_stretch <= 1:
            raise ValueError("method='arclength' needs max_inner_stretch > 1 (where to stop the trace)")
    A, B = float(inner_radius), float(outer_radius)
    m = _make_mesh(mesh, A, B)
    prob = _Problem(m, Material(1.0, float(alpha), float(kappa) / float(C)), formulation)
    u0 = np.zeros(prob.free.size)
    ref = float(np.linalg.norm(prob.rk(u0, 0.0, tangent=False)[2]))  # |f_p| at unit pressure
    # round-off floor of the residual: kappa/C times eps times the force scale (plus the load)
    floor = 1e3 * np.finfo(float).eps * max(prob.mat.kappa, 1.0) * ref

    def solve(lam, guess):
        return newton(lambda x: prob.rk(x, lam)[:2], guess, ref_norm=ref * max(lam, 1e-3), rtol=rtol,
                      xtol=1e-9, atol=floor * (1 + lam), admissible=prob.admissible, load=f"p = {lam * C:.6g} Pa")

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
        steps = arc_length(lambda x, l: prob.rk(x, l), u0, 0.0, ds,
                           stop=lambda x, l: prob.stretches(x)[0] >= max_inner_stretch,
                           admissible=prob.admissible, ref_norm=ref, rtol=rtol, atol=floor, ds_max=2 * ds)
        lam = np.array([0.0] + [s[0] for s in steps])
        xs = [u0] + [s[1] for s in steps]
        its = np.array([0] + [s[2] for s in steps])
        wall = np.array([0.0] + [s[3] for s in steps])
    st = np.array([prob.stretches(x) for x in xs])
    u = prob.full(xs[-1])[:prob.asm.n_u].reshape(-1, 2) * A
    f, P, _, q = prob.asm.stress(prob.full(xs[-1]), prob.mat)
    vm = cm.von_mises(cm.cauchy(f, P)) * C
    wq = prob.asm.w
    return BlastulaResult(pressure=lam * C, inner_stretch=st[:, 0], outer_stretch=st[:, 1],
                          newton_iterations=its, wall_time=wall, mesh=m, displacement=u,
                          deformed_nodes=m.X.T * A + u,
                          hydrostatic_pressure=-(q * wq).sum(1) / wq.sum(1) * C,
                          von_mises=(vm * wq).sum(1) / wq.sum(1), method=method)
