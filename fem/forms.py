r"""Vectorised assembly of the axisymmetric weak forms (no Python loop over elements or points).

Internal virtual work (reference configuration, dV = 2 pi R dR dZ):

    r_int = int B^T P dV,   K = int B^T A B dV (+ condensed mixed term)

Formulations (``Assembler(mesh, formulation=...)``):
* ``"mixed"`` (default): Q2 displacement / P1-discontinuous field q (basis psi = 1, X - Xc, Z - Zc per
  element; q is the mean Cauchy stress, the hydrostatic pressure is -q), perturbed Lagrangian
  Pi = int W_iso + q (J - 1) - q^2/(2 kappa) dV. The unknown vector x = (u, q): the 3 q-dofs of element
  e are ``n_u + 3 e + (0, 1, 2)``. Residual (r_u, r_q) = (int B^T (P_iso + q dJ) dV, int psi (J - 1) dV
  - M q / kappa) and the symmetric tangent [[K_uu, G^T], [G, -M/kappa]] (Newton in (u, q) converges
  for kappa/C = 1e7, unlike a condensed q(u)).
* ``"displacement"``: W_iso + U(J) at the quadrature points (locks for kappa >> C; for comparison).

Extra stress hook (viscoelasticity): ``internal(x, mat, extra_S=S0, iso_scale=s)`` uses the total
2nd Piola stress S = S_vol + s S_iso + S0, S0 (n_el, n_qp, 5) fixed during the step, so the
tangent is s A_iso + d(F S0)/dF + volumetric part. ``iso_S(u, mat)`` returns S_iso at the points.

Surface tension (``fem.surface``): ``Assembler.surface`` (None by default), a ``SurfaceTension`` whose
gamma dA/du and gamma d2A/du2 ``internal`` adds to the residual and the tangent.

Follower pressure p (scaled by C) on a boundary curve (``follower_pressure(u, p, edges)``): the
traction -p n on the deformed surface (p > 0 pushes into the material), with n da = (z', -r') 2 pi r dxi
for edges oriented with the material on their left (as ``fem.mesh`` stores them):
f_a = -p int N_a (z', -r') 2 pi r dxi, and its exact linearisation.

API: ``Material(C, alpha, kappa)`` NamedTuple (scaled), ``Assembler`` with ``.internal``,
``.iso_S``, ``.stress`` (f, P, A, q at the points), ``.f_at``, ``.follower_pressure``,
``.surface_mean_stretch``, ``.volume``; sizes ``n_u`` (displacement dofs, interleaved (u_r, u_z) per
node: 2 i, 2 i + 1), ``ndof`` (= n_u + 3 n_elements for "mixed"). All methods take the full x.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import scipy.sparse as sp

from tissuemech.fem import constitutive as cm
from tissuemech.fem.kinematics import IDENTITY5, b_matrix, dfirst_from_second, dJ, first_from_second, invariants
from tissuemech.fem.mesh import AxiMesh

if TYPE_CHECKING:
    from tissuemech.fem.surface import SurfaceTension

__all__ = ["Material", "Assembler", "line_shape"]


class Material(NamedTuple):
    """Fung parameters in the units the engine uses (C = 1 after scaling by C)."""

    C: float
    alpha: float
    kappa: float


def line_shape(nn: int, xi: np.ndarray):
    """1D Lagrange shape functions and derivatives on [-1, 1] for 2 or 3 nodes (ends, [mid])."""
    if nn == 2:
        return np.array([(1 - xi) / 2, (1 + xi) / 2]), np.array([-0.5 + 0 * xi, 0.5 + 0 * xi])
    return (np.array([xi * (xi - 1) / 2, 1 - xi**2, xi * (xi + 1) / 2]), np.array([xi - 0.5, -2 * xi, xi + 0.5]))


class _Pattern:
    """COO -> CSR map built once: K.data = bincount(perm, values) is the whole global assembly."""

    def __init__(self, rows: np.ndarray, cols: np.ndarray, n: int):
        key = rows.ravel().astype(np.int64) * n + cols.ravel()
        uniq, self.inv = np.unique(key, return_inverse=True)
        self.keys = uniq
        self.indptr = np.searchsorted(uniq // n, np.arange(n + 1)).astype(np.int32)
        self.indices = (uniq % n).astype(np.int32)
        self.n, self.nnz = n, uniq.size
        self._tpl = sp.csr_matrix((np.zeros(self.nnz), self.indices, self.indptr), shape=(n, n))
        self._tpl.has_sorted_indices = True
        self.indices, self.indptr = self._tpl.indices, self._tpl.indptr

        self._sub: dict = {}

    def matrix(self, values: np.ndarray) -> sp.csr_matrix:
        """CSR matrix with the summed values on the precomputed (canonical) pattern."""
        data = np.bincount(self.inv, weights=values.ravel(), minlength=self.nnz)
        return self._tpl._with_data(data, copy=False)

    def positions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Positions in the stored values of the entries (rows, cols) (ValueError if one is not in the pattern)."""
        key = rows.ravel().astype(np.int64) * self.n + cols.ravel()
        pos = np.searchsorted(self.keys, key)
        if pos.size and (pos.max() >= self.nnz or not np.array_equal(self.keys[pos], key)):
            raise ValueError("entries outside the assembled sparsity pattern (a boundary curve off the mesh?)")
        return pos

    def restricted(self, free: np.ndarray):
        """(src, template): K[free][:, free] (CSR, canonical) has the values ``data[src]`` of the full
        pattern; built once per free set (``free`` sorted, unique): the same pattern at every call (one
        solver plan, no dropped zeros)."""
        key = free.tobytes()
        if key not in self._sub:
            new = np.full(self.n, -1, dtype=np.int64)
            new[free] = np.arange(free.size)
            r, c = new[self.keys // self.n], new[self.keys % self.n]
            src = np.nonzero((r >= 0) & (c >= 0))[0]  # row-major order is kept (free is sorted)
            m = free.size
            indptr = np.searchsorted(r[src], np.arange(m + 1)).astype(np.int32)
            tpl = sp.csr_matrix((np.zeros(src.size), c[src].astype(np.int32), indptr), shape=(m, m))
            tpl.has_sorted_indices = True
            self._sub[key] = (src, tpl)
        return self._sub[key]


_PATTERNS: list = []  # (ndof, element dofs, _Pattern): meshes with one connectivity share their pattern


def _element_pattern(alld: np.ndarray, n: int) -> _Pattern:
    """The element-block pattern of the element dofs ``alld`` (ne, nd) over n dofs, shared between meshes
    with the same connectivity (the fitted spheroid meshes: one per contact-edge position; issue 14). The
    pattern depends on the connectivity only, so one object serves them all (and the solver plans keyed on
    its arrays are found by identity)."""
    for i, (m, a, pat) in enumerate(_PATTERNS):
        if m == n and a.shape == alld.shape and np.array_equal(a, alld):
            if i:
                _PATTERNS.insert(0, _PATTERNS.pop(i))
            return pat
    nd = alld.shape[1]
    rows = np.repeat(alld[:, :, None], nd, axis=2)
    cols = np.repeat(alld[:, None, :], nd, axis=1)
    pat = _Pattern(rows, cols, n)
    _PATTERNS.insert(0, (n, alld.copy(), pat))
    del _PATTERNS[4:]
    return pat


class Assembler:
    """Precomputed B matrices, weights and sparsity for one mesh (dimensionless)."""

    def __init__(self, mesh: AxiMesh, formulation: str = "mixed"):
        if formulation not in ("mixed", "displacement"):
            raise ValueError(f"formulation must be 'mixed' or 'displacement', got {formulation!r}")
        self.mesh, self.formulation = mesh, formulation
        b = mesh.basis
        nb = b.Nbfun
        self._N = np.array([np.asarray(b.basis[i][0]) for i in range(nb)])  # (nb, ne, nq)
        dN = np.array([b.basis[i][0].grad for i in range(nb)])  # (nb, 2, ne, nq)
        ed = b.element_dofs  # (nb, ne)
        self._ed = ed
        self.edofs = np.stack([2 * ed, 2 * ed + 1], axis=-1).reshape(nb, -1, 2).transpose(1, 0, 2).reshape(-1, 2 * nb)
        self.n_u = 2 * b.N
        ne = self.edofs.shape[0]
        self.n_el = ne
        alld = self.edofs
        if formulation == "mixed":
            self.qdofs = self.n_u + np.arange(3 * ne).reshape(ne, 3)
            alld = np.concatenate([self.edofs, self.qdofs], axis=1)
        self.ndof = self.n_u + (3 * ne if formulation == "mixed" else 0)
        self.alldofs = alld
        self._pattern = _element_pattern(alld, self.ndof)
        self._edofs_flat = np.ascontiguousarray(self.edofs.ravel())
        self._geometry(dN, mesh.quadrature_points, np.asarray(b.dx))
        self._edge_cache: dict = {}
        # an extra boundary energy (``fem.surface.SurfaceTension``) that ``internal`` adds to r and K; None: none
        self.surface: SurfaceTension | None = None
        self._f_last: tuple[np.ndarray, np.ndarray] | None = None  # (u, F(u)): see f_at

    def _geometry(self, dN: np.ndarray, xq: np.ndarray, dx: np.ndarray) -> None:
        """The arrays that depend on the node positions: shape-function gradients dN (nb, 2, ne, nq), quadrature
        points xq (2, ne, nq) and their weights dx (ne, nq) (the Gauss weights times the map's determinant)."""
        self._dN, self.xq = dN, xq
        self.R = xq[0]
        self.w = 2 * np.pi * self.R * dx  # (ne, nq)
        self.B = b_matrix(self._N, dN, self.R)  # (ne, nq, 5, 2nb)
        self._Bt: np.ndarray | None = None  # B^T per element (the tangent's), made on first use
        self._B2 = self.B.reshape(self.n_el, -1, self.B.shape[-1])  # (ne, nq * 5, nd), a view
        if self.formulation == "mixed":
            xc = np.sum(xq * self.w, axis=2) / self.w.sum(axis=1)
            self.psi = np.stack([np.ones_like(self.R), xq[0] - xc[0][:, None], xq[1] - xc[1][:, None]], -1)
            self.M = np.einsum("eqa,eqb,eq->eab", self.psi, self.psi, self.w)
            self._psiT = np.ascontiguousarray(self.psi.transpose(0, 2, 1))

    @property
    def Bt(self) -> np.ndarray:
        """B^T per element (ne, nd, nq * 5), contiguous (the tangent's element products)."""
        if self._Bt is None:
            self._Bt = np.ascontiguousarray(self._B2.transpose(0, 2, 1))
        return self._Bt

    def motion(self, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(V at the quadrature points (2, ne, nq), its gradient dV_i / dX_j there (2, 2, ne, nq)) of a nodal
        field V (2, n_nodes) of the mesh's Q2 space (e.g. the motion of its nodes)."""
        Ve = np.asarray(V, float)[:, self._ed]  # (2, nb, ne)
        return np.einsum("ike,keq->ieq", Ve, self._N), np.einsum("ike,kjeq->ijeq", Ve, self._dN)

    def moved(self, V: np.ndarray, eps: float) -> Assembler:
        """This assembler on the mesh whose nodes are X + eps V (V (2, n_nodes) in the mesh's Q2 space; same
        connectivity, dofs and pattern): the isoparametric map moves by eps V(xi), so its Jacobian is (I + eps
        grad V) dX/dxi, the shape-function gradients dN (I + eps grad V)^-1, the weights dx det(I + eps grad V)
        and the points xq + eps V(xi), all exact. Its ``surface`` is None (a caller with a surface tension moves
        it: ``fem.surface.SurfaceTension``). Used for the residual's derivative in a fitted mesh's motion
        (``fem.fitted_sensitivity``) without building the moved mesh's basis."""
        Vq, G = self.motion(V)
        a, b_, c, d = (eps * G[0, 0] + 1.0, eps * G[0, 1], eps * G[1, 0], eps * G[1, 1] + 1.0)
        det_ = a * d - b_ * c
        inv = np.stack([np.stack([d, -b_]), np.stack([-c, a])]) / det_  # (2, 2, ne, nq)
        dN = np.einsum("kieq,ijeq->kjeq", self._dN, inv)
        dx = self.w / (2 * np.pi * self.R) * det_
        out = copy.copy(self)
        out.surface = None
        out._f_last = None
        out._edge_cache = {}
        out._geometry(dN, self.xq + eps * Vq, dx)
        return out

    # ---- kinematics at quadrature points ------------------------------------------------
    @property
    def pattern(self):
        """The element sparsity pattern of the tangent (shared by assemblers whose meshes have one connectivity)."""
        return self._pattern

    def f_at(self, u: np.ndarray) -> np.ndarray:
        """5-comp deformation gradient (ne, nq, 5) for the global displacement u (the displacement dofs or
        the full vector (u, q)), by one stacked matmul per element; READ-ONLY.

        The last (u, F) is kept: a call with equal u returns the same array (newton checks a trial state's
        admissibility, then evaluates its residual: one F for both). The array is read-only, so no caller
        can change the kept value."""
        last = self._f_last
        if last is not None and last[0].shape == u.shape and np.array_equal(last[0], u):
            return last[1]
        ne, nq = self.w.shape
        f = np.matmul(self._B2, u[self.edofs][:, :, None]).reshape(ne, nq, 5)
        f += IDENTITY5
        f.flags.writeable = False
        self._f_last = (np.array(u, dtype=float), f)
        return f

    def q_at(self, x: np.ndarray) -> np.ndarray:
        """The mixed field q (mean Cauchy stress, scaled) at the points (ne, nq)."""
        return np.einsum("eqa,ea->eq", self.psi, x[self.qdofs])

    def iso_S(self, u: np.ndarray, mat: Material) -> np.ndarray:
        """Isochoric 2nd Piola-Kirchhoff stress at the points (ne, nq, 5) (for viscoelastic updates)."""
        return cm.iso_second_piola(self.f_at(u), mat.C, mat.alpha)

    def stress(self, u: np.ndarray, mat: Material, extra_S=None, iso_scale: float = 1.0, tangent: bool = True):
        """(f, P, A, q): total first Piola stress and tangent at the points, q the volumetric field (the mean
        Cauchy stress of the mixed form, or kappa (J - 1)). ``tangent=False``: A is None, P from the fused
        kernel ``constitutive.total_stress`` (the same numbers to round-off, no 5 x 5 tangent per point)."""
        if not tangent:
            f, q = self._fields(u)
            kappa = None if q is not None else mat.kappa
            P, _, J = cm.total_stress(f, mat.C, mat.alpha, q=q, kappa=kappa, iso_scale=iso_scale, extra_S=extra_S,
                                      tangent=False)  # fmt: skip
            return f, P, None, (q if q is not None else mat.kappa * (J - 1.0))
        f = self.f_at(u)
        P, A = cm.iso_stress(f, mat.C, mat.alpha)
        if iso_scale != 1.0:
            P, A = iso_scale * P, iso_scale * A
        if self.formulation == "mixed":
            q = self.q_at(u)
            Pv, Av = cm.vol_q(f, q)
        else:
            _, J = invariants(f)
            q = mat.kappa * (J - 1.0)
            Pv, Av = cm.vol_penalty(f, mat.kappa)
        P, A = P + Pv, A + Av
        if extra_S is not None:
            P = P + first_from_second(f, extra_S)
            A = A + dfirst_from_second(extra_S)
        return f, P, A, q

    def internal(
        self,
        u: np.ndarray,
        mat: Material,
        extra_S: np.ndarray | None = None,
        iso_scale: float = 1.0,
        tangent: bool | str = True,
    ):
        """Internal residual (ndof,) and tangent (CSR) of the elastic (+ extra) stress at x = (u, q).

        Args:
            u: the full unknown vector x = (u, q) (scaled).
            mat: scaled material.
            extra_S: fixed 2nd Piola stress (n_el, n_qp, 5) or None.
            iso_scale: factor on the isochoric stress.
            tangent: True assembles K; False returns (r, None); "lazy" returns r and a zero-argument callable
                that assembles K, for ``fem.newton`` (it calls it only when it needs K).
        Returns:
            (r, K): r (ndof,), K CSR (ndof, ndof) with the same canonical pattern at every call (the sparsity
            pattern is built once; only the values are assembled).
        One fused constitutive pass (``constitutive.total_stress``), weights folded in, element blocks
        written in place, global values by one ``bincount`` over a precomputed COO -> CSR map.
        """
        f, q = self._fields(u)
        kw = dict(q=q, kappa=None if q is not None else mat.kappa, iso_scale=iso_scale, extra_S=extra_S, weight=self.w)
        P, A, J = cm.total_stress(f, mat.C, mat.alpha, tangent=tangent, **kw)  # type: ignore[arg-type]
        r = self._residual(u, P, J, mat)
        surf = self.surface
        if surf is not None and surf.gamma != 0.0:  # surface tension (fem.surface): gamma dA/du, gamma d2A/du2
            r += surf.residual(u, self.ndof)
            if tangent == "lazy":
                uc = np.array(u, dtype=float)
                return r, lambda: surf.add_tangent(self._pattern.matrix(self._tangent_values(f, A(), mat)), uc)
            if tangent:
                return r, surf.add_tangent(self._pattern.matrix(self._tangent_values(f, A, mat)), u)
        if tangent == "lazy":
            return r, lambda: self._pattern.matrix(self._tangent_values(f, A(), mat))
        if not tangent:
            return r, None
        return r, self._pattern.matrix(self._tangent_values(f, A, mat))

    @property
    def q_ref(self) -> float:
        """The mixed field's value at rest (scaled mean Cauchy stress): -2 gamma / a of a surface tension with a
        balanced reference (``fem.surface.SurfaceTension.balance_reference``), else 0."""
        surf = self.surface
        return 0.0 if surf is None else surf.gamma * surf.q_per_gamma

    def rest_state(self) -> np.ndarray:
        """x at rest: u = 0 and the mixed field at :attr:`q_ref` (the exact equilibrium of a balanced reference)."""
        x = np.zeros(self.ndof)
        if self.formulation == "mixed":
            x[self.qdofs[:, 0]] = self.q_ref
        return x

    def tension_derivative(self, x: np.ndarray, mat: Material, surface: SurfaceTension | None = None) -> np.ndarray:
        """d r / d gamma (scaled gamma) at x: dA/du + b on the displacement dofs and, with a balanced reference,
        d(q_ref)/d gamma M e_1 / kappa on the mixed dofs, of ``surface`` (default: the attached one; zeros without
        one). A surface that is not attached gives the derivative at gamma = 0 of attaching it."""
        surf = self.surface if surface is None else surface
        if surf is None:
            return np.zeros(self.ndof)
        r = surf.unit_residual(x, self.ndof)
        if surf.q_per_gamma and self.formulation == "mixed":
            r[self.n_u :] += (surf.q_per_gamma / mat.kappa) * self.M[:, :, 0].ravel()
        return r

    def _fields(self, u: np.ndarray):
        """(f, q) at the points: 5-comp F (ne, nq, 5) and the mixed field (ne, nq) or None."""
        f = self.f_at(u)
        q = np.matmul(self.psi, u[self.qdofs][:, :, None])[..., 0] if self.formulation == "mixed" else None
        return f, q

    def _residual(self, u: np.ndarray, P: np.ndarray, J: np.ndarray, mat: Material) -> np.ndarray:
        """Global internal residual (ndof,) from the weighted stress P and J at the points."""
        ne, nq = self.w.shape
        re = np.matmul(P.reshape(ne, 1, nq * 5), self._B2)[:, 0]
        r = np.bincount(self._edofs_flat, weights=re.ravel(), minlength=self.ndof)
        if self.formulation == "mixed":  # the q-dofs of element e are n_u + 3 e + (0, 1, 2): no sum needed
            rq = np.matmul(self._psiT, ((J - 1.0) * self.w)[:, :, None])[..., 0]
            rq -= np.matmul(self.M, u[self.qdofs][:, :, None])[..., 0] / mat.kappa
            q_ref = self.q_ref
            if q_ref:  # the law q = q_ref + kappa (J - 1) of a balanced reference (fem.surface)
                rq += (q_ref / mat.kappa) * self.M[:, :, 0]
            r[self.n_u :] = rq.ravel()
        return r

    def _tangent_values(self, f: np.ndarray, A: np.ndarray, mat: Material) -> np.ndarray:
        """Element tangent blocks (ne, nd', nd') in ``alldofs`` order from the weighted A at the points."""
        ne, nq, _, nd = self.B.shape
        AB = np.matmul(A, self.B).reshape(ne, nq * 5, nd)
        if self.formulation != "mixed":
            return np.matmul(self.Bt, AB)
        Ke = np.empty((ne, nd + 3, nd + 3))
        np.matmul(self.Bt, AB, out=Ke[:, :nd, :nd])
        a_, b_, c_, d_, e_ = (f[..., i] for i in range(5))
        gJw = np.stack([e_ * d_, -e_ * c_, -e_ * b_, e_ * a_, a_ * d_ - b_ * c_], axis=-1) * self.w[..., None]
        dJB = np.matmul(gJw[:, :, None, :], self.B)[:, :, 0, :]  # (ne, nq, nd)
        G = np.matmul(self._psiT, dJB)
        Ke[:, nd:, :nd] = G
        Ke[:, :nd, nd:] = G.transpose(0, 2, 1)
        np.multiply(self.M, -1.0 / mat.kappa, out=Ke[:, nd:, nd:])
        return Ke

    def internal_follower(
        self,
        u: np.ndarray,
        mat: Material,
        p: float,
        edges: np.ndarray,
        *,
        free: np.ndarray | None = None,
        extra_S: np.ndarray | None = None,
        iso_scale: float = 1.0,
        tangent: bool | str = True,
    ):
        """Internal forces, the follower force at unit pressure and the tangent of r_int - p f_p on ONE pattern.

        Args:
            u: the full unknown vector x = (u, q) (scaled).
            mat: scaled material.
            p: follower pressure (scaled by C) in the tangent.
            edges: the loaded boundary curve (``mesh.edges``).
            free: sorted unique dof indices: the tangent is restricted to ``K[free][:, free]`` by a gather cached
                per free set (None: the full matrix).
            extra_S: as in :meth:`internal`.
            iso_scale: as in :meth:`internal`.
            tangent: True (a CSR matrix), False (None) or "lazy": a zero-argument callable that assembles the
                tangent when called (``fem.newton`` calls it only for states whose tangent it needs).
        Returns:
            (r_int (ndof,), f_p (ndof,) at unit pressure, K): K = d(r_int - p f_p)/dx, CSR on the element
            pattern (the follower edges lie inside it; their values are added at their positions, explicit
            zeros kept): the same pattern at every call. Equals ``internal`` and
            ``follower_pressure`` combined as ``(K_int - p K_p)[free][:, free]`` to round-off.
        Raises:
            ValueError: ``tangent`` not True, False or "lazy"; edges whose dofs are outside the element pattern.
        """
        if not (tangent == "lazy" or isinstance(tangent, (bool, np.bool_))):
            raise ValueError(f"tangent must be True, False or 'lazy', got {tangent!r}")
        f, q = self._fields(u)
        kw = dict(q=q, kappa=None if q is not None else mat.kappa, iso_scale=iso_scale, extra_S=extra_S, weight=self.w)
        P, A, J = cm.total_stress(f, mat.C, mat.alpha, tangent=tangent, **kw)  # type: ignore[arg-type]
        r = self._residual(u, P, J, mat)
        fp, _ = self._follower_values(u, 1.0, edges, tangent=False)
        if not tangent:
            return r, fp, None

        def assemble(A=A):
            if callable(A):  # lazy: the tangent from the stress pass's intermediates
                A = A()
            Ke = self._tangent_values(f, A, mat)
            _, Kp = self._follower_values(u, 1.0, edges, tangent=True)
            inv = self._follower_inv(edges)
            data = np.bincount(inv, weights=np.concatenate([Ke.ravel(), -p * Kp.ravel()]), minlength=self._pattern.nnz)
            if free is None:
                return self._pattern._tpl._with_data(data, copy=False)
            src, tpl = self._pattern.restricted(np.asarray(free))
            return tpl._with_data(data[src], copy=False)

        return r, fp, (assemble if tangent == "lazy" else assemble())

    def _follower_inv(self, edges: np.ndarray) -> np.ndarray:
        """COO -> internal-pattern map of the element entries followed by the edge entries (cached)."""
        key = ("inv", edges.tobytes(), edges.shape)
        if key not in self._edge_cache:
            d = np.stack([2 * edges, 2 * edges + 1], -1).reshape(edges.shape[0], -1)
            rows = np.repeat(d[:, :, None], d.shape[1], 2)
            cols = np.repeat(d[:, None, :], d.shape[1], 1)
            self._edge_cache[key] = np.concatenate([self._pattern.inv, self._pattern.positions(rows, cols)])
        return self._edge_cache[key]

    def internal_reference(
        self, u: np.ndarray, mat: Material, extra_S=None, iso_scale: float = 1.0, tangent: bool = True
    ):
        """The straightforward assembly (``stress`` + np.block + a fresh COO->CSR matrix): the reference that
        :meth:`internal` must equal to round-off (tests); slower."""
        f, P, A, _ = self.stress(u, mat, extra_S, iso_scale)
        ne, nq, _, nd = self.B.shape
        re = np.matmul((P * self.w[..., None]).reshape(ne, 1, nq * 5), self.B.reshape(ne, nq * 5, nd))[:, 0]
        if self.formulation == "mixed":
            _, J = invariants(f)
            rq = (
                np.einsum("eqa,eq->ea", self.psi, (J - 1.0) * self.w)
                - np.einsum("eab,eb->ea", self.M, u[self.qdofs]) / mat.kappa
                + (self.q_ref / mat.kappa) * self.M[:, :, 0]
            )
            re = np.concatenate([re, rq], axis=1)
        r = np.bincount(self.alldofs.ravel(), weights=re.ravel(), minlength=self.ndof)
        if not tangent:
            return r, None
        AB = np.matmul(A * self.w[..., None, None], self.B).reshape(ne, nq * 5, nd)
        Ke = np.matmul(self.Bt, AB)
        if self.formulation == "mixed":
            dJB = np.matmul((dJ(f) * self.w[..., None])[..., None, :], self.B)[..., 0, :]  # (ne, nq, nd)
            G = np.matmul(self.psi.transpose(0, 2, 1), dJB)
            Ke = np.block([[Ke, np.swapaxes(G, 1, 2)], [G, -self.M / mat.kappa]])
        rows = np.repeat(self.alldofs[:, :, None], Ke.shape[1], axis=2)
        cols = np.repeat(self.alldofs[:, None, :], Ke.shape[1], axis=1)
        return r, sp.csr_matrix((Ke.ravel(), (rows.ravel(), cols.ravel())), shape=(self.ndof, self.ndof))

    # ---- boundary curves --------------------------------------------------------------
    def _edge(self, edges: np.ndarray, nq: int = 4):
        key = (edges.tobytes(), edges.shape, nq)
        if key not in self._edge_cache:
            xi, wq = np.polynomial.legendre.leggauss(nq)
            Nl, dNl = line_shape(edges.shape[1], xi)
            dofs = np.stack([2 * edges, 2 * edges + 1], -1)  # (ned, nn, 2)
            d = dofs.reshape(edges.shape[0], -1)
            rows = np.repeat(d[:, :, None], d.shape[1], 2)
            cols = np.repeat(d[:, None, :], d.shape[1], 1)
            self._edge_cache[key] = (Nl, dNl, wq, dofs, _Pattern(rows, cols, self.ndof))
        return self._edge_cache[key]

    def follower_pressure(self, u: np.ndarray, p: float, edges: np.ndarray, tangent: bool = True):
        """Equivalent nodal force of pressure p on the deformed curve and d(force)/du (CSR)."""
        F, K = self._follower_values(u, p, edges, tangent)
        if K is None:
            return F, None
        return F, self._edge(edges)[4].matrix(K)

    def _follower_values(self, u: np.ndarray, p: float, edges: np.ndarray, tangent: bool = True):
        """(F (ndof,), edge blocks (ned, nn, 2, nn, 2) of dF/du or None) of the follower pressure p."""
        Nl, dNl, wq, dofs, _ = self._edge(edges)
        x = self.mesh.X[:, edges] + u[dofs].transpose(2, 0, 1)  # (2, ned, nn)
        # (small matmuls instead of einsum: issue 14, the same sums to round-off)
        r = x[0] @ Nl
        rp, zp = x[0] @ dNl, x[1] @ dNl
        c = -2 * np.pi * p * wq
        cr = c * r
        fe = np.empty(edges.shape + (2,))  # (ned, nn, 2)
        np.matmul(cr * zp, Nl.T, out=fe[..., 0])
        np.matmul(cr * rp, Nl.T, out=fe[..., 1])
        fe[..., 1] *= -1.0
        F = np.bincount(dofs.ravel(), weights=fe.ravel(), minlength=self.ndof)
        if not tangent:
            return F, None
        ned, nn = edges.shape
        K = np.zeros((ned, nn, 2, nn, 2))
        K[:, :, 0, :, 0] = (Nl * (c * zp)[:, None, :]) @ Nl.T
        K01 = (Nl * cr[:, None, :]) @ dNl.T
        K[:, :, 0, :, 1] = K01
        K[:, :, 1, :, 0] = -((Nl * (c * rp)[:, None, :]) @ Nl.T) - K01
        return F, K

    def surface_mean_stretch(self, u: np.ndarray, edges: np.ndarray) -> float:
        """Mean of |x|/|X| over a reference surface (area weights 2 pi R ds): a spherical stretch."""
        Nl, dNl, wq, dofs, _ = self._edge(edges)
        key = ("stretch", edges.tobytes(), edges.shape)
        if key not in self._edge_cache:  # the reference surface: |X| and the area weights at the points
            X = self.mesh.X[:, edges]
            Xq = np.einsum("aq,iea->ieq", Nl, X)
            w = Xq[0] * np.hypot(*np.einsum("aq,iea->ieq", dNl, X)) * wq
            self._edge_cache[key] = (X, np.hypot(*Xq), w / np.sum(w))
        X, Xn, w = self._edge_cache[key]
        xq = np.einsum("aq,iea->ieq", Nl, X + u[dofs].transpose(2, 0, 1))
        return float(np.sum(np.hypot(xq[0], xq[1]) / Xn * w))

    def volume(self, u: np.ndarray | None = None) -> float:
        """Reference (u None) or deformed volume of the section's solid of revolution."""
        if u is None:
            return float(self.w.sum())
        return float(np.sum(invariants(self.f_at(u))[1] * self.w))
