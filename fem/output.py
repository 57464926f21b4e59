r"""Result containers and VTU / PVD export (ParaView); the figures are drawn by ``compare.plots.fields``.

API: ``SpheroidResult`` (spheroid compression, see its docstring), ``SpheroidField``,
``BlastulaResult`` (dataclass; arrays per converged step: ``pressure`` [Pa], ``inner_stretch``,
``outer_stretch``, ``newton_iterations``, ``wall_time`` [s]; final fields: ``mesh`` (AxiMesh),
``displacement`` (N, 2) [m], ``deformed_nodes`` (N, 2) [m], ``hydrostatic_pressure`` and
``von_mises`` per element (mean over its quadrature points) [Pa]; creep runs (``fem.blastula.creep``,
``method="creep"``) also have ``time`` [s] per step and ``parameters`` (the inputs); with
``store_fields=True`` also ``fields``: one ``BlastulaField`` per converged step),
both results give ``field_at(time=None)`` (the stored field closest to a time [s]; None: the last) and
the final ``displacement``, ``deformed_nodes``, ``von_mises``, ``hydrostatic_pressure`` under the same names,
``write_vtu(path, mesh, displacement, cell_data)``, ``write_pvd(path, mesh, frames)`` and
``plot_von_mises(mesh, displacement, vm, ax=None)``.

Time series for ParaView: ``BlastulaResult.to_pvd(path)`` and ``SpheroidResult.to_pvd(path)`` write a
PVD collection ``path`` (open it in ParaView: File > Open, then *Warp By Vector* on ``displacement``)
and one VTU per stored state next to it (``<stem>_0000.vtu``, ...). Each VTU holds the full Q2 section
(VTK biquadratic quads, 9 nodes, so curved edges stay curved) in reference coordinates (m) with point
data ``displacement`` [m] (warp-ready, 3 components, z = 0) and ``deformed_coordinates`` [m], cell data
``von_mises_Pa`` and ``hydrostatic_pressure_Pa`` (element means, hydrostatic pressure = -mean Cauchy
stress), for the spheroid point data ``contact_pressure_Pa`` and ``contact_nodal_force_N``, and field
data with the state's time (s), load and step. ``deformed=True`` writes deformed coordinates instead
(the displacement stays as point data).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

__all__ = [
    "BlastulaResult",
    "BlastulaField",
    "SpheroidResult",
    "SpheroidField",
    "Frame",
    "write_vtu",
    "write_pvd",
    "read_pvd",
    "contact_pressure",
    "plot_von_mises",
]


@dataclass
class BlastulaField:
    """Fields of one converged blastula step: ``pressure`` [Pa], ``time`` [s] (creep runs; None for
    load-controlled and arc-length runs), ``displacement``/``deformed_nodes`` (N, 2) [m] at the mesh
    dofs, element means of ``von_mises`` and ``hydrostatic_pressure`` (= -mean Cauchy stress) [Pa]."""

    pressure: float
    time: float | None
    displacement: np.ndarray
    deformed_nodes: np.ndarray
    von_mises: np.ndarray
    hydrostatic_pressure: np.ndarray


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
    fields: list | None = None
    gradient: dict | None = None  # inflate(gradient=True): {"C": d inner_stretch/dC (1/Pa), "alpha": ...} per step

    def _stored_fields(self) -> list[BlastulaField]:
        """``fields``, or the final state's field when only that was kept."""
        if self.fields:
            return self.fields
        t_end = None if self.time is None else float(self.time[-1])
        return [
            BlastulaField(
                float(self.pressure[-1]),
                t_end,
                self.displacement,
                self.deformed_nodes,
                self.von_mises,
                self.hydrostatic_pressure,
            )
        ]

    def field_at(self, time: float | None = None) -> BlastulaField:
        """The stored field closest to ``time`` (s; creep runs), None: the last (as ``SpheroidResult.field_at``).

        Raises ValueError for a time on a run without times (load-controlled or arc-length)."""
        fields = self._stored_fields()
        if time is None:
            return fields[-1]
        if self.time is None:
            raise ValueError("field_at(time) needs a creep run (time in s); this run has pressures only")
        return min(fields, key=lambda f: abs(float(f.time) - float(time)) if f.time is not None else np.inf)

    def _frames(self) -> list[Frame]:
        fields = self._stored_fields()
        frames = []
        for k, f in enumerate(fields):
            if self.method == "creep" and f.time is not None:
                t = float(f.time)
            elif self.method == "load":
                t = float(f.pressure)
            else:  # arc-length: the pressure falls past the limit point; the step number is the time axis
                t = float(k if fields is self.fields else len(self.pressure) - 1)
            frames.append(
                Frame(
                    time=t,
                    displacement=f.displacement,
                    cell_data={"von_mises_Pa": f.von_mises, "hydrostatic_pressure_Pa": f.hydrostatic_pressure},
                    point_data={},
                    field_data={
                        "pressure_Pa": float(f.pressure),
                        **({} if f.time is None else {"time_s": float(f.time)}),
                    },
                )
            )
        return frames

    def to_pvd(self, path: str | os.PathLike, *, deformed: bool = False) -> list[Path]:
        """Write the run as a ParaView time series: a PVD collection ``path`` and one VTU per state.

        States: every converged step if the run kept them (``inflate(..., store_fields=True)``,
        ``creep(..., store_fields=True)``), else the final state only. ParaView's time value is the
        time (s) for creep runs, the pressure (Pa) for load-controlled runs and the step number for
        arc-length runs (whose pressure falls past the limit point); each VTU also carries
        ``pressure_Pa`` (and for creep runs ``time_s``) as field data. ``deformed``: write deformed coordinates (m)
        instead of reference ones. Returns the paths written (the PVD first).
        Raises ValueError if ``path`` does not end in ``.pvd``.
        """
        return write_pvd(path, self.mesh, self._frames(), deformed=deformed)

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


