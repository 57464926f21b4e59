r"""History (Gauss-point fields) between meshes of one body: interpolation in the reference configuration.

``gauss_transfer(old, new) -> transfer``: ``transfer(f)`` maps fields (..., n_el, n_qp, c) given at the
Gauss points of the ``old`` mesh (Maxwell branch stresses Q_m, S_iso) to the Gauss points of ``new`` (same
quadrature rule, Q2 elements): each new point is located in the old mesh and the old element's tensor-product
quadratic through its 3 x 3 Gauss values is evaluated there (exact for fields quadratic in the element's
reference coordinates); ``continuous=True`` evaluates the continuous Q2 field through the element nodes instead
(those quadratics averaged at shared nodes): stable when chained, continuous in the new points' positions.
Chaining the element-wise fit is NOT stable: a smooth field carried through 16 / 64 fitted meshes (edge 0.1 ->
0.3) drifts by 3e-2 / 7e-2 of its amplitude (one transfer: 2e-3), the continuous one by 6e-3 / 5e-3.
``deformation_at(mesh, x, points)``: the deformation gradient of a displacement on one mesh at the Gauss points
of another (the history kept on fixed material points while the mesh moves: ``fem.contact.timed_fitted``).
``locate`` finds points in a mesh, ``local_coordinates`` inverts the isoparametric Q2 map; ``lagrange2`` is the
1D quadratic Lagrange basis.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from tissuemech.fem.mesh import AxiMesh

__all__ = [
    "gauss_transfer",
    "gauss_transfers",
    "deformation_at",
    "locate",
    "locate_many",
    "locate_near",
    "located",
    "points_in",
    "nodal_average",
    "own_points",
    "ContinuousJet",
    "ElementJet",
    "local_coordinates",
    "lagrange2",
]


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


def locate(mesh: AxiMesh, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(element (n,), reference coordinates (2, n)) of the points ``pts`` (2, n) (reference configuration,
    dimensionless) in the Q2 ``mesh``: the element of the nearest Gauss point first, then those of the next
    nearest Gauss points and element centres; a point outside every element (just outside the discretised
    boundary) gets the element it is least outside of (its coordinates then leave [0, 1]^2 slightly)."""
    return locate_many([mesh], pts)[0]


def _excess(lc: np.ndarray) -> np.ndarray:
    """How far reference coordinates (2, n) lie outside [0, 1]^2 (0 inside)."""
    return np.max(np.maximum(np.maximum(-lc, lc - 1.0), 0.0), axis=0)


_CANDIDATES_PER_ROUND = 4  # the second pass of the point search tries this many candidate elements per round


