"""``tissuemech calibrate-indentation``: tabulate the FE-calibrated equilibrium law of a spherical probe on a ball
resting on a plate (the table ``reduced.indentation`` ships in ``reduced/data/``; see
:mod:`tissuemech.compare.calibrate_indentation`)."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import Any

from tissuemech.compare import calibrate_indentation as ci
from tissuemech.compare.cli.common import Command

__all__ = ["COMMAND", "add_parser", "run", "main"]

DESCRIPTION = (
    "Tabulate the probe-on-ball equilibrium law h(y, alpha, rho) = F_eq / F_Hertz,series from static FE runs "
    "(a Richardson extrapolation of two levels, checked against a third)."
)


def _floats(text: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a comma list of numbers, got {text!r}") from None


def _options(ap: argparse.ArgumentParser) -> argparse.ArgumentParser:
    ap.add_argument("--out", default="indentation_master.npz", help="table to write (default: %(default)s)")
    ap.add_argument("--install", action="store_true", help=f"write the shipped table {ci.DEFAULT_OUT}")
    ap.add_argument("--store", default=None, help="folder for per-slice results (resume)")
    ap.add_argument("--mesh", type=int, default=2, help="FE level of the table (default: %(default)s)")
    ap.add_argument("--coarse-mesh", type=int, default=1, help="coarser level of the Richardson table (-1: none)")
    ap.add_argument("--order", type=float, default=ci.ORDER, help="Richardson order in n_zone (default: %(default)s)")
    ap.add_argument("--check-rhos", type=_floats, default=list(ci.CHECK_RHOS), help="rho values of the check slices")
    ap.add_argument(
        "--check-mesh", type=int, default=3, help="finer level of the check (-1: none; default: %(default)s)"
    )
    ap.add_argument("--rhos", type=_floats, default=list(ci.RHOS), help="probe radius / ball radius values")
    ap.add_argument("--alphas", type=_floats, default=list(ci.ALPHAS), help="Fung exponents (increasing)")
    ap.add_argument("--ys", type=_floats, default=list(ci.YS), help="depth ratios y = d_1 / R_1 (increasing, > 0)")
    ap.add_argument("--serial", action="store_true", help="one process (default: compare.batch's local pool)")
    return ap


def _execute(a: argparse.Namespace, error: Any) -> int:
    for name in ("rhos", "alphas", "ys", "check_rhos"):
        if not getattr(a, name):
            error(f"--{name.replace('_', '-')} must list at least one number")
    if any(v <= 0 for v in a.rhos + a.check_rhos):
        error("--rhos / --check-rhos (probe radius / ball radius) must be > 0")
    if any(v <= 0 for v in a.ys):
        error("--ys (depth ratios d_1 / R_1) must be > 0 (y = 0 is added: h = 1 there)")
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    table, meta = ci.tabulate(
        rhos=a.rhos, alphas=a.alphas, ys=a.ys, mesh=a.mesh, coarse_mesh=None if a.coarse_mesh < 0 else a.coarse_mesh,
        order=a.order, check_rhos=a.check_rhos, check_mesh=None if a.check_mesh < 0 else a.check_mesh,
        executor="serial" if a.serial else None, store=a.store,
    )  # fmt: skip
    out = ci.DEFAULT_OUT if a.install else Path(a.out)
    ci.write(out, table, meta)
    print(f"wrote {out}: y up to {meta['y_max']:g}, discretisation error {meta['discretisation_error']:.2e} "
          f"({meta['discretisation_error_at']}), {meta['wall_seconds']:.0f} s")  # fmt: skip
    return 0


COMMAND = Command(
    "calibrate-indentation",
    "regenerate the FE-calibrated probe-on-ball table of the reduced indentation model",
    DESCRIPTION,
    _options,
    _execute,
)
add_parser, run, main = COMMAND.add_parser, COMMAND.run, COMMAND.main

if __name__ == "__main__":
    raise SystemExit(main())
