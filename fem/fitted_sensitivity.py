r"""Exact parameter sensitivities of a time run on contact-edge-fitted meshes (issue 38).

A fitted time step n is the state x_n on the mesh m(e_n) whose surface node sits at the contact edge e_n, with the
step's algorithmic Maxwell stress from the history H_n(m(e_n)) before the step (``fem.contact.history_before``:
the replay of every past step's stress field from its own mesh while the plate moves, the previous step's history
interpolated while it is held). Every step satisfies

    r(x_n; m(e_n), theta, H_n(m(e_n); past, theta)) = 0,        phi(x_n, e_n) = N_edge / F = 0,

so the tangent-linear step is, per parameter theta (the active set held, the plate held):

    K dx + r_e de = -dr/dtheta|_(x, e),     dphi/dx dx + dphi/de de = -dphi/dtheta,

with dr/dtheta|_(x, e) holding the history's sensitivity to every past state and edge. The mesh moves with its edge
by V = dX / d ln e at its nodes (from the fitted meshes' nodes at e (1 -+ h), ``fem.mesh.fitted_nodes``, h =
``fem.spheroid.EDGE_STEP``; no mesh or basis is built): r_e is the central difference of the residual ASSEMBLY on
the meshes X -+ h V (``fem.forms.Assembler.moved``: the isoparametric map's Jacobian (I + eps grad V) dX/dxi, exact;
the plate dofs re-imposed on the moved plate, the history moved with the points), the state held: no nonlinear
solve is differenced. The history's sensitivity on a fixed mesh is linear in the past steps' sensitivities:

* "replay": the Maxwell recursion run on the transferred stress fields of every past step k and on their
  sensitivities, T_{m_k -> m}(dS_k) + de_k d/d ln e_k T_{m_k -> m}(S_k): the second term is the motion of the past
  step's own mesh (its nodes by V_k, and the stress of its held displacement there), the exact derivative of the
  continuous interpolation (``fem.transfer.ContinuousJet``);
* "transfer" (the plate held): T_{H -> m}(dH) + de_H d/d ln e_H T_{H -> m}(H), dH the total sensitivity of the
  previous step's history values (their mesh's motion included), the element-wise interpolation's exact
  derivative in its source's motion (``fem.transfer.ElementJet``).

The motion of m itself (the target of the interpolation: its Gauss points by V) is carried by r_e through the
same jets. Each step's tangent is refined from Newton's kept factorisation, all parameters and the edge column as
one block (``fem.sensitivity.solve_block``).

Under force control the plate's motion dd/dtheta is a third unknown of the step, with dF = df_target/dtheta.
With a surface tension gamma (a parameter too) the edge condition is the slope dz/dr = 0 at the edge node
(``fem.contact.edge_slope``), linearised exactly in the state and by the moved plate in the edge (the surface
energy moved with the mesh, ``fem.surface.SurfaceTension.moved``). Scope:
history="replay" (the default), every step with fitted contact (no node-by-node steps beyond the fitted range, no
lost contact), a non-wetting plate (contact angle pi); other runs raise ValueError naming the step.
Verified against central differences of whole runs with a tight edge tolerance
(``tests/test_fem_fitted_sensitivity.py``, ``python -m tissuemech.compare.bench.fem_gradient --only-fitted``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
import scipy.sparse as sp

from tissuemech.fem import sensitivity as sens
from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.contact import HistorySource, PlateStep, edge_slope, edge_slope_change
from tissuemech.fem.mesh import AxiMesh, fitted_nodes
from tissuemech.fem.transfer import ContinuousJet, ElementJet, located, own_points, points_in

__all__ = ["FittedTimeSensing", "SENSITIVITY_TOL"]


def _both(t: Callable[[np.ndarray], np.ndarray], Q: np.ndarray, S: np.ndarray, axis: int = 0):
    """(t(Q), t(S)) by one call of the Gauss-point map t: Q has the branches' axis at ``axis``, S has none."""
    QS = t(np.concatenate([Q, np.expand_dims(S, axis)], axis=axis))
    n = Q.shape[axis]
    return QS[(slice(None),) * axis + (slice(0, n),)], QS[(slice(None),) * axis + (n,)]


SENSITIVITY_TOL = 1e-10  # relative residual of the block solves (the edge's share is a small difference of them)
REFACTOR_AFTER = 4  # refinement iterations after which the next step's tangent is factored afresh


