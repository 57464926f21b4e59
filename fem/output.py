r"""Result containers, VTU export (meshio) and the von Mises figure on the deformed section.

API: ``SpheroidResult`` (spheroid compression, see its docstring), ``SpheroidField``,
``BlastulaResult`` (dataclass; arrays per converged step: ``pressure`` [Pa], ``inner_stretch``,
``outer_stretch``, ``newton_iterations``, ``wall_time`` [s]; final fields: ``mesh`` (AxiMesh),
``displacement`` (N, 2) [m], ``deformed_nodes`` (N, 2) [m], ``hydrostatic_pressure`` and
``von_mises`` per element (mean over its quadrature points) [Pa]; creep runs (``fem.blastula.creep``,
``method="creep"``) also have ``time`` [s] per step and ``parameters`` (the inputs)),
``write_vtu(path, mesh, displacement, cell_data)`` and ``plot_von_mises(mesh, displacement, vm, ax=None)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BlastulaResult", "SpheroidResult", "SpheroidField", "write_vtu", "plot_von_mises"]


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
    time: np.ndarray | None = None
    parameters: dict | None = None

    def to_vtu(self, path: str) -> None:
        """Write the final deformed state (ParaView) with displacement and element fields."""
        write_vtu(
            path,
            self.mesh,
            self.displacement,
            {"von_mises_Pa": self.von_mises, "hydrostatic_pressure_Pa": self.hydrostatic_pressure},
        )

    def plot(self, ax=None):
        """Von Mises stress on the deformed section (seed Fig. 3)."""
        return plot_von_mises(self.mesh, self.displacement, self.von_mises, ax=ax)


def _quads(mesh) -> np.ndarray:
    return mesh.mesh.t[:4].T  # corner nodes (counterclockwise) of each element


def write_vtu(path: str, mesh, displacement: np.ndarray, cell_data: dict | None = None) -> None:
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


@dataclass
class SpheroidField:
    """Fields of one converged step: ``displacement``/``deformed_nodes`` (N, 2) [m] at the mesh dofs,
    element means of ``von_mises`` and ``hydrostatic_pressure`` (= -mean Cauchy stress) [Pa],
    ``contact_nodal_force`` (compressive nodal contact force per candidate node, N; 0 where inactive)."""

    time: float
    displacement: np.ndarray
    deformed_nodes: np.ndarray
    von_mises: np.ndarray
    hydrostatic_pressure: np.ndarray
    contact_nodal_force: np.ndarray


@dataclass
class SpheroidResult:
    """FE spheroid compression (``fem.spheroid.compress``); arrays have one entry per converged step.

    ``time`` [s] (static runs: pseudo-time 0..1), ``approach`` (total plate approach delta = 2 x the
    plate displacement of the quarter model) [m], ``force`` (plate force from the contact multipliers)
    [N], ``reaction_force`` (reaction of the midplane symmetry constraint) [N], ``midplane_radius`` [m],
    ``midplane_area`` (pi r_mid^2) [m^2], ``nominal_stress`` (F / A_mid) [Pa], ``mean_von_mises``
    (average over the deformed volume) [Pa], ``contact_radius`` (deformed contact radius: edge estimate
    between the outermost node in contact and the next, from the gaps of the first free nodes, g ~ (r - a)^1.5)
    [m], ``contact_radius_node`` (the outermost node in contact) [m], ``min_gap`` (smallest plate gap
    of the surface nodes, >= 0 to round-off) [m], ``min_contact_force`` (smallest nodal contact force of
    the active nodes, >= 0 to round-off) [N], ``newton_iterations`` and ``contact_passes`` (active-set passes) per step,
    ``wall_time`` [s] per step. ``fields``: SpheroidField at the requested ``field_times`` and the end.
    """

    time: np.ndarray
    approach: np.ndarray
    force: np.ndarray
    reaction_force: np.ndarray
    midplane_radius: np.ndarray
    midplane_area: np.ndarray
    nominal_stress: np.ndarray
    mean_von_mises: np.ndarray
    contact_radius: np.ndarray
    contact_radius_node: np.ndarray
    min_gap: np.ndarray
    min_contact_force: np.ndarray
    newton_iterations: np.ndarray
    contact_passes: np.ndarray
    wall_time: np.ndarray
    mesh: object
    fields: list
    static: bool = False
    parameters: dict | None = None

    def field_at(self, time: float | None = None) -> SpheroidField:
        """The stored field closest to ``time`` (s; None: the last)."""
        if time is None:
            return self.fields[-1]
        return min(self.fields, key=lambda f: abs(f.time - float(time)))

    def to_vtu(self, path: str, time: float | None = None) -> None:
        """Write the stored state closest to ``time`` (default: the last) as VTU (ParaView)."""
        f = self.field_at(time)
        write_vtu(
            path,
            self.mesh,
            f.displacement,
            {"von_mises_Pa": f.von_mises, "hydrostatic_pressure_Pa": f.hydrostatic_pressure},
        )

    def plot_von_mises(self, time: float | None = None, ax=None):
        """Von Mises stress on the deformed quarter section (seed Fig. 8)."""
        f = self.field_at(time)
        ax = plot_von_mises(self.mesh, f.displacement, f.von_mises, ax=ax)
        ax.set_title(f"von Mises stress, t = {f.time:.4g} s")
        return ax

    def plot_relaxation(self, axes=None):
        """Nominal stress F/A_mid and mean von Mises stress vs time (seed Figs 9-10)."""
        import matplotlib.pyplot as plt

        if axes is None:
            _, axes = plt.subplots(1, 2, figsize=(10, 4))
        t = self.time
        for ax, y, lab in zip(
            axes,
            (self.nominal_stress, self.mean_von_mises),
            ("nominal stress F / A_mid (Pa)", "mean von Mises stress (Pa)"),
        ):
            ax.plot(t, y, "o-", ms=3)
            ax.set_xlabel("pseudo-time" if self.static else "time t (s)")
            ax.set_ylabel(lab)
            if not self.static and t[0] > 0 and t[-1] / t[0] > 100:
                ax.set_xscale("log")
            ax.grid(alpha=0.3)
        return axes
