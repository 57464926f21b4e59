"""fem.transfer: Gauss-point history between contact-edge-fitted meshes."""

import numpy as np

from tissuemech.fem.mesh import fitted_mesh
from tissuemech.fem.transfer import deformation_at, gauss_transfer, lagrange2, local_coordinates

A0 = 500e-6


def test_gauss_point_history_transfer_between_fitted_meshes():
    """The Maxwell history moves to a new fitted mesh by interpolation in the reference configuration: exact
    for fields linear in (R, Z) even when the edge moves by 40 % (points change elements), identity on the
    same mesh, and second order for a smooth field (vs carrying the values by index: O(1) of the shift)."""

    a, b = fitted_mesh(A0, 1, 0.2), fitted_mesh(A0, 1, 0.28)
    xa, xb = (np.asarray(m.basis.mapping.F(m.basis.X)) for m in (a, b))
    lin = lambda x: np.stack([1 + x[0] + 2 * x[1], x[0] - 3 * x[1]], axis=-1)
    assert np.max(np.abs(gauss_transfer(a, b)(lin(xa)[None]) - lin(xb)[None])) < 1e-12
    f = np.random.default_rng(0).random((2,) + xa.shape[1:] + (5,))
    assert np.max(np.abs(gauss_transfer(a, a)(f) - f)) < 1e-12
    smooth = lambda x: (np.sin(3 * x[1]) + x[0] ** 3)[..., None]
    moved = np.max(np.abs(smooth(xa) - smooth(xb)))
    assert np.max(np.abs(gauss_transfer(a, b)(smooth(xa)) - smooth(xb))) < 0.02 * moved


def test_gauss_point_transfer_takes_each_point_from_an_old_element_that_contains_it():
    """Every Gauss point of the new fitted mesh that lies in the old mesh takes its history from an old element
    that contains it (reference coordinates in [0, 1]^2), not by extrapolation from a neighbour: an element-wise
    constant field arrives as the index of such an element. (Before issue 14's search from the nearest old
    Gauss point, 31 points of this pair came from an element they lie 8-33 % of an element outside.)"""

    a, b = fitted_mesh(A0, 1, 0.05), fitted_mesh(A0, 1, 0.1)
    ne, nq = a.basis.nelems, a.basis.X.shape[1]
    index = np.repeat(np.arange(ne, dtype=float)[:, None, None], nq, axis=1)
    got = gauss_transfer(a, b)(index).ravel()
    elem = np.rint(got).astype(int)
    assert np.abs(got - elem).max() < 1e-9  # a constant arrives unchanged
    pts = np.asarray(b.basis.mapping.F(b.basis.X)).reshape(2, -1)
    ref = np.asarray(a.basis.elem.doflocs, float).T
    xe = a.basis.doflocs[:, a.basis.element_dofs]
    excess = lambda lc: np.max(np.maximum(np.maximum(-lc, lc - 1.0), 0.0), axis=0)
    chosen = excess(local_coordinates(xe[:, :, elem], ref, pts, iters=30))
    outside = np.flatnonzero(chosen > 1e-10)
    assert outside.size < 0.05 * pts.shape[1]
    for k in outside:  # outside the chosen element: then outside every old element (beyond the old boundary)
        lc = local_coordinates(xe, ref, np.repeat(pts[:, [k]], ne, axis=1), iters=30)
        assert excess(lc).min() > 1e-10, (k, elem[k], int(np.argmin(excess(lc))))


def test_deformation_at_evaluates_the_fe_field_at_another_meshs_points():
    """deformation_at: on the mesh itself the assembler's F to round-off; at another fitted mesh's Gauss points
    a linear displacement's F exactly (the Q2 isoparametric field reproduces it everywhere)."""
    from tissuemech.fem.forms import Assembler

    a, b = fitted_mesh(A0, 1, 0.2), fitted_mesh(A0, 1, 0.3)
    asm = Assembler(a)
    X = a.X
    x = np.zeros(asm.ndof)
    x[0 : asm.n_u : 2] = 0.05 * X[0] + 0.02 * X[0] * X[1] ** 2
    x[1 : asm.n_u : 2] = -0.04 * X[1] + 0.01 * X[0] ** 2
    assert np.abs(deformation_at(a, x, a) - asm.f_at(x)).max() < 1e-13
    lin = np.zeros(asm.ndof)
    lin[0 : asm.n_u : 2], lin[1 : asm.n_u : 2] = 0.05 * X[0], -0.04 * X[1] + 0.03 * X[0]
    f = deformation_at(a, lin, b)
    np.testing.assert_allclose(f, np.broadcast_to([1.05, 0.0, 0.03, 0.96, 1.05], f.shape), rtol=0, atol=1e-12)


