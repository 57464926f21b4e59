"""Parameter scans of the reduced models, with FE spot-checks, as tidy pandas tables.

    from tissuemech.compare import scan
    table = scan.spheroid(C=(100.0, 300.0), tau=(10.0, 1000.0), n=20, fe_checks=3)
    scan.to_netcdf(table, "scan.nc")

* :mod:`.evaluation`: designs (grid, random, Latin hypercube) and the reduced models evaluated over them
  (:func:`spheroid`, :func:`blastula`, :func:`design`, :func:`default_times`, :func:`evaluate_in_chunks`);
* :mod:`.fe_checks`: FE spot-checks at points spread over the design (:func:`spread_indices`,
  :func:`spot_check`), run through ``compare.batch``;
* :mod:`.io`: the table as an ``xarray.Dataset`` / netCDF file and back (:func:`to_xarray`,
  :func:`from_xarray`, :func:`to_netcdf`);
* :mod:`.sensitivity`: which parameter drives which summary (exact JAX derivatives; the FE's at spot-checks);
* :mod:`.table`: the columns (:func:`column` ``"C"`` -> ``"C [Pa]"``, :func:`unit_of`, :data:`UNITS`).

Figures of a scan: ``compare.plots.scan``; the command ``tissuemech scan``: ``compare.cli.scan``.
"""

from __future__ import annotations

from tissuemech.compare.scan.evaluation import (
    BLOCK,
    CHUNK,
    MAX_SCAN_BYTES,
    TINY,
    blastula,
    check_normal,
    default_times,
    design,
    evaluate_in_chunks,
    spheroid,
    spheroid_times,
    summaries,
    vmap_in_blocks,
)
from tissuemech.compare.scan.fe_checks import FE_COLUMNS, design_points, select, spot_check, spread_indices
from tissuemech.compare.scan.io import LONG_NAMES, from_xarray, to_netcdf, to_xarray
from tissuemech.compare.scan.sensitivity import (
    BLASTULA_SUMMARIES,
    SPHEROID_SUMMARIES,
    fe_sensitivities,
    sensitivities,
)
from tissuemech.compare.scan.table import (
    BLASTULA_PARAMS,
    SPHEROID_PARAMS,
    UNITS,
    column,
    is_log_sampled,
    parameters_of,
    scene_of,
    scene_parameters,
    split_column,
    unit_of,
    unit_words,
    varied_parameters,
)

__all__ = [
    "design",
    "spheroid",
    "blastula",
    "default_times",
    "spheroid_times",
    "summaries",
    "evaluate_in_chunks",
    "spread_indices",
    "select",
    "spot_check",
    "design_points",
    "to_xarray",
    "from_xarray",
    "to_netcdf",
    "sensitivities",
    "fe_sensitivities",
    "column",
    "unit_of",
    "unit_words",
    "split_column",
    "scene_of",
    "scene_parameters",
    "parameters_of",
    "varied_parameters",
    "is_log_sampled",
    "UNITS",
    "SPHEROID_PARAMS",
    "BLASTULA_PARAMS",
    "SPHEROID_SUMMARIES",
    "BLASTULA_SUMMARIES",
    "FE_COLUMNS",
    "LONG_NAMES",
    "check_normal",
    "MAX_SCAN_BYTES",
    "BLOCK",
    "vmap_in_blocks",
    "CHUNK",
    "TINY",
]