class _Entry(NamedTuple):
    """An accepted fitted step as later steps' histories see it: its mesh and that mesh's nodal motion with its edge
    V (d X / d ln e, (2, n_nodes)), its stress S_iso, the stress's derivative in its own edge S_e (d / d ln e, the
    held displacement on the moving mesh), its sensitivity on its fixed mesh dS (P, ...) and its edge's d ln e /
    d theta (P,)."""

    mesh: AxiMesh
    V: np.ndarray
    S: np.ndarray
    S_e: np.ndarray
    dS: np.ndarray
    de: np.ndarray


class _Motion(NamedTuple):
    """A fitted mesh's motion with its edge e: V = d X / d ln e at the nodes (2, n_nodes) and Vq at the Gauss points
    (2, n), and the problem's assembler and plate on the meshes X -+ h V (``fem.forms.Assembler.moved``)."""

    V: np.ndarray
    Vq: np.ndarray
    lo: tuple[Any, Any]
    hi: tuple[Any, Any]


class FittedTimeSensing:
    """Forward sensitivities through the steps of a fitted time run (see the module docstring), taken as the march
    accepts each step (:meth:`wrap`). ``fit``: the run's ``fem.contact.EdgeSearch``; ``names`` / ``which`` as in
    ``fem.spheroid``'s node-by-node sensing; ``edge_step`` the relative step of the moved meshes. ``force_control``:
    the plate force is prescribed: one more column (the plate moved, every held node's u_z by -1) and, per parameter,
    the edge's and the plate's motion (de, dd) from dF = df_target and dphi = 0. ``out``: per accepted step
    {name: (dF, dr_mid, dd)} (scaled; dd = 0 under displacement control, dF = df_target under force control)."""

    def __init__(
        self,
        fit: Any,
        names: list[str],
        which: dict[str, tuple[str, int]],
        beta: np.ndarray,
        tau: np.ndarray,
        long_time: float,
        edge_step: float,
        force_control: bool = False,
    ) -> None:
        self.fit, self.names, self.which, self.force_control = fit, names, which, force_control
        self.beta, self.tau, self.long_time, self.h = beta, tau, long_time, edge_step
        self.entries: list[_Entry] = []
        self.dvisco: tuple[np.ndarray, np.ndarray] | None = None  # the last step's history values' total sensitivity
        self.out: list[dict] = []
        self.kept: tuple[int, Callable] | None = None  # (size, a solve with a recent factorisation of the tangent)
        self._jets: dict[tuple[int, int], tuple] = {}  # (old, new, ElementJet) of held steps (_held_jet)
        self._motions: dict[int, tuple] = {}  # (problem, _Motion) of the recent steps' problems (_motion)
        self.refinements: list[int] = []  # per step: refinement iterations of the block solve (-1: factored)

    def wrap(self, step: Callable) -> Callable:
        """The march's step function with the sensitivities of every state it returns."""

        def sensed(t0, old, t1, prev):
            new, its = step(t0, old, t1, prev)
            self.add(new, float(t1) - float(t0), f"t = {float(t1):.6g} s")
            return new, its

        return sensed

    # ---- the mesh's motion with its edge ---------------------------------------------------------------------------
    def _motion(self, prob: Any, e: float) -> _Motion:
        """The motion of ``prob``'s fitted mesh (edge e) with its edge, kept for the next steps (while the plate is
        held the edge mostly stays where it is): V from the fitted meshes' nodes at e (1 -+ h)
        (``fem.mesh.fitted_nodes``: no basis built), the assembler (and its surface tension) and the plate moved by
        -+ h V, exact for the isoparametric map (the central differences of the residual are then those of the
        fitted meshes at e (1 -+ h) to O(h^2))."""
        key = id(prob)
        if key in self._motions and self._motions[key][0] is prob:
            return self._motions[key][1]
        h, fit = self.h, self.fit
        V = (fitted_nodes(fit.a0, fit.level, e * (1 + h)) - fitted_nodes(fit.a0, fit.level, e * (1 - h))) / (2 * h)
        asm = prob.asm
        Vq = asm.motion(V)[0].reshape(2, -1)
        moved = []
        for sign in (-1.0, 1.0):
            a = asm.moved(V, sign * h)
            if asm.surface is not None:
                asm.surface.moved(sign * h * V, a)
            moved.append((a, prob.plane.moved(sign * h * V)))
        if len(self._motions) > 8:
            self._motions.pop(next(iter(self._motions)))
        out = _Motion(V, Vq, moved[0], moved[1])
        self._motions[key] = (prob, out)
        return out

    # ---- the history's sensitivity on a fixed mesh ----------------------------------------------------------------
    def _history_tangent(self, src: HistorySource, m: AxiMesh, shape: tuple) -> tuple[np.ndarray, np.ndarray]:
        """(dQ, dS) of ``history_before(src, m)`` at m's fixed Gauss points, from the past steps' sensitivities."""
        P, nb = len(self.names), self.beta.size
        zero = (np.zeros((P, nb) + shape), np.zeros((P,) + shape))
        if src.kind == "none":
            return self.dvisco if self.dvisco is not None else zero
        if src.kind == "transfer":
            assert self.dvisco is not None and src.mesh is not None
            last = self.entries[-1]
            assert last.mesh is src.mesh, "the held step's history lives on the previous step's mesh"
            jet = self._held_jet(src.mesh, m)
            dQ, dS = self.dvisco if src.mesh is m else _both(jet.value, *self.dvisco, axis=1)
            # the history's own mesh moving with its edge (its nodes by V per ln e)
            dq, ds = _both(lambda g: jet.moved(g, None, last.V), src.state.Q, src.state.S_iso)
            de = last.de[:, None, None, None]
            return dQ + de[:, None] * dq[None], dS + de * ds[None]
        raise AssertionError("replayed histories: _replayed")

    def _held_jet(self, old: AxiMesh, new: AxiMesh) -> ElementJet:
        """The element-wise transfer of a held step's history (``fem.contact.history_before``, kind "transfer") from
        ``old`` to ``new``'s Gauss points (located as history_before locates them) with its derivatives in both
        meshes' motion, kept for the next steps (while the plate is held every step transfers between the same
        meshes)."""
        key = (id(old), id(new))
        if key not in self._jets:
            if len(self._jets) > 16:
                self._jets.pop(next(iter(self._jets)))
            (where,) = located([old], new.quadrature_points.reshape(2, -1), [own_points(new)])
            self._jets[key] = (old, new, ElementJet(old, *where, new.quadrature_points.shape[1:]))
        return self._jets[key][2]

    def _replayed(
        self, src: HistorySource, m: AxiMesh, dp: np.ndarray, shape: tuple
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(dQ, dS) of a replayed history (``fem.contact.replayed_history``) on m at its fixed Gauss points, and
        (dQ_e, dS_e): its derivative in m's own edge (d / d ln e; its Gauss points move by ``dp`` (2, n) per ln e).
        One point search of m's Gauss points in every past step's mesh; every motion (of the past step's mesh, of m's
        points) is the exact derivative of the continuous interpolation there (``fem.transfer.ContinuousJet``)."""
        path = src.path
        if len(path) != len(self.entries):
            raise ValueError("the replayed history holds steps without sensitivities (node-by-node or free steps)")
        P, nb = len(self.names), self.beta.size
        meshes: list[AxiMesh] = []
        index: dict[int, int] = {}
        for en in self.entries:
            if id(en.mesh) not in index:
                index[id(en.mesh)] = len(meshes)
                meshes.append(en.mesh)
        at = points_in(meshes, m)  # m's points in every past step's mesh (the search of the plain run's replay)
        jets = [ContinuousJet(mm, *at[i], shape[:2]) for i, mm in enumerate(meshes)]
        Q, S = np.zeros((nb,) + shape), np.zeros(shape)
        dQ, dS = np.zeros((P, nb) + shape), np.zeros((P,) + shape)
        dQe, dSe = np.zeros((nb,) + shape), np.zeros(shape)
        for k, en in enumerate(self.entries):
            dt = float(path[k][3])
            jet = jets[index[id(en.mesh)]]
            # the step's stress, its motion with its own edge (the held displacement's stress on the moved meshes),
            # its sensitivity on its fixed mesh
            nd = jet.nodal(np.concatenate([en.S[None], en.S_e[None], en.dS]))
            vals = jet.value(nd)
            Sk = vals[0]
            own = vals[1] + jet.moved(nd[:1], None, en.V)[0]  # d / d ln e_k of the transferred stress
            dSk = vals[2:] + en.de[:, None, None, None] * own[None]
            dSek = jet.moved(nd[:1], dp, None)[0]  # d / d ln e of m's points
            coef = sens.maxwell_coefficients(self.beta, self.tau, dt)
            decay, b = coef[0][:, None, None, None], coef[1][:, None, None, None]
            dQ = sens.history_update_tangent(self.names, self.which, coef, Q, S, Sk, dQ, dS, dSk)
            dQe = decay * dQe + b * (dSek - dSe)[None]
            Q = decay * Q + b * (Sk - S)[None]
            S, dS, dSe = Sk, dSk, dSek
        return dQ, dS, dQe, dSe

    # ---- one accepted step ----------------------------------------------------------------------------------------
    def add(self, new: PlateStep, dt: float, what: str) -> None:
        """The sensitivities of the accepted fitted step ``new`` (a step of dt seconds)."""
        s, prob, e, src = new.state, new.problem, float(new.edge), new.source
        if src is None or new.before is None or not np.isfinite(e) or e <= 0.0 or not s.active.any():
            raise ValueError(
                f"gradient=True on fitted meshes: the step at {what} is not a fitted contact step (node-by-node "
                "beyond the fitted range, or the contact lost): use contact='nodal' for this run"
            )
        names, which, beta, tau, h = self.names, self.which, self.beta, self.tau, self.h
        P = len(names)
        mat, asm, x = prob.mat, prob.asm, s.x
        mo = self._motion(prob, e)
        (asm_lo, plane_lo), (asm_hi, plane_hi) = mo.lo, mo.hi
        act = np.flatnonzero(s.active)
        fixed = prob.plane.dofs[act]
        keep = np.zeros(asm.ndof, bool)
        keep[prob.free] = True
        keep[fixed] = False
        U = np.flatnonzero(keep)  # the free dofs less the held ones (sorted, as numpy.setdiff1d's)
        h_plate = 1.0 - s.delta
        # the held state on the moved meshes: the same unknowns, their plate dofs on the plate
        xl, xh = plane_lo.impose(x, h_plate, s.active), plane_hi.impose(x, h_plate, s.active)
        xl[U], xh[U] = x[U], x[U]
        H0 = new.before
        f = asm.f_at(x)
        shape = f.shape
        if src.kind == "replay":  # the moved meshes' histories to first order (their central difference is exact)
            dQ, dS, dQe, dSe = self._replayed(src, prob.m, mo.Vq, shape)
        elif src.kind == "transfer":  # history_before's interpolation moving with the mesh's points
            assert src.mesh is not None
            jet = self._held_jet(src.mesh, prob.m)
            dQe, dSe = _both(lambda g: jet.moved(g, mo.Vq, None), src.state.Q, src.state.S_iso)
            dQ, dS = self._history_tangent(src, prob.m, shape)
        else:  # no history yet: the same on every mesh
            dQe, dSe = np.zeros_like(H0.Q), np.zeros_like(H0.S_iso)
            dQ, dS = self._history_tangent(src, prob.m, shape)
        H_lo = ve.MaxwellState(H0.Q - h * dQe, H0.S_iso - h * dSe)
        H_hi = ve.MaxwellState(H0.Q + h * dQe, H0.S_iso + h * dSe)

        def residual(a, xx, H) -> np.ndarray:
            iso_m, extra_m = ve.algorithmic(H, beta, tau, dt, self.long_time)
            return a.internal(xx, mat, extra_S=extra_m, iso_scale=iso_m, tangent=False)[0]

        r_e = (residual(asm_hi, xh, H_hi) - residual(asm_lo, xl, H_lo)) / (2 * h)  # per ln e
        lin = sens.IsoLinearisation(f, mat.C, mat.alpha)
        coef = sens.maxwell_coefficients(beta, tau, dt) if beta.size else None
        gamma = asm.surface.gamma if asm.surface is not None else 0.0
        R = sens.explicit_residuals(prob, x, f, lin, float(s.iso_scale), names, which, coef, dQ, dS, H0, gamma)
        R = np.column_stack([R, r_e])
        _, K = asm.internal(x, mat, extra_S=s.extra_S, iso_scale=s.iso_scale, tangent=True)
        K = sp.csr_matrix(K)
        if K.nnz == asm.pattern.nnz:  # the unknowns' block gathered from the shared pattern (as fem.spheroid's)
            src_idx, tpl = asm.pattern.restricted(U)
            KUU = tpl._with_data(K.data[src_idx], copy=False)
        else:  # the surface tangent added entries: slice
            KUU = K[U][:, U]
        # refined from this sensing's last factorisation, or Newton's where it factored during this step; a new one
        # after slow refinement (handed to Newton as its kept factor: in the hold Newton's is the ramp's)
        newton = self.fit.linear.kept
        approx = self.kept if self.kept is not None and self.kept[0] == U.size else None
        if newton is not None and newton.solve is not None and newton.age == 0 and newton.n == U.size:
            approx = (U.size, getattr(newton.solve, "unrefined", newton.solve))
        if src.kind == "replay" or (self.refinements and self.refinements[-1] >= REFACTOR_AFTER):
            approx = None  # the plate moves (the last factorisations, of other meshes and states, refined in 6+
            # iterations or not at all on Fig. 10's ramp), or the kept factorisation has drifted
        cols = -R[U]
        if (
            self.force_control
        ):  # the plate moved: u_z = h - Z on the held dofs, dh = -dd: the right-hand side K[U, fixed] 1
            cols = np.column_stack([cols, np.asarray(K[fixed].sum(axis=0)).ravel()[U]])
        dXU, solve, its = sens.solve_block(
            KUU, None if approx is None else approx[1], cols, what, tol=SENSITIVITY_TOL, max_iter=6
        )
        self.kept = (U.size, solve)
        self.refinements.append(its)
        if its < 0 and newton is not None:
            newton.store(solve, U.size)
        dX = np.zeros((asm.ndof, cols.shape[1]))
        dX[U] = dXU
        if self.force_control:
            dX[fixed, -1] = -1.0
            R = np.column_stack([R, np.zeros(asm.ndof)])
        dN = -(R[fixed] + K[fixed] @ dX)  # every held node's multiplier, per column
        F = -float(np.sum(s.residual[fixed]))
        N_edge = -float(s.residual[fixed[-1]])
        if gamma > 0:  # the edge condition of a tension: the surface leaves the plate tangentially, dz/dr = 0
            n_act = act.size  # (fem.contact.edge_slope; on the moved meshes the held displacement moves with X)
            dphi = np.array([edge_slope_change(prob.plane, x, n_act, dX[:, j]) for j in range(dX.shape[1])])
            dphi[P] += (edge_slope(plane_hi, xh, n_act) - edge_slope(plane_lo, xl, n_act)) / (2 * h)
        else:  # phi = N_edge / F
            dphi = (dN[-1] - N_edge / F * dN.sum(axis=0)) / F
        dF = dN.sum(axis=0)
        dd = np.zeros(P)
        if self.force_control:  # the force prescribed (f = F / (C a0^2): df / dln C = -f) and phi = 0: (de, dd)
            target = np.zeros(P)
            target[0] = -F
            A = np.array([[dF[P], dF[P + 1]], [dphi[P], dphi[P + 1]]])
            de, dd = np.linalg.solve(A, np.vstack([target - dF[:P], -dphi[:P]]))
            dx = dX[:, :P] + dX[:, P : P + 1] * de[None, :] + dX[:, P + 1 :] * dd[None, :]
            dF = target
        else:
            de = -dphi[:P] / dphi[P]  # d ln e / d theta
            dx = dX[:, :P] + dX[:, P:] * de[None, :]
            dF = dF[:P] + dF[P] * de
        eq = 2 * prob.equator
        self.out.append({n: (float(dF[j]), float(dx[eq, j]), float(dd[j])) for j, n in enumerate(names)})
        # the step's stress on its fixed mesh, and on the moved ones (the edge's motion of later histories)
        # (the held displacement's stress on the moved meshes to first order: S_e = dS(df_e), df_e the central
        # difference of its deformation gradient there, f being affine in the mesh's motion to O(h^2))
        df_e = (asm_hi.f_at(xh) - asm_lo.f_at(xl)) / (2 * h)
        dSall = lin.dS(np.concatenate([sens.point_increments(asm, dx), df_e[None]]))
        dSx, S_e = dSall[:P], dSall[P]
        dSx[1] += lin.d_alpha[..., None] * lin.S
        self.entries.append(_Entry(prob.m, mo.V, s.visco.S_iso, S_e, dSx, de))
        # the total sensitivity of the history values after the step (their mesh's motion included)
        dEdge = de[:, None, None, None]
        dS_post = dSx + dEdge * S_e[None]
        if beta.size:
            assert coef is not None
            dQ_pre = dQ + dEdge[:, None] * dQe[None]
            dS_pre = dS + dEdge * dSe[None]
            dQ_post = sens.history_update_tangent(
                names, which, coef, H0.Q, H0.S_iso, s.visco.S_iso, dQ_pre, dS_pre, dS_post
            )
        else:
            dQ_post = np.zeros((P, 0) + shape)
        self.dvisco = (dQ_post, dS_post)
