r"""Records and their readers: one compression level is a :class:`Record` (time s, nominal stress Pa, total
approach m); :func:`read_table` parses a CSV-like text table, :func:`read_csv` reads one record,
:func:`load_records` reads the files of ``tissuemech fit``.

CSV format (one file per compression level)
-------------------------------------------
* text, one sample per line: time in s, then nominal stress in Pa (``F / A_mid``) or plate force in N;
  further columns are ignored. Fields separated by commas, semicolons, tabs or spaces; fields may be quoted
  (RFC 4180: ``"1.0","2.0"``, ``"time, in s"``), a delimiter at the end of every line is ignored.
* UTF-8 (with or without BOM), Latin-1, or UTF-16 with its BOM (Excel's "Unicode text" export, tab-separated).
  A local regular file of at most :data:`MAX_TABLE_BYTES` bytes (a device, a pipe or a larger file is refused:
  no reader here runs without end).
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

import csv
import math
import os
import re
import stat
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
    "check_ramp",
    "Table",
    "read_table",
    "read_table_fast",
    "read_csv",
    "load_records",
    "COLUMN_UNITS",
    "UM",
    "MAX_TABLE_BYTES",
    "read_text",
    "header_columns",
]

UM = 1e-6  # one micrometre in m (the command line's unit of lengths)
MAX_TABLE_BYTES = 256 * 2**20  # largest text table the readers take (256 MiB, some 10 million time-stress rows)


class Record(NamedTuple):
    """One compression level: ``time`` (s), ``nominal_stress`` (Pa), ``displacement`` (total approach, m)."""

    time: np.ndarray
    nominal_stress: np.ndarray
    displacement: float


def as_records(
    records: Sequence[Any],
    quantity: tuple[str, str] = ("nominal_stress", "Pa"),
    approach: str = "displacement (the total approach of the plates)",
) -> list[Record]:
    """Checked :class:`Record` objects from records or ``(time [s], nominal_stress [Pa], displacement [m])``
    tuples (one Record alone is taken as a list of one); ValueError naming the record for malformed ones.
    ``quantity`` (name, unit) and ``approach`` name the measured values and the approach in the messages (another
    scene's records, e.g. ("probe force", "N") and the probe's travel: ``compare.fit.fe_indentation``; the values
    then sit in the records' ``nominal_stress`` field)."""
    q, unit_q = quantity
    if isinstance(records, Record):
        records = [records]
    out = []
    for k, r in enumerate(records):
        try:
            t, s, d = r
        except (TypeError, ValueError):
            raise ValueError(
                f"record {k}: expected (time [s], {q} [{unit_q}], {approach.split(' (')[0]} [m])"
            ) from None
        for name, unit, v in (("time", "s", t), (q, unit_q, s)):
            if np.asarray(v).dtype.kind == "b":  # True/False would be read as 1/0 s or Pa
                raise ValueError(
                    f"record {k}: {name} must be numbers ({unit}); got booleans (True/False): a mask or flags given in "
                    "place of the samples?"
                )
        t = np.asarray(t, dtype=float).ravel()
        s = np.asarray(s, dtype=float).ravel()
        if t.shape != s.shape:
            raise ValueError(f"record {k}: time and {q} need the same length; got {t.size} and {s.size}")
        if t.size < 2:
            raise ValueError(f"record {k}: {t.size} sample; a record needs at least 2 (time, {q}) samples")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(s))):
            raise ValueError(f"record {k}: time and {q} must be finite numbers (found NaN or inf)")
        if np.any(t < 0):
            raise ValueError(f"record {k}: time must not be negative (s); got {t.min():g}")
        back = np.nonzero(np.diff(t) < 0)[0]
        if back.size:
            i = int(back[0]) + 1
            raise ValueError(
                f"record {k}: time runs backwards at sample {i} ({t[i - 1]:g} s, then {t[i]:g} s): give each record's "
                f"samples in time order (and check that time and {q} are not swapped)"
            )
        validate_positive(f"record {k}: {approach}", d, "m")
        out.append(Record(t, s, float(d)))
    if not out:
        raise ValueError(f"at least one record (time, {q}, {approach.split(' (')[0]}) is needed")
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


_QUOTED = re.compile(r'"(?:[^"]|"")*"')


