r"""Structured (mapped) axisymmetric meshes of a hollow-sphere wall and a solid ball.

API
---
``AxiMesh``                 dataclass: skfem mesh + scalar ``skfem.CellBasis`` (Q2 isoparametric or Q1),
                            nodal coordinates ``X`` (2, N) in units of ``length_scale`` (dimensionless),
                            ``nodes[name]`` (scalar dof indices on a boundary) and ``edges[name]``
                            ((n_edges, 2 or 3) dof indices ordered along each boundary edge, oriented
                            with the material on the left: outward normal ~ (dZ, -dR)).
``shell_section(A, B, n_radial, n_circ, *, grading=1.0, order=2, half=False)``
                            quarter (0 <= theta <= 90 deg from the equator) or half wall section of a
                            hollow sphere, lengths scaled by A; tags "inner", "outer", "symmetry" (Z = 0),
                            "axis" (R = 0; for ``half`` the two axis segments). ``grading`` > 1 refines
                            toward the inner surface (geometric ratio of the outermost to innermost layer).
``ball_section(a0, n_core, n_radial, *, grading=1.0, pole_grading=1.0, order=2, pole_points=None,
radial_points=None, n_equator=None, split_angle=pi/4)``
                            quarter disk (R >= 0, Z >= 0) of a solid ball as an O-grid (core square + two
                            curved blocks), lengths scaled by a0, refined toward the surface (``grading``)
                            and toward the top pole R = 0, Z = a0 (``pole_grading``); tags "axis" (R = 0),
                            "symmetry" (Z = 0), "outer" (surface). Explicit node positions
                            (``pole_points``, ``radial_points``) place a node on a contact edge; the node
                            numbering depends on the divisions only, not on the positions.
Coordinates: (R, Z) = (radial, axial); the axis of symmetry is R = 0.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
import skfem
from scipy.optimize import brentq
from scipy.spatial import cKDTree

__all__ = [
    "AxiMesh",
    "shell_section",
    "ball_section",
    "graded_points",
    "fitted_mesh",
    "fitted_nodes",
    "FITTED_LEVELS",
    "FITTED_SPLIT",
    "FITTED_EDGE_MAX",
    "full_ball_section",
    "zone_points",
    "surface_layers",
]


@dataclass
class AxiMesh:
    """A meshed axisymmetric section (dimensionless coordinates; multiply by ``length_scale`` for m)."""

    mesh: skfem.Mesh
    basis: skfem.CellBasis
    order: int
    length_scale: float
    nodes: dict = field(default_factory=dict)
    edges: dict = field(default_factory=dict)
    _cache: dict = field(default_factory=dict, repr=False, compare=False)  # derived data (e.g. search trees)

    def search_trees(self) -> tuple[cKDTree, cKDTree]:
        """(k-d tree of the quadrature points, k-d tree of the element centres) in reference coordinates, built
        once per mesh (``fem.transfer`` locates points in the mesh with them)."""
        if "search_trees" not in self._cache:
            self._cache["search_trees"] = (
                cKDTree(self.quadrature_points.reshape(2, -1).T),
                cKDTree(self.element_nodes().mean(axis=1).T),
            )
        return self._cache["search_trees"]

    def derived(self, key: str, build: Callable[[], Any]) -> Any:
        """Data derived from this mesh alone (or kept with it, e.g. other meshes' point locations), built once by
        ``build()`` and kept as long as the mesh lives (``fem.transfer``'s operators and searches)."""
        if key not in self._cache:
            self._cache[key] = build()
        return self._cache[key]

    def element_nodes(self) -> np.ndarray:
        """Reference coordinates of every element's nodes (2, nodes per element, n_elements), dimensionless
        (gathered once per mesh: ``fem.transfer`` inverts the element maps with them)."""
        if "element_nodes" not in self._cache:
            self._cache["element_nodes"] = self.basis.doflocs[:, self.basis.element_dofs]
        return self._cache["element_nodes"]

    @property
    def quadrature_points(self) -> np.ndarray:
        """Reference coordinates (R, Z) of the quadrature points (2, n_elements, n_points), dimensionless
        (computed once per mesh)."""
        if "quadrature_points" not in self._cache:
            self._cache["quadrature_points"] = np.asarray(self.basis.mapping.F(self.basis.X))
        return self._cache["quadrature_points"]

    @property
    def X(self) -> np.ndarray:
        """Nodal (dof) coordinates (2, N), dimensionless."""
        return self.basis.doflocs

    @property
    def n_nodes(self) -> int:
        return self.basis.N

    @property
    def n_dofs(self) -> int:
        """Displacement dofs, interleaved (u_r, u_z) per node: dof 2 i is u_r, 2 i + 1 is u_z."""
        return 2 * self.basis.N


def graded_points(n: int, ratio: float = 1.0) -> np.ndarray:
    """n + 1 points on [0, 1]; consecutive intervals grow geometrically so last/first = ratio."""
    if n < 1:
        raise ValueError(f"a mesh needs at least one division, got {n}")
    if ratio <= 0 or not np.isfinite(ratio):
        raise ValueError(f"mesh grading must be a positive finite ratio, got {ratio}")
    if n == 1 or abs(ratio - 1.0) < 1e-14:
        return np.linspace(0.0, 1.0, n + 1)
    q = ratio ** (1.0 / (n - 1))
    h = q ** np.arange(n)
    return np.concatenate([[0.0], np.cumsum(h) / h.sum()])


def _finish(mesh1: skfem.Mesh, order: int, mapper, scale: float, tagger, intorder: int | None = None) -> AxiMesh:
    """Make the Q1 mesh quadratic (if order 2), map all geometry nodes, build basis (Gauss rule exact to
    degree ``intorder``, default 2 order + 2) and tags."""
    if order == 2:
        m = skfem.MeshQuad2.from_mesh(mesh1)
        m = skfem.MeshQuad2(mapper(m.doflocs), m.t)
        elem = skfem.ElementQuad2()
    elif order == 1:
        m = skfem.MeshQuad(mapper(mesh1.p), mesh1.t)
        elem = skfem.ElementQuad1()
    else:
        raise ValueError(f"element order must be 1 or 2, got {order}")
    if intorder is None:
        intorder = 2 * order + 2
    elif isinstance(intorder, bool) or not isinstance(intorder, (int, np.integer)) or intorder < 2 * order:
        raise ValueError(
            f"intorder (the polynomial degree the Gauss rule integrates exactly) must be a whole number >= "
            f"{2 * order} for order-{order} elements, got {intorder!r}"
        )
    basis = skfem.CellBasis(m, elem, intorder=int(intorder))
    X = basis.doflocs
    bf = m.boundary_facets()
    v = m.facets[:, bf]  # (2, nbf) vertex (= nodal dof) indices
    # orient every boundary edge positively: the material on its left (outward normal (z', -r'))
    el = m.f2t[0, bf]
    cen = m.p[:, m.t[:4, el]].mean(axis=1)
    p0, p1 = m.p[:, v[0]], m.p[:, v[1]]
    flip = (p1[0] - p0[0]) * (cen[1] - p0[1]) - (p1[1] - p0[1]) * (cen[0] - p0[0]) < 0
    v = np.where(flip, v[::-1], v)
    if order == 2:
        mid = basis.facet_dofs[0, bf]
        ed = np.stack([v[0], mid, v[1]], axis=1)
    else:
        ed = v.T.copy()
    nodes, edges = {}, {}
    for name, test in tagger.items():
        on = np.all(test(X[:, ed]), axis=1)
        edges[name] = ed[on]
        nodes[name] = np.unique(ed[on])
    return AxiMesh(m, basis, order, float(scale), nodes, edges)


def shell_section(
    inner_radius: float,
    outer_radius: float,
    n_radial: int,
    n_circ: int,
    *,
    grading: float = 1.0,
    order: int = 2,
    half: bool = False,
    intorder: int | None = None,
) -> AxiMesh:
    """Mapped mesh of the hollow-sphere wall A <= rho <= B (lengths scaled by A).

    theta (from the equator Z = 0) spans [0, 90] deg (quarter, with Z-symmetry) or [-90, 90] deg
    (``half``, the seed's section). Isoparametric Q2 elements represent the circles exactly up to
    the quadratic interpolation of the polar map. ``intorder``: polynomial degree the basis's Gauss
    rule integrates exactly (default 2 order + 2; ``fem.blastula`` takes 2 order: 3 x 3 points on Q2).
    """
    if not (0 < inner_radius < outer_radius):
        raise ValueError(f"need 0 < inner_radius < outer_radius, got {inner_radius}, {outer_radius}")
    b = outer_radius / inner_radius
    s = graded_points(n_radial, grading)  # fine near s = 0 (inner) when grading > 1
    t = np.linspace(0.0, 1.0, n_circ + 1)
    m1 = skfem.MeshQuad.init_tensor(s, t)
    th0, th1 = (-0.5 * np.pi if half else 0.0), 0.5 * np.pi

    def mapper(p):
        rho = 1.0 + (b - 1.0) * p[0]
        th = th0 + (th1 - th0) * p[1]
        return np.array([rho * np.cos(th), rho * np.sin(th)])

    tol = 1e-9
    rad = lambda P: np.hypot(P[0], P[1])
    tags = {
        "inner": lambda P: np.abs(rad(P) - 1.0) < tol,
        "outer": lambda P: np.abs(rad(P) - b) < tol,
        "axis": lambda P: np.abs(P[0]) < tol,
    }
    if not half:
        tags["symmetry"] = lambda P: np.abs(P[1]) < tol
    return _finish(m1, order, mapper, inner_radius, tags, intorder)


def _check_points(p, n: int, name: str) -> np.ndarray:
    p = np.asarray(p, dtype=float)
    if p.shape != (n + 1,) or abs(p[0]) > 1e-14 or abs(p[-1] - 1) > 1e-14 or np.any(np.diff(p) <= 0):
        raise ValueError(f"{name} must be {n + 1} increasing numbers from 0 to 1 (fractions of the block edge)")
    return np.r_[0.0, p[1:-1], 1.0]


def ball_section(
    radius: float,
    n_core: int,
    n_radial: int,
    *,
    grading: float = 1.0,
    pole_grading: float = 1.0,
    order: int = 2,
    pole_points: np.ndarray | None = None,
    radial_points: np.ndarray | None = None,
    n_equator: int | None = None,
    split_angle: float = 0.25 * np.pi,
    intorder: int | None = None,
) -> AxiMesh:
    """O-grid quarter disk of a solid ball (lengths scaled by ``radius``).

    Core square [0, c]^2 (c = 0.55) with ``n_core`` divisions per side, two curved blocks between the
    square and the arc with ``n_radial`` layers. ``grading`` > 1 refines toward the surface,
    ``pole_grading`` > 1 refines toward the top pole (R = 0, Z = 1), the plate contact zone.
    ``pole_points`` (n_core + 1 increasing values from 0 to 1; replaces ``pole_grading``): the node
    positions along the pole block, as fractions of its arc (the surface angle from the pole is
    (pi/4) u) and of the core's top edge (R = c u): e.g. a surface node placed on a contact edge.
    ``radial_points`` (n_radial + 1 increasing values from 0 at the core to 1 at the surface;
    replaces ``grading``): the layer boundaries of both curved blocks. ``n_equator`` (default ``n_core``):
    divisions of the equator block's arc and of the core in Z (the core is n_core x n_equator).
    ``split_angle`` (rad from the pole, default pi/4): where the pole block's arc ends and the equator
    block's begins; the core is the rectangle [0, c sqrt2 sin(split)] x [0, c sqrt2 cos(split)].
    ``intorder``: polynomial degree the basis's Gauss rule integrates exactly (default 2 order + 2).
    """
    out = _ball_section(radius, n_core, n_radial, grading=grading, pole_grading=pole_grading, order=order,
                        pole_points=pole_points, radial_points=radial_points, n_equator=n_equator,
                        split_angle=split_angle, intorder=intorder, nodes_only=False)  # fmt: skip
    assert isinstance(out, AxiMesh)
    return out


def _ball_section(
    radius: float,
    n_core: int,
    n_radial: int,
    *,
    grading: float,
    pole_grading: float,
    order: int,
    pole_points: np.ndarray | None,
    radial_points: np.ndarray | None,
    n_equator: int | None,
    split_angle: float,
    intorder: int | None,
    nodes_only: bool,
) -> AxiMesh | np.ndarray:
    """:func:`ball_section`; ``nodes_only``: only the node (dof) coordinates (2, n_nodes) of that mesh, without
    building its basis where the divisions' topology is known (:func:`fitted_nodes`)."""
    if not (radius > 0 and np.isfinite(radius)):
        raise ValueError(f"ball radius must be positive, got {radius}")
    c = 0.55
    if not (0.05 < split_angle < 0.5 * np.pi - 0.05):
        raise ValueError(f"split_angle must be in (0.05, pi/2 - 0.05) rad, got {split_angle}")
    cr, cz = c * np.sqrt(2) * np.sin(split_angle), c * np.sqrt(2) * np.cos(split_angle)
    if abs(split_angle - 0.25 * np.pi) < 1e-15:
        cr = cz = c
    u_pole = graded_points(n_core, pole_grading)  # 0 at the axis, fine there if pole_grading > 1
    if pole_points is not None:
        u_pole = _check_points(pole_points, n_core, "pole_points")
    n_eq = n_core if n_equator is None else int(n_equator)
    if n_eq < 1:
        raise ValueError(f"a mesh needs at least one division, got n_equator = {n_equator}")
    u_eq = np.linspace(0.0, 1.0, n_eq + 1)
    v = graded_points(n_radial, 1.0 / grading)  # 0 at the core, 1 at the surface (fine there)
    if radial_points is not None:
        v = _check_points(radial_points, n_radial, "radial_points")

    pts: list[np.ndarray] = []
    quads: list[np.ndarray] = []

    def block(P):  # P: (n1+1, n2+1, 2) structured block -> quads (counterclockwise checked later)
        n1, n2 = P.shape[0] - 1, P.shape[1] - 1
        off = sum(len(q) for q in pts)
        pts.append(P.reshape(-1, 2))
        idx = off + np.arange((n1 + 1) * (n2 + 1)).reshape(n1 + 1, n2 + 1)
        quads.append(np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], -1).reshape(-1, 4))

    # core: R = cr u_pole (graded toward the axis), Z = cz u_eq
    block(np.stack(np.meshgrid(cr * u_pole, cz * u_eq, indexing="ij"), -1))
    # equator block: inner edge (cr, cz u), outer arc at angle (pi/2 - split) u from the equator
    inner = np.stack([np.full_like(u_eq, cr), cz * u_eq], -1)
    phi = (0.5 * np.pi - split_angle) * u_eq
    outer = np.stack([np.cos(phi), np.sin(phi)], -1)
    block((1 - v)[:, None, None] * inner[None] + v[:, None, None] * outer[None])
    # pole block: inner edge (cr u, cz), outer arc at angle split u from the pole
    inner = np.stack([cr * u_pole, np.full_like(u_pole, cz)], -1)
    outer = np.stack([np.sin(split_angle * u_pole), np.cos(split_angle * u_pole)], -1)
    block((1 - v)[None, :, None] * inner[:, None] + v[None, :, None] * outer[:, None])

    P = np.concatenate(pts)
    key = (n_core, n_radial, n_eq, order, intorder, float(split_angle))
    if key in _BALL_TOPOLOGY:  # the same divisions: only the node positions change (fitted meshes, issue 14)
        if nodes_only:
            return _moved_nodes(_BALL_TOPOLOGY[key], P)
        return _moved_ball(_BALL_TOPOLOGY[key], P, radius)
    Q = np.concatenate(quads)
    m1, first = _merged(P, Q)  # the blocks' shared points merged (one numbering per divisions), counterclockwise

    mapper: Callable[..., np.ndarray]
    if order == 2:
        mapper, mids = _on_arc(m1)
    else:
        mapper = lambda p: p

    tol = 1e-9
    tags = {
        "axis": lambda P: np.abs(P[0]) < tol,
        "symmetry": lambda P: np.abs(P[1]) < tol,
        "outer": lambda P: np.abs(np.hypot(P[0], P[1]) - 1.0) < 1e-9,
    }
    out = _finish(m1, order, mapper, radius, tags, intorder)
    if order == 2:
        _BALL_TOPOLOGY[key] = _BallTopology(first, mids, m1.facets, m1.t2f, m1.t, out, intorder or 2 * order + 2)
        while len(_BALL_TOPOLOGY) > 8:
            _BALL_TOPOLOGY.pop(next(iter(_BALL_TOPOLOGY)))
    return out


