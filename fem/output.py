r"""Result containers, VTU export (meshio) and the von Mises figure on the deformed section.

API: ``BlastulaResult`` (dataclass; arrays per converged step: ``pressure`` [Pa], ``inner_stretch``,
``outer_stretch``, ``newton_iterations``, ``wall_time`` [s]; final fields: ``mesh`` (AxiMesh),
``displacement`` (N, 2) [m], ``deformed_nodes`` (N, 2) [m], ``hydrostatic_pressure`` and
``von_mises`` per element (mean over its quadrature points) [Pa]),
``write_vtu(path, mesh, displacement, cell_data)`` and ``plot_von_mises(mesh, displacement, vm, ax=None)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

__all__ = ["BlastulaResult", "write_vtu", "plot_von_mises"]


@dataclass
class BlastulaResult:
    pressure: np.ndarray
    inner_stretch: np.ndarray
    outer_stretch: np.ndarray
    newton_iterations: np.ndarray
    wall_time: np.ndarray
    mesh: object
    displacement: np.ndarray
    deformed_nodes: np.ndarray
    hydrostatic_pressure: np.ndarray
    von_mises: np.ndarray
    method: str = "load"

    def to_vtu(self, path: str) -> None:
        """Write the final deformed state (ParaView) with displacement and element fields."""
        write_vtu(path, self.mesh, self.displacement,
                  {"von_mises_Pa": self.von_mises, "hydrostatic_pressure_Pa": self.hydrostatic_pressure})

    def plot(self, ax=None):
        """Von Mises stress on the deformed section (seed Fig. 3)."""
        return plot_von_mises(self.mesh, self.displacement, self.von_mises, ax=ax)


def _quads(mesh) -> np.ndarray:
    return mesh.mesh.t[:4].T  # corner nodes (counterclockwise) of each element


def write_vtu(path: str, mesh, displacement: np.ndarray, cell_data: Optional[dict] = None) -> None:
    """VTU of the reference section (x, y = R, Z in m) with point data 'displacement'."""
    import meshio

    L = mesh.length_scale
    nv = mesh.mesh.nvertices
    pts = np.zeros((nv, 3))
    pts[:, :2] = mesh.X[:, :nv].T * L
    disp = np.zeros((nv, 3))
    disp[:, :2] = displacement[:nv]
    cd = {k: [np.asarray(v, float)] for k, v in (cell_data or {}).items()}
    meshio.Mesh(pts, [("quad", _quads(mesh))], point_data={"displacement": disp}, cell_data=cd).write(path)


def plot_von_mises(mesh, displacement: np.ndarray, vm: np.ndarray, ax=None):
    """Colour each deformed element by its von Mises stress (Pa); axes in um."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    L = mesh.length_scale
    nv = mesh.mesh.nvertices
    x = (mesh.X[:, :nv].T * L + displacement[:nv]) * 1e6
    pc = PolyCollection(x[_quads(mesh)], array=np.asarray(vm), cmap="viridis", edgecolors="face")
    ax.add_collection(pc)
    ax.autoscale()
    ax.set_aspect("equal")
    ax.set_xlabel("r (um)")
    ax.set_ylabel("z (um)")
    ax.figure.colorbar(pc, ax=ax, label="von Mises stress (Pa)")
    return ax
