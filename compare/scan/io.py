"""A scan table as an ``xarray.Dataset`` and a netCDF file, and back (exact round trip).

:func:`to_xarray` names the variables by their plain names with ``units`` (SI; "1" for dimensionless) and
``long_name`` attributes; :func:`from_xarray` gives back the unit-labelled table; :func:`to_netcdf` writes it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from tissuemech.compare.scan.table import scene_parameters, split_column

__all__ = ["to_xarray", "from_xarray", "to_netcdf", "LONG_NAMES"]

LONG_NAMES = {
    "radius": "ball radius a0",
    "C": "Fung stiffness C",
    "alpha": "Fung exponent alpha",
    "beta": "energy factor beta of the Maxwell branch",
    "tau": "relaxation time tau of the Maxwell branch",
    "displacement": "total approach of the plates",
    "ramp_time": "duration of the loading ramp",
    "inner_radius": "inner radius A of the shell",
    "outer_radius": "outer radius B of the shell",
    "pressure": "internal pressure p",
    "sigma_peak": "nominal stress F/A_mid at the end of the ramp (peak)",
    "sigma_end": "nominal stress at the end of the hold",
    "relaxed_fraction": "relaxed fraction 1 - sigma_end/sigma_peak",
    "t_half": "time at which the stress has fallen half-way from peak to end",
    "inner_stretch": "inner stretch a/A (NaN where the shell bursts or leaves 0.5..10)",
    "outer_stretch": "outer stretch b/B (NaN where the shell bursts or leaves 0.5..10)",
    "p_limit": "limit (burst) pressure of the exact shell (NaN: none up to stretch 10)",
    "bursts": "the pressure is at or above the limit pressure",
    "fe_sigma_peak": "FE nominal stress at the end of the ramp",
    "fe_sigma_end": "FE nominal stress at the end of the hold",
    "fe_inner_stretch": "FE inner stretch a/A",
    "deviation": "largest relative difference reduced vs FE (NaN: no FE run at this point)",
    "sigma": "nominal stress F/A_mid",
    "time": "time since first contact",
}


def _cf_units(unit: str) -> str:
    return "1" if unit == "-" else unit


def to_xarray(table: pd.DataFrame) -> Any:
    """A scan table (from :func:`spheroid` or :func:`blastula`) as an ``xarray.Dataset``.

    Variables carry the plain names (``C``, ``sigma_peak``, ``inner_stretch``, ``deviation``...) with
    ``units`` (SI; "1" for dimensionless) and ``long_name`` attributes. Dimensions are the varied
    parameters when the table is a full factorial grid over them (``design_method="grid"``): one
    dimension per varied parameter, its sorted values as the coordinate. Other designs (random,
    Latin hypercube, ``points=``) have one dimension ``point`` with the parameters as coordinates
    along it. Parameters held fixed are scalar coordinates. A curves column (``sigma [Pa]``, from
    ``curves=True``) becomes the variable ``sigma`` with the extra dimension ``time`` (s).
    ``ds.attrs``: ``scene`` ("spheroid" or "blastula"), ``layout`` ("grid" or "points").

    Raises ValueError if ``table`` lacks the parameter columns of a scan.
    """
    import xarray as xr

    cols = {split_column(c)[0]: c for c in table.columns}
    scene, params = scene_parameters(list(cols))
    n = len(table)
    if n == 0:
        raise ValueError("table is empty (no scan points)")
    values = {k: table[cols[k]].to_numpy(dtype=float) for k in params}
    varied = [k for k in params if np.unique(values[k]).size > 1]
    fixed = [k for k in params if k not in varied]

    levels = {k: np.unique(values[k]) for k in varied}
    shape = tuple(levels[k].size for k in varied)
    codes = [np.searchsorted(levels[k], values[k]) for k in varied]
    grid = bool(varied) and int(np.prod(shape)) == n
    if grid:
        flat = np.ravel_multi_index(codes, shape)
        grid = np.unique(flat).size == n
    if grid:
        dims: tuple[str, ...] = tuple(varied)
        order = np.argsort(flat)  # rows in C order of the grid
    else:
        dims = ("point",)
        shape = (n,)
        order = np.arange(n)

    def attrs(name: str, unit: str, label: str | None = None) -> dict:
        a = {"units": _cf_units(unit)} if unit else {}  # a column without a unit gets none (it stays unitless)
        if name in LONG_NAMES:
            a["long_name"] = LONG_NAMES[name]
        if label is not None:
            a["column"] = label  # the table's column name, for an exact round trip
        return a

    coords: dict[str, Any] = {}
    for k in params:
        unit = split_column(cols[k])[1]
        if k in fixed:
            coords[k] = ((), float(values[k][0]), attrs(k, unit, cols[k]))
        elif grid:
            coords[k] = ((k,), levels[k], attrs(k, unit, cols[k]))
        else:
            coords[k] = (("point",), values[k], attrs(k, unit, cols[k]))
    if not grid:
        coords["point"] = (("point",), np.arange(n), {"long_name": "index of the point in the scan table"})
    data_vars: dict[str, Any] = {}
    curves = None
    for name, col in cols.items():
        if name in params:
            continue
        unit = split_column(col)[1]
        if table[col].dtype == object:  # curves: one array per row
            arr = np.stack([np.asarray(v, dtype=float) for v in table[col].to_numpy()[order]])
            curves = (name, unit)
            data_vars[name] = (dims + ("time",), arr.reshape(shape + arr.shape[1:]), attrs(name, unit, col))
            continue
        v = table[col].to_numpy()[order]
        a = attrs(name, unit, col)
        if v.dtype == bool:
            v = v.astype(bool)
        elif np.issubdtype(v.dtype, np.integer):  # kept whole (netCDF3 stores int32; read back as this dtype)
            a["pandas_dtype"] = v.dtype.str
        else:
            v = v.astype(float)
        data_vars[name] = (dims, v.reshape(shape), a)
    if curves is not None:
        t = table.attrs.get("time [s]")
        if t is None:
            raise ValueError(
                'a curves column needs the output times in table.attrs["time [s]"] (as scan.spheroid sets)'
            )
        coords["time"] = (("time",), np.asarray(t, dtype=float), attrs("time", "s"))
    ds = xr.Dataset(data_vars, coords=coords)
    ds.attrs.update(scene=scene, layout="grid" if grid else "points", source="tissuemech.compare.scan")
    return ds


def from_xarray(ds: Any) -> pd.DataFrame:
    """The scan table of a Dataset from :func:`to_xarray` (or read back from :func:`to_netcdf`).

    Unit-labelled columns as the scans return them (parameters first); rows in the Dataset's order
    (C order of the grid dimensions, or the ``point`` order); curves back as a ``sigma [Pa]`` column of
    arrays with ``attrs["time [s]"]``.
    """
    scene, params = scene_parameters(list(ds.variables))

    def label(name: str) -> str:
        a = ds[name].attrs
        if "column" in a:
            return str(a["column"])
        if "units" not in a:  # a column without a unit
            return name
        u = a["units"]
        return f"{name} [{'-' if u == '1' else u}]"

    dims = [d for d in ds.dims if d != "time"]
    n = int(np.prod([ds.sizes[d] for d in dims])) if dims else 1
    out: dict[str, Any] = {}
    for k in params:
        v = ds[k].reset_coords(drop=True)
        for d in dims:
            if d not in v.dims:
                v = v.expand_dims({d: ds.sizes[d]})
        out[label(k)] = np.asarray(v.transpose(*dims).values, dtype=float).reshape(n)
    names = sorted(ds.data_vars, key=lambda v: "time" in ds[v].dims)  # curves last, as the scans return them
    for name in names:
        var = ds[name]
        if "time" in var.dims:
            arr = np.asarray(var.transpose(*dims, "time").values).reshape(n, -1)
            out[label(name)] = list(arr)
        else:
            v = np.asarray(var.transpose(*dims).values).reshape(n)
            if "pandas_dtype" in var.attrs:
                v = v.astype(np.dtype(str(var.attrs["pandas_dtype"])))
            out[label(name)] = v
    df = pd.DataFrame(out)
    if "time" in ds.coords:
        df.attrs["time [s]"] = np.asarray(ds["time"].values, dtype=float)
    return df


def to_netcdf(table_or_dataset: Any, path: Any, *, engine: str = "scipy") -> Any:
    """Write a scan table (DataFrame, converted by :func:`to_xarray`) or a Dataset to a netCDF file.

    engine  ``"scipy"`` (default; netCDF3 64-bit offset, needs nothing beyond scipy) or
            ``"h5netcdf"`` / ``"netcdf4"`` (netCDF4, if that package is installed).
    Returns the path (``pathlib.Path``). Read back with ``xarray.open_dataset(path)`` and
    :func:`from_xarray`.
    """
    from pathlib import Path

    import xarray as xr

    ds = table_or_dataset if isinstance(table_or_dataset, xr.Dataset) else to_xarray(table_or_dataset)
    path = Path(path)
    if engine == "scipy":
        ds.to_netcdf(path, engine="scipy", format="NETCDF3_64BIT")
    elif engine in ("h5netcdf", "netcdf4"):
        ds.to_netcdf(path, engine=engine)  # type: ignore[call-overload]  # xarray stubs: engine is a checked str, not a Literal
    else:
        raise ValueError(f'engine must be "scipy", "h5netcdf" or "netcdf4"; got {engine!r}')
    return path
