"""``tissuemech scan spheroid|blastula ...``: a parameter scan of a reduced model to table + figures.

    tissuemech scan spheroid --C 100:400 --tau 10:1000:log --beta 0.2:1.5 --n 100000 --fe-checks 8
    tissuemech scan blastula --alpha 0:0.3 --outer-radius-um 52:75 --pressure 0:1000 --n 100000

Every model parameter takes a value (``--C 200``), a range ``LOW:HIGH`` (``--C 100:400``), a log-scaled
range ``LOW:HIGH:log`` (``--tau 10:1000:log``) or a list ``A,B,C`` (``--alpha 0,0.1,0.2``; grid design
only). ``--design grid|random|lhs`` and ``--n`` choose the design (grid: ``n`` values per range;
random / lhs: ``n`` points). ``--fe-checks N`` runs the FE model at N points spread over the design
(through ``compare.batch``, resumable in ``OUT/fe_store``). The output folder gets ``table.csv``,
``scan.nc`` (netCDF, ``compare.scan.to_netcdf``), ``map.png``, ``curves.png``, ``sensitivity.png``,
``parity.png`` (with FE checks) and ``summary.md``.

Wiring: ``add_parser(subparsers)`` adds the ``scan`` command to the ``tissuemech`` parser;
``run(args) -> int`` executes it (0: done; 2: bad input, one line on stderr).
"""

from __future__ import annotations

import argparse
import math
import os
import shlex
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

__all__ = ["add_parser", "run", "parse_value", "ScanInputError", "SPHEROID_OPTIONS", "BLASTULA_OPTIONS"]


class ScanInputError(ValueError):
    """Bad input to ``tissuemech scan``: printed as one line, exit code 2."""


class Option(NamedTuple):
    flag: str  # command-line flag
    name: str  # parameter of compare.scan
    unit: str  # unit on the command line
    factor: float  # command-line unit -> SI
    default: str
    help: str


SPHEROID_OPTIONS = (
    Option("--radius-um", "radius", "um", 1e-6, "500", "ball radius a0"),
    Option("--C", "C", "Pa", 1.0, "200", "Fung stiffness C (shear modulus 2C)"),
    Option("--alpha", "alpha", "-", 1.0, "0.2", "Fung exponent alpha >= 0"),
    Option("--beta", "beta", "-", 1.0, "1.2", "energy factor beta of the Maxwell branch"),
    Option("--tau", "tau", "s", 1.0, "200", "relaxation time tau of the Maxwell branch"),
    Option("--displacement-um", "displacement", "um", 1e-6, "200", "total approach of the plates"),
    Option("--ramp-time", "ramp_time", "s", 1.0, "0.2", "duration of the loading ramp"),
)
BLASTULA_OPTIONS = (
    Option("--inner-radius-um", "inner_radius", "um", 1e-6, "50", "inner radius A of the shell"),
    Option("--outer-radius-um", "outer_radius", "um", 1e-6, "75", "outer radius B of the shell"),
    Option("--C", "C", "Pa", 1.0, "200", "Fung stiffness C"),
    Option("--alpha", "alpha", "-", 1.0, "0.2", "Fung exponent alpha >= 0"),
    Option("--pressure", "pressure", "Pa", 1.0, "0:1000", "internal pressure p"),
)

_TINY = float(np.finfo(np.float64).tiny)  # the smallest normal float64

_SYNTAX = (
    "Each model parameter is a VALUE, a range LOW:HIGH, a log-scaled range LOW:HIGH:log, or a list "
    "A,B,C (grid design only), in the unit its option names (a range from a negative number: --opt=-1:2)."
)


def _unit_text(unit: str) -> str:
    return "dimensionless" if unit == "-" else unit


class Parsed(NamedTuple):
    value: Any  # float, (lo, hi) tuple or list, in SI units
    log: bool
    text: str


