"""ParaView time series (``to_pvd``) of both FE scenes: read back by meshio and a plain XML parse."""

import meshio
import numpy as np
import pytest

from tissuemech.fem.blastula import creep, inflate
from tissuemech.fem.output import contact_pressure, read_pvd
from tissuemech.fem.spheroid import compress

A, B, C = 50e-6, 75e-6, 200.0
A0 = 500e-6


def _read(path):
    entries = read_pvd(path)
    return [t for t, _ in entries], [meshio.read(f) for _, f in entries]


def test_blastula_series_every_step(tmp_path):
    p = [200.0, 500.0, 1000.0]
    r = inflate(inner_radius=A, outer_radius=B, C=C, alpha=0.2, pressures=p, mesh=(2, 4), store_fields=True)
    assert len(r.fields) == 3
    written = r.to_pvd(tmp_path / "run" / "blastula.pvd")
    assert len(written) == 4 and all(f.exists() for f in written)
    times, meshes = _read(written[0])
    assert times == p  # load control: ParaView's time axis is the pressure (Pa)
    n = r.mesh.n_nodes
    for k, (m, f) in enumerate(zip(meshes, r.fields)):
        assert m.cells[0].type == "quad9" and m.points.shape == (n, 3)
        assert np.allclose(m.points[:, :2], r.mesh.X.T * A)  # reference coordinates + warp vector
        assert np.allclose(m.point_data["displacement"][:, :2], f.displacement)
        assert np.allclose(m.point_data["deformed_coordinates"][:, :2], f.deformed_nodes)
        assert np.allclose(m.cell_data["von_mises_Pa"][0], f.von_mises)
        assert np.allclose(m.cell_data["hydrostatic_pressure_Pa"][0], f.hydrostatic_pressure)
        assert float(m.field_data["pressure_Pa"][0]) == p[k] and int(m.field_data["step"][0]) == k
        # the deformed inner surface has radius lambda_a A (the shell stays spherical; steps differ by > 10 %)
        inner = r.mesh.nodes["inner"]
        rad = np.hypot(*m.point_data["deformed_coordinates"][inner, :2].T)
        assert np.allclose(rad / A, r.inner_stretch[k], rtol=3e-3)  # coarse 2 x 4 mesh
    # the last stored step is the result's final state
    assert np.allclose(r.fields[-1].von_mises, r.von_mises)
    assert np.allclose(r.fields[-1].displacement, r.displacement)
    # von Mises grows with the pressure in every element
    vm = np.array([f.von_mises for f in r.fields])
    assert np.all(np.diff(vm, axis=0) > 0)


def test_blastula_series_final_only_and_deformed(tmp_path):
    r = inflate(inner_radius=A, outer_radius=B, C=C, alpha=0.2, pressures=[300.0], mesh=(2, 4))
    assert r.fields is None
    written = r.to_pvd(tmp_path / "b.pvd", deformed=True)
    times, meshes = _read(written[0])
    assert times == [300.0]
    assert np.allclose(meshes[0].points[:, :2], r.deformed_nodes)
    with pytest.raises(ValueError, match=r"\.pvd"):
        r.to_pvd(tmp_path / "b.vtu")


def test_blastula_creep_series_times(tmp_path):
    r = creep(
        inner_radius=A,
        outer_radius=B,
        C=C,
        alpha=0.2,
        branches=[(0.5, 100.0)],
        pressure=300.0,
        ramp_time=1.0,
        end_time=200.0,
        mesh=(2, 4),
        n_ramp=2,
        n_hold=6,
        store_fields=True,
    )
    written = r.to_pvd(tmp_path / "creep.pvd")
    times, meshes = _read(written[0])
    assert np.allclose(times, r.time) and len(meshes) == len(r.time)
    assert np.allclose([float(m.field_data["time_s"][0]) for m in meshes], r.time)
    # creep: the displacement keeps growing under the held pressure
    ur = [float(np.max(m.point_data["displacement"][:, 0])) for m in meshes]
    assert np.all(np.diff(ur) > 0)
    assert np.allclose(meshes[-1].cell_data["von_mises_Pa"][0], r.von_mises)


def test_blastula_arclength_series_uses_step_numbers(tmp_path):
    r = inflate(
        inner_radius=A,
        outer_radius=B,
        C=C,
        alpha=0.0,
        pressures=None,
        mesh=(2, 4),
        method="arclength",
        max_inner_stretch=2.0,
        store_fields=True,
    )
    times, meshes = _read(r.to_pvd(tmp_path / "a.pvd")[0])
    assert times == list(range(len(r.pressure)))  # increasing although p falls past the limit point
    assert np.allclose([float(m.field_data["pressure_Pa"][0]) for m in meshes], r.pressure)


