r"""Surface tension: the energy gamma * (deformed area) of a boundary of the axisymmetric body, and its tangent.

A tissue (a cell aggregate) has a surface tension gamma (N/m): its free surface stores the energy
Pi_s = gamma A(u), A the current area of the surface of revolution swept by a boundary curve of the
section. On an edge with nodes x_a = X_a + u_a (quadratic: 3 nodes, parameter xi in [-1, 1]), with
r = N_a r_a, r' = N_a' r_a, z' = N_a' z_a and l = sqrt(r'^2 + z'^2):

    A = sum_edges int 2 pi r l dxi   (Gauss, 4 points per edge),

    dA/dr_a = 2 pi int (N_a l + r r' N_a' / l),     dA/dz_a = 2 pi int r z' N_a' / l,

and the consistent tangent (symmetric; l^2 - r'^2 = z'^2):

    d2A/dr_a dr_b = 2 pi int ((N_a N_b' + N_a' N_b) r' / l + r N_a' N_b' z'^2 / l^3)
    d2A/dr_a dz_b = 2 pi int (N_a N_b' z' / l - r N_a' N_b' r' z' / l^3)
    d2A/dz_a dz_b = 2 pi int r N_a' N_b' r'^2 / l^3.

The residual gets gamma dA/du, the tangent gamma d2A/du2 (a tensile membrane: it pulls every surface node
along the surface's mean curvature normal; on a sphere of radius a the nodal forces are those of the
Laplace pressure 2 gamma / a). In the scaled engine (lengths by L, stresses by C) gamma enters as the
elastocapillary number gamma / (C L).

Which part of the boundary carries gamma is the scene's choice (``fem.spheroid``: the whole outer surface,
the wetted disc included, see there why that is the 180 degree contact angle).

The balanced reference (:meth:`SurfaceTension.balance_reference`): a ball of radius a at rest under its tension
carries the Laplace pressure 2 gamma / a with no deformation. The discrete surface (quadratic edges through nodes
on the sphere) is not exactly a sphere: its nodal tension forces differ from those of a uniform pressure by the
edges' approximation error (2.3e-5 of them on level 0, 3.4e-7 on level 3), so that without a correction the free
ball deforms by that much and its pressure is 2 gamma / a only to that error. The reference state is therefore
made an exact equilibrium: the mixed field's law becomes q = q_ref + kappa (J - 1) with q_ref = -2 gamma / a (the
mean Cauchy stress of the ball at rest: the radius a is the one measured on the ball with its tension), and the
tension's residual gets the constant vector gamma b, b = (2 / a) G - dA/du(0) with G the body's residual of a unit
mean stress at rest (its pressure load on the discrete surface): b vanishes with the edges' error, and the ball at
rest, u = 0 and q = -2 gamma / a, solves the discrete equations to round-off. ``internal`` includes both
(``Assembler.q_ref``); ``Assembler.tension_derivative`` is the residual's derivative in gamma with them.

API: :class:`SurfaceTension` (``.area``, ``.residual``, ``.add_tangent``, ``.balance_reference``), attached to an
assembler as ``Assembler.surface`` (``fem.forms``): ``internal`` then includes it in the residual and the tangent.
"""

from __future__ import annotations

import copy

import numpy as np
import scipy.sparse as sp

from tissuemech.fem.forms import Material, line_shape

__all__ = ["SurfaceTension", "N_GAUSS"]

N_GAUSS = 4  # Gauss points per edge (the integrand r l is not polynomial; 4 points as the follower load)


