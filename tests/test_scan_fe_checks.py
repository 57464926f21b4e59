"""compare.scan.fe_checks: FE spot-checks at points spread over the design, their columns and deviations."""

from __future__ import annotations

import numpy as np
import pytest
from fakes import fake_nominal_stress

from tissuemech.compare import scan


def _fake_fe(*, radius, C, alpha, beta, tau, displacement, ramp_time, end_time):
    t = scan.default_times(ramp_time, end_time)
    s = np.asarray(
        fake_nominal_stress(
            t,
            radius=radius,
            C=C * 1.01,
            alpha=alpha,
            branches=[(beta, tau)],
            displacement=displacement,
            ramp_time=ramp_time,
        )
    )
    return {"time": t, "nominal_stress": s}


def test_spheroid_fe_checks_columns(tmp_path):
    df = scan.spheroid(
        C=(100.0, 300.0),
        alpha=(0.0, 0.3),
        n=20,
        design_method="lhs",
        model=fake_nominal_stress,
        fe_checks=3,
        fe_function=_fake_fe,
        fe_executor="serial",
        fe_store=str(tmp_path),
    )
    checked = df["deviation [-]"].notna()
    assert checked.sum() == 3
    # the fake FE is 1 % stiffer: deviation = 1 - 1/1.01 at every checked point
    assert np.allclose(df.loc[checked, "deviation [-]"], 1 - 1 / 1.01, rtol=1e-9)
    assert len(list(tmp_path.glob("*.npz"))) == 3


def test_spread_indices_distinct_and_spread():
    pts = scan.design({"x": (0.0, 1.0), "y": (0.0, 1.0)}, n=11, method="grid")
    idx = scan.spread_indices(pts, 5)
    assert len(set(idx)) == 5
    chosen = pts.iloc[idx].to_numpy()
    d = np.min([np.linalg.norm(a - b) for i, a in enumerate(chosen) for b in chosen[i + 1 :]])
    assert d > 0.4


def test_blastula_scan_fe_spot_checks_agree():
    """FE spot-checks (fem.blastula, default mesh, kappa = 2.2 GPa) against the exact shell: < 1e-5."""
    df = scan.blastula(
        alpha=[0.2], outer_radius=[60e-6, 75e-6], pressure=(10.0, 60.0), n=4, fe_checks=2, fe_executor="serial"
    )
    checked = df["deviation [-]"].notna()
    assert checked.sum() == 2
    assert (df.loc[checked, "deviation [-]"] < 1e-5).all()
    assert np.allclose(df.loc[checked, "fe_inner_stretch [-]"], df.loc[checked, "inner_stretch [-]"], rtol=1e-5)


def test_spot_check_of_a_finished_table_selects_holding_points(tmp_path):
    """scan.spot_check on a finished blastula table: only points where the shell holds at p > 0 are checked."""
    df = scan.blastula(alpha=[1e-5], outer_radius=[75e-6], pressure=(0.0, 300.0), n=7)
    idx = scan.select(df, 3)
    assert len(idx) == 3 and (df["pressure [Pa]"].to_numpy()[idx] > 0).all()
    assert df["inner_stretch [-]"].notna().to_numpy()[idx].all()  # 300 Pa bursts this shell: never chosen
    with pytest.raises(ValueError, match="times"):
        scan.spot_check(scan.spheroid(n=1, model=fake_nominal_stress, equilibrium="fake"), 1, executor="serial")
