"""Scheduler-free job arrays: a points table split into interleaved chunks, one per array task, each computed into a
shared store (``compare.batch.run``); :func:`collect` gathers the stored results into one table.

:func:`read_points` reads the points table (CSV, one column per keyword argument, SI units), :func:`chunk`
gives the points of one task, :func:`array_index` the task's index from the scheduler's environment (SLURM,
PBS, SGE, LSF), :func:`resolve_function` the function named on the command line.
"""

from __future__ import annotations

import importlib
import inspect
import io
import os
import re
import sys
import sysconfig
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from tissuemech.compare.batch.points import FUNCTIONS
from tissuemech.compare.batch.store import (
    CorruptResultError,
    StoreError,
    StoreWarning,
    describe,
    function_name,
    load,
    point_key,
)

__all__ = [
    "ARRAY_INDEX",
    "chunk",
    "array_index",
    "array_task",
    "read_points",
    "collect",
    "resolve_function",
    "UserFunctionWarning",
]

ARRAY_INDEX = (  # (environment variable, its first index)
    ("SLURM_ARRAY_TASK_ID", 0),
    ("PBS_ARRAY_INDEX", 0),
    ("PBS_ARRAYID", 0),
    ("SGE_TASK_ID", 1),
    ("LSB_JOBINDEX", 1),
)


class UserFunctionWarning(UserWarning):
    """A batch runs a function of the user's own code: the points table's columns become its arguments."""


_DOTTED = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")


def _library_roots() -> list[Path]:
    """Folders of the Python installation: the standard library and installed packages (site-packages)."""
    roots = set()
    for key in ("stdlib", "platstdlib", "purelib", "platlib"):
        for scheme_vars in ({}, {"base": sys.base_prefix, "platbase": sys.base_exec_prefix}):
            try:
                roots.add(Path(sysconfig.get_paths(vars=scheme_vars)[key]).resolve())
            except (KeyError, OSError):
                continue
    roots.update(Path(p).resolve() for p in sys.path if p and ("site-packages" in p or "dist-packages" in p))
    return sorted(roots)


def _is_library_file(path: Path) -> bool:
    path = path.resolve()
    return any(path == r or r in path.parents for r in _library_roots())


def resolve_function(spec: str) -> Callable[..., Any]:
    """The function a batch runs: a name of :data:`FUNCTIONS` (the project's FE point functions) or
    ``module:function`` naming a Python function (``def``) in a module of the user's own code.

    A user function gets a :class:`UserFunctionWarning`: every column of the points table becomes one of its keyword
    arguments. Refused with ValueError (one line): a malformed spec, a module that cannot be imported, builtins and
    C functions, functions of the standard library or of installed packages (``os:system``, ``subprocess:run``...),
    and tissuemech functions other than the FE point functions."""
    if not isinstance(spec, str):
        raise ValueError(f"--function must be a name, got {spec!r}")
    if spec in FUNCTIONS:
        return FUNCTIONS[spec]
    choices = f"one of {sorted(FUNCTIONS)} or module:function (a function of your own code)"
    mod, sep, name = spec.partition(":")
    if not sep or not _DOTTED.match(mod) or not _DOTTED.match(name):
        raise ValueError(f"--function {spec!r}: expected {choices}")
    top = mod.split(".")[0]
    if top in sys.stdlib_module_names or top == "builtins":
        raise ValueError(f"--function {spec!r}: {mod} is part of Python's standard library; batches run {choices}")
    try:
        module = importlib.import_module(mod)
    except Exception as exc:  # ImportError, or an error raised while importing the user's module
        raise ValueError(
            f"--function {spec!r}: module {mod!r} cannot be imported ({type(exc).__name__}: {exc})"
        ) from None
    obj: Any = module
    try:
        for part in name.split("."):
            obj = getattr(obj, part)
    except AttributeError:
        raise ValueError(f"--function {spec!r}: {mod} has no function {name!r}") from None
    if not inspect.isfunction(obj):
        raise ValueError(
            f"--function {spec!r} is not a Python function (a {type(obj).__name__}); batches run {choices}"
        )
    if obj in FUNCTIONS.values():
        return obj
    home = inspect.getmodule(obj)
    home_name = getattr(home, "__name__", "") or ""
    home_file = getattr(home, "__file__", None)
    if home_name.split(".")[0] == "tissuemech":
        raise ValueError(f"--function {spec!r}: of tissuemech, batches run only {sorted(FUNCTIONS)}")
    if home_name.split(".")[0] in sys.stdlib_module_names or home_file is None or _is_library_file(Path(home_file)):
        raise ValueError(
            f"--function {spec!r} is defined in {home_name or 'no file'} (the standard library or an installed "
            f"package), not in your own code; batches run {choices}"
        )
    warnings.warn(
        f"--function {spec}: running your own function {home_name}.{obj.__qualname__}; every column of the points "
        "table becomes one of its keyword arguments",
        UserFunctionWarning,
        stacklevel=2,
    )
    return obj


SI_UNITS = {"", "-", "1", "m", "s", "Pa", "N", "kg", "J"}  # units a points-table header may state