def _cells(mesh) -> tuple[str, np.ndarray]:
    """meshio cell block of the full section: 9-node quads (VTK order: corners, mid-edges 01 12 23 30,
    centre; the same as scikit-fem's ElementQuad2 dofs) for Q2 meshes, 4-node quads for Q1."""
    ed = np.asarray(mesh.basis.element_dofs)
    if ed.shape[0] == 9:
        return "quad9", ed.T.copy()
    return "quad", ed[:4].T.copy()


class Frame(NamedTuple):
    """One state of a time series: ``time`` (ParaView's time value), ``displacement`` (N, 2) [m] at the
    mesh dofs, ``cell_data``/``point_data`` (name -> per element / per dof arrays), ``field_data``
    (name -> number)."""

    time: float
    displacement: np.ndarray
    cell_data: dict
    point_data: dict
    field_data: dict


def _frame_mesh(mesh, frame: Frame, deformed: bool):
    import meshio

    L = mesh.length_scale
    X = mesh.X.T * L
    u = np.asarray(frame.displacement, float)
    if u.shape != X.shape:
        raise ValueError(f"displacement (m) must have shape {X.shape} (one (u_r, u_z) per mesh dof), got {u.shape}")
    pad = lambda a: np.column_stack([a, np.zeros(len(a))])
    pts = pad(X + u if deformed else X)
    pdata = {"displacement": pad(u), "deformed_coordinates": pad(X + u)}
    pdata.update({k: np.asarray(v, float) for k, v in frame.point_data.items()})
    ctype, conn = _cells(mesh)
    cdata = {k: [np.asarray(v, float)] for k, v in frame.cell_data.items()}
    return meshio.Mesh(pts, [(ctype, conn)], point_data=pdata, cell_data=cdata)


def _add_field_data(vtu: Path, field_data: dict) -> None:
    """Insert ``<FieldData>`` (one ascii Float64 value per name) into a VTU written by meshio, which
    does not write meshio's ``field_data`` (it reads it back, as ParaView does)."""
    tree = ET.parse(vtu)
    grid = tree.getroot().find("UnstructuredGrid")
    fd = ET.Element("FieldData")
    for name, value in field_data.items():
        da = ET.SubElement(fd, "DataArray", type="Float64", Name=name, NumberOfTuples="1", format="ascii")
        da.text = repr(float(value))
    if grid is None:
        raise ValueError(f"{vtu}: not a VTK UnstructuredGrid file")
    grid.insert(0, fd)
    tree.write(vtu, xml_declaration=True, encoding="utf-8")


def write_pvd(path: str | os.PathLike, mesh, frames: Sequence[Frame], *, deformed: bool = False) -> list[Path]:
    """Write ``frames`` as a PVD collection (``path``, ending in .pvd) and one VTU per frame beside it.

    The VTUs are ``<stem>_0000.vtu``, ``<stem>_0001.vtu``, ... in the PVD's folder (existing ones with
    those names are overwritten), referenced by relative names, each with its frame's ``time`` as
    ParaView's time value. Points: the mesh dofs in reference (``deformed=False``) or deformed
    coordinates (m); see the module docstring for the fields. Returns [pvd, vtu_0, vtu_1, ...].
    Each file is written to a temporary name and renamed: a failed write (a full disk) leaves no truncated file.
    Raises ValueError for a path without the .pvd suffix or an empty list of frames, OSError naming the file for a
    failed write.
    """
    p = Path(path)
    if p.suffix.lower() != ".pvd":
        raise ValueError(f"the time-series path must end in .pvd, got {str(path)!r}")
    if not len(frames):
        raise ValueError("no states to write (frames is empty)")
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), str(p.parent)) from None
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(root, "Collection")
    written = [p]
    for k, fr in enumerate(frames):
        vtu = p.with_name(f"{p.stem}_{k:04d}.vtu")
        frame_mesh = _frame_mesh(mesh, fr, deformed)

        def write_vtu_file(tmp: Path, fr=fr, k=k, frame_mesh=frame_mesh) -> None:
            frame_mesh.write(tmp, file_format="vtu")
            _add_field_data(tmp, {**fr.field_data, "time": fr.time, "step": k})

        _atomic_write(vtu, write_vtu_file)
        ET.SubElement(coll, "DataSet", timestep=repr(float(fr.time)), group="", part="0", file=vtu.name)
        written.append(vtu)
    ET.indent(root)
    _atomic_write(p, lambda tmp: ET.ElementTree(root).write(tmp, xml_declaration=True, encoding="utf-8"))
    return written


