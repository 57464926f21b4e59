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
    return p


def run(args: argparse.Namespace) -> int:
    """Carry out ``tissuemech coverage``."""
    import pandas as pd

    from tissuemech.compare.fit import DEFAULT_MODEL_ERROR_REL, model_error_of
    from tissuemech.compare.studies import coverage

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