def test_continuous_transfer_is_continuous_and_stable_when_chained():
    """gauss_transfer(..., continuous=True): a smooth field carried through a chain of 16 fitted meshes (the edge
    moving 0.1 -> 0.3) stays within 1e-2 of the field at the last mesh (the element-wise fit, not continuous,
    drifts 10x further); a point moving across an old element boundary sees no jump."""
    smooth = lambda x: (np.sin(3 * x[1]) + x[0] ** 3)[..., None]
    es = np.linspace(0.1, 0.3, 17)
    drift = {}
    for cont in (True, False):
        v = smooth(fitted_mesh(A0, 1, es[0]).quadrature_points)
        for e0, e1 in zip(es[:-1], es[1:]):
            v = gauss_transfer(fitted_mesh(A0, 1, e0), fitted_mesh(A0, 1, e1), continuous=cont)(v)
        drift[cont] = np.abs(v - smooth(fitted_mesh(A0, 1, es[-1]).quadrature_points)).max()
    assert drift[True] < 1e-2 < drift[False]
    # two meshes whose edges differ by 1e-9: the continuous transfers from one old mesh differ by ~1e-9
    old = fitted_mesh(A0, 1, 0.2)
    f = np.random.default_rng(1).random((1,) + old.quadrature_points.shape[1:] + (2,))
    t1 = gauss_transfer(old, fitted_mesh(A0, 1, 0.25), continuous=True)(f)
    t2 = gauss_transfer(old, fitted_mesh(A0, 1, 0.25 + 1e-9), continuous=True)(f)
    assert np.abs(t1 - t2).max() < 1e-6


def test_locating_in_many_meshes_at_once_is_locating_in_each():
    """fem.transfer.locate_many (the replayed history's one search over every step's mesh) finds the same elements
    and reference coordinates as one search per mesh, for fitted meshes whose edges differ a little (every point
    found in the first pass) and a lot (points that change element go through the candidate rounds)."""
    from tissuemech.fem.transfer import locate, locate_many

    target = fitted_mesh(A0, 1, 0.3)
    pts = target.quadrature_points.reshape(2, -1)
    meshes = [fitted_mesh(A0, 1, e) for e in (0.05, 0.2, 0.29, 0.3, 0.45)]
    for mesh, (elem, loc) in zip(meshes, locate_many(meshes, pts)):
        e1, l1 = locate(mesh, pts)
        assert np.array_equal(elem, e1)
        np.testing.assert_allclose(loc, l1, rtol=0, atol=1e-13)
        inside = np.all((loc >= -1e-10) & (loc <= 1 + 1e-10), axis=0)
        assert inside.mean() > 0.99
        # the element's isoparametric map at the coordinates found gives the point back
        b = mesh.basis
        ref = np.asarray(b.elem.doflocs, float).T
        ia, ib = (np.rint(2.0 * r).astype(int) for r in ref)
        (v0, _), (v1, _) = lagrange2(loc[0]), lagrange2(loc[1])
        x = np.einsum("ikn,kn->in", b.doflocs[:, b.element_dofs][:, :, elem], v0[ia] * v1[ib])
        assert np.max(np.abs(x - pts)[:, inside]) < 1e-12


