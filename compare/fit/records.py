r"""Records and their readers: one compression level is a :class:`Record` (time s, nominal stress Pa, total
approach m); :func:`read_table` parses a CSV-like text table, :func:`read_csv` reads one record,
:func:`load_records` reads the files of ``tissuemech fit``.

CSV format (one file per compression level)
-------------------------------------------
* text, one sample per line: time in s, then nominal stress in Pa (``F / A_mid``) or plate force in N;
  further columns are ignored. Fields separated by commas, semicolons, tabs or spaces.
* an optional header line (the first non-comment line), e.g. ``time_s,stress_Pa`` or
  ``time_s,force_N``, or in the ``name [unit]`` style of tissuemech's own tables
  ``time [s],stress [Pa]`` / ``time [s],force [N]`` (also space-separated: ``time [s] force [N]``):
  a second-column name containing "force" or ending in "_N", "(N)" or "[N]" means force
  (``quantity="auto"``); forces are turned into nominal stress with the incompressible midplane
  estimate r_mid = a0 / sqrt(1 - delta(t)/(2 a0)) (fit them with the same estimate:
  :func:`tissuemech.compare.fit.incompressible_model`). A unit in the header is converted to SI
  (:data:`COLUMN_UNITS`), an unknown one refused; a known name without a unit is taken in SI.
* lines starting with ``#`` are comments; ``# displacement_um: 50`` in a file gives that file's total
  plate approach (um) when no displacement is given.
* time >= 0 from first contact (t = 0), the ramp lasting ``ramp_time`` s, then the hold.

A malformed file raises ValueError with one line naming the file and, where it applies, the line.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from tissuemech.reduced.material import validate_positive

__all__ = [
    "Record",
    "as_records",
    "check_record",
    "check_information",
    "Table",
    "read_table",
    "read_csv",
    "load_records",
    "COLUMN_UNITS",
    "UM",
]

UM = 1e-6  # one micrometre in m (the command line's unit of lengths)


class Record(NamedTuple):
    """One compression level: ``time`` (s), ``nominal_stress`` (Pa), ``displacement`` (total approach, m)."""

    time: np.ndarray
    nominal_stress: np.ndarray
    displacement: float


def as_records(records: Sequence[Any]) -> list[Record]:
    """Checked :class:`Record` objects from records or ``(time [s], nominal_stress [Pa], displacement [m])``
    tuples (one Record alone is taken as a list of one); ValueError naming the record for malformed ones."""
    if isinstance(records, Record):
        records = [records]
    out = []
    for k, r in enumerate(records):
        try:
            t, s, d = r
        except (TypeError, ValueError):
            raise ValueError(f"record {k}: expected (time [s], nominal_stress [Pa], displacement [m])") from None
        t = np.asarray(t, dtype=float).ravel()
        s = np.asarray(s, dtype=float).ravel()
        if t.shape != s.shape:
            raise ValueError(f"record {k}: time and nominal_stress need the same length; got {t.size} and {s.size}")
        if t.size < 2:
            raise ValueError(f"record {k}: {t.size} sample; a record needs at least 2 (time, stress) samples")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(s))):
            raise ValueError(f"record {k}: time and stress must be finite numbers (found NaN or inf)")
        if np.any(t < 0):
            raise ValueError(f"record {k}: time must not be negative (s); got {t.min():g}")
        validate_positive(f"record {k}: displacement (the total approach of the plates)", d, "m")
        out.append(Record(t, s, float(d)))
    if not out:
        raise ValueError("at least one record (time, nominal_stress, displacement) is needed")
    return out


def check_information(recs: Sequence[Record], names: tuple[str, ...]) -> None:
    """ValueError for records that cannot determine the parameters ``names`` (one line, naming the record)."""
    for k, r in enumerate(recs):
        check_record(r, f"record {k}")
    n = sum(r.time.size for r in recs)
    if n <= len(names):
        raise ValueError(
            f"the records hold {n} data points in all, not more than the {len(names)} parameters "
            f"{names}: at least {len(names) + 1} are needed (more for a noise estimate worth having)"
        )


def check_record(r: Any, what: str = "record") -> None:
    """ValueError (one line, starting with ``what``: a record number, a file name) for one record that cannot
    inform the fit: fewer than 2 samples, all at one time, a constant or non-positive nominal stress. ``r``: a
    :class:`Record` or a ``(time [s], nominal_stress [Pa], displacement [m])`` tuple."""
    if not isinstance(r, Record):
        try:
            r = as_records([r])[0]
        except ValueError as e:
            raise ValueError(f"{what}: {str(e).removeprefix('record 0: ')}") from None
    if np.ptp(r.time) == 0:
        raise ValueError(f"{what}: all {r.time.size} samples are at the same time ({r.time[0]:g} s)")
    if np.ptp(r.nominal_stress) == 0:
        raise ValueError(
            f"{what}: the nominal stress is constant ({r.nominal_stress[0]:g} Pa at all "
            f"{r.time.size} times): no information on the parameters"
        )
    if np.max(r.nominal_stress) <= 0 or np.mean(r.nominal_stress) <= 0:
        raise ValueError(
            f"{what}: the nominal stress must be positive in compression (Pa); its mean is "
            f"{np.mean(r.nominal_stress):g} Pa (negate data recorded tension-positive)"
        )


@dataclass
class Table:
    """A parsed numeric text table: ``header`` names (or ``()``), ``values`` (n_rows, n_cols), ``meta``
    (``# key: value`` comment lines), ``lines`` (the line number of each row, 1-based)."""

    path: str
    header: tuple[str, ...]
    values: np.ndarray
    meta: dict[str, str] = field(default_factory=dict)
    lines: tuple[int, ...] = ()


_META = re.compile(r"^#\s*([A-Za-z_][A-Za-z0-9_ ]*?)\s*[:=]\s*(.+?)\s*$")


def _split(line: str) -> list[str]:
    for sep in (",", ";", "\t"):
        if sep in line:
            return [f.strip() for f in line.split(sep)]
    return line.split()


def _header_fields(line: str) -> list[str]:
    """Header names; with whitespace separators a ``[unit]`` / ``(unit)`` token joins the name before it."""
    fields = _split(line)
    if any(sep in line for sep in (",", ";", "\t")):
        return fields
    out: list[str] = []
    for f in fields:
        if out and f[:1] in "[(" and f[-1:] in "])":
            out[-1] = f"{out[-1]} {f}"
        else:
            out.append(f)
    return out


def _number(text: str) -> float | None:
    try:
        v = float(text)
    except ValueError:
        return None
    return v


def read_table(path: str | Path) -> Table:
    """Read a CSV-like numeric table (module doc: the format). Raises ValueError with one line naming
    the file and, where it applies, the line: empty, binary, ragged, one column, text in numbers."""
    path = str(path)
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the file ({exc.strerror or exc})") from None
    if b"\x00" in raw:
        raise ValueError(f"{path}: binary file, not a text CSV (time in s, stress in Pa)")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        try:
            text = raw.decode("latin-1")
        except UnicodeDecodeError:  # pragma: no cover (latin-1 decodes anything)
            raise ValueError(f"{path}: not a text file") from None
        if sum(ch < " " and ch not in "\r\n\t" for ch in text) > 0:
            raise ValueError(f"{path}: binary file, not a text CSV (time in s, stress in Pa)") from None
    header: tuple[str, ...] = ()
    rows: list[list[float]] = []
    lines: list[int] = []
    meta: dict[str, str] = {}
    ncol = None
    for no, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            m = _META.match(s)
            if m:
                meta[m.group(1).strip().lower().replace(" ", "_")] = m.group(2)
            continue
        if any(ch < " " and ch != "\t" for ch in s):
            raise ValueError(f"{path}, line {no}: control characters (a binary file?), not a text CSV")
        fields = _split(s)
        nums = [_number(f) for f in fields]
        if ncol is None and not header and not rows and any(v is None for v in nums):
            if all(_number(f) is None and f for f in fields):
                header = tuple(_header_fields(s))
                ncol = len(header)
                continue
        if ncol is None:
            ncol = len(fields)
        if len(fields) != ncol:
            raise ValueError(f"{path}, line {no}: {len(fields)} fields, but the table has {ncol} (ragged rows)")
        for k, (f, v) in enumerate(zip(fields, nums), start=1):
            if v is None:
                raise ValueError(f"{path}, line {no}, column {k}: {f!r} is not a number")
            if not math.isfinite(v):
                raise ValueError(f"{path}, line {no}, column {k}: {f!r} is not a finite number")
        rows.append([float(v) for v in nums])  # type: ignore[arg-type]
        lines.append(no)
    if not rows:
        raise ValueError(f"{path}: no data rows (empty file); expected lines 'time [s], stress [Pa]'")
    if ncol is not None and ncol < 2:
        raise ValueError(f"{path}: only one column; expected time (s) and nominal stress (Pa) or force (N)")
    return Table(path, header, np.array(rows, dtype=float), meta, tuple(lines))


# header names and units the reader knows (factor to SI); a column's unit comes as ``name_unit``, ``name [unit]``
# or ``name (unit)``; a known name without a unit is taken in SI
COLUMN_UNITS = {
    "time": {"s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0},
    "stress": {"Pa": 1.0, "mPa": 1e-3, "kPa": 1e3, "MPa": 1e6},
    "force": {"N": 1.0, "mN": 1e-3, "uN": 1e-6, "µN": 1e-6, "μN": 1e-6, "nN": 1e-9},
}
_NAMES = {
    "time": ("t", "time"),
    "stress": ("stress", "sigma", "nominal_stress", "stress_nominal"),
    "force": ("force", "f", "plate_force", "load"),
}


def _column(name: str) -> tuple[str | None, str | None]:
    """(quantity, unit) of a header name: quantity 'time' / 'stress' / 'force' or None (not one of these), unit as
    written or None (none given)."""
    m = re.match(r"^\s*(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]\s*$", name)
    base, unit = (m.group(1), m.group(2)) if m else (name, None)
    if m is None and "_" in name:
        head, tail = name.rsplit("_", 1)
        if any(tail in units for units in COLUMN_UNITS.values()):
            base, unit = head, tail
    key = base.strip().lower().replace(" ", "_")
    kind = next((k for k, names in _NAMES.items() if key in names), None)
    return kind, unit


def _columns(table: Table, quantity: str) -> tuple[int, int, float, float, bool]:
    """(time column, value column, time factor to s, value factor to Pa or N, value is a force) of a table, from
    its header's names and units; columns 0 and 1 in SI where the header does not name them (or there is none)."""
    parsed = [_column(h) for h in table.header]
    kinds = [k for k, _ in parsed]
    ti = kinds.index("time") if "time" in kinds else 0
    vi = next((i for i, k in enumerate(kinds) if k in ("stress", "force") and i != ti), 1 if ti != 1 else 0)
    if vi >= table.values.shape[1] or ti >= table.values.shape[1]:
        raise ValueError(f"{table.path}: the header {list(table.header)} names more columns than the rows have")
    factors = []
    for i, default in ((ti, "time"), (vi, None)):
        kind, unit = parsed[i] if i < len(parsed) else (None, None)
        kind = kind or default
        if unit is None or kind is None:
            factors.append(1.0)
            continue
        if unit not in COLUMN_UNITS[kind]:
            raise ValueError(
                f"{table.path}: column {table.header[i]!r}: unit {unit!r} is not one this reader knows for {kind} "
                f"({', '.join(COLUMN_UNITS[kind])}); convert the column or rename its header"
            )
        factors.append(COLUMN_UNITS[kind][unit])
    named = parsed[vi][0] if vi < len(parsed) else None
    if quantity != "auto" and named is not None and named != quantity:
        raise ValueError(
            f"{table.path}: --quantity {quantity} but the header names column {table.header[vi]!r} a {named}"
        )
    force = quantity == "force" if quantity != "auto" else named == "force"
    return ti, vi, factors[0], factors[1], force


def _incompressible_rmid(t: np.ndarray, radius: float, displacement: float, ramp_time: float) -> np.ndarray:
    x = np.minimum(np.asarray(t) / ramp_time, 1.0) * displacement / (2.0 * radius)
    return radius / np.sqrt(1.0 - np.minimum(x, 0.999))


def load_records(
    paths: list[str],
    *,
    radius: float,
    displacements: list[float] | None,
    ramp_time: float,
    quantity: str = "auto",
) -> tuple[list[tuple[np.ndarray, np.ndarray, float]], list[bool]]:
    """Records (time s, nominal stress Pa, displacement m) from CSV files, and which were forces (N).

    ``displacements`` (m): one per file, one for all, or None to read ``# displacement_um:`` from each file.
    """
    if displacements is not None and len(displacements) not in (1, len(paths)):
        raise ValueError(
            f"--displacement-um: give one value for all files or one per file ({len(paths)}); got {len(displacements)}"
        )
    recs, forces = [], []
    for k, p in enumerate(paths):
        table = read_table(p)
        if displacements is not None:
            d = displacements[0] if len(displacements) == 1 else displacements[k]
        elif "displacement_um" in table.meta:
            v = _number(table.meta["displacement_um"])
            if v is None or not v > 0:
                raise ValueError(
                    f"{p}: '# displacement_um:' must be a positive number (um); got {table.meta['displacement_um']!r}"
                )
            d = v * UM
        else:
            raise ValueError(f"{p}: no displacement: give --displacement-um (um) or a '# displacement_um: ...' line")
        ti, vi, t_si, y_si, force = _columns(table, quantity)
        t, y = table.values[:, ti] * t_si, table.values[:, vi] * y_si
        if np.any(t < 0):
            i = int(np.argmax(t < 0))
            raise ValueError(f"{p}, line {table.lines[i]}: time must not be negative (s); got {t[i]:g}")
        check_record((t, y, d), str(p))  # the fit's own checks, naming the file
        if force:
            y = y / (math.pi * _incompressible_rmid(t, radius, d, ramp_time) ** 2)
        recs.append((t, y, d))
        forces.append(force)
    return recs, forces


def read_csv(path: str, *, displacement: float, time_column: str | int = 0, stress_column: str | int = 1) -> Record:
    """Read a relaxation record from a CSV file: a time column (s) and a nominal-stress column (Pa).

    A header line is optional (columns may then be chosen by name; a unit in it, ``time_ms`` or ``stress [kPa]``,
    is converted to SI, an unknown one refused), ``#`` lines are comments;
    ``displacement`` is the total plate approach in m. Returns a :class:`Record` ready for
    :func:`relaxation`. Raises ValueError (one line naming the file and line) for malformed files.
    """
    validate_positive("displacement (the total approach of the plates)", displacement, "m")
    table = read_table(path)
    cols = []
    for c in (time_column, stress_column):
        if isinstance(c, int):
            if c >= table.values.shape[1]:
                raise ValueError(f"{path}: column {c} not found; it has {table.values.shape[1]} columns")
            cols.append(c)
        else:
            if c not in table.header:
                raise ValueError(f"{path}: column {c!r} not found; it has {list(table.header)}")
            cols.append(table.header.index(c))
    scaled = []
    for c, want in zip(cols, ("time", "stress")):
        kind, unit = _column(table.header[c]) if c < len(table.header) else (None, None)
        if kind not in (None, want):
            raise ValueError(f"{path}: column {table.header[c]!r} holds {kind}, not {want}")
        if unit is not None and unit not in COLUMN_UNITS[want]:
            raise ValueError(
                f"{path}: column {table.header[c]!r}: unit {unit!r} is not one of {', '.join(COLUMN_UNITS[want])} ({want})"
            )
        scaled.append(table.values[:, c] * (1.0 if unit is None else COLUMN_UNITS[want][unit]))
    return as_records([(scaled[0], scaled[1], displacement)])[0]
