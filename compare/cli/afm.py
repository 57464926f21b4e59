"""``tissuemech afm``: fit AFM stress-relaxation curves (spherical probe on a resting ball), print the table."""

from __future__ import annotations

import argparse
import json
from argparse import Namespace
from pathlib import Path
from typing import Any

from tissuemech.compare.cli.common import CLIError, figure_path, positive, save_figure

__all__ = ["add_parser", "run", "load_curves"]

UM = 1e-6


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Register ``afm`` on an argparse subparsers object."""
    s = sub.add_parser(
        "afm",
        help="fit AFM stress-relaxation curves (JPK or CSV): contact point, indentation history, 1 and 2 branches",
        description="Read AFM force curves (a .jpk-force file, a folder or .zip of them: needs the afm extra; or a "
        "CSV export with units in the header), find each contact point, build the measured indentation history "
        "and fit the lumped Maxwell model of a spherical probe on a ball resting on a plate to each hold (one and "
        "two branches; alpha fixed at 0). Prints the table; --out writes the figure, --json the numbers.",
    )
    s.add_argument("data", nargs="+", help="JPK file/folder/.zip or CSV file(s) (.csv or .csv.gz)")
    s.add_argument("--probe-radius-um", type=positive(), required=True, help="radius of the spherical probe (um)")
    s.add_argument(
        "--radius-um", type=float, required=True, help="radius of the indented ball (um); 'inf' for a half-space"
    )
    s.add_argument("--spring-constant", type=positive(), help="cantilever spring constant (N/m), overrides the file's")
    s.add_argument(
        "--sensitivity-nm-per-v", type=positive(), help="deflection sensitivity (nm/V), overrides the file's"
    )
    s.add_argument("--curves", help="indices of the curves to fit, e.g. 0,1,2 (default: all)")
    s.add_argument("--out", help="PNG of data, fits, residuals and the parameter spread")
    s.add_argument("--json", help="write every fit's numbers to this JSON file")
    return s


def load_curves(paths: list[str], *, spring_constant: float | None = None, sensitivity: float | None = None) -> list:
    """Curves from JPK (file, folder, .zip) or CSV paths, in order."""
    from tissuemech.compare.afm import records

    curves = []
    for p in paths:
        path = Path(p)
        if not path.exists():
            raise CLIError(f"no such file or folder: {p}")
        name = path.name.lower()
        if name.endswith((".csv", ".csv.gz", ".txt")):
            curves += records.read_csv(path, spring_constant=spring_constant, sensitivity=sensitivity)
        else:
            try:
                got = records.read_jpk(path)
            except ImportError as exc:
                raise CLIError(str(exc)) from None
            if spring_constant is not None or sensitivity is not None:
                got = [records.recalibrated(c, spring_constant=spring_constant, sensitivity=sensitivity) for c in got]
            curves += got
    return curves


def run(args: Namespace) -> None:
    """Run ``tissuemech afm`` with parsed arguments."""
    from tissuemech.compare.afm import study

    out = figure_path("--out", args.out) if args.out else None
    if not args.radius_um > 0:
        raise CLIError(f"--radius-um must be positive (or inf); got {args.radius_um}")
    sens = args.sensitivity_nm_per_v * 1e-9 if args.sensitivity_nm_per_v else None
    try:
        curves = load_curves(args.data, spring_constant=args.spring_constant, sensitivity=sens)
        if args.curves:
            idx = [int(v) for v in args.curves.split(",")]
            bad = [i for i in idx if not 0 <= i < len(curves)]
            if bad:
                raise CLIError(f"--curves {args.curves}: indices must be in 0..{len(curves) - 1}")
            curves = [curves[i] for i in idx]
        st = study.run(curves, probe_radius=args.probe_radius_um * UM, radius=args.radius_um * UM)
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    print(st.report())
    if out:
        from tissuemech.compare.plots.afm import relaxation_figure

        save_figure(relaxation_figure(st.one, st.two), out)
        print(f"wrote {out}")
    if args.json:
        rows = [a.row() for a in st.one] + [b.row() for b in st.two]
        Path(args.json).write_text(json.dumps(rows, indent=1, default=float))
        print(f"wrote {args.json}")
