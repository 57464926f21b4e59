r"""``tissuemech fit``: fit the spheroid model to your own compression-relaxation measurements.

    tissuemech fit DATA.csv [DATA2.csv ...] --radius-um R --displacement-um D [D2 ...] --ramp-time T
                   [--quantity auto|stress|force] [--equilibrium fem|hertz] [--branches N]
                   [--model-error auto|X] [--out DIR]

The files: one CSV per compression level, time in s and nominal stress in Pa or plate force in N, an optional
header naming the columns with units, ``#`` comments (:mod:`tissuemech.compare.fit.records` has the format).

Output: the parameter table with 95 % intervals and the identifiability report (stdout), and in
``--out`` (default ``fit-results``): ``fit.json`` (everything: parameters, intervals and their kind,
noise, covariance, identifiability, the inputs) and ``fit.png`` (data, model and residuals).
A malformed file gives one line naming the file and the line (exit code 2).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from tissuemech.compare.cli.common import nonnegative, output_folder, positive, save_figure
from tissuemech.compare.fit.records import UM

__all__ = ["add_parser", "run"]

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
    f.add_argument(
        "--misfit",
        type=nonnegative,
        default=0.0,
        help="lower bound of the model's smooth misfit (relative RMS, e.g. 0.002) the intervals allow for; the "
        "residuals show only the part the parameters cannot absorb (default 0: estimated from them alone)",
    )
    f.add_argument("--out", default="fit-results", help="folder for fit.json and fit.png (default: %(default)s)")
    f.add_argument("--no-figure", action="store_true", help="skip fit.png")
    return f


def run(args: argparse.Namespace) -> None:
    """Carry out ``tissuemech fit`` (errors: ValueError with a one-line message)."""
    from tissuemech.compare import fit
    from tissuemech.compare.cli.blastula import enable_jit_cache

    enable_jit_cache()  # compiled residuals kept between runs (the compile is most of a dense record's time)
    if args.branches < 1:
        raise ValueError(f"--branches must be at least 1; got {args.branches}")
    output_folder("--out", args.out)  # before the fit
    radius = args.radius_um * UM
    disps = None if args.displacement_um is None else [d * UM for d in args.displacement_um]
    recs, forces = fit.load_records(
        list(args.files), radius=radius, displacements=disps, ramp_time=args.ramp_time, quantity=args.quantity
    )
    if any(forces) and not all(forces):
        raise ValueError("mix of force (N) and stress (Pa) files: give all records as the same quantity")
    midplane = "incompressible" if all(forces) else ("fem" if args.equilibrium == "fem" else "incompressible")
    model = fit.incompressible_model() if all(forces) else None
    res = fit.relaxation(
        recs,
        radius=radius,
        ramp_time=args.ramp_time,
        n_branches=args.branches,
        equilibrium=args.equilibrium,
        model=model,
        model_error=args.model_error,
        misfit=args.misfit,
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
        "misfit_rel": args.misfit,
    }
    (out / "fit.json").write_text(json.dumps(d, indent=1))
    written = [str(out / "fit.json")]
    if not args.no_figure:
        from tissuemech.compare.plots.fit import fit_figure

        fig = fit_figure(
            recs, res, radius=radius, ramp_time=args.ramp_time, equilibrium=args.equilibrium, midplane=midplane
        )
        save_figure(fig, str(out / "fit.png"))
        written.append(str(out / "fit.png"))
    print("wrote " + ", ".join(written))