def _split(line: str) -> list[str]:
    """The fields of a line: separated by the first of ',', ';', tab found outside quotes, else by spaces; RFC-4180
    quotes removed (``"1,5"`` stays one field), surrounding spaces stripped."""
    bare = _QUOTED.sub("", line) if '"' in line else line
    for sep in (",", ";", "\t"):
        if sep in bare:
            if '"' in line:
                return [f.strip() for f in next(csv.reader([line], delimiter=sep, skipinitialspace=True))]
            return [f.strip() for f in line.split(sep)]
    if '"' in line:
        return [f.strip() for f in next(csv.reader([line], delimiter=" ", skipinitialspace=True)) if f.strip()]
    return line.split()


def _delimited(line: str) -> bool:
    """True for a line whose fields a ',', ';' or tab separates (outside quotes)."""
    bare = _QUOTED.sub("", line) if '"' in line else line
    return any(sep in bare for sep in (",", ";", "\t"))


def _header_fields(line: str) -> list[str]:
    """Header names; with whitespace separators a ``[unit]`` / ``(unit)`` token joins the name before it."""
    fields = _split(line)
    if _delimited(line):
        return fields[:-1] if len(fields) > 1 and fields[-1] == "" else fields
    out: list[str] = []
    for f in fields:
        if out and f[:1] in "[(" and f[-1:] in "])":
            out[-1] = f"{out[-1]} {f}"
        else:
            out.append(f)
    return out


_DECIMAL_COMMA = re.compile(r"^[+-]?\d*,\d+(?:[eE][+-]?\d+)?$")


def _decimal_commas(line: str) -> bool:
    """True for a data line written with decimal commas: fields separated by ';', a tab or spaces, at least one
    of the form ``0,2`` and all numbers once ',' reads '.' (``0,2;8,61``; a comma-separated line is never one)."""
    for sep in (";", "\t"):
        if sep in line:
            parts = [f.strip() for f in line.split(sep)]
            break
    else:
        parts = line.split()
    if parts and parts[-1] == "":  # a delimiter at the end of the line
        parts.pop()
    if len(parts) < 2 or not any(_DECIMAL_COMMA.match(f) for f in parts):
        return False
    return all(_DECIMAL_COMMA.match(f) or _number(f) is not None for f in parts)


def _number(text: str) -> float | None:
    try:
        v = float(text)
    except ValueError:
        return None
    return v


def read_text(path: str | Path, what: str = "") -> str:
    """The text of a local table file, bounded: ValueError (one line, naming the file) for a file that is missing,
    unreadable, not a regular file (a device such as /dev/zero, a pipe: a stream without end), larger than
    :data:`MAX_TABLE_BYTES`, or binary. Decodes UTF-8 (BOM or not), UTF-16 with a BOM (Excel's "Unicode text"),
    else Latin-1. ``what`` prefixes the file name in messages (e.g. "points table")."""
    name = f"{what} {path}" if what else str(path)
    try:
        st = os.stat(path)
    except OSError as exc:
        raise ValueError(f"{name}: cannot read the file ({exc.strerror or exc})") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a folder" if stat.S_ISDIR(st.st_mode) else "a device, pipe or socket (a stream without end?)"
        raise ValueError(f"{name}: not a regular file but {kind}; give a text table saved as a file")
    limit = MAX_TABLE_BYTES
    too_big = (
        f"{name}: the file is larger than the readers' limit of {limit / 2**20:g} MiB "
        "(tissuemech.compare.fit.records.MAX_TABLE_BYTES): split it or thin its rows (for a fit, a few "
        "thousand samples per record inform it as well)"
    )
    if st.st_size > limit:
        raise ValueError(f"{too_big}; it has {st.st_size / 2**20:.4g} MiB")
    try:
        with open(path, "rb") as fh:
            raw = fh.read(limit + 1)
    except OSError as exc:
        raise ValueError(f"{name}: cannot read the file ({exc.strerror or exc})") from None
    if len(raw) > limit:  # grew while read
        raise ValueError(too_big)
    binary = f"{name}: binary file, not a text table"
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):  # UTF-16 with its BOM: Excel's "Unicode text"
        try:
            return raw.decode("utf-16")
        except UnicodeDecodeError:
            raise ValueError(f"{binary} (it starts with a UTF-16 mark but does not decode as UTF-16)") from None
    if b"\x00" in raw:
        raise ValueError(f"{binary} (save it as CSV text: UTF-8, or UTF-16 with its byte-order mark)")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    if any(ch < " " and ch not in "\r\n\t" for ch in text):
        raise ValueError(binary)
    return text


_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")