def _atomic_write(path: Path, write) -> None:
    """``write(tmp)`` to a temporary file beside ``path``, then renamed to it: a failed write (a full disk) leaves
    no truncated ``path`` (an existing one stays as it was). An OSError names ``path`` (its ``filename`` too)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.part")
    try:
        write(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def read_pvd(path: str | os.PathLike) -> list[tuple[float, Path]]:
    """The (time value, VTU path) entries of a PVD collection, in file order (plain XML parse)."""
    p = Path(path)
    root = ET.parse(p).getroot()
    return [(float(d.get("timestep", "nan")), p.parent / d.get("file", "")) for d in root.iter("DataSet")]


def contact_pressure(mesh, deformed_nodes: np.ndarray, nodal_force: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    r"""Nodal contact pressure (Pa) on the surface ``edges["outer"]`` of an axisymmetric section.

    mesh           AxiMesh with boundary edges ``edges["outer"]`` (3 dofs per edge for Q2, 2 for Q1).
    deformed_nodes (N, 2) deformed dof coordinates (m).
    nodal_force    compressive contact force (N) per node of ``nodes`` (the axisymmetric nodal reaction,
                   2 pi r included), 0 off contact.
    nodes          dof indices the forces belong to.

    The pressure p = sum_j p_j phi_j on the deformed surface whose consistent nodal forces are the given
    ones: M p = F with the surface mass matrix M_ij = \int phi_i phi_j 2 pi r ds (Gauss-Legendre,
    4 points per edge). Exact for any pressure field the surface elements can represent (e.g. uniform),
    its L2 projection otherwise (a Hertz-like profile shows small over- and undershoots next to the
    contact edge; negative values of the projection are set to 0); sum_i F_i is the plate force.
    Dividing F_i by the consistent area instead fails on the axis, where that area of a quadratic
    element vanishes. Returns one value per entry of ``nodes``.
    """
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    ed = np.asarray(mesh.edges["outer"])
    x = np.asarray(deformed_nodes, float)
    xi, w = np.polynomial.legendre.leggauss(4)
    if ed.shape[1] == 3:
        N = np.stack([xi * (xi - 1) / 2, 1 - xi**2, xi * (xi + 1) / 2])  # (3, q)
        dN = np.stack([xi - 0.5, -2 * xi, xi + 0.5])
    else:
        N = np.stack([(1 - xi) / 2, (1 + xi) / 2])
        dN = np.stack([-0.5 + 0 * xi, 0.5 + 0 * xi])
    xe = x[ed]  # (ne, nen, 2)
    pos = np.einsum("aq,ead->eqd", N, xe)
    tang = np.einsum("aq,ead->eqd", dN, xe)
    jac = 2 * np.pi * pos[..., 0] * np.linalg.norm(tang, axis=-1) * w  # (ne, q)
    Me = np.einsum("aq,bq,eq->eab", N, N, jac)
    surf, loc = np.unique(ed, return_inverse=True)
    loc = loc.reshape(ed.shape)
    n = surf.size
    rows = np.repeat(loc, ed.shape[1], axis=1).ravel()
    cols = np.tile(loc, (1, ed.shape[1])).ravel()
    M = sp.csc_matrix((Me.ravel(), (rows, cols)), shape=(n, n))
    nodes = np.asarray(nodes, int)
    where = np.searchsorted(surf, nodes)
    if np.any(where >= n) or np.any(surf[np.minimum(where, n - 1)] != nodes):
        raise ValueError("contact nodes must lie on the surface edges['outer'] of the mesh")
    F = np.zeros(n)
    F[where] = np.asarray(nodal_force, float)
    return np.maximum(spla.spsolve(M, F)[where], 0.0)


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
    """Colour each deformed element by its von Mises stress (Pa); axes in um (drawn by
    ``tissuemech.compare.plots.fields.element_von_mises``; fem itself draws nothing)."""
    from tissuemech.compare.plots.fields import element_von_mises

    return element_von_mises(mesh, displacement, vm, ax=ax)


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
    contact_nodes: np.ndarray | None = None  # dof indices of contact_nodal_force (None: outer minus midplane)


def _final_field(name: str, doc: str) -> property:
    """A read-only attribute that reads ``name`` of the last stored field."""
    return property(lambda self: getattr(self.fields[-1], name), doc=doc)


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
    ``wall_time`` [s] per step, ``in_contact`` (bool per step: False where the plates have lost the ball, force 0).
    ``fields``: SpheroidField at the requested ``field_times`` and the end.
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
    gradient: dict | None = None  # compress(gradient=True): {"C": {"force": dF/dC [N/Pa], ...}, "alpha": ..., ...}
    in_contact: np.ndarray | None = None  # bool per step: the plate touches the ball (False: force 0, contact lost)

    def field_at(self, time: float | None = None) -> SpheroidField:
        """The stored field closest to ``time`` (s; None: the last)."""
        if time is None:
            return self.fields[-1]
        return min(self.fields, key=lambda f: abs(f.time - float(time)))

    # the final state's fields under the names BlastulaResult uses (read-only, from ``fields[-1]``)
    displacement = _final_field("displacement", "Final nodal displacement (N, 2) [m].")
    deformed_nodes = _final_field("deformed_nodes", "Final deformed dof coordinates (N, 2) [m].")
    von_mises = _final_field("von_mises", "Final element von Mises stress [Pa].")
    hydrostatic_pressure = _final_field(
        "hydrostatic_pressure", "Final element hydrostatic pressure (-mean Cauchy) [Pa]."
    )

    def _contact_nodes(self, f: SpheroidField) -> np.ndarray:
        if f.contact_nodes is not None:
            return np.asarray(f.contact_nodes, int)
        m: Any = self.mesh  # fem.spheroid's candidates: the surface off the midplane, from the pole outward
        cand = np.setdiff1d(m.nodes["outer"], m.nodes["symmetry"])
        cand = cand[np.argsort(np.arctan2(m.X[0, cand], m.X[1, cand]))]
        if cand.size != np.size(f.contact_nodal_force):
            raise ValueError(
                f"contact_nodal_force (N) has {np.size(f.contact_nodal_force)} entries for {cand.size} "
                "surface nodes: set SpheroidField.contact_nodes"
            )
        return cand

    def to_pvd(self, path: str | os.PathLike, *, deformed: bool = False) -> list[Path]:
        """Write the stored states as a ParaView time series: a PVD collection ``path`` and one VTU each.

        States: ``fields`` (those at ``compress(..., field_times=...)`` and the last step;
        ``field_times="all"`` keeps every converged step). ParaView's time value is the time (s), for
        static runs the load fraction. Besides displacement, von Mises and hydrostatic pressure each VTU
        has the point data ``contact_pressure_Pa`` (nodal contact force over its consistent deformed area,
        :func:`contact_pressure`; 0 off contact) and ``contact_nodal_force_N``, and the field data
        ``approach_m`` and ``force_N`` of the step. ``deformed``: deformed coordinates (m) instead of
        reference ones. Returns the paths written (the PVD first). Raises ValueError if ``path`` does
        not end in ``.pvd``.
        """
        frames = []
        n = int(getattr(self.mesh, "n_nodes"))  # noqa: B009 (mesh is typed as object)
        for f in self.fields:
            nodes = self._contact_nodes(f)
            fc = np.asarray(f.contact_nodal_force, float)
            pc = contact_pressure(self.mesh, f.deformed_nodes, fc, nodes)
            p_full, f_full = np.zeros(n), np.zeros(n)
            p_full[nodes], f_full[nodes] = pc, fc
            k = int(np.argmin(np.abs(self.time - f.time)))
            frames.append(
                Frame(
                    time=float(f.time),
                    displacement=f.displacement,
                    cell_data={"von_mises_Pa": f.von_mises, "hydrostatic_pressure_Pa": f.hydrostatic_pressure},
                    point_data={"contact_pressure_Pa": p_full, "contact_nodal_force_N": f_full},
                    field_data={"approach_m": float(self.approach[k]), "force_N": float(self.force[k])},
                )
            )
        return write_pvd(path, self.mesh, frames, deformed=deformed)

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
        """Nominal stress F/A_mid and mean von Mises stress vs time (seed Figs 9-10; drawn by
        ``tissuemech.compare.plots.fields.relaxation_curves``)."""
        from tissuemech.compare.plots.fields import relaxation_curves

        return relaxation_curves(self, axes=axes)
