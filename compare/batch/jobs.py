"""Scheduler-free job arrays: a points table split into interleaved chunks, one per array task, each computed into a
shared store (``compare.batch.run``); :func:`collect` gathers the stored results into one table.

:func:`read_points` reads the points table (CSV, one column per keyword argument, SI units), :func:`chunk`
gives the points of one task, :func:`array_index` the task's index from the scheduler's environment (SLURM,
PBS, SGE, LSF), :func:`resolve_function` the function named on the command line.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Sequence
from typing import Any

from tissuemech.compare.batch.points import FUNCTIONS
from tissuemech.compare.batch.store import load, point_key

__all__ = ["ARRAY_INDEX", "chunk", "array_index", "read_points", "collect", "resolve_function"]

ARRAY_INDEX = (  # (environment variable, its first index)
    ("SLURM_ARRAY_TASK_ID", 0),
    ("PBS_ARRAY_INDEX", 0),
    ("PBS_ARRAYID", 0),
    ("SGE_TASK_ID", 1),
    ("LSB_JOBINDEX", 1),
)


def resolve_function(spec: str) -> Callable[..., Any]:
    """A name of :data:`FUNCTIONS` or ``module:function``; raises ValueError if it cannot be found."""
    if spec in FUNCTIONS:
        return FUNCTIONS[spec]
    mod, sep, name = spec.partition(":")
    if not sep or not mod or not name:
        raise ValueError(f"--function must be one of {sorted(FUNCTIONS)} or 'module:function', got {spec!r}")
    try:
        obj: Any = importlib.import_module(mod)
        for part in name.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError) as exc:
        raise ValueError(f"--function {spec!r} not found: {exc}") from None
    if not callable(obj):
        raise ValueError(f"--function {spec!r} is not callable")
    return obj


SI_UNITS = {"", "-", "1", "m", "s", "Pa", "N", "kg", "J"}  # units a points-table header may state


def read_points(path: str | os.PathLike) -> list[dict[str, Any]]:
    """The points of a CSV table (header = keyword names; numbers in SI units), one dict per row, with
    Python ints/floats/strings (integral columns stay ints). Raises ValueError for an empty table."""
    import pandas as pd

    df = pd.read_csv(path)
    if df.empty:
        raise ValueError(f"{path}: the points table has no rows")
    names = []
    for c in map(str, df.columns):  # 'C [Pa]' -> 'C'; the numbers must be SI: a unit is checked, not dropped
        name, _, unit = c.partition(" [")
        unit = unit.rstrip("]").strip()
        if unit not in SI_UNITS:
            raise ValueError(
                f"{path}: column {c!r}: the points are passed as they are, in SI units ({', '.join(sorted(SI_UNITS - {''}))}); "
                f"convert the column to SI and name it so (e.g. 'C [Pa]', 'radius [m]')"
            )
        names.append(name.strip())
    df.columns = names
    return [{k: (v.item() if hasattr(v, "item") else v) for k, v in row.items()} for row in df.to_dict("records")]


def chunk(n_points: int, index: int, chunks: int) -> list[int]:
    """Indices of the points in chunk ``index`` of ``chunks`` (interleaved: k with k mod chunks == index).
    Raises ValueError unless 0 <= index < chunks."""
    if chunks < 1:
        raise ValueError(f"--chunks must be >= 1, got {chunks}")
    if not 0 <= index < chunks:
        raise ValueError(f"--index must be in 0..{chunks - 1} (the chunk number), got {index}")
    return list(range(index, n_points, chunks))


def array_index() -> int | None:
    """The 0-based index of this job-array task from the scheduler's environment (``ARRAY_INDEX``: SLURM and PBS
    count from 0, SGE and LSF from 1), or None outside a job array."""
    for name, base in ARRAY_INDEX:
        v = os.environ.get(name)
        if v not in (None, "", "undefined"):
            try:
                return int(v) - base
            except ValueError:
                raise ValueError(f"{name}={v!r} is not an integer array index") from None
    return None


def collect(points: Sequence[dict], store: str | os.PathLike, function: Callable[..., Any]):
    """DataFrame: the points, ``stored`` (bool) and every scalar field of the stored results (NaN where
    not stored yet); curves (arrays) stay in the store (``compare.batch.load``)."""
    from pathlib import Path

    import numpy as np
    import pandas as pd

    rows = []
    for p in points:
        f = Path(store) / f"{point_key(function, p)}.npz"
        row: dict[str, Any] = dict(p)
        row["stored"] = f.exists()
        if f.exists():
            r = load(f)
            for k, v in r.items():
                if k != "__point__" and np.ndim(v) == 0 and k not in p:
                    row[k] = v.item() if hasattr(v, "item") else v
        rows.append(row)
    return pd.DataFrame(rows)