@pytest.fixture(scope="module")
def relax_all():
    return compress(
        radius=A0,
        C=150.0,
        alpha=0.2,
        branches=[(0.4, 200.0)],
        displacement=50e-6,
        ramp_time=0.2,
        end_time=1500.0,
        mesh="coarse",
        field_times="all",
    )


def test_spheroid_series_every_step(relax_all, tmp_path):
    r = relax_all
    assert len(r.fields) == len(r.time)
    written = r.to_pvd(tmp_path / "spheroid.pvd")
    times, meshes = _read(written[0])
    assert np.allclose(times, r.time)
    for k, (m, f) in enumerate(zip(meshes, r.fields)):
        assert np.allclose(m.point_data["displacement"][:, :2], f.displacement)
        assert np.allclose(m.cell_data["von_mises_Pa"][0], f.von_mises)
        pc = m.point_data["contact_pressure_Pa"]
        assert np.all(pc >= 0)
        # contact pressure integrated over the deformed surface (consistent forces) = plate force
        fn = m.point_data["contact_nodal_force_N"]
        assert np.isclose(fn.sum(), r.force[k], rtol=1e-12)
        assert np.isclose(float(m.field_data["force_N"][0]), r.force[k])
        assert np.isclose(float(m.field_data["approach_m"][0]), r.approach[k])
        # the peak contact pressure sits on the plate z = a0 - delta/2
        z = m.point_data["deformed_coordinates"][:, 1]
        assert abs(z[np.argmax(pc)] - (A0 - r.approach[k] / 2)) < 1e-9 * A0
    # relaxation: the mean contact pressure follows the plate force down during the hold
    pmax = [float(m.point_data["contact_pressure_Pa"].max()) for m in meshes]
    hold = r.time > 0.2
    assert np.all(np.diff(np.array(pmax)[hold]) < 0)


def test_spheroid_field_times_rejects_other_strings():
    with pytest.raises(ValueError, match="field_times"):
        compress(
            radius=A0,
            C=150.0,
            alpha=0.2,
            displacement=50e-6,
            ramp_time=0.2,
            end_time=1.0,
            mesh="coarse",
            field_times="every",
        )


def test_contact_pressure_follows_hertz_at_small_compression():
    # 2 % of the diameter: the FE contact pressure has the Hertz profile p0 sqrt(1 - r^2/a^2) with the
    # FE's own force and contact radius, p0 = 3 F / (2 pi a^2)
    r = compress(
        radius=A0, C=150.0, alpha=0.2, displacement=20e-6, ramp_time=1.0, end_time=1.0, mesh="fine", static=True
    )
    f = r.fields[-1]
    pc = contact_pressure(r.mesh, f.deformed_nodes, f.contact_nodal_force, f.contact_nodes)
    F, a = r.force[-1], r.contact_radius[-1]
    p0 = 3 * F / (2 * np.pi * a**2)
    rr = f.deformed_nodes[f.contact_nodes, 0]
    inside = rr < 0.8 * a
    assert inside.sum() >= 5
    hertz = p0 * np.sqrt(1 - (rr[inside] / a) ** 2)
    assert np.max(np.abs(pc[inside] - hertz)) < 0.05 * p0
    assert np.all(pc[rr > 1.3 * a] < 0.1 * p0)


def test_both_scenes_store_fields_the_same_way(relax_all):
    """field_at(time) and the final fields under the same names in BlastulaResult and SpheroidResult."""
    s = relax_all
    assert s.field_at() is s.fields[-1] and s.field_at(0.2).time == pytest.approx(0.2)
    for name in ("displacement", "deformed_nodes", "von_mises", "hydrostatic_pressure"):
        assert getattr(s, name) is getattr(s.fields[-1], name)
    kw = dict(inner_radius=A, outer_radius=B, C=C, alpha=0.2, mesh=(2, 4))
    b = creep(**kw, branches=[(0.5, 10.0)], pressure=100.0, ramp_time=1.0, end_time=20.0, n_ramp=2, n_hold=4)
    assert b.fields is None and b.field_at().time == pytest.approx(20.0)  # only the final state was kept
    assert np.array_equal(b.field_at(5.0).von_mises, b.von_mises)
    bl = inflate(**kw, pressures=[100.0, 200.0], store_fields=True)
    assert bl.field_at() is bl.fields[-1] and bl.field_at().pressure == pytest.approx(200.0)
    with pytest.raises(ValueError, match="creep run"):
        bl.field_at(1.0)