def _merged(P: np.ndarray, Q: np.ndarray) -> tuple[skfem.MeshQuad, np.ndarray]:
    """(Q1 mesh, first): the blocks' points P (n, 2) and quads Q merged where they coincide, each point mapped to the
    first point within 1e-10 of it (a distance, not a rounding of the coordinates: two copies 1e-16 apart that
    straddle a rounding boundary stayed apart before and left a seam of unconnected nodes at some pole_points),
    numbered in order of first appearance (not sorted by coordinates, so meshes with the same divisions share one
    node numbering whatever their point positions), quads counterclockwise; ``first`` the kept points."""
    near = cKDTree(P).query_ball_point(P, r=1e-10)
    rep = np.fromiter((min(nb) for nb in near), dtype=np.int64, count=P.shape[0])
    first, inv = np.unique(rep, return_inverse=True)  # first: sorted = order of first appearance
    P, Q = P[first], inv.ravel()[Q]
    x, y = P[Q, 0], P[Q, 1]
    area = 0.5 * np.sum(x * np.roll(y, -1, 1) - np.roll(x, -1, 1) * y, axis=1)
    Q[area < 0] = Q[area < 0][:, ::-1]
    return skfem.MeshQuad(P.T.copy(), Q.T.copy()), first


def _on_arc(m1: skfem.MeshQuad) -> tuple[Callable[..., np.ndarray], np.ndarray]:
    """(mapper, arc midpoint dofs) of the quadratic version of a Q1 ball mesh whose surface is the unit circle:
    the surface facet midpoints moved onto the arc, the element centres a transfinite (serendipity) blend of
    the edge midpoints."""
    m2 = skfem.MeshQuad2.from_mesh(m1)
    dl = m2.doflocs.copy()
    nv, nf = m1.nvertices, m1.facets.shape[1]
    bf = m1.boundary_facets()
    fv = m1.p[:, m1.facets[:, bf]]
    onarc = np.all(np.abs(np.hypot(fv[0], fv[1]) - 1.0) < 1e-12, axis=0)
    mids = nv + bf[onarc]
    dl[:, mids] /= np.hypot(dl[0, mids], dl[1, mids])
    t2f = m1.t2f
    cen = nv + nf + np.arange(m1.nelements)
    dl[:, cen] = 0.5 * dl[:, nv + t2f].sum(axis=1) - 0.25 * m1.p[:, m1.t].sum(axis=1)
    return (lambda p, dl=dl: dl), mids