def _plain_table(path: str, text: str) -> Table | None:
    """The table of a plain, well-formed text (no quotes, one separator, finite numbers, no decimal commas) parsed in
    one vectorised pass (a million rows in about a second); None for anything else: the line-by-line parse of
    :func:`read_table` then reads it or names the line at fault."""
    if '"' in text or _CONTROL.search(text):
        return None
    meta: dict[str, str] = {}
    rows: list[str] = []
    lines: list[int] = []
    for no, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if not s:
            continue
        if s[0] == "#":
            m = _META.match(s)
            if m:
                meta[m.group(1).strip().lower().replace(" ", "_")] = m.group(2)
            continue
        rows.append(s)
        lines.append(no)
    if not rows:
        return None
    header: tuple[str, ...] = ()
    fields = _split(rows[0])
    if len(fields) > 1 and fields[-1] == "" and _delimited(rows[0]):
        fields.pop()
    if any(_number(f) is None for f in fields):
        if not all(_number(f) is None and f for f in fields):
            return None
        header = tuple(_header_fields(rows[0]))
        rows, lines = rows[1:], lines[1:]
        if not rows:
            return None
    sep = next((c for c in (",", ";", "\t") if c in rows[0]), None)
    body = "\n".join(rows)
    if sep is None and any(c in body for c in ",;\t"):
        return None
    if sep in (";", "\t") and "," in body:  # decimal commas? the line-by-line parse tells
        return None
    if sep is None:
        counts = {len(r.split()) for r in rows}
    else:
        rows = [r[:-1].rstrip() if r.endswith(sep) else r for r in rows]  # a delimiter at the end of the line
        counts = {r.count(sep) + 1 for r in rows}
        body = "\n".join(rows).replace(sep, " ")
    if len(counts) != 1:
        return None
    ncol = counts.pop()
    if ncol < 2 or (header and len(header) != ncol):
        return None
    tokens = body.split()
    if len(tokens) != ncol * len(rows):
        return None
    try:
        values = np.array(tokens, dtype=float).reshape(len(rows), ncol)
    except ValueError:
        return None
    if not np.all(np.isfinite(values)):
        return None
    return Table(path, header, values, meta, tuple(lines))


_ODD_CHARS = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f\u2028\u2029]")  # control chars, odd line breaks
_BLANK_OR_COMMENT = re.compile(r"\n[ \t]*(?:#|\n)")
# a space-separated token like ',5' or '1,5' (read line by line as a decimal comma: '1 ,5', '1,5 2'); wider than
# the line-by-line test (a match only sends the file to the line-by-line reader)
_SPACED_DECIMAL_COMMA = (re.compile(r" [+-]?\d*,\d"), re.compile(r"^[+-]?\d*,\d+(?:[eE][+-]?\d+)? ", re.MULTILINE))
_PLAIN_BYTES = bytes(range(0x20, 0x7F)) + b"\t\n\r"


def read_table_fast(path: str | Path) -> Table | None:
    """:func:`read_table`'s result for a plain, regular table, parsed in C (``numpy.loadtxt``: ~0.4 s for 1e6 rows
    where the line-by-line reader takes ~7 s), or None where the file is anything else (comments or blank lines
    among the rows, mixed separators, decimal commas, a malformed or non-finite field, an odd character): then
    :func:`read_table` reads it line by line and gives its one-line errors. Where it returns a table, the table is
    the one :func:`read_table` returns (the same header, values, meta and line numbers)."""
    try:
        text = read_text(path)  # bounded: a regular file within MAX_TABLE_BYTES (else the reader below says why)
    except ValueError:
        return None
    raw = text.encode("utf-8")
    rest = raw.translate(None, _PLAIN_BYTES)  # what is not printable ASCII or a tab / line break
    if rest and (rest.translate(None, bytes(range(0x80, 0x100))) or _ODD_CHARS.search(text)):
        return None
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    meta: dict[str, str] = {}
    header: tuple[str, ...] = ()
    pos, no = 0, 0
    while pos < len(text):  # the preamble: blank and comment lines, the header; stops at the first data row
        end = text.find("\n", pos)
        end = len(text) if end < 0 else end
        s = text[pos:end].strip()
        if s and not s.startswith("#"):
            fields = _split(s)
            if header or all(_number(f) is not None for f in fields):
                break
            if not all(_number(f) is None and f for f in fields):
                return None  # text among the numbers of the first row: the line-by-line reader says where
            header = tuple(_header_fields(s))
        elif s:
            m = _META.match(s)
            if m:
                meta[m.group(1).strip().lower().replace(" ", "_")] = m.group(2)
        pos, no = end + 1, no + 1
    body = text[pos:].rstrip()
    if not body or not body.isascii() or _BLANK_OR_COMMENT.search(body):
        return None
    first = body[: body.find("\n")] if "\n" in body else body
    sep = next((c for c in (",", ";", "\t") if c in first), None)
    others = {",": ";\t", ";": ",", "\t": ",;", None: ",;\t"}[sep]
    if any(c in body for c in others):
        return None
    if sep == "," and " " in body and any(p.search(body) for p in _SPACED_DECIMAL_COMMA):
        return None
    import io

    try:
        values = np.loadtxt(io.StringIO(body), delimiter=sep, comments=None, ndmin=2, dtype=float)
    except ValueError:
        return None
    ncol = len(header) if header else values.shape[1]
    if values.shape[1] != ncol or ncol < 2 or not np.all(np.isfinite(values)):
        return None
    rows = values.shape[0]
    return Table(str(path), header, values, meta, tuple(range(no + 1, no + 1 + rows)))


