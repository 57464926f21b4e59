"""``tissuemech coverage``: the coverage study of the fit's 95 % intervals (:mod:`tissuemech.compare.studies.coverage`).

tissuemech coverage [--n-reduced 200] [--n-fe 30] [--noise 0.005 0.01 0.03] [--no-fe] [--seed 0] [--csv FILE]
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

from tissuemech.compare.cli.common import positive

__all__ = ["add_parser", "run", "main"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``tissuemech coverage`` on an argparse subparsers object."""
    p = subparsers.add_parser(
        "coverage",
        help="coverage study: do the fit's 95 %% intervals hold the truth 95 %% of the time?",
        description="Coverage study of compare.fit.relaxation on synthetic records (reduced- and FE-made): "
        "empirical coverage of the 95 % intervals per noise level and parameter, with its binomial range.",
    )
    p.add_argument("--n-reduced", type=int, default=200, help="reduced-made records per noise level (default 200)")
    p.add_argument("--n-fe", type=int, default=30, help="FE-made records per noise level (default 30)")
    p.add_argument("--fe-truths", type=positive(int), default=6, help="distinct FE parameter sets (default 6)")
    p.add_argument("--noise", type=positive(), nargs="+", default=[0.005, 0.01, 0.03], help="relative noise levels")
    p.add_argument("--no-fe", action="store_true", help="reduced-made records only (a couple of minutes)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--csv", default=None, help="write every fit (one row per parameter) to this CSV")
    p.add_argument(
        "--scenarios",
        nargs="*",
        default=None,
        metavar="NAME",
        help="run the error-model rows instead (all when no NAME is given): "
        + "; ".join(f"'{k}'" for k in _scenario_names()).replace("%", "%%"),  # argparse %-formats help
    )
    p.add_argument("--n-scenario", type=int, default=200, help="fits per error-model row (default 200)")
    p.add_argument(
        "--intervals",
        choices=["profile", "wald"],
        default="profile",
        help="interval method of the fits (default profile)",
    )
    return p


def _scenario_names() -> list[str]:
    from tissuemech.compare.studies.coverage import SCENARIOS

    return list(SCENARIOS)


def run(args: argparse.Namespace) -> int:
    """Carry out ``tissuemech coverage``."""
    import pandas as pd

    from tissuemech.compare.fit import DEFAULT_MODEL_ERROR_REL, model_error_of
    from tissuemech.compare.studies import coverage

    if args.scenarios is not None:
        names = args.scenarios or list(coverage.SCENARIOS)
        unknown = [n for n in names if n not in coverage.SCENARIOS]
        if unknown:
            raise ValueError(f"--scenarios: unknown {unknown}; choose from {list(coverage.SCENARIOS)}")
        if args.n_scenario < 1:
            raise ValueError(f"--n-scenario must be >= 1; got {args.n_scenario}")
        df = coverage.scenario_study(names, args.n_scenario, seed=args.seed, intervals=args.intervals)
        if args.csv:
            df.to_csv(args.csv, index=False)
        table = coverage.summarise_scenarios(df)
        cov = table.pivot_table(index=["scenario", "parameter"], columns="errors", values="coverage %", sort=False)
        with pd.option_context("display.width", 200, "display.max_columns", 20):
            print(table[table["errors"] == "default"].to_string(index=False, float_format=lambda v: f"{v:.3g}"))
            print("\ncoverage % of the Wald intervals under each error model ('default': the fits' own intervals):")
            print(cov.to_string(float_format=lambda v: f"{v:.0f}"))
        return 0
    if args.n_reduced < 0 or args.n_fe < 0:
        raise ValueError(f"--n-reduced and --n-fe must be >= 0; got {args.n_reduced} and {args.n_fe}")
    eps = model_error_of("fem")
    src = "table metadata" if eps != DEFAULT_MODEL_ERROR_REL else "default (table lacks model_error_rel)"
    print(f"model-error term for FE-made fits: {100 * eps:.3g} % ({src})")
    df, table = coverage.run(args.n_reduced, args.n_fe, args.noise, args.seed, args.fe_truths, fe=not args.no_fe)
    if args.csv:
        df.to_csv(args.csv, index=False)
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tissuemech.compare.coverage [options]``: the same as ``tissuemech coverage [options]``."""
    from tissuemech.compare.cli import main as cli_main

    return cli_main(["coverage", *(sys.argv[1:] if argv is None else argv)])