def full_ball_section(
    radius: float,
    top_points: np.ndarray,
    bottom_points: np.ndarray,
    radial_points: np.ndarray,
    *,
    n_equator: int = 8,
    split_angle: float = 0.25 * np.pi,
    intorder: int | None = None,
) -> AxiMesh:
    """The whole meridian half disk (R >= 0, -1 <= Z <= 1) of a solid ball as an O-grid, lengths scaled by
    ``radius``, Q2: a core rectangle [0, c sqrt2 sin(split)] x [-c sqrt2 cos(split), c sqrt2 cos(split)] (c = 0.55),
    a top and a bottom pole block (surface arcs 0..``split_angle`` from each pole) and an equator block between
    them (2 ``n_equator`` divisions). ``top_points`` / ``bottom_points`` (n + 1 increasing numbers from 0 to 1,
    the same n): node positions along each pole block as fractions of its arc (and of the core's top / bottom
    edge); the core's columns run straight from one to the other, so the two poles are refined independently (a
    ball on a plate under a probe, ``fem.indentation``). ``radial_points``: layer boundaries of the curved blocks
    (0 at the core, 1 at the surface). Tags "axis" (R = 0), "outer" (the surface) and an empty "symmetry" (no
    midplane condition)."""
    if not (radius > 0 and np.isfinite(radius)):
        raise ValueError(f"ball radius must be positive, got {radius}")
    if len(top_points) != len(bottom_points):
        raise ValueError("top_points and bottom_points need the same number of divisions")
    n = len(top_points) - 1
    ut = _check_points(top_points, n, "top_points")
    ub = _check_points(bottom_points, n, "bottom_points")
    v = _check_points(radial_points, len(radial_points) - 1, "radial_points")
    if int(n_equator) < 1:
        raise ValueError(f"a mesh needs at least one division, got n_equator = {n_equator}")
    c = 0.55
    cr, cz = c * np.sqrt(2) * np.sin(split_angle), c * np.sqrt(2) * np.cos(split_angle)
    t = np.linspace(0.0, 1.0, 2 * int(n_equator) + 1)
    pts: list[np.ndarray] = []
    quads: list[np.ndarray] = []

    def block(P):  # P: (n1 + 1, n2 + 1, 2) structured block -> quads (orientation fixed below)
        n1, n2 = P.shape[0] - 1, P.shape[1] - 1
        off = sum(len(q) for q in pts)
        pts.append(P.reshape(-1, 2))
        idx = off + np.arange((n1 + 1) * (n2 + 1)).reshape(n1 + 1, n2 + 1)
        quads.append(np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], -1).reshape(-1, 4))

    core_r = cr * (ub[:, None] * (1 - t[None]) + ut[:, None] * t[None])
    block(np.stack([core_r, np.broadcast_to(cz * (2 * t - 1), core_r.shape)], -1))
    inner = np.stack([np.full_like(t, cr), cz * (2 * t - 1)], -1)
    ph = (0.5 * np.pi - split_angle) * (2 * t - 1)
    outer = np.stack([np.cos(ph), np.sin(ph)], -1)
    block((1 - v)[:, None, None] * inner[None] + v[:, None, None] * outer[None])
    for u, sg in ((ut, 1.0), (ub, -1.0)):
        inner = np.stack([cr * u, np.full_like(u, sg * cz)], -1)
        outer = np.stack([np.sin(split_angle * u), sg * np.cos(split_angle * u)], -1)
        block((1 - v)[None, :, None] * inner[:, None] + v[None, :, None] * outer[:, None])
    m1, _ = _merged(np.concatenate(pts), np.concatenate(quads))
    mapper, _ = _on_arc(m1)
    tol = 1e-9
    tags = {
        "axis": lambda X: np.abs(X[0]) < tol,
        "symmetry": lambda X: np.zeros(X.shape[1:], bool),
        "outer": lambda X: np.abs(np.hypot(X[0], X[1]) - 1.0) < 1e-9,
    }
    return _finish(m1, 2, mapper, radius, tags, intorder)


