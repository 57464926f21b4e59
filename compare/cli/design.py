"""``tissuemech design``: experiment design for compression-relaxation fits (predicted interval widths).

    tissuemech design [--first-um 25 50 100] [--noise 0.01] [--ramp-time 0.2] [--model-error 0]
                      [--out design.png] [--check N]

prints the predicted widths of the default protocol, the level pair and triple that identify alpha best, a table
of the predicted widths against the second level, writes the figure, and with ``--check N`` fits N noisy
reduced-made records per check protocol (:mod:`tissuemech.compare.fit.design`).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

from tissuemech.compare.cli.common import figure_path, nonnegative, positive, save_figure

__all__ = ["add_parser", "run", "main"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``tissuemech design`` on an argparse subparsers object."""
    ap = subparsers.add_parser(
        "design",
        help="experiment design: predicted 95 %% interval widths per protocol, best compression levels for alpha",
        description="Experiment design for compression-relaxation fits: predicted interval widths from the Fisher "
        "matrix of the fit's statistical model, the best compression levels for alpha, and (--check N) a check "
        "against N fits to noisy records per protocol.",
    )
    ap.add_argument(
        "--first-um", type=positive(), nargs="+", default=[25.0, 50.0, 100.0], help="first levels to scan (um)"
    )
    ap.add_argument(
        "--noise", type=positive(), default=0.01, help="noise sd relative to each record's peak (default 0.01)"
    )
    ap.add_argument("--ramp-time", type=positive(), default=0.2, help="ramp duration in s (default 0.2)")
    ap.add_argument("--model-error", type=nonnegative, default=0.0, help="relative model error per record (default 0)")
    ap.add_argument("--out", default="design.png", help="figure file (default design.png)")
    ap.add_argument("--check", type=int, default=0, metavar="N", help="also fit N noisy records per check protocol")
    return ap


def run(args: argparse.Namespace) -> int:
    """Carry out ``tissuemech design``."""
    import pandas as pd

    from tissuemech.compare.fit.design import (
        CHECK_PROTOCOLS,
        DEFAULT_TRUTH,
        NAMES,
        Protocol,
        check,
        check_levels,
        predict,
        recommend,
        scan_second_level,
    )
    from tissuemech.compare.plots.design import second_level_figure

    out = figure_path("--out", args.out)
    if args.check < 0:
        raise ValueError(f"--check must be >= 0 (fits per protocol); got {args.check}")
    pc = Protocol(noise=args.noise, ramp_time=args.ramp_time)
    for f in args.first_um:  # before any output: a level beyond the table or the diameter is refused
        try:
            check_levels(f * 1e-6, pc)
        except ValueError as exc:
            raise ValueError(f"--first-um {f:g}: {exc}") from None
    fmt = lambda v: f"{v:.3g}"
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        base = predict(pc, model_error=args.model_error)
        print(f"truth {DEFAULT_TRUTH}; protocol {pc.label()}")
        print("predicted 95 % width (% of value): " + ", ".join(f"{n} {100 * base.width[n]:.3g}" for n in NAMES))
        for n_lv in (1, 2, 3):
            lv, pr = recommend(pc, n_levels=n_lv, model_error=args.model_error)
            print(
                f"best {n_lv} level(s) for alpha: "
                + " + ".join(f"{d * 1e6:.4g}" for d in lv)
                + " um -> widths "
                + ", ".join(f"{n} {100 * pr.width[n]:.3g} %" for n in NAMES)
            )
        scans = [scan_second_level(f * 1e-6, pc, model_error=args.model_error) for f in args.first_um]
        print(pd.concat(scans).to_string(index=False, float_format=fmt))
        title = f"Predicted 95 % widths, noise {100 * args.noise:g} %, truth C 150, alpha 0.2, beta 0.4, tau 200"
        save_figure(second_level_figure(scans, title), out)
        print(f"wrote {out}")
        if args.check:
            df = check(CHECK_PROTOCOLS, n_draws=args.check)
            print(df.to_string(index=False, float_format=fmt))
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tissuemech.compare.design [options]``: the same as ``tissuemech design [options]``."""
    from tissuemech.compare.cli import main as cli_main

    return cli_main(["design", *(sys.argv[1:] if argv is None else argv)])