def locate_many(meshes: list[AxiMesh], pts: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`locate` of the same points in several meshes (e.g. the fitted meshes of a time run's steps): the
    Newton inversions of all meshes run as one array computation, in each of the two passes (a point's iterates
    are its own: the same result as one call per mesh, without the array overhead of many small calls)."""
    ref = np.asarray(meshes[0].basis.elem.doflocs, float).T  # (2, 9): the Q2 nodes in [0, 1]^2 (isoparametric)
    n = pts.shape[1]
    # first the element of the nearest Gauss point, from that point's reference coordinates (10 Newton steps: a
    # point inside converges in ~5, in one where the meshes coincide; most points that move are found there too,
    # issue 14)
    first = []
    for mesh in meshes:
        nq = mesh.quadrature_points.shape[2]
        _, near = mesh.search_trees()[0].query(pts.T)
        first.append((near // nq, mesh.element_nodes(), _gauss_reference(mesh)[:, near]))
    loc_all = local_coordinates(
        np.concatenate([xe[:, :, elem] for elem, xe, _ in first], axis=2),
        ref,
        np.tile(pts, (1, len(meshes))),
        iters=10,
        start=np.concatenate([start for _, _, start in first], axis=1),
    )
    elems = [elem.copy() for elem, _, _ in first]
    locs = [loc_all[:, i * n : (i + 1) * n].copy() for i in range(len(meshes))]
    # the rest (near strongly graded elements, or just outside the discretised boundary): the elements of the 16
    # nearest Gauss points (from their reference coordinates) and of the 8 nearest element centres (from the
    # centre), in one pass, taken in that order: the first that contains the point wins, else the least excess (a
    # point-by-point search's choice)
    rest = []  # (mesh index, points, candidates (n_out, nc), starts (2, n_out, nc))
    for i, mesh in enumerate(meshes):
        out = np.flatnonzero(_excess(locs[i]) > 1e-10)
        if not out.size:
            continue
        ne, nq = mesh.quadrature_points.shape[1:]
        points, centres = mesh.search_trees()
        _, near = points.query(pts[:, out].T, k=min(16, ne * nq))
        _, cen = centres.query(pts[:, out].T, k=min(8, ne))
        cand = np.concatenate([near // nq, cen.reshape(out.size, -1)], axis=1)
        start = np.full((2,) + cand.shape, 0.5)
        start[:, :, : near.shape[1]] = _gauss_reference(mesh)[:, near]
        rest.append((i, out, cand, start))
    if not rest:
        return list(zip(elems, locs))
    nc = rest[0][2].shape[1]
    groups = [rest] if all(c.shape[1] == nc for _, _, c, _ in rest) else [[r] for r in rest]  # tiny meshes: apart
    for group in groups:
        k_nc = group[0][2].shape[1]
        nodes = [meshes[i].element_nodes() for i, _, _, _ in group]
        offsets = np.cumsum([0] + [xe.shape[2] for xe in nodes])[:-1]
        xe_all = np.concatenate(nodes, axis=2)  # the group's meshes' elements, one numbering (offsets)
        cand = np.concatenate([c for _, _, c, _ in group])  # (N, nc) elements of each point's own mesh
        gcand = np.concatenate([c + o for (_, _, c, _), o in zip(group, offsets)])  # in the joint numbering
        start = np.concatenate([st for _, _, _, st in group], axis=1)  # (2, N, nc)
        p_out = np.concatenate([pts[:, out] for _, out, _, _ in group], axis=1)  # (2, N)
        best = np.concatenate([_excess(locs[i][:, out]) for i, out, _, _ in group])
        el = np.concatenate([elems[i][out] for i, out, _, _ in group])
        lo = np.concatenate([locs[i][:, out] for i, out, _, _ in group], axis=1)
        # the candidates a few at a time, each round for the points no candidate has contained yet (a later
        # candidate cannot replace one that contains the point): the same choice as all at once, ~1/4 the work
        for j0 in range(0, k_nc, _CANDIDATES_PER_ROUND):
            r = np.flatnonzero(best > 1e-10)
            if not r.size:
                break
            js = np.arange(j0, min(j0 + _CANDIDATES_PER_ROUND, k_nc))
            lc = local_coordinates(
                xe_all[:, :, gcand[r][:, js].ravel()],
                ref,
                np.repeat(p_out[:, r], js.size, axis=1),
                iters=10,
                start=start[:, r][:, :, js].reshape(2, -1),
            ).reshape(2, r.size, js.size)
            ex = _excess(lc.reshape(2, -1)).reshape(r.size, js.size)
            for jj, j in enumerate(js):
                better = (best[r] > 1e-10) & (ex[:, jj] < best[r] - 1e-14)
                b = r[better]
                best[b], el[b], lo[:, b] = ex[better, jj], cand[b, j], lc[:, better, jj]
        a = 0
        for i, out, _, _ in group:
            elems[i][out], locs[i][:, out] = el[a : a + out.size], lo[:, a : a + out.size]
            a += out.size
    return list(zip(elems, locs))


def _gauss_reference(mesh: AxiMesh) -> np.ndarray:
    """The reference coordinates in [0, 1]^2 of every Gauss point, element by element (2, n_el n_qp)."""
    return np.tile(np.asarray(mesh.basis.X, float), (1, mesh.quadrature_points.shape[1]))


def gauss_transfer(old: AxiMesh, new: AxiMesh, continuous: bool = False) -> Callable[[np.ndarray], np.ndarray]:
    """Map Gauss-point fields (..., n_el, n_qp, c) of ``old`` to the Gauss points of ``new`` (same quadrature)
    by interpolation in the reference configuration: each new Gauss point is located in the old mesh
    (:func:`locate`), and the old element's field is evaluated there from its tensor-product quadratic through the
    element's 3 x 3 Gauss values (exact for fields quadratic in the element's reference coordinates; slightly
    extrapolated for a point just outside the old discretised boundary). ``continuous``: that quadratic's values
    at the element's nodes are averaged over the elements that share a node and the continuous Q2 field is
    evaluated instead (still exact for quadratic fields; continuous in the new points' positions, so a search
    over trial meshes sees no jumps where a point crosses an old element's boundary)."""
    return gauss_transfers([old], new, continuous)[0]


def gauss_transfers(
    olds: list[AxiMesh], new: AxiMesh, continuous: bool = False, near: list | None = None
) -> list[Callable[[np.ndarray], np.ndarray]]:
    """:func:`gauss_transfer` from each of ``olds`` to ``new`` (one point search for all: :func:`locate_many`).
    ``near``: per old mesh None or (element, reference coordinates) of ``new``'s points in a mesh close to it (the
    same mesh with its nodes moved a little, or ``new`` moved a little: :func:`located` of the pair): the points
    are first sought there (:func:`locate_near`)."""
    if near is None or all(g is None for g in near):
        at = points_in(olds, new)
    else:
        at = located(olds, new.quadrature_points.reshape(2, -1), near)
    return [_transfer(old, new, elem, loc, continuous) for old, (elem, loc) in zip(olds, at)]


def points_in(olds: list[AxiMesh], new: AxiMesh) -> list[tuple[np.ndarray, np.ndarray]]:
    """(element, reference coordinates) of ``new``'s Gauss points in each of ``olds`` (:func:`locate_many`, one
    search for the meshes not sought before), kept with ``new`` per old mesh: a fitted step's replayed history and
    its sensitivities (``fem.fitted_sensitivity``) seek the same points in the same past meshes."""
    kept: dict = new.derived("points_in", dict)
    missing = list({id(o): o for o in olds if kept.get(id(o), (None,))[0] is not o}.values())
    if missing:
        for o, got in zip(missing, locate_many(missing, new.quadrature_points.reshape(2, -1))):
            kept[id(o)] = (o, got)
    return [kept[id(o)][1] for o in olds]


def located(olds: list[AxiMesh], pts: np.ndarray, near: list | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """(element, reference coordinates) of the points ``pts`` (2, n) in each of ``olds``: :func:`locate_near` where
    ``near`` gives a start for that mesh, :func:`locate_many` (one search) for the others."""
    near = near if near is not None else [None] * len(olds)
    far = [i for i, g in enumerate(near) if g is None]
    out: list = [None] * len(olds)
    for i, got in zip(far, locate_many([olds[i] for i in far], pts) if far else []):
        out[i] = got
    for i, g in enumerate(near):
        if g is not None:
            out[i] = locate_near(olds[i], pts, g[0], g[1])
    return out


def own_points(mesh: AxiMesh) -> tuple[np.ndarray, np.ndarray]:
    """(element, reference coordinates) of ``mesh``'s own Gauss points: the ``near`` start of :func:`gauss_transfers`
    between meshes that nearly coincide (a fitted mesh and the next step's while the plate is held, or the same
    mesh with its contact edge moved by a small fraction)."""
    ne, nq = mesh.quadrature_points.shape[1:]
    return np.repeat(np.arange(ne), nq), _gauss_reference(mesh)


def locate_near(mesh: AxiMesh, pts: np.ndarray, elem: np.ndarray, start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`locate` of points ``pts`` (2, n) known to lie in (or next to) the elements ``elem`` near the reference
    coordinates ``start`` (2, n) (their location in a slightly different mesh): a few Newton steps from there; the
    points that leave [0, 1]^2 of that element are searched afresh (:func:`locate_many`), so the result is
    :func:`locate`'s (an element that contains the point)."""
    ref = np.asarray(mesh.basis.elem.doflocs, float).T
    loc = local_coordinates(mesh.element_nodes()[:, :, elem], ref, pts, iters=10, start=start)
    elem = np.asarray(elem).copy()
    out = np.flatnonzero((_excess(loc) > 1e-10) & (_excess(np.asarray(start)) <= 1e-10))
    if out.size:
        e2, l2 = locate_many([mesh], pts[:, out])[0]
        elem[out], loc[:, out] = e2, l2
    return elem, loc


def _transfer(
    old: AxiMesh, new: AxiMesh, elem: np.ndarray, loc: np.ndarray, continuous: bool
) -> Callable[[np.ndarray], np.ndarray]:
    """The transfer of :func:`gauss_transfer` with ``new``'s Gauss points located in ``old`` (``elem``, ``loc``)."""
    xq = new.quadrature_points  # (2, n_el, n_qp)
    ne, nq = xq.shape[1:]
    pts = xq.reshape(2, -1)
    if continuous:
        b = old.basis
        ref = np.asarray(b.elem.doflocs, float).T  # (2, 9)
        ia, ib = (np.rint(2.0 * r).astype(int) for r in ref)
        (v0, _), (v1, _) = lagrange2(loc[0]), lagrange2(loc[1])
        W = _at_points(old, elem, v0[ia] * v1[ib])  # the Q2 shape functions at the new points

        def smooth(f: np.ndarray) -> np.ndarray:
            lead, c = f.shape[:-3], f.shape[-1]
            g = f.reshape((-1,) + f.shape[-3:])  # (m, n_el, n_qp, c)
            out = _apply(W, nodal_average(old, g))  # (m, n, c)
            return out.reshape(lead + (ne, nq, c))

        return smooth

    G = np.asarray(old.basis.X)  # (2, n_qp) in [0, 1]^2
    powers = [(i, j) for i in range(3) for j in range(3)]
    V = np.stack([G[0] ** i * G[1] ** j for i, j in powers], axis=1)  # (n_qp, 9)
    P = np.stack([loc[0] ** i * loc[1] ** j for i, j in powers], axis=1)  # (n, 9)
    L = P @ np.linalg.inv(V)  # (n, n_qp): weights of the old element's Gauss values
    assert L.shape == (pts.shape[1], nq)
    T = _gauss_rows(old, elem, L)
    return lambda f: _apply_gauss(T, f, (ne, nq))


def _gauss_rows(old: AxiMesh, elem: np.ndarray, L: np.ndarray) -> sp.csr_matrix:
    """(n, old n_el n_qp): one row per point, the weights L (n, n_qp) of its old element ``elem`` (n,)'s Gauss
    values (CSR directly: a row's columns are distinct)."""
    nq = L.shape[1]
    cols = (np.asarray(elem)[:, None] * nq + np.arange(nq)).ravel()
    return sp.csr_matrix(
        (L.ravel(), cols, np.arange(0, L.size + 1, nq)), shape=(L.shape[0], old.quadrature_points.shape[1] * nq)
    )


def _apply_gauss(T: sp.csr_matrix, f: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """T (n, old n_el n_qp) applied to Gauss-point fields f (..., old n_el, n_qp, c): (..., n_el, n_qp, c) with
    n = n_el n_qp (``shape``)."""
    lead, c = f.shape[:-3], f.shape[-1]
    g = f.reshape((-1,) + f.shape[-3:])  # (m, old n_el, n_qp, c)
    out = T @ np.ascontiguousarray(g.transpose(1, 2, 0, 3)).reshape(-1, g.shape[0] * c)
    return np.ascontiguousarray(out.reshape(shape + (g.shape[0], c)).transpose(2, 0, 1, 3)).reshape(lead + shape + (c,))


class ElementJet:
    """The element-wise transfer of :func:`gauss_transfer` (``continuous=False``) from ``old`` to the points (2, n)
    located at (``elem``, ``loc``) in it, with its first derivatives in the meshes' motion: :meth:`value` is the
    transfer; :meth:`moved` its derivative when the points move by dp (2, n) and the old mesh's nodes by dX (2,
    n_nodes): the point's reference coordinates move by J^-1 (dp - sum_b N_b(xi) dX_b) (J the old element's map,
    N_b its Q2 shape functions) and the element's tensor-product quadratic through its Gauss values is
    differentiated there (the values held). Exact derivatives of the interpolation in the element that holds the
    point (``fem.fitted_sensitivity``: a held step's history on its mesh and on its moving neighbours)."""

    def __init__(self, old: AxiMesh, elem: np.ndarray, loc: np.ndarray, shape: tuple[int, int]) -> None:
        b = old.basis
        G = np.asarray(b.X)  # (2, n_qp)
        powers = [(i, j) for i in range(3) for j in range(3)]
        Vinv = np.linalg.inv(np.stack([G[0] ** i * G[1] ** j for i, j in powers], axis=1))
        u, v = loc
        P = np.stack([u**i * v**j for i, j in powers], axis=1)  # (n, 9)
        dPu = np.stack([i * u ** max(i - 1, 0) * v**j for i, j in powers], axis=1)
        dPv = np.stack([j * u**i * v ** max(j - 1, 0) for i, j in powers], axis=1)
        self.old, self.elem, self.shape = old, np.asarray(elem), shape
        self._ops: dict[tuple[int, int], tuple] = {}  # (dp, dX, operator) of recent motions (:meth:`moved`)
        self.T = _gauss_rows(old, self.elem, P @ Vinv)
        self.dL = (dPu @ Vinv, dPv @ Vinv)  # (n, n_qp) each: d weights / d xi, d eta
        ref = np.asarray(b.elem.doflocs, float).T  # (2, 9)
        ia, ib = (np.rint(2.0 * r).astype(int) for r in ref)
        (v0, d0), (v1, d1) = lagrange2(u), lagrange2(v)
        self.N = v0[ia] * v1[ib]  # (9, n): the Q2 shape functions of the old element's map
        dN = np.stack([d0[ia] * v1[ib], v0[ia] * d1[ib]])  # (2, 9, n)
        self.dofs = b.element_dofs[:, self.elem]  # (9, n)
        xe = np.asarray(b.doflocs)[:, self.dofs]  # (2, 9, n)
        J = np.einsum("ikn,dkn->idn", xe, dN)  # (2, 2, n): dx_i / dxi_d
        det = J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0]
        self.Jinv = np.stack([np.stack([J[1, 1], -J[0, 1]]), np.stack([-J[1, 0], J[0, 0]])]) / det

    def value(self, f: np.ndarray) -> np.ndarray:
        """The transferred fields (..., n_el, n_qp, c) of Gauss-value fields f (..., old n_el, n_qp, c)."""
        return _apply_gauss(self.T, f, self.shape)

    def moved(self, f: np.ndarray, dp: np.ndarray | None, dX: np.ndarray | None) -> np.ndarray:
        """The change of the transferred fields f (..., old n_el, n_qp, c) for the points moved by dp (2, n) and the
        old mesh's nodes by dX (2, n_nodes) (either None: fixed). The operator of the last few motions is kept
        (by the motions' identity: a held run moves the same meshes the same way at every step)."""
        key = (id(dp), id(dX))
        hit = self._ops.get(key)
        if hit is None or hit[0] is not dp or hit[1] is not dX:
            dx = np.zeros((2, self.N.shape[1])) if dp is None else np.array(dp, float)
            if dX is not None:
                dx -= np.einsum("ikn,kn->in", np.asarray(dX)[:, self.dofs], self.N)
            dxi = np.einsum("din,in->dn", self.Jinv, dx)  # (2, n)
            W = self.dL[0] * dxi[0][:, None] + self.dL[1] * dxi[1][:, None]
            if len(self._ops) > 3:
                self._ops.pop(next(iter(self._ops)))
            hit = self._ops[key] = (dp, dX, _gauss_rows(self.old, self.elem, W))
        return _apply_gauss(hit[2], f, self.shape)


def nodal_average(mesh: AxiMesh, f: np.ndarray) -> np.ndarray:
    """The continuous Q2 field of Gauss-value fields f (m, n_el, n_qp, c) of ``mesh``: each element's
    tensor-product quadratic through its Gauss values evaluated at its nodes, averaged over the elements that share
    a node: (m, n_nodes, c). One sparse product with an operator built once per mesh."""
    A = mesh.derived("nodal_average", lambda: _nodal_average_operator(mesh))
    m, ne, nq, c = f.shape
    g = np.ascontiguousarray(f.transpose(1, 2, 0, 3)).reshape(ne * nq, m * c)
    return np.ascontiguousarray((A @ g).reshape(-1, m, c).transpose(1, 0, 2))


def _nodal_average_operator(mesh: AxiMesh) -> sp.csr_matrix:
    """(n_nodes, n_el n_qp): Gauss values -> the element quadratics' values at the nodes, averaged per node."""
    b = mesh.basis
    ref = np.asarray(b.elem.doflocs, float).T  # (2, 9)
    G = np.asarray(b.X)  # (2, n_qp)
    powers = [(i, j) for i in range(3) for j in range(3)]
    V = np.stack([G[0] ** i * G[1] ** j for i, j in powers], axis=1)
    Pn = np.stack([ref[0] ** i * ref[1] ** j for i, j in powers], axis=1)
    to_nodes = Pn @ np.linalg.inv(V)  # (9, n_qp): the element quadratic at its nodes
    ed = b.element_dofs  # (9, n_el)
    ne, nq = ed.shape[1], G.shape[1]
    count = np.bincount(ed.ravel(), minlength=b.N).astype(float)
    rows = np.broadcast_to(ed[:, :, None], (9, ne, nq))
    cols = np.broadcast_to(np.arange(ne)[None, :, None] * nq + np.arange(nq)[None, None, :], (9, ne, nq))
    vals = to_nodes[:, None, :] / count[ed][:, :, None]
    return sp.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=(b.N, ne * nq))


def _at_points(mesh: AxiMesh, elem: np.ndarray, weights: np.ndarray) -> sp.csr_matrix:
    """(n, n_nodes): the combination ``weights`` (9, n) of the nodes of each point's element ``elem`` (n,)."""
    dofs = mesh.basis.element_dofs[:, elem]  # (9, n): distinct within a row, so CSR directly (no COO sort)
    k, n = dofs.shape
    indptr = np.arange(0, k * n + 1, k)
    return sp.csr_matrix((weights.T.ravel(), dofs.T.ravel(), indptr), shape=(n, mesh.basis.N))


def _apply(W: sp.csr_matrix, nodal: np.ndarray) -> np.ndarray:
    """W (n, n_nodes) applied to nodal fields (m, n_nodes, c): (m, n, c)."""
    m, N, c = nodal.shape
    out = W @ np.ascontiguousarray(nodal.transpose(1, 0, 2)).reshape(N, m * c)
    return out.reshape(-1, m, c).transpose(1, 0, 2)


class ContinuousJet:
    """The continuous transfer of :func:`gauss_transfer` (``continuous=True``) from ``old`` to the points ``pts``
    (2, n) located at (``elem``, ``loc``) in it, with its first derivatives in the meshes' motion: :meth:`value`
    is the transfer itself; :meth:`moved` is its derivative when the points move by dp (2, n) and the old mesh's
    nodes by dX (2, n_nodes) (the nodal values held: the element quadratic of a Gauss-value field is fixed by the
    values, its nodal average by the numbering; the point's reference coordinates move by J^-1 (dp - sum_b N_b(xi)
    dX_b), J the old element's map). Exact derivatives of the interpolation in the element that holds the point
    (the fitted time runs' sensitivities: ``fem.fitted_sensitivity``)."""

    def __init__(self, old: AxiMesh, elem: np.ndarray, loc: np.ndarray, shape: tuple[int, int]) -> None:
        b = old.basis
        self.old = old
        ref = np.asarray(b.elem.doflocs, float).T  # (2, 9)
        ia, ib = (np.rint(2.0 * r).astype(int) for r in ref)
        (v0, d0), (v1, d1) = lagrange2(loc[0]), lagrange2(loc[1])
        self.elem = np.asarray(elem)
        self.N = v0[ia] * v1[ib]  # (9, n)
        self.W = _at_points(old, self.elem, self.N)  # (n, n_nodes): the transfer of nodal values
        self.dN = np.stack([d0[ia] * v1[ib], v0[ia] * d1[ib]])  # (2, 9, n): d/dxi, d/deta
        self.dofs = b.element_dofs[:, self.elem]  # (9, n)
        xe = np.asarray(b.doflocs)[:, self.dofs]  # (2, 9, n) the old element's nodes
        J = np.einsum("ikn,dkn->idn", xe, self.dN)  # (2, 2, n): dx_i / dxi_d
        det = J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0]
        self.Jinv = np.stack([np.stack([J[1, 1], -J[0, 1]]), np.stack([-J[1, 0], J[0, 0]])]) / det  # (2, 2, n)
        self.shape = shape  # (n_el, n_qp) of the points

    def nodal(self, f: np.ndarray) -> np.ndarray:
        """The continuous (nodally averaged) element quadratics of the Gauss-value fields f (m, old n_el, n_qp, c) at
        the old mesh's nodes: (m, n_nodes, c), the input of :meth:`value` and :meth:`moved` (:func:`nodal_average`)."""
        return nodal_average(self.old, f)

    def value(self, nd: np.ndarray) -> np.ndarray:
        """The transferred fields (m, n_el, n_qp, c) from :meth:`nodal`'s (m, n_nodes, c)."""
        return _apply(self.W, nd).reshape((nd.shape[0],) + self.shape + (nd.shape[-1],))

    def moved(self, nd: np.ndarray, dp: np.ndarray | None, dX: np.ndarray | None) -> np.ndarray:
        """The change of the transferred fields (m, n_el, n_qp, c) (:meth:`nodal`'s nd) for the points moved by dp
        (2, n) and the old mesh's nodes by dX (2, n_nodes) (either None: fixed)."""
        dx = np.zeros((2, self.N.shape[1])) if dp is None else np.array(dp, float)
        if dX is not None:
            dx -= np.einsum("ikn,kn->in", np.asarray(dX)[:, self.dofs], self.N)
        dxi = np.einsum("din,in->dn", self.Jinv, dx)  # (2, n)
        dNv = np.einsum("dkn,dn->kn", self.dN, dxi)  # (9, n)
        return _apply(_at_points(self.old, self.elem, dNv), nd).reshape((nd.shape[0],) + self.shape + (nd.shape[-1],))


def deformation_at(mesh: AxiMesh, x: np.ndarray, points: AxiMesh) -> np.ndarray:
    """The 5-component deformation gradient f = (F_rR, F_rZ, F_zR, F_zZ, F_tt) (n_el, n_qp, 5) of the
    displacement ``x`` (interleaved (u_r, u_z) dofs of the Q2 ``mesh``, or the full unknown vector) at the Gauss
    points of ``points`` (another mesh of the same body: material points in the reference configuration). The
    FE field itself is evaluated there (no interpolation of point values): on ``points is mesh`` it is the
    assembler's f to round-off. ``x`` (k, n): k displacements of the mesh at once (one search), f (k, n_el,
    n_qp, 5)."""
    xq = points.quadrature_points
    ne, nq = xq.shape[1:]
    pts = xq.reshape(2, -1)
    elem, loc = locate(mesh, pts)
    b = mesh.basis
    ref = np.asarray(b.elem.doflocs, float).T
    ia, ib = (np.rint(2.0 * r).astype(int) for r in ref)
    (v0, d0), (v1, d1) = lagrange2(loc[0]), lagrange2(loc[1])
    N, Na, Nb = v0[ia] * v1[ib], d0[ia] * v1[ib], v0[ia] * d1[ib]  # (9, n) and the derivatives in xi, eta
    ed = b.element_dofs[:, elem]  # (9, n)
    xe = b.doflocs[:, ed]  # (2, 9, n)
    xs = np.asarray(x, float)
    many = xs.ndim == 2
    xs = xs if many else xs[None]
    ue = np.stack([xs[:, 2 * ed], xs[:, 2 * ed + 1]], axis=1)  # (k, 2, 9, n)
    Ja, Jb = np.einsum("ikn,kn->in", xe, Na), np.einsum("ikn,kn->in", xe, Nb)  # dX/dxi, dX/deta (2, n)
    det = Ja[0] * Jb[1] - Jb[0] * Ja[1]
    ua, ub = np.einsum("sikn,kn->sin", ue, Na), np.einsum("sikn,kn->sin", ue, Nb)
    # du/dX = [du/dxi du/deta] J^-1, J = [[dR/dxi, dR/deta], [dZ/dxi, dZ/deta]]
    dR = (ua * Jb[1] - ub * Ja[1]) / det
    dZ = (-ua * Jb[0] + ub * Ja[0]) / det
    R = np.einsum("kn,kn->n", xe[0], N)
    ur = np.einsum("skn,kn->sn", ue[:, 0], N)
    f = np.stack([1.0 + dR[:, 0], dZ[:, 0], dR[:, 1], 1.0 + dZ[:, 1], 1.0 + ur / R], axis=-1)
    f = f.reshape(xs.shape[0], ne, nq, 5)
    return f if many else f[0]