def read_table(path: str | Path) -> Table:
    """Read a CSV-like numeric table (module doc: the format). Raises ValueError with one line naming
    the file and, where it applies, the line: missing, not a regular file, beyond :data:`MAX_TABLE_BYTES`, empty,
    binary, ragged, one column, text in numbers, decimal commas."""
    fast = read_table_fast(path)  # plain regular tables in C (bounded like read_text); anything else below
    if fast is not None:
        return fast
    path = str(path)
    text = read_text(path)
    fast = _plain_table(path, text)
    if fast is not None:
        return fast
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
        if "," in s and _decimal_commas(s.replace('"', "")):
            raise ValueError(
                f"{path}, line {no}: {s!r} uses decimal commas (0,2 meaning 0.2); this reader needs decimal points: "
                "export the file with '.' as the decimal separator (or replace ',' by '.' when the fields are "
                "separated by ';' or tabs), or read it with pandas.read_csv(path, sep=';', decimal=',') and pass "
                "the columns to tissuemech.compare.fit.relaxation"
            )
        fields = _split(s)
        if len(fields) > 1 and fields[-1] == "" and _delimited(s):
            fields.pop()  # a delimiter at the end of the line
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
    "approach": {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6, "nm": 1e-9},
}
_NAMES = {
    "time": ("t", "time"),
    "stress": ("stress", "sigma", "nominal_stress", "stress_nominal"),
    "force": ("force", "f", "plate_force", "load"),
    "approach": ("approach", "delta", "plate_approach", "displacement", "compression"),
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


def header_columns(table: Table) -> dict[str, tuple[int, float]]:
    """The columns a table's header names: quantity ("time", "stress", "force", "approach") -> (column index,
    factor to SI); the first column of each quantity; ValueError naming the column for an unknown unit."""
    out: dict[str, tuple[int, float]] = {}
    for i, name in enumerate(table.header):
        kind, unit = _column(name)
        if kind is None or kind in out:
            continue
        if unit is not None and unit not in COLUMN_UNITS[kind]:
            raise ValueError(
                f"{table.path}: column {name!r}: unit {unit!r} is not one this reader knows for {kind} "
                f"({', '.join(COLUMN_UNITS[kind])}); convert the column or rename its header"
            )
        out[kind] = (i, 1.0 if unit is None else COLUMN_UNITS[kind][unit])
    return out


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
        tcol = f"column {ti + 1}" + (f" ({table.header[ti]!r})" if ti < len(table.header) else " (no header)")
        if np.any(t < 0):
            i = int(np.argmax(t < 0))
            raise ValueError(f"{p}, line {table.lines[i]}: time must not be negative (s); got {t[i]:g}")
        _check_times(p, table, t, y, tcol)
        check_record((t, y, d), str(p))  # the fit's own checks, naming the file
        check_ramp(t, y, ramp_time, str(p), tcol)
        if force:
            y = y / (math.pi * _incompressible_rmid(t, radius, d, ramp_time) ** 2)
        recs.append((t, y, d))
        forces.append(force)
    if displacements is not None and len(displacements) == 1 and len(paths) > 1:
        _check_shared_displacement(paths, recs, displacements[0])
    return recs, forces


def _check_times(path: str, table: Table, t: np.ndarray, y: np.ndarray, tcol: str) -> None:
    """One-line errors for a time column that runs backwards (swapped columns?) or repeats a time."""
    dt = np.diff(t)
    back = np.nonzero(dt < 0)[0]
    if back.size:
        i = int(back[0]) + 1
        swapped = bool(np.all(np.diff(y) > 0)) if y.size > 2 else False
        hint = (
            "the other column increases: are the columns swapped? Put time first or name them in a header line "
            "(stress_Pa,time_s)"
            if swapped
            else "the samples must be in time order from first contact (sort them; or name the columns in a header "
            "line, time_s,stress_Pa, if time is not the first)"
        )
        raise ValueError(
            f"{path}, line {table.lines[i]}: time runs backwards in {tcol} ({t[i - 1]:g} s, then {t[i]:g} s): {hint}"
        )
    same = np.nonzero(dt == 0)[0]
    if same.size:
        i = int(same[0]) + 1
        raise ValueError(
            f"{path}, lines {table.lines[i - 1]} and {table.lines[i]}: the time {t[i]:g} s appears twice in {tcol}: "
            "each sample needs its own time (times rounded to too few digits? export more decimals; two records in "
            "one file? give one file per compression level)"
        )


def check_ramp(t: np.ndarray, y: np.ndarray, ramp_time: float, what: str, column: str = "the time column") -> None:
    """ValueError (one line, starting with ``what``) when a record's rise contradicts the stated ramp time: the
    stress peaks early in the ramp and has clearly fallen by its end (minutes read as seconds: the times are 60
    times too small), or it still clearly rises long after the ramp's end (milliseconds read as seconds). "Clearly":
    by more than 5 noise sd (from the second differences) and 2 % of the peak."""
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    if t.size < 8 or not ramp_time > 0:
        return
    d2 = np.diff(y, 2)
    noise = 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)
    k = int(np.argmax(y))
    peak, t_pk = float(y[k]), float(t[k])
    tol = max(5.0 * noise, 0.02 * abs(peak))
    in_ramp = np.nonzero(t <= ramp_time)[0]
    if t_pk < 0.5 * ramp_time and in_ramp.size >= 4 and in_ramp[-1] > k:
        end = float(np.mean(y[in_ramp[-3:]]))
        if peak - end > tol:
            raise ValueError(
                f"{what}: the stress peaks at t = {t_pk:.3g} s and has fallen by {100 * (peak - end) / peak:.0f} % "
                f"when the stated ramp ends ({ramp_time:g} s), but a loading ramp only raises it: is {column} in "
                "seconds? Minutes read as seconds look like this: name the unit in a header line ('time [min]') or "
                "convert the times to s; otherwise check the ramp time"
            )
    after = np.nonzero(t >= ramp_time)[0]
    if t_pk > 3.0 * ramp_time and after.size >= 4 and after[0] < k:
        start = float(np.mean(y[after[:3]]))
        if peak - start > tol:
            raise ValueError(
                f"{what}: the stress still rises until t = {t_pk:.3g} s, {t_pk / ramp_time:.3g} ramp times after the "
                f"stated ramp ends ({ramp_time:g} s), but it relaxes once the plates stop: is {column} in seconds "
                "(milliseconds read as seconds?) and the ramp time right? Name the unit in a header line "
                "('time [ms]') or convert the times to s"
            )


def _check_shared_displacement(paths: Sequence[str], recs: Sequence[tuple], d: float) -> None:
    """One displacement for several files is right only for replicates at one compression level: their long-time
    stresses then agree; a spread beyond 1.5-fold means different levels."""
    ends = []
    for _, y, _ in recs:
        tail = y[-max(1, y.size // 20) :]
        ends.append(float(np.mean(tail)))
    lo, hi = int(np.argmin(ends)), int(np.argmax(ends))
    if ends[lo] > 0 and ends[hi] / ends[lo] > 1.5:
        raise ValueError(
            f"--displacement-um {d / UM:g} was given once for {len(paths)} files, but their long-time stresses differ "
            f"{ends[hi] / ends[lo]:.2g}-fold ({paths[lo]} {ends[lo]:.3g} Pa, {paths[hi]} {ends[hi]:.3g} Pa): records "
            "at different compression levels need one displacement each (--displacement-um D1 D2 ... in file order, "
            f"or a '# displacement_um:' line per file); replicates at one level: repeat it ({' '.join([f'{d / UM:g}'] * len(paths))})"
        )


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