def zone_points(n_zone: int, n_out: int, zone: float) -> np.ndarray:
    """Node positions (fractions of a pole block's arc) with ``n_zone`` equal divisions over [0, ``zone``] (the
    contact zone, 0 < zone < 1) and ``n_out`` geometrically growing ones beyond it, the first as long as a zone
    division (``full_ball_section``)."""
    if not 0 < zone < 1:
        raise ValueError(f"the refined zone must be a fraction of the pole block's arc in (0, 1), got {zone!r}")
    inner = np.linspace(0.0, zone, n_zone + 1)
    outer = zone + _geometric(n_out, 1.0 - zone, min(zone / n_zone, (1.0 - zone) / n_out))
    return np.r_[inner, outer[1:]]


def surface_layers(n_radial: int, depth: float, thickness: float) -> np.ndarray:
    """Radial layer boundaries (0 at the core, 1 at the surface) of the curved blocks: geometric towards the
    surface with the outermost layer ``depth`` thick (scaled length) in a block ``thickness`` thick, uniform if
    that is finer."""
    v = np.linspace(0.0, 1.0, n_radial + 1)
    if depth < thickness * (v[-1] - v[-2]):
        v = 1.0 - _geometric(n_radial, 1.0, depth / thickness)[::-1]
    return v


class _BallTopology(NamedTuple):
    """What a quadratic ball_section mesh keeps from its divisions alone (its node numbering does not depend on
    the node positions): the merge of the blocks' points (``first``), the dofs of the surface facet midpoints,
    the facets, the element-to-facet map and vertex connectivity of the Q1 mesh, and the first mesh built (its
    skfem mesh's connectivity, tags and edges)."""

    first: np.ndarray
    arc_mids: np.ndarray
    facets: np.ndarray
    t2f: np.ndarray
    t: np.ndarray
    mesh: AxiMesh
    intorder: int


