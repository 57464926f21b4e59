"""fem.mesh: shell and ball sections, their Gauss rules, known topologies, contact-edge-fitted balls."""

import numpy as np
import pytest

from tissuemech.fem.forms import Assembler
from tissuemech.fem.mesh import (
    FITTED_EDGE_MAX,
    FITTED_LEVELS,
    FITTED_SPLIT,
    ball_section,
    fitted_mesh,
    graded_points,
    shell_section,
)

A0 = 500e-6


def test_shell_section_volume_and_tags():
    m = shell_section(50e-6, 75e-6, 4, 8)
    a = Assembler(m)
    exact = 2 * np.pi / 3 * (1.5**3 - 1)  # half of the hollow ball, scaled by A
    err8 = abs(a.volume() / exact - 1)
    err16 = abs(Assembler(shell_section(50e-6, 75e-6, 4, 16)).volume() / exact - 1)
    assert err8 < 1e-5 and err16 < err8 / 12  # quadratic geometry: O(h^4) volume error
    X = m.X
    assert np.allclose(np.hypot(*X[:, m.nodes["inner"]]), 1.0)
    assert np.allclose(np.hypot(*X[:, m.nodes["outer"]]), 1.5)
    assert np.allclose(X[0, m.nodes["axis"]], 0.0) and np.allclose(X[1, m.nodes["symmetry"]], 0.0)
    assert m.edges["inner"].shape == (8, 3)


def test_ball_section_volume_tags_grading():
    m = ball_section(500e-6, 6, 4, grading=3.0, pole_grading=3.0)
    a = Assembler(m)
    assert np.all(m.basis.dx > 0)
    assert abs(a.volume() / (2 * np.pi / 3) - 1) < 1e-5
    X = m.X
    assert np.allclose(X[0, m.nodes["axis"]], 0) and np.allclose(X[1, m.nodes["symmetry"]], 0)
    assert np.allclose(np.hypot(*X[:, m.nodes["outer"]]), 1.0)
    # surface tag covers the whole quarter arc: its edges' chord lengths add up to ~ pi/2
    e = m.edges["outer"]
    assert abs(np.sum(np.hypot(*(X[:, e[:, 2]] - X[:, e[:, 0]]))) - np.pi / 2) < 1e-2
    # graded toward the pole: the outer edge at the axis is shorter than at the equator
    L = np.hypot(*(X[:, e[:, 2]] - X[:, e[:, 0]]))
    top = np.argmax(np.max(X[1, e], axis=1))
    bottom = np.argmin(np.max(X[1, e], axis=1))
    assert L[top] < 0.7 * L[bottom]


def test_graded_points_ratio():
    p = graded_points(5, 4.0)
    h = np.diff(p)
    assert p[0] == 0 and abs(p[-1] - 1) < 1e-15 and abs(h[-1] / h[0] - 4) < 1e-12
    with pytest.raises(ValueError, match="at least one division"):
        graded_points(0)


def test_ball_section_gauss_rule_degree():
    """ball_section(intorder=4) gives the 3 x 3 rule the fitted meshes use; a rule too low for Q2 is refused."""
    assert ball_section(500e-6, 4, 3, intorder=4).basis.X.shape[1] == 9
    assert ball_section(500e-6, 4, 3).basis.X.shape[1] == 16  # default 2 order + 2 = 6: 4 x 4 points
    for bad in (-1, 0, 3, 2.5, "4", True):
        with pytest.raises(ValueError, match="intorder"):
            ball_section(500e-6, 4, 3, intorder=bad)


def test_ball_section_on_a_known_topology_is_the_full_construction():
    """A second ball_section with the same divisions only moves the nodes (issue 14: fitted meshes): the same
    node positions bit for bit, element dofs, quadrature weights, tags and edges as building it from scratch."""

    rng = np.random.default_rng(7)
    for n_core, n_radial in ((4, 3), (6, 5)):
        for k in range(2):
            pole = np.r_[0.0, np.sort(rng.uniform(0.05, 0.95, n_core - 1)), 1.0]
            radial = np.r_[0.0, np.sort(rng.uniform(0.05, 0.95, n_radial - 1)), 1.0]
            # a split angle no earlier mesh had: the first mesh of these divisions is built in full
            split = 0.9 + 0.01 * rng.uniform() + 0.02 * k
            kw = dict(pole_points=pole, radial_points=radial, split_angle=split, intorder=4)
            full = ball_section(500e-6, n_core, n_radial, **kw)
            ball_section(500e-6, n_core, n_radial, split_angle=split, intorder=4)  # the topology, other nodes
            moved = ball_section(500e-6, n_core, n_radial, **kw)
            assert moved.mesh is not full.mesh and np.array_equal(moved.X, full.X)
            assert np.array_equal(moved.basis.element_dofs, full.basis.element_dofs)
            assert np.array_equal(moved.basis.dx, full.basis.dx) and moved.length_scale == full.length_scale
            for tags in ("nodes", "edges"):
                a, b = getattr(moved, tags), getattr(full, tags)
                assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


def test_fitted_mesh_topology_is_fixed_and_edge_node_on_target():

    a, b = fitted_mesh(A0, 1, 0.2), fitted_mesh(A0, 1, 0.6)
    assert np.array_equal(a.mesh.t, b.mesh.t) and np.array_equal(a.nodes["outer"], b.nodes["outer"])
    k = FITTED_LEVELS[1][3]
    for m, e in ((a, 0.2), (b, 0.6)):
        th = np.arctan2(m.X[0, m.nodes["outer"]], m.X[1, m.nodes["outer"]])
        assert np.isclose(np.sort(th)[2 * k], FITTED_SPLIT * e, rtol=1e-12)
    with pytest.raises(ValueError, match="contact edge"):
        fitted_mesh(A0, 1, 0.99)


def test_fitted_meshes_have_one_topology_and_no_seam():
    """Every contact-edge position gives the same nodes (no unmerged copies of a block-interface point:
    edge 0.0232343... of level 1 left 3 pairs 1e-16 apart unmerged, a seam, with the coordinate rounding
    the merge used before) and the same numbering, so states carry over between fitted meshes."""
    from scipy.spatial import cKDTree

    seam = fitted_mesh(1.0, 1, 0.023234318257495955)
    near = fitted_mesh(1.0, 1, 0.0232)
    assert seam.basis.N == near.basis.N == 969
    assert not cKDTree(seam.mesh.p.T).query_pairs(1e-9)
    assert np.array_equal(seam.mesh.t, near.mesh.t)
    counts = {fitted_mesh(1.0, 1, e).basis.N for e in np.geomspace(0.005, FITTED_EDGE_MAX, 200)}
    assert counts == {969}


def test_search_trees_are_built_once_and_find_the_points():
    """AxiMesh.search_trees(): k-d trees of the quadrature points and element centres, built once per mesh."""
    m = fitted_mesh(A0, 0, 0.5)
    points, centres = m.search_trees()
    assert m.search_trees()[0] is points
    xq = m.quadrature_points.reshape(2, -1)
    assert points.n == xq.shape[1] and centres.n == m.basis.nelems
    d, i = points.query(xq[:, 7])
    assert d == 0.0 and i == 7