def read_points(path: str | os.PathLike) -> list[dict[str, Any]]:
    """The points of a CSV table (a local file, comma-separated; header = keyword names, optionally with SI units
    ``C [Pa]``; numbers in SI units), one dict per row, with Python ints/floats/strings (integral columns stay ints).
    Raises ValueError (naming the file) for a URL, a missing or unreadable file, a device or pipe, a file beyond
    ``compare.fit.records.MAX_TABLE_BYTES``, an empty table, a table separated by anything but commas, or a non-SI
    unit in the header."""
    import pandas as pd

    text = os.fspath(path)
    if isinstance(text, bytes):
        text = text.decode()
    if re.match(r"^[A-Za-z][A-Za-z0-9+.-]*://", text):
        raise ValueError(f"points table {text}: a URL; give a local CSV file (download it first)")
    file = Path(text)
    if not file.exists():
        raise ValueError(f"points table {file}: no such file")
    from tissuemech.compare.fit.records import read_text

    # bounded (a regular file of at most MAX_TABLE_BYTES), decoded (UTF-8, UTF-16 with BOM); pandas parses the
    # text only: it never opens a URL or another file
    content = read_text(file, "points table")
    try:
        df = pd.read_csv(io.StringIO(content))
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise ValueError(f"points table {file}: not a CSV table ({str(exc).strip().splitlines()[0]})") from None
    if len(df.columns) == 1:
        head = str(df.columns[0])
        for sep in (";", "\t", "|"):
            if sep in head:
                shown = "tabs" if sep == "\t" else repr(sep)
                raise ValueError(
                    f"points table {file}: its columns are separated by {shown}; write it comma-separated (CSV), "
                    f"e.g. {head.replace(sep, ',')!r}"
                )
    if df.empty:
        raise ValueError(f"points table {file}: the table has no rows")
    names = []
    for c in map(str, df.columns):  # 'C [Pa]' -> 'C'; the numbers must be SI: a unit is checked, not dropped
        name, _, unit = c.partition(" [")
        unit = unit.rstrip("]").strip()
        if unit not in SI_UNITS:
            raise ValueError(
                f"{file}: column {c!r}: the points are passed as they are, in SI units ({', '.join(sorted(SI_UNITS - {''}))}); "
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


def array_task() -> tuple[int, str] | None:
    """(0-based index of this job-array task, the variable it came from), from the scheduler's environment
    (``ARRAY_INDEX``: SLURM and PBS count from 0, SGE and LSF from 1), or None outside a job array.
    Raises ValueError (naming the variable) for a value that is not a whole number or below its first index."""
    for name, base in ARRAY_INDEX:
        v = os.environ.get(name)
        if v not in (None, "", "undefined"):
            try:
                index = int(str(v).strip())
            except ValueError:
                raise ValueError(f"{name}={v!r} is not an integer array index") from None
            if index < base:
                raise ValueError(f"{name}={v} is not a valid array index: {name} counts from {base}")
            return index - base, name
    return None


def array_index() -> int | None:
    """The 0-based index of this job-array task (:func:`array_task`), or None outside a job array."""
    task = array_task()
    return None if task is None else task[0]


def collect(points: Sequence[dict], store: str | os.PathLike, function: Callable[..., Any]):
    """DataFrame: the points, ``stored`` (bool) and every scalar field of the stored results (NaN where
    not stored yet); curves (arrays) stay in the store (``compare.batch.load``).

    Every stored file is verified (checksum, and that it is the result of this function at this point and version
    of the code); a damaged or foreign one counts as not stored (with a ``StoreWarning``). Raises ValueError when
    the store holds results but none of ``function`` for these points (saying what it holds), StoreError when a
    file cannot be read."""
    import numpy as np
    import pandas as pd

    folder = Path(store)
    if folder.exists() and not folder.is_dir():
        raise StoreError(f"store {folder} exists and is not a folder")
    rows = []
    present = False  # a file under one of these points' keys (a damaged one too): the function is the right one
    for p in points:
        key = point_key(function, p)
        f = folder / f"{key}.npz"
        row: dict[str, Any] = dict(p)
        r = None
        if f.exists():
            present = True
            try:
                r = load(f, key=key)
            except CorruptResultError as exc:
                warnings.warn(f"{exc}; counted as not stored", StoreWarning, stacklevel=2)
        row["stored"] = r is not None
        if r is not None:
            for k, v in r.items():
                if k != "__point__" and np.ndim(v) == 0 and k not in p:
                    row[k] = v.item() if hasattr(v, "item") else v
        rows.append(row)
    table = pd.DataFrame(rows)
    if rows and not present and folder.is_dir():
        held = describe(folder)
        if held:
            what = ", ".join(f"{n} result{'s' if n > 1 else ''} of {name}" for name, n in held.items())
            raise ValueError(
                f"store {folder} holds {what}, but none of {function_name(function)} at these "
                f"{len(rows)} points: is --function the one the batch ran with (and the points table its table)?"
            )
    return table