_BALL_TOPOLOGY: dict[tuple, _BallTopology] = {}  # (divisions, order, intorder, split) -> topology, last 8


def _moved_nodes(topo: _BallTopology, P: np.ndarray) -> np.ndarray:
    """The node positions (2, n_nodes) of the quadratic ball_section mesh of the block points P on a known
    topology (facet midpoints, surface midpoints on the arc, blended element centres)."""
    p = P[topo.first].T  # (2, n_vertices)
    nv, nf, ne = p.shape[1], topo.facets.shape[1], topo.t.shape[1]
    dl = np.empty((2, nv + nf + ne))
    dl[:, :nv] = p
    dl[:, nv : nv + nf] = 0.5 * (p[:, topo.facets[0]] + p[:, topo.facets[1]])
    mids = topo.arc_mids
    dl[:, mids] /= np.hypot(dl[0, mids], dl[1, mids])
    dl[:, nv + nf :] = 0.5 * dl[:, nv + topo.t2f].sum(axis=1) - 0.25 * p[:, topo.t].sum(axis=1)
    return dl


def _moved_ball(topo: _BallTopology, P: np.ndarray, radius: float) -> AxiMesh:
    """The quadratic ball_section mesh of the block points P (before merging) on a known topology: the node
    positions of ``ball_section``'s construction (facet midpoints, surface midpoints on the arc, blended
    element centres) without rebuilding the connectivity and tags (issue 14: fitted meshes)."""
    dl = _moved_nodes(topo, P)
    t = topo.mesh
    m = skfem.MeshQuad2(dl, t.mesh.t)
    basis = skfem.CellBasis(m, skfem.ElementQuad2(), intorder=topo.intorder)
    nodes = {k: v.copy() for k, v in t.nodes.items()}
    edges = {k: v.copy() for k, v in t.edges.items()}
    return AxiMesh(m, basis, t.order, float(radius), nodes, edges)


