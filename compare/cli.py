"""The ``tissuemech`` command line: the seed's scenes from the fast reduced models.

    tissuemech blastula [--out blastula.png] [--max-pressure 1000] [--step 100] [--fem]
    tissuemech spheroid [--out spheroid.png] [--C 150] [--alpha 0.2] [--beta 0.4] [--tau 200] ...
    tissuemech report [--out DIR] [--quick]     (figures, accuracy-vs-speed charts, stability map)

Tables go to stdout, the figure to a PNG. Bad arguments get a one-line error (exit code 2).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

UM = 1e-6
MAX_TABLE_ROWS = 10_000  # the blastula table: max_pressure / step rows at most

FIG4_ALPHAS = (1e-5, 0.1, 0.2, 0.3)
FIG5_OUTER_UM = (52.0, 60.0, 75.0)


class CLIError(Exception):
    """A user-facing error: printed as one line, exit code 2."""


def _positive(kind: type = float):
    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not value > 0:
            raise argparse.ArgumentTypeError(f"must be positive, got {text}")
        return value

    return parse


def _nonnegative(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must not be negative, got {text}")
    return value


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="tissuemech",
        description="Mechanics of developing tissue: blastula inflation and spheroid "
        "compression-relaxation (Peters & Iber scenes), fast reduced models with FE checks.",
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    b = sub.add_parser(
        "blastula",
        help="pressure-stretch table and plot for the seed's Fig. 4 and Fig. 5 sets",
        description="Inflate a hollow incompressible Fung sphere (inner radius 50 um) by internal "
        "pressure. Prints inner and outer stretch for the Fig. 4 sets (alpha = 1e-5, 0.1, 0.2, 0.3; "
        "outer radius 75 um) and the Fig. 5 sets (outer radius 52, 60, 75 um; alpha = 0.2), and the "
        "limit ('burst') pressure where one exists; writes the pressure-stretch plot to a PNG.",
    )
    b.add_argument("--out", default="blastula.png", help="PNG file for the plot (default: %(default)s)")
    b.add_argument("--C", type=_positive(), default=200.0, help="Fung stiffness C in Pa (default: 200)")
    b.add_argument("--inner-radius-um", type=_positive(), default=50.0, help="inner radius in um (default: 50)")
    b.add_argument("--max-pressure", type=_positive(), default=1000.0, help="largest pressure in Pa (default: 1000)")
    b.add_argument("--step", type=_positive(), default=100.0, help="pressure step of the table in Pa (default: 100)")
    b.add_argument("--fem", action="store_true", help="also run the finite-element model (slower) and show its stretch")

    s = sub.add_parser(
        "spheroid",
        help="relaxation curve of a compressed spheroid (the seed's Fig. 10 case by default)",
        description="Squeeze a Fung ball between two rigid plates (linear ramp of the total approach, "
        "then hold) with one generalized-Maxwell branch; prints plate force and nominal stress "
        "F / A_mid over time and writes the relaxation curve to a PNG. Defaults: the seed's Fig. 10 case.",
    )
    s.add_argument("--out", default="spheroid.png", help="PNG file for the plot (default: %(default)s)")
    s.add_argument("--radius-um", type=_positive(), default=500.0, help="ball radius in um (default: 500)")
    s.add_argument("--C", type=_positive(), default=150.0, help="Fung stiffness C in Pa (default: 150)")
    s.add_argument("--alpha", type=_nonnegative, default=0.2, help="Fung exponent alpha >= 0 (default: 0.2)")
    s.add_argument("--beta", type=_nonnegative, default=0.4, help="Maxwell energy factor beta (default: 0.4)")
    s.add_argument("--tau", type=_positive(), default=200.0, help="relaxation time tau in s (default: 200)")
    s.add_argument("--displacement-um", type=_positive(), default=50.0, help="total plate approach in um (default: 50)")
    s.add_argument("--ramp-time", type=_positive(), default=0.2, help="ramp duration in s (default: 0.2)")
    s.add_argument("--end-time", type=_positive(), default=1500.0, help="end of the hold in s (default: 1500)")
    s.add_argument(
        "--equilibrium",
        default="fem",
        choices=["fem", "hertz"],
        help="equilibrium law F_eq: 'fem' (FE-calibrated master curve, default) or 'hertz' (small strain)",
    )
    s.add_argument("--fem", action="store_true", help="also run the finite-element model (slower) and compare")

    from tissuemech.compare.report import add_parser as add_report_parser

    add_report_parser(sub)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        if args.command == "blastula":
            from tissuemech.compare.scenes import blastula_table

            rows = args.max_pressure / args.step
            if rows > MAX_TABLE_ROWS:
                raise CLIError(
                    f"--step {args.step:g} Pa with --max-pressure {args.max_pressure:g} Pa gives {rows:.3g} table rows "
                    f"(at most {MAX_TABLE_ROWS}); use a larger --step"
                )

            blastula_table(args)
        elif args.command == "spheroid":
            from tissuemech.compare.scenes import spheroid_table

            spheroid_table(args)
        elif args.command == "report":
            from tissuemech.compare.report import run_cli

            run_cli(args)
    except (ValueError, CLIError, OSError) as exc:
        msg = str(exc).replace("Use equilibrium='hertz'", "Use --equilibrium hertz")
        print(f"tissuemech {args.command}: error: {msg}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
