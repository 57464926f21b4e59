r"""``tissuemech fit``: fit the spheroid model to your own compression-relaxation measurements.

    tissuemech fit DATA.csv [DATA2.csv ...] --radius-um R --displacement-um D [D2 ...] --ramp-time T
                   [--quantity auto|stress|force] [--equilibrium fem|hertz] [--branches N]
                   [--model-error auto|X] [--out DIR]

CSV format (one file per compression level)
-------------------------------------------
* text, one sample per line: time in s, then nominal stress in Pa (``F / A_mid``) or plate force in N;
  further columns are ignored. Fields separated by commas, semicolons, tabs or spaces.
* an optional header line (the first non-comment line), e.g. ``time_s,stress_Pa`` or
  ``time_s,force_N``, or in the ``name [unit]`` style of tissuemech's own tables
  ``time [s],stress [Pa]`` / ``time [s],force [N]`` (also space-separated: ``time [s] force [N]``):
  a second-column name containing "force" or ending in "_N", "(N)" or "[N]" means force
  (``--quantity auto``); forces are turned into nominal stress with the incompressible midplane
  estimate r_mid = a0 / sqrt(1 - delta(t)/(2 a0)) and the model is fitted with the same estimate.
* lines starting with ``#`` are comments; ``# displacement_um: 50`` in a file gives that file's total
  plate approach (um) when ``--displacement-um`` is not given.
* time >= 0 from first contact (t = 0), the ramp lasting ``--ramp-time`` s, then the hold.

Output: the parameter table with 95 % intervals and the identifiability report (stdout), and in
``--out`` (default ``fit-results``): ``fit.json`` (everything: parameters, intervals and their kind,
noise, covariance, identifiability, the inputs) and ``fit.png`` (data, model and residuals).
A malformed file gives one line naming the file and the line (exit code 2).
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tissuemech.compare.cli.common import nonnegative, positive

UM = 1e-6
__all__ = ["Table", "read_table", "add_parser", "run", "load_records"]


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
_UNITS = {
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
        if any(tail in units for units in _UNITS.values()):
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
        if unit not in _UNITS[kind]:
            raise ValueError(
                f"{table.path}: column {table.header[i]!r}: unit {unit!r} is not one this reader knows for {kind} "
                f"({', '.join(_UNITS[kind])}); convert the column or rename its header"
            )
        factors.append(_UNITS[kind][unit])
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
    from tissuemech.compare import fit

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
        fit.check_record((t, y, d), str(p))  # the fit's own checks, naming the file
        if force:
            y = y / (math.pi * _incompressible_rmid(t, radius, d, ramp_time) ** 2)
        recs.append((t, y, d))
        forces.append(force)
    return recs, forces


@functools.lru_cache(maxsize=1)
def _incompressible_model():
    from tissuemech.reduced import spheroid

    return functools.partial(spheroid.nominal_stress, midplane="incompressible", adjoint="forward")


_positive = positive()


def _model_error(text: str):
    if text == "auto":
        return "auto"
    try:
        return nonnegative(text)
    except argparse.ArgumentTypeError as err:
        raise argparse.ArgumentTypeError(f"expected 'auto' or a relative error such as 0.005 ({err})") from None


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``tissuemech fit`` on an argparse subparsers object."""
    f = subparsers.add_parser(
        "fit",
        help="fit C, alpha, beta, tau with 95 %% intervals to your compression-relaxation CSV files",
        description="Fit the lumped generalized-Maxwell spheroid model (FE-calibrated equilibrium law) to "
        "measured compression-relaxation records, one CSV per compression level: time (s) and nominal "
        "stress (Pa) or plate force (N); a header line may name the columns with units, '#' comments. Prints the parameters with 95 % "
        "intervals and the identifiability report; writes fit.json and fit.png to --out.",
    )
    f.add_argument("files", nargs="+", metavar="DATA.csv", help="one CSV file per compression level")
    f.add_argument("--radius-um", type=_positive, required=True, help="undeformed spheroid radius a0 in um")
    f.add_argument(
        "--displacement-um",
        type=_positive,
        nargs="+",
        action="extend",  # a repeated option adds its values (it kept only the last)
        default=None,
        help="total plate approach in um: one for all files or one per file (default: '# displacement_um:' in each file)",
    )
    f.add_argument("--ramp-time", type=_positive, required=True, help="duration of the loading ramp in s")
    f.add_argument(
        "--quantity",
        choices=["auto", "stress", "force"],
        default="auto",
        help="second column: nominal stress in Pa or force in N (auto: from the header; default %(default)s)",
    )
    f.add_argument("--equilibrium", choices=["fem", "hertz"], default="fem", help="equilibrium law (default: fem)")
    f.add_argument("--branches", type=int, default=1, help="number of Maxwell branches (default: 1)")
    f.add_argument(
        "--model-error",
        type=_model_error,
        default="auto",
        help="relative 1-sigma model error of the force added to the noise model ('auto': the FE table's estimate)",
    )
    f.add_argument("--out", default="fit-results", help="folder for fit.json and fit.png (default: %(default)s)")
    f.add_argument("--no-figure", action="store_true", help="skip fit.png")
    return f