# ---- contact-edge-fitted ball meshes (fem.spheroid) ------------------------------------------------------
# level -> (n_core, n_radial, surface grading, n_contact, n_equator) of ``fitted_mesh``: the surface nodes of
# the pole block are placed so that node n_contact sits exactly on the contact edge (n_contact elements across
# the contact zone, n_core - n_contact beyond it, graded toward the edge; radial layers thin enough for the
# contact size; n_equator divisions of the equator block). Levels 1..4 are one self-similar sequence
# (h ~ 1/n_core): compare.bench fem-spheroid.
FITTED_LEVELS = {
    0: (8, 3, 2.0, 4, 3),
    1: (16, 6, 2.0, 7, 6),
    2: (32, 12, 2.0, 14, 12),
    3: (48, 18, 2.0, 21, 18),
    4: (64, 24, 2.0, 28, 24),
}
FITTED_SPLIT = np.radians(55.0)  # the pole block's arc: 0..55 deg from the pole (holds the edge to delta/(2 a0) ~ 0.45)
FITTED_EDGE_MAX = 0.92  # largest edge position, as a fraction of the pole block's arc
_INNER_GRADING = 1.5  # contact-zone elements: first / last (finer at the edge)
_DEPTH = 2.0  # outermost radial layer <= _DEPTH x the mean contact-zone element length