def parse_value(text: str, opt: Option) -> Parsed:
    """Parse one parameter option: ``200``, ``100:400``, ``10:1000:log``, ``0,0.1,0.2`` (command-line units).

    Returns the value in SI units (float, (lo, hi) or list) and whether it is log-scaled.
    Raises ScanInputError (one line naming the option and its unit) for anything else.
    """
    where = f"{opt.flag} {text}"
    unit = _unit_text(opt.unit)

    def number(s: str) -> float:
        try:
            v = float(s)
        except ValueError:
            raise ScanInputError(
                f"{where}: {s!r} is not a number; give a value, LOW:HIGH, LOW:HIGH:log or A,B,C ({unit})"
            ) from None
        if not math.isfinite(v):
            raise ScanInputError(f"{where}: values must be finite numbers ({unit})")
        if v != 0 and min(abs(v), abs(v * opt.factor)) < _TINY:
            raise ScanInputError(
                f"{where}: {s} is too small to compute with (below {_TINY:.3g}, the smallest normal float64 "
                f"number, the arithmetic underflows); give values of ordinary size ({unit})"
            )
        return v

    t = text.strip()
    if ":" in t:
        parts = t.split(":")
        if len(parts) == 3 and parts[2].strip().lower() in ("log", "lin", "linear"):
            log = parts[2].strip().lower() == "log"
            parts = parts[:2]
        elif len(parts) == 2:
            log = False
        else:
            raise ScanInputError(f"{where}: a range is LOW:HIGH or LOW:HIGH:log ({unit})")
        lo, hi = number(parts[0]), number(parts[1])
        if not lo < hi:
            raise ScanInputError(f"{where}: the low end {parts[0]} must be below the high end {parts[1]} ({unit})")
        if log and lo <= 0:
            raise ScanInputError(f"{where}: a log-scaled range needs a positive low end; got {parts[0]} ({unit})")
        return Parsed((lo * opt.factor, hi * opt.factor), log, text)
    if "," in t:
        vals = [number(s) for s in t.split(",") if s.strip()]
        if not vals:
            raise ScanInputError(f"{where}: an empty list ({unit})")
        return Parsed([v * opt.factor for v in vals] if len(vals) > 1 else vals[0] * opt.factor, False, text)
    return Parsed(number(t) * opt.factor, False, text)


