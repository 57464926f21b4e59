"""The columns of a scan table: names, SI units, scenes.

A scan table (``scan.spheroid`` / ``scan.blastula``) has one row per design point and unit-labelled
columns, ``"<name> [<unit>]"`` (``C [Pa]``, ``inner_stretch [-]``). :func:`column` builds that label from
a plain name, :func:`unit_of` gives the unit, :func:`split_column` takes a label apart.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

__all__ = [
    "UNITS",
    "SPHEROID_PARAMS",
    "BLASTULA_PARAMS",
    "column",
    "unit_of",
    "unit_words",
    "split_column",
    "scene_parameters",
    "scene_of",
    "parameters_of",
    "varied_parameters",
    "is_log_sampled",
]

SPHEROID_PARAMS = ("radius", "C", "alpha", "beta", "tau", "displacement", "ramp_time")
BLASTULA_PARAMS = ("inner_radius", "outer_radius", "C", "alpha", "pressure")

UNITS = {
    "radius": "m",
    "C": "Pa",
    "alpha": "-",
    "beta": "-",
    "tau": "s",
    "displacement": "m",
    "ramp_time": "s",
    "inner_radius": "m",
    "outer_radius": "m",
    "pressure": "Pa",
    "sigma_peak": "Pa",
    "sigma_end": "Pa",
    "relaxed_fraction": "-",
    "t_half": "s",
    "inner_stretch": "-",
    "outer_stretch": "-",
    "p_limit": "Pa",
    "bursts": "-",
    "fe_sigma_peak": "Pa",
    "fe_sigma_end": "Pa",
    "fe_inner_stretch": "-",
    "deviation": "-",
}


def unit_of(name: str) -> str:
    """The SI unit of a scan quantity (plain name): ``"C"`` -> ``"Pa"``, ``"alpha"`` -> ``"-"``.

    Raises ValueError for a name that is not a scan quantity."""
    try:
        return UNITS[name]
    except KeyError:
        raise ValueError(f"{name!r} is not a quantity of a scan table; choose from {sorted(UNITS)}") from None


def column(name: str) -> str:
    """The unit-labelled column of a scan quantity: ``"C"`` -> ``"C [Pa]"`` (ValueError for an unknown name)."""
    return f"{name} [{unit_of(name)}]"


def unit_words(name: str) -> str:
    """The unit of ``name`` as error messages say it (``"Pa"``, ``"dimensionless"``; ``""`` if unknown)."""
    unit = UNITS.get(name, "")
    return "dimensionless" if unit == "-" else unit


def split_column(label: str) -> tuple[str, str]:
    """``"C [Pa]"`` -> ``("C", "Pa")``; a column without a unit -> ``(label, "")``."""
    if label.endswith("]") and " [" in label:
        name, unit = label[:-1].rsplit(" [", 1)
        return name, unit
    return label, ""


def scene_parameters(names: Sequence[str]) -> tuple[str, tuple[str, ...]]:
    """(scene, its parameters) of a scan from the plain names of its columns (ValueError if neither)."""
    if set(SPHEROID_PARAMS) <= set(names):
        return "spheroid", SPHEROID_PARAMS
    if set(BLASTULA_PARAMS) <= set(names):
        return "blastula", BLASTULA_PARAMS
    raise ValueError(
        "table is not a scan table: it needs the parameter columns of scan.spheroid "
        f"({', '.join(column(k) for k in SPHEROID_PARAMS)}) or of scan.blastula "
        f"({', '.join(column(k) for k in BLASTULA_PARAMS)})"
    )


def scene_of(table: pd.DataFrame) -> str:
    """``"spheroid"`` or ``"blastula"`` from the parameter columns of a scan table (ValueError otherwise)."""
    return scene_parameters([split_column(str(c))[0] for c in table.columns])[0]


def parameters_of(table: pd.DataFrame) -> tuple[str, ...]:
    """The parameters (plain names, scene order) of a scan table."""
    return scene_parameters([split_column(str(c))[0] for c in table.columns])[1]


def varied_parameters(table: pd.DataFrame) -> list[str]:
    """The parameters (plain names, scene order) that take more than one value in the table."""
    return [k for k in parameters_of(table) if table[column(k)].nunique() > 1]


def is_log_sampled(values: np.ndarray, name: str, log: Sequence[str] | None) -> bool:
    """Whether parameter ``name`` is treated as log-scaled: named in ``log``; with ``log`` None, when its values
    are positive, span >= 20x and have their median nearer the geometric than the arithmetic middle."""
    if log is not None:
        return name in log
    v = values[np.isfinite(values)]
    if not (v.size and v.min() > 0 and v.max() / v.min() >= 20.0):
        return False
    med, lo, hi = np.median(v), v.min(), v.max()
    return bool(abs(np.log(med / np.sqrt(lo * hi))) < abs(np.log(med / (0.5 * (lo + hi)))))