def test_continuous_jet_is_the_transfer_and_its_derivative_in_both_meshes_motion():
    """``ContinuousJet``: its value is the continuous transfer; its motion terms equal central differences of the
    transfer between fitted meshes whose contact edge moves (the source's nodes, the target's points) to the
    differences' truncation (~1e-8 of the largest)."""
    from tissuemech.fem.mesh import fitted_mesh
    from tissuemech.fem.transfer import ContinuousJet, located

    h, e_src, e_tgt = 1e-4, 0.3, 0.31
    src, tgt = fitted_mesh(1.0, 1, e_src), fitted_mesh(1.0, 1, e_tgt)
    q = src.quadrature_points
    f = np.stack([np.sin(3 * q[0]) * np.cos(2 * q[1]), q[0] ** 2 + q[1]], -1)[None]
    (at,) = located([src], tgt.quadrature_points.reshape(2, -1))
    jet = ContinuousJet(src, *at, tgt.quadrature_points.shape[1:])
    nd = jet.nodal(f)
    np.testing.assert_allclose(jet.value(nd), gauss_transfer(src, tgt, continuous=True)(f), rtol=0, atol=1e-14)
    sl, sh = fitted_mesh(1.0, 1, e_src * (1 - h)), fitted_mesh(1.0, 1, e_src * (1 + h))
    fd = (gauss_transfer(sh, tgt, continuous=True)(f) - gauss_transfer(sl, tgt, continuous=True)(f)) / (2 * h)
    dX = (np.asarray(sh.basis.doflocs) - np.asarray(sl.basis.doflocs)) / (2 * h)
    assert np.max(np.abs(jet.moved(nd, None, dX) - fd)) <= 1e-7 * np.max(np.abs(fd))
    tl, th = fitted_mesh(1.0, 1, e_tgt * (1 - h)), fitted_mesh(1.0, 1, e_tgt * (1 + h))
    fd = (gauss_transfer(src, th, continuous=True)(f) - gauss_transfer(src, tl, continuous=True)(f)) / (2 * h)
    dp = (th.quadrature_points - tl.quadrature_points).reshape(2, -1) / (2 * h)
    assert np.max(np.abs(jet.moved(nd, dp, None) - fd)) <= 1e-7 * np.max(np.abs(fd))


def test_element_jet_is_the_element_wise_transfer_and_its_derivative_in_both_meshes_motion():
    """``ElementJet``: its value is the element-wise transfer; its motion terms equal central differences of the
    transfer between fitted meshes whose contact edge moves (the source's nodes, the target's points) to the
    differences' truncation (~1e-8 of the largest); the held step's case (a mesh onto itself moving) included."""
    from tissuemech.fem.mesh import fitted_mesh
    from tissuemech.fem.transfer import ElementJet, located

    h = 1e-4
    for e_src, e_tgt in ((0.3, 0.31), (0.3, 0.3)):
        src, tgt = fitted_mesh(1.0, 1, e_src), fitted_mesh(1.0, 1, e_tgt)
        q = src.quadrature_points
        f = np.stack([np.sin(3 * q[0]) * np.cos(2 * q[1]), q[0] ** 2 + q[1]], -1)[None]
        (at,) = located([src], tgt.quadrature_points.reshape(2, -1))
        jet = ElementJet(src, *at, tgt.quadrature_points.shape[1:])
        np.testing.assert_allclose(jet.value(f), gauss_transfer(src, tgt)(f), rtol=0, atol=1e-14)
        sl, sh = fitted_mesh(1.0, 1, e_src * (1 - h)), fitted_mesh(1.0, 1, e_src * (1 + h))
        fd = (gauss_transfer(sh, tgt)(f) - gauss_transfer(sl, tgt)(f)) / (2 * h)
        dX = (np.asarray(sh.basis.doflocs) - np.asarray(sl.basis.doflocs)) / (2 * h)
        assert np.max(np.abs(fd)) > 1e-3
        assert np.max(np.abs(jet.moved(f, None, dX) - fd)) <= 1e-7 * np.max(np.abs(fd))
        tl, th = fitted_mesh(1.0, 1, e_tgt * (1 - h)), fitted_mesh(1.0, 1, e_tgt * (1 + h))
        fd = (gauss_transfer(src, th)(f) - gauss_transfer(src, tl)(f)) / (2 * h)
        dp = (th.quadrature_points - tl.quadrature_points).reshape(2, -1) / (2 * h)
        assert np.max(np.abs(jet.moved(f, dp, None) - fd)) <= 1e-7 * np.max(np.abs(fd))