def _add_scene(sub, scene: str, options: Sequence[Option], description: str) -> None:
    p = sub.add_parser(
        scene,
        help=f"scan the reduced {scene} model over parameter ranges: table, netCDF, figures, summary",
        description=description + " " + _SYNTAX,
        epilog="Outputs in --out: table.csv, scan.nc (netCDF), map.png, curves.png, sensitivity.png, "
        "parity.png (with --fe-checks), summary.md.",
    )
    g = p.add_argument_group("model parameters (value, LOW:HIGH, LOW:HIGH:log or A,B,C)")
    for o in options:
        g.add_argument(
            o.flag,
            dest=f"param_{o.name}",
            metavar="SPEC",
            default=o.default,
            help=f"{o.help}, {_unit_text(o.unit)} (default: {o.default})",
        )
    if scene == "spheroid":
        g.add_argument("--end-time", default="1500", metavar="S", help="end of the hold, s (default: 1500)")
        g.add_argument(
            "--equilibrium",
            default="fem",
            choices=["fem", "hertz"],
            help="equilibrium law: 'fem' (FE-calibrated master curve, default) or 'hertz' (small strain)",
        )
    d = p.add_argument_group("design and FE spot-checks")
    d.add_argument("--design", default="lhs", choices=["grid", "random", "lhs"], help="design (default: lhs)")
    d.add_argument(
        "--n", default="1000", metavar="N", help="grid: values per range; random/lhs: number of points (default: 1000)"
    )
    d.add_argument(
        "--seed", default="0", metavar="SEED", help="random seed of the design and of the FE point choice (default: 0)"
    )
    d.add_argument(
        "--fe-checks", default="0", metavar="N", help="FE runs at this many points spread over the design (default: 0)"
    )
    d.add_argument(
        "--fe-workers",
        default="2",
        metavar="N",
        help="local processes for the FE runs; 0: in this process (default: 2)",
    )
    d.add_argument(
        "--fe-store", default=None, metavar="DIR", help="folder of the resumable FE results (default: OUT/fe_store)"
    )
    o = p.add_argument_group("output and figures")
    o.add_argument("--out", default=f"scan-{scene}", metavar="DIR", help="output folder (default: %(default)s)")
    o.add_argument(
        "--map", default=None, metavar="X,Y", help="the two varied parameters of the maps (default: automatic)"
    )
    o.add_argument(
        "--fix",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="maps: use only the points at this value of another parameter (its option's unit); default: averaged",
    )
    o.add_argument(
        "--color-by", default=None, metavar="NAME", help="parameter colouring the curves (default: the strongest)"
    )
    o.add_argument(
        "--sens-points", default="256", metavar="N", help="design points for the JAX sensitivities (default: 256)"
    )
    if scene == "spheroid":
        o.add_argument("--save-curves", action="store_true", help="also write every relaxation curve into scan.nc")
        o.add_argument(
            "--fe-sensitivities",
            default="0",
            metavar="N",
            help="also the sensitivities computed by the FE (exact parameter sensitivities, coarse mesh) at N points "
            "spread over the design: sensitivity_fe.png (for scans beyond the reduced model's table; default 0)",
        )
    o.add_argument("--no-progress", action="store_true", help="no progress bar")

    def one_line_error(message: str):
        print(f"tissuemech scan {scene}: error: {message}", file=sys.stderr)
        raise SystemExit(2)

    p.error = one_line_error  # type: ignore[method-assign]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``scan`` (with ``spheroid`` and ``blastula``) to the ``tissuemech`` subcommands; returns its parser."""
    s = subparsers.add_parser(
        "scan",
        help="parameter scans of the reduced models (table, netCDF, maps, curves, sensitivities, FE spot-checks)",
        description="Scan a reduced model over parameter ranges and write the table, a netCDF file, "
        "figures and a markdown summary. " + _SYNTAX,
    )
    sub = s.add_subparsers(dest="scan_scene", metavar="SCENE")
    _add_scene(
        sub,
        "spheroid",
        SPHEROID_OPTIONS,
        "Spheroid compression-relaxation: a Fung ball (one Maxwell branch) squeezed between rigid plates "
        "(linear ramp, then hold). Summaries: nominal stress at the end of the ramp and of the hold (Pa), "
        "relaxed fraction (-), half-relaxation time (s).",
    )
    _add_scene(
        sub,
        "blastula",
        BLASTULA_OPTIONS,
        "Blastula inflation: hollow incompressible Fung sphere under internal pressure (exact shell). "
        "Summaries: inner and outer stretch (-), burst (limit) pressure (Pa), bursts or holds.",
    )
    return s


# ---------------------------------------------------------------------------------------------
# running a scan
# ---------------------------------------------------------------------------------------------


def _int(args: Any, name: str, low: int) -> int:
    text = getattr(args, name.replace("-", "_"))
    try:
        v = int(str(text))
    except ValueError:
        raise ScanInputError(f"--{name} {text}: expected a whole number") from None
    if v < low:
        raise ScanInputError(f"--{name} {text}: must be at least {low}")
    return v