def _geometric(n: int, length: float, first: float) -> np.ndarray:
    """n + 1 points on [0, length]: n geometric intervals, the first one ``first`` long."""
    if n == 1:
        return np.array([0.0, length])
    if abs(first * n - length) <= 1e-14 * length:
        return np.linspace(0.0, length, n + 1)
    q = brentq(lambda q: first * (q**n - 1) / (q - 1) - length, 1e-3, 1e3) if first * n != length else 1.0
    iv = first * q ** np.arange(n)
    return np.r_[0.0, np.cumsum(iv)] * (length / iv.sum())


def fitted_mesh(radius: float, level: int, edge: float) -> AxiMesh:
    """The level's ball_section mesh with a surface node on the contact edge.

    ``edge``: reference position of the edge node as a fraction of the pole block's arc (the surface angle
    from the pole is FITTED_SPLIT * edge, FITTED_SPLIT = 55 deg), in (0, FITTED_EDGE_MAX]. Every edge gives the
    same topology and node numbering.
    """
    out = _fitted_section(radius, level, edge, False)
    assert isinstance(out, AxiMesh)
    return out


def fitted_nodes(radius: float, level: int, edge: float) -> np.ndarray:
    """The node coordinates (2, n_nodes) of ``fitted_mesh(radius, level, edge)`` (its ``X``), without building its
    basis: the motion of the fitted mesh with its edge (``fem.fitted_sensitivity``) is their difference."""
    out = _fitted_section(radius, level, edge, True)
    return out.X if isinstance(out, AxiMesh) else out


