"""compare.scan.to_xarray / to_netcdf / from_xarray: names, dims, units, exact netCDF round trips."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from fakes import fake_nominal_stress

from tissuemech.compare import scan


def test_grid_blastula_dims_units_and_round_trip(tmp_path):
    df = scan.blastula(alpha=[1e-5, 0.2], outer_radius=[60e-6, 75e-6], pressure=(0.0, 150.0), n=4)
    ds = scan.to_xarray(df)
    # a full factorial grid: one dimension per varied parameter, in the scene's parameter order
    assert ds["inner_stretch"].dims == ("outer_radius", "alpha", "pressure")
    assert dict(ds.sizes) == {"outer_radius": 2, "alpha": 2, "pressure": 4}
    assert ds["inner_radius"].ndim == 0 and float(ds["inner_radius"]) == 50e-6  # fixed: scalar coordinate
    assert ds["pressure"].attrs["units"] == "Pa" and ds["outer_radius"].attrs["units"] == "m"
    assert ds["inner_stretch"].attrs["units"] == "1" and ds["p_limit"].attrs["units"] == "Pa"
    assert ds.attrs["scene"] == "blastula" and ds.attrs["layout"] == "grid"
    # every table row is found at its coordinates
    for _, row in df.iterrows():
        at = ds.sel(outer_radius=row["outer_radius [m]"], alpha=row["alpha [-]"], pressure=row["pressure [Pa]"])
        assert float(at["outer_stretch"]) == pytest.approx(row["outer_stretch [-]"], rel=0, nan_ok=True)
        assert bool(at["bursts"]) == row["bursts [-]"]
    path = scan.to_netcdf(df, tmp_path / "b.nc")
    with xr.open_dataset(path) as back:
        assert back["bursts"].dtype == bool
        assert back["pressure"].attrs["units"] == "Pa"
        pd.testing.assert_frame_equal(scan.from_xarray(back), df)  # bit-exact, same row order


def test_lhs_spheroid_points_and_curves_round_trip(tmp_path):
    df = scan.spheroid(
        C=(100.0, 300.0),
        tau=(10.0, 500.0),
        n=12,
        design_method="lhs",
        model=fake_nominal_stress,
        equilibrium="fake",
        curves=True,
    )
    ds = scan.to_xarray(df)
    assert ds["sigma_peak"].dims == ("point",) and ds["C"].dims == ("point",)
    assert ds["sigma"].dims == ("point", "time") and ds["time"].attrs["units"] == "s"
    assert ds["tau"].attrs["units"] == "s" and ds["relaxed_fraction"].attrs["units"] == "1"
    assert np.array_equal(ds["time"].values, df.attrs["time [s]"])
    assert np.array_equal(ds["sigma"].values[5], df["sigma [Pa]"].iloc[5])
    scan.to_netcdf(ds, tmp_path / "s.nc")
    with xr.open_dataset(tmp_path / "s.nc") as back:
        got = scan.from_xarray(back)
    assert list(got.columns) == list(df.columns)
    pd.testing.assert_frame_equal(got.drop(columns="sigma [Pa]"), df.drop(columns="sigma [Pa]"))
    assert all(np.array_equal(a, b) for a, b in zip(got["sigma [Pa]"], df["sigma [Pa]"]))
    assert np.array_equal(got.attrs["time [s]"], df.attrs["time [s]"])


def test_fe_columns_keep_their_nans(tmp_path):
    df = scan.blastula(alpha=(0.1, 0.3), pressure=(10.0, 100.0), n=30, design_method="random")
    df["fe_inner_stretch [-]"] = np.nan
    df["deviation [-]"] = np.nan
    df.loc[[3, 7], "deviation [-]"] = [0.01, 0.02]
    scan.to_netcdf(df, tmp_path / "f.nc")
    with xr.open_dataset(tmp_path / "f.nc") as back:
        assert back.attrs["layout"] == "points"
        got = scan.from_xarray(back)
    pd.testing.assert_frame_equal(got, df)


def test_errors():
    with pytest.raises(ValueError, match="not a scan table"):
        scan.to_xarray(pd.DataFrame({"x [m]": [1.0]}))
    df = scan.blastula(pressure=10.0, n=1)
    with pytest.raises(ValueError, match="engine"):
        scan.to_netcdf(df, "x.nc", engine="zarr")


def test_unitless_and_integer_columns_round_trip_exactly(tmp_path):
    """A unitless column came back renamed 'batch_id []' (and as floats)."""
    df = scan.blastula(alpha=(0.1, 0.3), pressure=(10.0, 100.0), n=6, design_method="random")
    df["batch_id"] = np.arange(len(df), dtype=np.int64)
    df["note []"] = 0.5
    pd.testing.assert_frame_equal(scan.from_xarray(scan.to_xarray(df)), df)
    assert "units" not in scan.to_xarray(df)["batch_id"].attrs
    scan.to_netcdf(df, tmp_path / "u.nc")
    with xr.open_dataset(tmp_path / "u.nc") as back:
        pd.testing.assert_frame_equal(scan.from_xarray(back), df)