def _float(text: str, flag: str, unit: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise ScanInputError(f"{flag} {text}: expected a number ({unit})") from None
    if not (math.isfinite(v) and v > 0):
        raise ScanInputError(f"{flag} {text}: must be a positive number ({unit})")
    return v


def _check_out(out: Path) -> None:
    """The output folder: usable before anything is computed (one-line ScanInputError otherwise)."""
    if out.exists() and not out.is_dir():
        raise ScanInputError(f"--out {out}: exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=out, prefix=".write-test-"):
            pass
    except OSError as e:
        raise ScanInputError(f"--out {out}: cannot write there ({e.strerror or e})") from None


def _fe_checks(table: pd.DataFrame, k: int, kw: dict, args: Any, out: Path) -> int:
    """FE spot-checks at k points spread over the design (``compare.scan.spot_check``, through ``compare.batch``:
    resumable in the store); adds the ``fe_...`` and ``deviation [-]`` columns to ``table`` in place. Returns the
    number that ran."""
    from tissuemech.compare import batch, scan

    workers = _int(args, "fe-workers", 0)
    executor: Any = batch.process_pool(workers) if workers else "serial"
    try:
        return scan.spot_check(
            table,
            k,
            times=kw.get("times"),
            seed=kw["seed"],
            executor=executor,
            store=args.fe_store or str(out / "fe_store"),
            progress=not args.no_progress,
        )
    finally:
        if workers:
            executor.shutdown(wait=True, cancel_futures=True)


def _write(path: Path, write: Any) -> None:
    """``write(tmp)`` to a temporary file next to ``path``, then renamed to ``path``: a failed write (full disk)
    leaves no truncated file. Raises ScanInputError naming the file."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.part")
    try:
        write(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise ScanInputError(f"cannot write {path}: {exc.strerror or exc}") from None


def _map_axes(scene: str, varied: list[str], text: str | None, names: Sequence[str]) -> tuple[str, str] | None:
    if text:
        parts = [s.strip() for s in text.split(",")]
        if len(parts) != 2 or parts[0] == parts[1]:
            raise ScanInputError(f"--map {text}: give two different parameters X,Y")
        for s in parts:
            if s not in names:
                raise ScanInputError(f"--map {text}: {s!r} is not a parameter; choose from {list(names)}")
            if s not in varied:
                raise ScanInputError(f"--map {text}: {s} is not varied in this scan (give it a range or list)")
        return parts[0], parts[1]
    if len(varied) < 2:
        return None
    if scene == "blastula" and "pressure" in varied:
        return [k for k in varied if k != "pressure"][0], "pressure"
    return varied[0], varied[1]


def _strongest_axes(scene: str, sens: pd.DataFrame, varied: list[str], exclude: set) -> tuple[str, str] | None:
    """Default map axes: the two varied parameters with the largest summed sensitivity share
    (blastula with a pressure range: the strongest other parameter and the pressure)."""
    s = sens[sens["parameter"].isin([k for k in varied if k not in exclude])]
    order = list(s.groupby("parameter")["share [-]"].sum().sort_values(ascending=False).index)
    if scene == "blastula" and "pressure" in order:
        g = s[s["quantity"] == "inner_stretch"]
        rest = [k for k in g.sort_values("share [-]", ascending=False)["parameter"] if k != "pressure"]
        return (rest[0], "pressure") if rest else None
    return (order[0], order[1]) if len(order) >= 2 else None


def _parse_fix(items: Sequence[str], options: Sequence[Option]) -> dict[str, float]:
    by_name = {o.name: o for o in options}
    fixed = {}
    for item in items:
        if "=" not in item:
            raise ScanInputError(f"--fix {item}: expected NAME=VALUE")
        name, value = (s.strip() for s in item.split("=", 1))
        if name not in by_name:
            raise ScanInputError(f"--fix {item}: {name!r} is not a parameter; choose from {list(by_name)}")
        try:
            fixed[name] = float(value) * by_name[name].factor
        except ValueError:
            raise ScanInputError(
                f"--fix {item}: {value!r} is not a number ({_unit_text(by_name[name].unit)})"
            ) from None
    return fixed


def _fmt(v: float) -> str:
    return "nan" if not np.isfinite(v) else f"{v:.4g}"


def _summary_md(*, scene, argv_text, design, n_points, specs, options, table, timings, n_fe, sens, files, notes) -> str:
    from tissuemech.compare import scan

    lines = [f"# tissuemech scan {scene}", "", f"Command: `{argv_text}`", ""]
    lines += [f"Run: {time.strftime('%Y-%m-%d %H:%M:%S %Z')}", "", "## Design", ""]
    lines.append(f"{design} design, {n_points} points.")
    lines.append("")
    lines.append("| parameter | option | given | unit | varied |")
    lines.append("| --- | --- | --- | --- | --- |")
    for o in options:
        p = specs[o.name]
        kind = (
            "log range"
            if p.log
            else ("range" if isinstance(p.value, tuple) else ("list" if isinstance(p.value, list) else "fixed"))
        )
        lines.append(f"| {o.name} | `{o.flag}` | {p.text} | {o.unit} | {kind} |")
    lines += ["", "## Timing", ""]
    for k, v in timings.items():
        lines.append(f"- {k}: {v:.2f} s")
    lines += ["", "## Summaries over the design", "", "| quantity | unit | min | median | max | undefined |"]
    lines.append("| --- | --- | --- | --- | --- | --- |")
    qs = scan.SPHEROID_SUMMARIES if scene == "spheroid" else ("inner_stretch", "outer_stretch", "p_limit", "bursts")
    for q in qs:
        v = table[scan.column(q)].to_numpy(float)
        f = v[np.isfinite(v)]
        stats = [_fmt(np.min(f)), _fmt(np.median(f)), _fmt(np.max(f))] if f.size else ["nan"] * 3
        lines.append(f"| {q} | {scan.UNITS[q]} | {' | '.join(stats)} | {int(np.sum(~np.isfinite(v)))} |")
    if scene == "blastula":
        lines.append("")
        lines.append(
            f"{int(table['bursts [-]'].sum())} of {len(table)} points burst (pressure at or above the limit pressure)."
        )
        beyond = int(np.sum(np.isnan(table["inner_stretch [-]"].to_numpy(float)) & ~table["bursts [-]"].to_numpy(bool)))
        if beyond:
            lines.append(f"{beyond} points hold but lie outside the stretch range 0.5..10 searched (NaN stretch).")
    lines += ["", "## FE spot-checks", ""]
    if n_fe:
        chk = table[table["deviation [-]"].notna()]
        names = [o.name for o in options]
        red_fe = (
            [("sigma_peak", "fe_sigma_peak"), ("sigma_end", "fe_sigma_end")]
            if scene == "spheroid"
            else [("inner_stretch", "fe_inner_stretch")]
        )
        head = names + [c for pair in red_fe for c in pair] + ["deviation %"]
        lines.append("| " + " | ".join(head) + " |")
        lines.append("| " + " | ".join("---" for _ in head) + " |")
        for _, r in chk.iterrows():
            cells = [_fmt(r[scan.column(k)] * (1e6 if scan.UNITS[k] == "m" else 1)) for k in names]
            cells += [_fmt(r[scan.column(c)]) for pair in red_fe for c in pair]
            cells.append(f"{100 * r['deviation [-]']:.3g}")
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
        lines.append(
            f"Largest deviation of the reduced model from the FE: {100 * chk['deviation [-]'].max():.3g} % "
            f"(median {100 * chk['deviation [-]'].median():.3g} %). Lengths in um."
        )
    else:
        lines.append("None (use --fe-checks N).")
    lines += ["", "## Sensitivities", ""]
    if sens is not None:
        lines.append(
            "Share of the mean |dy/du| (exact JAX derivatives of the reduced model; u: the parameter "
            "scaled to its scan range, log-scaled for log ranges); sign: direction of the mean derivative."
        )
        lines.append("")
        ps = list(dict.fromkeys(sens["parameter"]))
        lines.append("| quantity | " + " | ".join(ps) + " |")
        lines.append("| --- |" + " --- |" * len(ps))
        for q, g in sens.groupby("quantity", sort=False):
            cells = []
            for p in ps:
                r = g[g["parameter"] == p].iloc[0]
                s = r["share [-]"]
                sign = "" if not np.isfinite(s) or s < 0.005 else ("+" if r["direction"] > 0 else "-")
                cells.append("nan" if not np.isfinite(s) else f"{sign}{100 * s:.0f} %")
            lines.append(f"| {q} | " + " | ".join(cells) + " |")
    else:
        lines.append("Not computed (no varied parameter).")
    if notes:
        lines += ["", "## Notes", ""] + [f"- {n}" for n in notes]
    lines += ["", "## Files", ""] + [f"- `{f}`: {d}" for f, d in files]
    return "\n".join(lines) + "\n"


def run(args: argparse.Namespace) -> int:
    """Run ``tissuemech scan`` from parsed arguments. Returns 0, or 2 after a one-line error on stderr."""
    scene = getattr(args, "scan_scene", None)
    if scene is None:
        print("tissuemech scan: error: name the scene: tissuemech scan spheroid|blastula ...", file=sys.stderr)
        return 2
    try:
        return _run(args, scene)
    except (ValueError, OSError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        msg = msg.replace("Use equilibrium='hertz'", "Use --equilibrium hertz")
        print(f"tissuemech scan {scene}: error: {msg}", file=sys.stderr)
        return 2


def _run(args: argparse.Namespace, scene: str) -> int:
    from tissuemech.compare import scan
    from tissuemech.compare.plots import scan as sp

    options = SPHEROID_OPTIONS if scene == "spheroid" else BLASTULA_OPTIONS
    specs = {o.name: parse_value(getattr(args, f"param_{o.name}"), o) for o in options}
    design = args.design
    for o in options:
        if isinstance(specs[o.name].value, list) and design != "grid":
            raise ScanInputError(f"{o.flag} {specs[o.name].text}: a list of values needs --design grid")
    if scene == "blastula":  # the shell is inflated from rest: the curves run from 0 to the largest pressure
        spec = specs["pressure"]
        values = spec.value if isinstance(spec.value, (tuple, list)) else [spec.value]
        if not max(values) > 0:
            raise ScanInputError(
                f"--pressure {spec.text}: the largest pressure must be positive (Pa): the shell is inflated from rest "
                "(0 Pa) to each pressure of the scan"
            )
    n = _int(args, "n", 1)
    seed = _int(args, "seed", 0)
    k_fe = _int(args, "fe-checks", 0)
    _int(args, "fe-workers", 0)
    n_sens = _int(args, "sens-points", 1)
    fixed_map = _parse_fix(args.fix, options)
    log = tuple(o.name for o in options if specs[o.name].log)
    params = {o.name: specs[o.name].value for o in options}
    ranged = [k for k, v in params.items() if isinstance(v, tuple)]
    n_expected = (
        n ** len(ranged) * int(np.prod([len(v) for v in params.values() if isinstance(v, list)]))
        if design == "grid"
        else n
    )
    if n_expected > 20_000_000:
        raise ScanInputError(f"--n {n}: the {design} design would have {n_expected} points (at most 20000000)")
    curve_params = [o.name for o in options] if scene == "spheroid" else ["inner_radius", "outer_radius", "C", "alpha"]
    if args.color_by is not None and args.color_by not in curve_params:  # before anything is computed or written
        raise ScanInputError(f"--color-by {args.color_by}: choose from {curve_params}")
    out = Path(args.out)
    _check_out(out)  # before anything is computed
    progress = not args.no_progress
    end_time = _float(args.end_time, "--end-time", "s") if scene == "spheroid" else None

    timings: dict[str, float] = {}
    notes: list[str] = []
    t0, c0 = time.perf_counter(), time.process_time()
    pts = scan.design(params, n=n, method=design, seed=seed, log=log)
    varied = [k for k in pts.columns if pts[k].nunique() > 1]
    axes = _map_axes(scene, varied, args.map, [o.name for o in options])
    for name in fixed_map:
        if axes and name in axes:
            raise ScanInputError(f"--fix {name}=...: {name} is a map axis")
    if scene == "spheroid":
        assert end_time is not None  # parsed above for the spheroid scene
        if not end_time > float(pts["ramp_time"].max()):
            raise ScanInputError(
                f"--end-time {end_time:g}: must be after the end of the ramp ({pts['ramp_time'].max():g} s)"
            )
        times = scan.spheroid_times(pts["ramp_time"].to_numpy(), end_time)
        kw = dict(times=times, equilibrium=args.equilibrium, curves=True, seed=seed, log=log)
        stiff_row = int(np.argmax(pts["ramp_time"].to_numpy() / pts["tau"].to_numpy()))
        table = scan.evaluate_in_chunks(scan.spheroid, pts, varied, kw, progress=progress, stiff_row=stiff_row)
    else:
        kw = dict(seed=seed, log=log)
        table = scan.evaluate_in_chunks(scan.blastula, pts, varied, kw, progress=progress)
    timings["reduced model (design, compilation, evaluation)"] = time.perf_counter() - t0
    timings["reduced model, CPU time of this process (all threads)"] = time.process_time() - c0
    print(f"reduced {scene}: {len(table)} points in {timings['reduced model (design, compilation, evaluation)']:.2f} s")

    n_fe = 0
    if k_fe:
        t1 = time.perf_counter()
        n_fe = _fe_checks(table, k_fe, kw, args, out)
        timings[f"FE spot-checks ({n_fe} of {k_fe} ran)"] = time.perf_counter() - t1
        print(f"FE spot-checks: {n_fe} of {k_fe} in {time.perf_counter() - t1:.2f} s")
        if n_fe < k_fe:
            notes.append(
                f"{k_fe - n_fe} of the {k_fe} FE spot-checks did not run or failed (no deviation at those points)."
            )

    t3 = time.perf_counter()
    import matplotlib.pyplot as plt  # on the Agg backend: tissuemech's main chose it (files only, no window)

    files: list[tuple[str, str]] = []
    figures: list[tuple[str, Any, str]] = []  # (file, figure, description), written at the end
    sens = None
    if varied:
        sens = scan.sensitivities(
            table,
            n_points=n_sens,
            seed=seed,
            log=log,
            **({"equilibrium": args.equilibrium} if scene == "spheroid" else {}),
        )
        fig = sp.sensitivity_chart(
            sens,
            title=f"{scene} scan: which parameter drives which summary\n"
            f"(exact JAX derivatives at {min(n_sens, len(table))} design points;\n"
            "parameters scaled to their scan range; sign: direction)",
        )
        figures.append(("sensitivity.png", fig, "share of each parameter in the derivative of each summary"))
    timings["sensitivities (JAX derivatives)"] = time.perf_counter() - t3
    k_fs = _int(args, "fe-sensitivities", 0) if scene == "spheroid" else 0
    if varied and k_fs > 0:
        t_fs = time.perf_counter()
        sens_fe = scan.fe_sensitivities(table, k_fs, seed=seed, log=log, progress=not args.no_progress)
        fig = sp.sensitivity_chart(
            sens_fe,
            title=f"{scene} scan: which parameter drives which summary\n"
            f"(the FE's exact sensitivities at {min(k_fs, len(table))} spread points, coarse mesh;\n"
            "parameters scaled to their scan range; sign: direction)",
        )
        figures.append(("sensitivity_fe.png", fig, "the same shares from the FE at spread points"))
        timings["sensitivities (FE)"] = time.perf_counter() - t_fs

    t4 = time.perf_counter()
    if axes is not None and not args.map and sens is not None:
        axes = _strongest_axes(scene, sens, varied, set(fixed_map)) or axes
    if axes is not None:
        qs = ["sigma_peak", "relaxed_fraction", "t_half"] if scene == "spheroid" else ["inner_stretch", "bursts"]
        if scene == "blastula" and "pressure" not in axes:
            qs.append("p_limit")
        fig = sp.summary_maps(
            table,
            qs,
            axes[0],
            axes[1],
            fixed=fixed_map or None,
            log=log,
            title=f"{scene} scan, {len(table)} points ({design})"
            + (f"; white circles: {n_fe} FE spot-checks, labelled by deviation" if n_fe else ""),
        )
        figures.append(
            ("map.png", fig, f"summaries over ({axes[0]}, {axes[1]}); FE spot-checks labelled by their deviation")
        )
    else:
        notes.append("No map: it needs two varied parameters.")
    color_by = args.color_by
    if color_by is None:
        color_by = curve_params[0]
        cand = [k for k in varied if k in curve_params]
        if cand:
            color_by = cand[0]
            if sens is not None:
                key = "relaxed_fraction" if scene == "spheroid" else "inner_stretch"
                s = sens[(sens["quantity"] == key) & sens["parameter"].isin(cand)].dropna(subset=["share [-]"])
                if len(s):
                    color_by = str(s.sort_values("share [-]").iloc[-1]["parameter"])
    fig = sp.curve_bundle(table, color_by, log=log, seed=seed)
    what = "relaxation curves" if scene == "spheroid" else "pressure-stretch curves (exact shell)"
    figures.append(("curves.png", fig, f"{what} coloured by {color_by}"))
    if n_fe:
        fig = sp.parity_plot(table)
        figures.append(("parity.png", fig, "reduced vs FE at the spot-checks, coloured by the deviation"))
    timings["figures"] = time.perf_counter() - t4

    # everything is computed and drawn: only now are the files written (a failure above leaves none)
    t2 = time.perf_counter()
    curves_col = "sigma [Pa]"
    flat = table.drop(columns=[curves_col]) if curves_col in table.columns else table
    _write(out / "table.csv", lambda f: flat.to_csv(f, index=False))
    files.append(("table.csv", "one row per design point: parameters and summaries (SI units in the column names)"))
    save_curves = scene == "spheroid" and args.save_curves
    nc_table = table if save_curves else flat
    if not save_curves:
        nc_table = flat.copy()
        nc_table.attrs = {}
    _write(out / "scan.nc", lambda f: scan.to_netcdf(nc_table, f))
    files.append(
        (
            "scan.nc",
            "the same as an xarray Dataset (netCDF3); dims: the varied parameters for a grid, "
            "else `point`" + ("; relaxation curves `sigma(..., time)`" if save_curves else ""),
        )
    )
    timings["table.csv + scan.nc"] = time.perf_counter() - t2

    t5 = time.perf_counter()
    for name, fig, description in figures:
        _write(out / name, lambda f, fig=fig: fig.savefig(f, dpi=120, format="png"))
        files.append((name, description))
    plt.close("all")
    timings["figures"] += time.perf_counter() - t5
    timings["total"] = time.perf_counter() - t0

    argv_text = _reconstruct(args, scene, options)
    files.append(("summary.md", "this summary"))
    md = _summary_md(
        scene=scene,
        argv_text=argv_text,
        design=design,
        n_points=len(table),
        specs=specs,
        options=options,
        table=table,
        timings=timings,
        n_fe=n_fe,
        sens=sens,
        files=files,
        notes=notes,
    )
    _write(out / "summary.md", lambda f: f.write_text(md))
    print(f"wrote {', '.join(f for f, _ in files)} to {out}{os.sep} (total {timings['total']:.2f} s)")
    return 0


def _reconstruct(args: argparse.Namespace, scene: str, options: Sequence[Option]) -> str:
    parts = ["tissuemech", "scan", scene]
    for o in options:
        parts += [o.flag, getattr(args, f"param_{o.name}")]
    parts += ["--design", args.design, "--n", str(args.n), "--seed", str(args.seed)]
    if scene == "spheroid":
        parts += ["--end-time", str(args.end_time), "--equilibrium", args.equilibrium]
    if str(args.fe_checks) != "0":
        parts += ["--fe-checks", str(args.fe_checks)]
        for flag, value in (("--fe-workers", args.fe_workers), ("--fe-store", args.fe_store)):
            if value is not None:
                parts += [flag, str(value)]
    if args.map:
        parts += ["--map", args.map]
    for fix in args.fix:
        parts += ["--fix", fix]
    if args.color_by is not None:
        parts += ["--color-by", args.color_by]
    parts += ["--sens-points", str(args.sens_points)]
    if getattr(args, "save_curves", False):
        parts.append("--save-curves")
    parts += ["--out", str(args.out)]
    return " ".join(shlex.quote(str(p)) for p in parts)