def _figure(recs, res, model_kw, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tissuemech.reduced import spheroid

    p = res.params
    nb = len([n for n in res.names if n.startswith("beta")])
    bn = [n for n in res.names if n.startswith("beta")]
    tn = [n for n in res.names if n.startswith("tau")]
    branches = [(p[b], p[t]) for b, t in zip(bn, tn)]
    fig, (ax, axr) = plt.subplots(2, 1, figsize=(7, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    for j, (t, y, d) in enumerate(recs):
        kw = dict(radius=model_kw["radius"], C=p["C"], alpha=p["alpha"], branches=branches, displacement=d)
        kw.update(ramp_time=model_kw["ramp_time"], equilibrium=model_kw["equilibrium"], midplane=model_kw["midplane"])
        tt = np.unique(np.concatenate([np.linspace(0, max(t.max(), 1e-9), 400), t]))
        m_dense = np.asarray(spheroid.nominal_stress(tt, **kw))
        m = np.asarray(spheroid.nominal_stress(t, **kw))
        if res.model_error_factors:
            m_dense = m_dense * res.model_error_factors[j]
            m = m * res.model_error_factors[j]
        line = ax.plot(t, y, ".", ms=3, label=f"data, {d / UM:.4g} um")[0]
        ax.plot(tt, m_dense, "-", color=line.get_color(), lw=1.2, label=f"model, {d / UM:.4g} um")
        axr.plot(t, y - m, ".", ms=3, color=line.get_color())
    del nb
    ax.set_xscale("symlog", linthresh=max(model_kw["ramp_time"], 1e-6))
    ax.set_ylabel("nominal stress F / A_mid (Pa)")
    txt = ", ".join(f"{n} = {p[n]:.4g}" for n in res.names)
    ax.set_title("tissuemech fit: " + txt, fontsize=8)
    ax.legend(fontsize=7, ncol=2)
    axr.axhline(0.0, color="k", lw=0.6)
    axr.set_ylabel("residual (Pa)")
    axr.set_xlabel("time (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def run(args: argparse.Namespace) -> None:
    """Carry out ``tissuemech fit`` (errors: ValueError with a one-line message)."""
    from tissuemech.compare import fit
    from tissuemech.compare.cli.common import output_folder

    if args.branches < 1:
        raise ValueError(f"--branches must be at least 1; got {args.branches}")
    output_folder("--out", args.out)  # before the fit
    radius = args.radius_um * UM
    disps = None if args.displacement_um is None else [d * UM for d in args.displacement_um]
    recs, forces = load_records(
        list(args.files), radius=radius, displacements=disps, ramp_time=args.ramp_time, quantity=args.quantity
    )
    if any(forces) and not all(forces):
        raise ValueError("mix of force (N) and stress (Pa) files: give all records as the same quantity")
    midplane = "incompressible" if all(forces) else ("fem" if args.equilibrium == "fem" else "incompressible")
    model = _incompressible_model() if all(forces) else None
    res = fit.relaxation(
        recs,
        radius=radius,
        ramp_time=args.ramp_time,
        n_branches=args.branches,
        equilibrium=args.equilibrium,
        model=model,
        model_error=args.model_error,
    )
    print(res.summary())
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    d = res.to_dict()
    d["inputs"] = {
        "files": [str(f) for f in args.files],
        "radius_m": radius,
        "displacement_m": [r[2] for r in recs],
        "ramp_time_s": args.ramp_time,
        "quantity": ["force_N" if f else "stress_Pa" for f in forces],
        "equilibrium": args.equilibrium,
        "midplane": midplane,
        "n_points": [int(r[0].size) for r in recs],
    }
    (out / "fit.json").write_text(json.dumps(d, indent=1))
    written = [str(out / "fit.json")]
    if not args.no_figure:
        _figure(
            recs,
            res,
            dict(radius=radius, ramp_time=args.ramp_time, equilibrium=args.equilibrium, midplane=midplane),
            out / "fit.png",
        )
        written.append(str(out / "fit.png"))
    print("wrote " + ", ".join(written))