def _fitted_section(radius: float, level: int, edge: float, nodes_only: bool) -> AxiMesh | np.ndarray:
    """:func:`fitted_mesh` (or only its nodes)."""
    if level not in FITTED_LEVELS:
        raise ValueError(f"mesh level must be an integer 0..4 (0 coarse, 1 default, 2 fine), got {level!r}")
    if not (0 < edge <= FITTED_EDGE_MAX):
        raise ValueError(
            f"the contact edge at {np.degrees(FITTED_SPLIT) * edge:.3g} deg from the pole is outside the meshable range "
            f"(0, {np.degrees(FITTED_SPLIT) * FITTED_EDGE_MAX:.3g}] deg; reduce the approach"
        )
    nc, nr, gr, k = FITTED_LEVELS[level][:4]
    neq = FITTED_LEVELS[level][4] if len(FITTED_LEVELS[level]) > 4 else None
    inner = edge * graded_points(k, 1.0 / _INNER_GRADING)
    he = inner[-1] - inner[-2]
    outer = edge + _geometric(nc - k, 1.0 - edge, min(he, (1.0 - edge) / (nc - k)))
    v = graded_points(nr, 1.0 / gr)
    c_thick = 1.0 - 0.55 * np.sqrt(2) * np.cos(FITTED_SPLIT)  # pole-block thickness at the axis (ball_section)
    hc = _DEPTH * edge * FITTED_SPLIT / k
    if hc < c_thick * (v[-1] - v[-2]):
        v = 1.0 - _geometric(nr, 1.0, hc / c_thick)[::-1]
    return _ball_section(
        radius, nc, nr, grading=1.0, pole_grading=1.0, order=2, pole_points=np.r_[inner, outer[1:]], radial_points=v,
        n_equator=neq, split_angle=FITTED_SPLIT, intorder=4, nodes_only=nodes_only,
    )  # fmt: skip
