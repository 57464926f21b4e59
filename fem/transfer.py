r"""History (Gauss-point fields) between meshes of one body: interpolation in the reference configuration.

``gauss_transfer(old, new) -> transfer``: ``transfer(f)`` maps fields (..., n_el, n_qp, c) given at the
Gauss points of the ``old`` mesh (Maxwell branch stresses Q_m, S_iso) to the Gauss points of ``new`` (same
quadrature rule, Q2 elements): each new point is located in the old mesh and the old element's tensor-product
quadratic through its 3 x 3 Gauss values is evaluated there (exact for fields quadratic in the element's
reference coordinates). ``local_coordinates`` inverts the isoparametric Q2 map; ``lagrange2`` is the 1D
quadratic Lagrange basis. Used by ``fem.spheroid`` when a time step moves to another contact-edge-fitted mesh.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tissuemech.fem.mesh import AxiMesh

__all__ = ["gauss_transfer", "local_coordinates", "lagrange2"]


def lagrange2(t: np.ndarray):
    """1D quadratic Lagrange basis on the nodes 0, 1/2, 1 of [0, 1] at t (n,): values and derivatives,
    (3, n) each, one row per node."""
    v = np.stack([2 * (t - 0.5) * (t - 1), -4 * t * (t - 1), 2 * t * (t - 0.5)])
    d = np.stack([4 * t - 3, -8 * t + 4, 4 * t - 1])
    return v, d


def local_coordinates(xe: np.ndarray, ref: np.ndarray, x: np.ndarray, iters: int = 30, start=None) -> np.ndarray:
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
        (v0, d0), (v1, d1) = lagrange2(Xa[0]), lagrange2(Xa[1])
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


def gauss_transfer(old: AxiMesh, new: AxiMesh) -> Callable[[np.ndarray], np.ndarray]:
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
    points, centres = old.search_trees()
    # first the element of the nearest old Gauss point, from that point's reference coordinates (10 Newton
    # steps: a point inside converges in ~5, in one where the meshes coincide; most points that move are found
    # there too, issue 14); the others are looked for below
    _, near = points.query(pts.T)
    elem = near // nq
    loc = local_coordinates(xe[:, :, elem], ref, pts, iters=10, start=G_ref[:, near])
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
        lc = local_coordinates(
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
