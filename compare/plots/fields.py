"""Smooth drawing of FE fields on the curved Q2 geometry (used by the seed's Figs 3 and 8).

The FE results store one value per element (the element mean of, e.g., von Mises). ``q2_triangulation``
recovers nodal values (the area-weighted mean of the elements that share a node) and evaluates the
element's 9-node Q2 map on an ``n_sub`` x ``n_sub`` sub-grid, so both the geometry (curved edges) and
the field are drawn as the Q2 interpolation, not as flat facets.

The FE results' own figures (``fem.output``: ``BlastulaResult.plot``, ``SpheroidResult.plot_von_mises`` and
``plot_relaxation``, ``fem.output.plot_von_mises``) are drawn here: ``element_von_mises`` (one flat colour per
deformed element) and ``relaxation_curves`` (nominal and mean von Mises stress against time). They draw on the
given axes, or on new ones of the current pyplot backend (no backend is chosen here).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tissuemech.compare.cases import UM

__all__ = ["nodal_average", "q2_triangulation", "draw_field", "element_von_mises", "relaxation_curves", "subgrid"]


def subgrid(n_sub: int) -> np.ndarray:
    """The (2, (n_sub+1)^2) reference points [0, 1]^2 of the drawing sub-grid, in the order
    ``q2_triangulation`` uses (values given per point must follow it)."""
    s = np.linspace(0.0, 1.0, n_sub + 1)
    S, T = np.meshgrid(s, s, indexing="ij")
    return np.vstack([S.ravel(), T.ravel()])


def _ref_area(mesh: Any) -> np.ndarray:
    p = mesh.mesh.p[:, mesh.mesh.t[:4]]  # (2, 4, nel) corners, counterclockwise
    x, y = p[0], p[1]
    return 0.5 * np.abs(np.sum(x * np.roll(y, -1, axis=0) - np.roll(x, -1, axis=0) * y, axis=0))


def nodal_average(mesh: Any, element_values: np.ndarray) -> np.ndarray:
    """Values at the Q2 nodes: the area-weighted mean of the element values around each node."""
    dofs = mesh.basis.element_dofs  # (9, nel)
    w = _ref_area(mesh)
    num = np.zeros(mesh.basis.N)
    den = np.zeros(mesh.basis.N)
    v = np.asarray(element_values, float)
    for k in range(dofs.shape[0]):
        np.add.at(num, dofs[k], w * v)
        np.add.at(den, dofs[k], w)
    return num / np.where(den > 0, den, 1.0)


def q2_triangulation(
    mesh: Any, displacement: np.ndarray | None, element_values: np.ndarray, *, n_sub: int = 4
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(x_um, y_um, triangles, values) of the field on the (deformed) Q2 geometry.

    mesh: an ``fem.mesh.AxiMesh`` (Q2); displacement: (N, 2) nodal displacement in m, or None for the
    reference configuration; element_values: one value per element (drawn as their nodal average), or
    values at the sub-grid points (n_el, (n_sub+1)^2), points ordered as :func:`subgrid`.
    """
    elem = mesh.basis.elem
    dofs = mesh.basis.element_dofs  # (9, nel)
    ref = subgrid(n_sub)  # (2, m) on the reference square [0, 1]^2
    phi = np.array([np.asarray(elem.lbasis(ref, i)[0]) for i in range(dofs.shape[0])])  # (9, m)
    X = mesh.X.T * mesh.length_scale  # (N, 2) m
    if displacement is not None:
        X = X + np.asarray(displacement)[:, :2]
    xe = np.einsum("km,kec->ecm", phi, X[dofs])  # (nel, 2, m)
    if np.ndim(element_values) == 2:  # values at the sub-grid points
        ve = np.asarray(element_values, float).reshape(dofs.shape[1], ref.shape[1])
    else:
        ve = np.einsum("km,ke->em", phi, nodal_average(mesh, element_values)[dofs])  # (nel, m)
    nel, m = ve.shape
    idx = np.arange(m).reshape(n_sub + 1, n_sub + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    local = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    tri = (local[None, :, :] + (np.arange(nel) * m)[:, None, None]).reshape(-1, 3)
    return xe[:, 0, :].ravel() / UM, xe[:, 1, :].ravel() / UM, tri, ve.ravel()


def draw_field(
    ax: Any,
    mesh: Any,
    displacement: np.ndarray | None,
    element_values: np.ndarray,
    *,
    mirror: bool = False,
    vmin: float | None = None,
    vmax: float | None = None,
    cmap: str = "viridis",
    n_sub: int = 4,
) -> Any:
    """Draw the smooth field on ``ax`` (axes in um); ``mirror`` reflects the quarter section to the full one.

    Returns the ``TriMesh``/``PolyCollection`` for a colour bar.
    """
    x, y, tri, v = q2_triangulation(mesh, displacement, element_values, n_sub=n_sub)
    copies = [(1, 1)] + ([(-1, 1), (1, -1), (-1, -1)] if mirror else [])
    xs = np.concatenate([sx * x for sx, _ in copies])
    ys = np.concatenate([sy * y for _, sy in copies])
    ts = np.concatenate([tri + k * x.size for k in range(len(copies))])
    vs = np.concatenate([v] * len(copies))
    lo = float(np.min(vs)) if vmin is None else vmin
    hi = float(np.max(vs)) if vmax is None else vmax
    coll = ax.tripcolor(xs, ys, ts, vs, shading="gouraud", cmap=cmap, vmin=lo, vmax=hi, rasterized=True)
    ax.set_aspect("equal")
    return coll


def element_von_mises(mesh: Any, displacement: np.ndarray, vm: np.ndarray, ax: Any = None) -> Any:
    """Colour each deformed element by its von Mises stress (Pa); axes in um. Returns the axes."""
    from matplotlib.collections import PolyCollection

    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5, 5))
    L = mesh.length_scale
    nv = mesh.mesh.nvertices
    x = (mesh.X[:, :nv].T * L + displacement[:nv]) / UM
    quads = mesh.mesh.t[:4].T  # corner nodes (counterclockwise) of each element
    pc = PolyCollection(x[quads], array=np.asarray(vm), cmap="viridis", edgecolors="face")
    ax.add_collection(pc)
    ax.autoscale()
    ax.set_aspect("equal")
    ax.set_xlabel("r (um)")
    ax.set_ylabel("z (um)")
    ax.figure.colorbar(pc, ax=ax, label="von Mises stress (Pa)")
    return ax


def relaxation_curves(result: Any, axes: Any = None) -> Any:
    """Nominal stress F/A_mid and mean von Mises stress of a ``fem.output.SpheroidResult`` against time (seed
    Figs 9-10), on two axes (new ones when None). Returns the axes."""
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(1, 2, figsize=(10, 4))
    t = result.time
    for ax, y, lab in zip(
        axes,
        (result.nominal_stress, result.mean_von_mises),
        ("nominal stress F / A_mid (Pa)", "mean von Mises stress (Pa)"),
    ):
        ax.plot(t, y, "o-", ms=3)
        ax.set_xlabel("pseudo-time" if result.static else "time t (s)")
        ax.set_ylabel(lab)
        if not result.static and t[0] > 0 and t[-1] / t[0] > 100:
            ax.set_xscale("log")
        ax.grid(alpha=0.3)
    return axes
