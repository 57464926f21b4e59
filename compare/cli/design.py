"""``tissuemech design``: experiment design for compression-relaxation fits (predicted interval widths).

    tissuemech design [--first-um 25 50 100] [--noise 0.01] [--ramp-time 0.2] [--model-error 0]
                      [--truth C=150 alpha=0.2 beta=0.4 tau=200] [--model reduced|fe] [--mesh coarse]
                      [--out design.png] [--check N]

prints the predicted widths of the default protocol, the level pair and triple that identify alpha best, a table
of the predicted widths against the second level, writes the figure, and with ``--check N`` fits N noisy
reduced-made records per check protocol (:mod:`tissuemech.compare.fit.design`). ``--model fe`` makes the prediction
and the second-level scans from the FE's exact sensitivities (``fe_level_fisher``: truths with alpha beyond the
table's 1.5, second levels up to x = 0.5), e.g. ``tissuemech design --model fe --truth C=150 alpha=1.8 beta=0.4
tau=200 --first-um 50``.
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
    ap.add_argument(
        "--model",
        choices=["reduced", "fe"],
        default="reduced",
        help="the model whose sensitivities make the prediction: reduced (default) or fe (the FE's exact "
        "sensitivities, one coarse-mesh run per level: truths and levels beyond the reduced model's table)",
    )
    ap.add_argument("--mesh", default="coarse", help="--model fe: the FE mesh level (default %(default)s)")
    ap.add_argument(
        "--truth",
        nargs=4,
        metavar="NAME=VALUE",
        default=None,
        help="the parameter guess in SI (default C=150 alpha=0.2 beta=0.4 tau=200)",
    )
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
    truth = _truth(args.truth, NAMES) if args.truth else dict(DEFAULT_TRUTH)
    if args.model == "fe":
        return _run_fe(args, pc, truth, out)
    for f in args.first_um:  # before any output: a level beyond the table or the diameter is refused
        try:
            check_levels(f * 1e-6, pc)
        except ValueError as exc:
            raise ValueError(f"--first-um {f:g}: {exc}") from None
    fmt = lambda v: f"{v:.3g}"
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        base = predict(pc, truth, model_error=args.model_error)
        print(f"truth {truth}; protocol {pc.label()}")
        print("predicted 95 % width (% of value): " + ", ".join(f"{n} {100 * base.width[n]:.3g}" for n in NAMES))
        for n_lv in (1, 2, 3):
            lv, pr = recommend(pc, truth, n_levels=n_lv, model_error=args.model_error)
            print(
                f"best {n_lv} level(s) for alpha: "
                + " + ".join(f"{d * 1e6:.4g}" for d in lv)
                + " um -> widths "
                + ", ".join(f"{n} {100 * pr.width[n]:.3g} %" for n in NAMES)
            )
        scans = [scan_second_level(f * 1e-6, pc, truth, model_error=args.model_error) for f in args.first_um]
        print(pd.concat(scans).to_string(index=False, float_format=fmt))
        title = f"Predicted 95 % widths, noise {100 * args.noise:g} %, truth " + _truth_text(truth)
        save_figure(second_level_figure(scans, title), out)
        print(f"wrote {out}")
        if args.check:
            df = check(CHECK_PROTOCOLS, n_draws=args.check)
            print(df.to_string(index=False, float_format=fmt))
    return 0


def _truth(items: Sequence[str], names: Sequence[str]) -> dict[str, float]:
    """``--truth C=150 alpha=0.2 beta=0.4 tau=200`` as a dict (SI); ValueError naming what is wrong."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            sep = ""
        if not sep:
            raise ValueError(f"--truth {item!r}: expected NAME=VALUE with a number, e.g. alpha=1.8")
    if set(out) != set(names):
        raise ValueError(f"--truth must give each of {', '.join(names)} once (SI: C Pa, alpha -, beta -, tau s)")
    return out


def _truth_text(truth: dict[str, float]) -> str:
    return ", ".join(f"{n} {v:g}" for n, v in truth.items())


def _run_fe(args: argparse.Namespace, pc: Any, truth: dict[str, float], out: str) -> int:
    """``tissuemech design --model fe``: the prediction and the second-level scans from the FE's exact sensitivities
    (one FE run per level and truth; the best-level search and --check are the reduced model's)."""
    import pandas as pd

    from tissuemech.compare.fit.design import NAMES, predict, scan_second_level
    from tissuemech.compare.plots.design import second_level_figure

    if args.check:
        raise ValueError("--check fits reduced-made records: use it with --model reduced")
    base = predict(pc, truth, model_error=args.model_error, model="fe", mesh=args.mesh)
    print(f"truth {truth}; protocol {pc.label()}; FE sensitivities (mesh {args.mesh})")
    print("predicted 95 % width (% of value): " + ", ".join(f"{n} {100 * base.width[n]:.3g}" for n in NAMES))
    scans = []
    for f in args.first_um:
        scans.append(scan_second_level(f * 1e-6, pc, truth, model_error=args.model_error, model="fe", mesh=args.mesh))
        print(f"first level {f:g} um: {len(scans[-1])} second levels done", file=sys.stderr, flush=True)
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(pd.concat(scans).to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    title = f"Predicted 95 % widths (FE, mesh {args.mesh}), noise {100 * args.noise:g} %, truth " + _truth_text(truth)
    save_figure(second_level_figure(scans, title), out)
    print(f"wrote {out}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tissuemech.compare.design [options]``: the same as ``tissuemech design [options]``."""
    from tissuemech.compare.cli import main as cli_main

    return cli_main(["design", *(sys.argv[1:] if argv is None else argv)])
