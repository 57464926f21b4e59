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

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from tissuemech.fem import constitutive as cm
from tissuemech.fem.kinematics import IDENTITY5, b_matrix, dfirst_from_second, dJ, first_from_second, invariants
from tissuemech.fem.mesh import AxiMesh

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
        self.indptr = np.searchsorted(uniq // n, np.arange(n + 1)).astype(np.int32)
        self.indices = (uniq % n).astype(np.int32)
        self.n, self.nnz = n, uniq.size
        self._tpl = sp.csr_matrix((np.zeros(self.nnz), self.indices, self.indptr), shape=(n, n))
        self._tpl.has_sorted_indices = True
        self.indices, self.indptr = self._tpl.indices, self._tpl.indptr

    def matrix(self, values: np.ndarray) -> sp.csr_matrix:
        """CSR matrix with the summed values on the precomputed (canonical) pattern."""
        data = np.bincount(self.inv, weights=values.ravel(), minlength=self.nnz)
        return self._tpl._with_data(data, copy=False)


class Assembler:
    """Precomputed B matrices, weights and sparsity for one mesh (dimensionless)."""

    def __init__(self, mesh: AxiMesh, formulation: str = "mixed"):
        if formulation not in ("mixed", "displacement"):
            raise ValueError(f"formulation must be 'mixed' or 'displacement', got {formulation!r}")
        self.mesh, self.formulation = mesh, formulation
        b = mesh.basis
        nb = b.Nbfun
        N = np.array([np.asarray(b.basis[i][0]) for i in range(nb)])  # (nb, ne, nq)
        dN = np.array([b.basis[i][0].grad for i in range(nb)])  # (nb, 2, ne, nq)
        xq = np.asarray(b.global_coordinates())  # (2, ne, nq)
        self.R = xq[0]
        self.w = 2 * np.pi * self.R * b.dx  # (ne, nq)
        self.B = b_matrix(N, dN, self.R)  # (ne, nq, 5, 2nb)
        self.Bt = np.ascontiguousarray(self.B.reshape(self.B.shape[0], -1, self.B.shape[-1]).transpose(0, 2, 1))
        ed = b.element_dofs  # (nb, ne)
        self.edofs = np.stack([2 * ed, 2 * ed + 1], axis=-1).reshape(nb, -1, 2).transpose(1, 0, 2).reshape(-1, 2 * nb)
        self.n_u = 2 * b.N
        ne = self.edofs.shape[0]
        self.n_el = ne
        alld = self.edofs
        if formulation == "mixed":
            xc = np.sum(xq * self.w, axis=2) / self.w.sum(axis=1)
            self.psi = np.stack([np.ones_like(self.R), xq[0] - xc[0][:, None], xq[1] - xc[1][:, None]], -1)
            self.M = np.einsum("eqa,eqb,eq->eab", self.psi, self.psi, self.w)
            self.qdofs = self.n_u + np.arange(3 * ne).reshape(ne, 3)
            alld = np.concatenate([self.edofs, self.qdofs], axis=1)
        self.ndof = self.n_u + (3 * ne if formulation == "mixed" else 0)
        self.alldofs = alld
        nd = alld.shape[1]
        rows = np.repeat(alld[:, :, None], nd, axis=2)
        cols = np.repeat(alld[:, None, :], nd, axis=1)
        self._pattern = _Pattern(rows, cols, self.ndof)
        self._alld_flat = np.ascontiguousarray(alld.ravel())
        self._B2 = np.ascontiguousarray(self.B.reshape(ne, -1, self.B.shape[-1]))  # (ne, nq * 5, nd)
        if formulation == "mixed":
            self._psiT = np.ascontiguousarray(self.psi.transpose(0, 2, 1))
        self._edge_cache: dict = {}

    # ---- kinematics at quadrature points ------------------------------------------------
    def f_at(self, u: np.ndarray) -> np.ndarray:
        """5-comp deformation gradient (ne, nq, 5) for the global displacement u."""
        return IDENTITY5 + np.matmul(self.B, u[self.edofs][:, None, :, None])[..., 0]

    def q_at(self, x: np.ndarray) -> np.ndarray:
        """The mixed field q (mean Cauchy stress, scaled) at the points (ne, nq)."""
        return np.einsum("eqa,ea->eq", self.psi, x[self.qdofs])

    def iso_S(self, u: np.ndarray, mat: Material) -> np.ndarray:
        """Isochoric 2nd Piola-Kirchhoff stress at the points (ne, nq, 5) (for viscoelastic updates)."""
        return cm.iso_second_piola(self.f_at(u), mat.C, mat.alpha)

    def stress(self, u: np.ndarray, mat: Material, extra_S=None, iso_scale: float = 1.0):
        """(f, P, A, q): total first Piola stress and tangent at the points, q the volumetric field."""
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

    def internal(self, u: np.ndarray, mat: Material, extra_S=None, iso_scale: float = 1.0, tangent: bool = True):
        """Internal residual (ndof,) and tangent (CSR) of the elastic (+ extra) stress at x = (u, q).

        Args:
            u: the full unknown vector x = (u, q) (scaled).
            mat: scaled material; extra_S: fixed 2nd Piola stress (n_el, n_qp, 5) or None;
            iso_scale: factor on the isochoric stress; tangent: False returns (r, None).
        Returns:
            (r, K): r (ndof,), K CSR (ndof, ndof) with the same canonical pattern at every call (the sparsity
            pattern is built once; only the values are assembled).
        One fused constitutive pass (``constitutive.total_stress``), weights folded in, element blocks
        written in place, global values by one ``bincount`` over a precomputed COO -> CSR map.
        """
        ne, nq, _, nd = self.B.shape
        ue = u[self.edofs]
        f = np.matmul(self._B2, ue[:, :, None]).reshape(ne, nq, 5)
        f += IDENTITY5
        mixed = self.formulation == "mixed"
        q = np.matmul(self.psi, u[self.qdofs][:, :, None])[..., 0] if mixed else None
        P, A, J = cm.total_stress(
            f,
            mat.C,
            mat.alpha,
            q=q,
            kappa=None if mixed else mat.kappa,
            iso_scale=iso_scale,
            extra_S=extra_S,
            weight=self.w,
            tangent=tangent,
        )
        re = np.matmul(P.reshape(ne, 1, nq * 5), self._B2)[:, 0]
        if mixed:
            rq = np.matmul(self._psiT, ((J - 1.0) * self.w)[:, :, None])[..., 0]
            rq -= np.matmul(self.M, u[self.qdofs][:, :, None])[..., 0] / mat.kappa
            re = np.concatenate([re, rq], axis=1)
        r = np.bincount(self._alld_flat, weights=re.ravel(), minlength=self.ndof)
        if not tangent:
            return r, None
        AB = np.matmul(A, self.B).reshape(ne, nq * 5, nd)
        if not mixed:
            return r, self._pattern.matrix(np.matmul(self.Bt, AB))
        Ke = np.empty((ne, nd + 3, nd + 3))
        np.matmul(self.Bt, AB, out=Ke[:, :nd, :nd])
        a_, b_, c_, d_, e_ = (f[..., i] for i in range(5))
        gJw = np.stack([e_ * d_, -e_ * c_, -e_ * b_, e_ * a_, a_ * d_ - b_ * c_], axis=-1) * self.w[..., None]
        dJB = np.matmul(gJw[:, :, None, :], self.B)[:, :, 0, :]  # (ne, nq, nd)
        G = np.matmul(self._psiT, dJB)
        Ke[:, nd:, :nd] = G
        Ke[:, :nd, nd:] = G.transpose(0, 2, 1)
        np.multiply(self.M, -1.0 / mat.kappa, out=Ke[:, nd:, nd:])
        return r, self._pattern.matrix(Ke)

    def _internal_reference(
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
        Nl, dNl, wq, dofs, pattern = self._edge(edges)
        X = self.mesh.X
        x = X[:, edges] + np.stack([u[dofs[..., 0]], u[dofs[..., 1]]])  # (2, ned, nn)
        r = np.einsum("aq,ea->eq", Nl, x[0])
        rp, zp = np.einsum("aq,ea->eq", dNl, x[0]), np.einsum("aq,ea->eq", dNl, x[1])
        c = -2 * np.pi * p * wq
        fr = np.einsum("aq,eq->ea", Nl, c * r * zp)
        fz = -np.einsum("aq,eq->ea", Nl, c * r * rp)
        fe = np.stack([fr, fz], -1)  # (ned, nn, 2)
        F = np.bincount(dofs.ravel(), weights=fe.ravel(), minlength=self.ndof)
        if not tangent:
            return F, None
        ned, nn = edges.shape
        K = np.zeros((ned, nn, 2, nn, 2))
        K[:, :, 0, :, 0] = np.einsum("aq,bq,eq->eab", Nl, Nl, c * zp)
        K[:, :, 0, :, 1] = np.einsum("aq,bq,eq->eab", Nl, dNl, c * r)
        K[:, :, 1, :, 0] = -np.einsum("aq,bq,eq->eab", Nl, Nl, c * rp) - np.einsum("aq,bq,eq->eab", Nl, dNl, c * r)
        return F, pattern.matrix(K)

    def surface_mean_stretch(self, u: np.ndarray, edges: np.ndarray) -> float:
        """Mean of |x|/|X| over a reference surface (area weights 2 pi R ds): a spherical stretch."""
        Nl, dNl, wq, dofs, _ = self._edge(edges)
        X = self.mesh.X[:, edges]
        x = X + np.stack([u[dofs[..., 0]], u[dofs[..., 1]]])
        Xq, xq = np.einsum("aq,iea->ieq", Nl, X), np.einsum("aq,iea->ieq", Nl, x)
        ds = np.hypot(*np.einsum("aq,iea->ieq", dNl, X))
        w = Xq[0] * ds * wq
        lam = np.hypot(*xq) / np.hypot(*Xq)
        return float(np.sum(lam * w) / np.sum(w))

    def volume(self, u: np.ndarray | None = None) -> float:
        """Reference (u None) or deformed volume of the section's solid of revolution."""
        if u is None:
            return float(self.w.sum())
        return float(np.sum(invariants(self.f_at(u))[1] * self.w))