class SurfaceTension:
    """The surface energy gamma A(u) of the boundary curve ``edges`` (n_edges, 2 or 3 nodes) of the section
    with reference coordinates ``X`` (2, n_nodes) (scaled), tension ``gamma`` (scaled: gamma / (C L))."""

    def __init__(self, X: np.ndarray, edges: np.ndarray, gamma: float):
        edges = np.asarray(edges, dtype=int)
        if edges.ndim != 2 or edges.shape[1] not in (2, 3) or edges.shape[0] == 0:
            raise ValueError("surface tension needs a non-empty (n_edges, 2 or 3) array of boundary edges")
        if not (np.isfinite(gamma) and gamma >= 0):
            raise ValueError(f"surface tension must be finite and >= 0 (scaled gamma / (C L)), got {gamma!r}")
        self.X, self.edges, self.gamma = np.asarray(X, float), edges, float(gamma)
        xi, self.wq = np.polynomial.legendre.leggauss(N_GAUSS)
        self.N, self.dN = line_shape(edges.shape[1], xi)  # (nn, nq)
        self.dofs = np.stack([2 * edges, 2 * edges + 1], -1)  # (ned, nn, 2)
        self._pos: dict = {}
        # the balanced reference (:meth:`balance_reference`): b per unit gamma on the displacement dofs, and
        # q_ref / gamma of the mixed field (0: none)
        self.balance: np.ndarray | None = None
        self.q_per_gamma = 0.0
        # per-edge factors on gamma (None: 1): a wetted edge of a plate with contact angle theta stores
        # gamma_SL - gamma_SV = -gamma cos(theta) per area (Young), see :meth:`wet`
        self.weights: np.ndarray | None = None
        self._radius = 1.0  # of the balanced reference (:meth:`balance_reference`)

    def wet(self, edges_mask: np.ndarray, contact_angle: float) -> None:
        """Give the edges ``edges_mask`` (bool, n_edges) the energy of a surface wetting a plate with contact angle
        theta (rad, measured through the body): -gamma cos(theta) per area instead of gamma (1 at theta = pi, the
        non-wetting plate, where nothing changes). Energy gamma (A_free - cos(theta) A_wet) = gamma A - gamma (1 +
        cos(theta)) A_wet: the work of adhesion gamma (1 + cos(theta)) per wetted area."""
        w = np.ones(self.edges.shape[0])
        w[np.asarray(edges_mask, bool)] = -np.cos(contact_angle)
        self.weights = None if np.all(w == 1.0) else w

    def _c(self) -> np.ndarray:
        """2 pi w_q (per edge weight): (n_edges, n_q) or (n_q,)."""
        c = 2 * np.pi * self.wq
        return c if self.weights is None else self.weights[:, None] * c

    def balance_reference(self, asm, radius: float = 1.0) -> None:
        """Make the body at rest (u = 0, mean stress q = -2 gamma / ``radius``, scaled) an exact equilibrium of the
        assembler ``asm`` (``fem.forms.Assembler``, mixed) under this tension: see the module's docstring. The
        surface must be the whole free surface of a ball of that radius (scaled), attached as ``asm.surface``."""
        if asm.formulation != "mixed":
            raise ValueError("the balanced reference of a surface tension needs the mixed formulation")
        x = np.zeros(asm.ndof)
        x[asm.qdofs[:, 0]] = 1.0  # q = 1 (psi = 1, X - Xc, Z - Zc per element)
        saved, asm.surface = asm.surface, None
        weights, self.weights = self.weights, None  # the free ball: no wetted part
        try:  # the body alone at rest under a unit mean stress: no deviatoric stress at F = I (any material)
            G = asm.internal(x, Material(1.0, 0.1, 1.0), tangent=False)[0]
            G[asm.n_u :] = 0.0
            self.balance = (2.0 / radius) * G - self.area_gradient(np.zeros(asm.ndof), asm.ndof)
        finally:
            asm.surface, self.weights = saved, weights
        self.q_per_gamma = -2.0 / radius
        self._radius = float(radius)

    def moved(self, dX: np.ndarray, asm) -> SurfaceTension:
        """This surface on the section whose nodes moved by dX (2, n_nodes), attached to ``asm`` (that section's
        assembler: ``fem.forms.Assembler.moved``) and balanced there as this one is (the same ball, its nodes
        placed differently: a fitted mesh at another contact edge). Returns the copy; ``asm.surface`` is set."""
        out = copy.copy(self)
        out.X = self.X + np.asarray(dX, float)
        out._pos = {}
        asm.surface = out
        if self.balance is not None:
            out.balance_reference(asm, self._radius)
        return out

    def _geometry(self, u: np.ndarray):
        x = self.X[:, self.edges] + u[self.dofs].transpose(2, 0, 1)  # (2, ned, nn)
        r, rp, zp = x[0] @ self.N, x[0] @ self.dN, x[1] @ self.dN  # (ned, nq)
        return r, rp, zp, np.hypot(rp, zp)

    def area(self, u: np.ndarray) -> float:
        """Deformed area (scaled by L^2) of the surface swept by the edges (u: displacement or full vector); with
        :meth:`wet` the wetted edges count with their factor -cos(theta) (the energy per gamma)."""
        r, _, _, l = self._geometry(u)
        return float(np.sum(r * l * self._c()))

    def area_gradient(self, u: np.ndarray, ndof: int) -> np.ndarray:
        """dA/du (scaled by L) as a vector of length ``ndof`` (zeros off the edge dofs; no gamma, no balance)."""
        r, rp, zp, l = self._geometry(u)
        c = self._c()
        fe = np.empty(self.edges.shape + (2,))
        fe[..., 0] = np.einsum("eq,aq->ea", c * l, self.N) + np.einsum("eq,aq->ea", c * r * rp / l, self.dN)
        fe[..., 1] = np.einsum("eq,aq->ea", c * r * zp / l, self.dN)
        return np.bincount(self.dofs.ravel(), weights=fe.ravel(), minlength=ndof)

    def unit_residual(self, u: np.ndarray, ndof: int) -> np.ndarray:
        """dA/du + b (b: the balanced reference's vector, 0 without it): the residual per unit gamma."""
        r = self.area_gradient(u, ndof)
        if self.balance is not None:
            r[: min(ndof, self.balance.size)] += self.balance[:ndof]
        return r

    def residual(self, u: np.ndarray, ndof: int) -> np.ndarray:
        """gamma (dA/du + b) as a vector of length ``ndof`` (zeros off the edge dofs; b the balanced reference's
        constant vector, :meth:`balance_reference`, 0 without it)."""
        return self.gamma * self.unit_residual(u, ndof)

    def blocks(self, u: np.ndarray) -> np.ndarray:
        """gamma d2A/du2 per edge, (ned, nn, 2, nn, 2) (node, component) x (node, component)."""
        r, rp, zp, l = self._geometry(u)
        c = self.gamma * self._c()
        N, dN = self.N, self.dN
        NdN = np.einsum("aq,bq->abq", N, dN)
        dNdN = np.einsum("aq,bq->abq", dN, dN)
        l3 = l**3
        K = np.empty(self.edges.shape + (2,) + self.edges.shape[1:] + (2,))
        K[:, :, 0, :, 0] = np.einsum("abq,eq->eab", NdN + NdN.transpose(1, 0, 2), c * rp / l) + np.einsum(
            "abq,eq->eab", dNdN, c * r * zp**2 / l3
        )
        Krz = np.einsum("abq,eq->eab", NdN, c * zp / l) - np.einsum("abq,eq->eab", dNdN, c * r * rp * zp / l3)
        K[:, :, 0, :, 1] = Krz
        K[:, :, 1, :, 0] = Krz.transpose(0, 2, 1)
        K[:, :, 1, :, 1] = np.einsum("abq,eq->eab", dNdN, c * r * rp**2 / l3)
        return K

    def _positions(self, K: sp.csr_matrix) -> np.ndarray:
        """Positions in K.data of the edge entries (cached per sparsity pattern); ValueError if one is missing."""
        key = (K.shape, hash(K.indptr.tobytes()), hash(K.indices.tobytes()))
        if key not in self._pos:
            d = self.dofs.reshape(self.edges.shape[0], -1)
            rows = np.repeat(d[:, :, None], d.shape[1], 2).ravel().astype(np.int64)
            cols = np.repeat(d[:, None, :], d.shape[1], 1).ravel().astype(np.int64)
            n = K.shape[1]
            if not K.has_sorted_indices:
                K.sort_indices()
            krow = np.repeat(np.arange(K.shape[0], dtype=np.int64), np.diff(K.indptr))
            keys = krow * n + K.indices
            want = rows * n + cols
            pos = np.searchsorted(keys, want)
            if pos.max() >= keys.size or not np.array_equal(keys[pos], want):
                raise ValueError("the surface edges' entries are outside the tangent's sparsity pattern")
            self._pos[key] = pos
        return self._pos[key]

    def add_tangent(self, K: sp.csr_matrix, u: np.ndarray) -> sp.csr_matrix:
        """K with gamma d2A/du2 added IN PLACE on its own sparsity pattern (the edge entries must be in it)."""
        pos = self._positions(K)
        K.data += np.bincount(pos, weights=self.blocks(u).ravel(), minlength=K.nnz)
        return K

    def tangent(self, u: np.ndarray, ndof: int) -> sp.csr_matrix:
        """gamma d2A/du2 as a (ndof, ndof) CSR matrix (for checks)."""
        d = self.dofs.reshape(self.edges.shape[0], -1)
        rows = np.repeat(d[:, :, None], d.shape[1], 2).ravel()
        cols = np.repeat(d[:, None, :], d.shape[1], 1).ravel()
        return sp.csr_matrix((self.blocks(u).ravel(), (rows, cols)), shape=(ndof, ndof))
