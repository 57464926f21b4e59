"""``tissuemech spheroid``: relaxation curve (force, nominal stress) of a compressed spheroid, PNG plot."""

from __future__ import annotations

import argparse
import time
from argparse import Namespace
from typing import Any

import numpy as np

from tissuemech.compare import cases
from tissuemech.compare.cases import UM
from tissuemech.compare.cli.common import CLIError, figure_path, nonnegative, positive, save_figure

__all__ = ["add_parser", "run", "spheroid_times", "spheroid_table"]

_FIG10 = cases.FIG10


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Register ``spheroid`` on an argparse subparsers object (defaults: the seed's Fig. 10 case)."""
    (beta, tau), *_ = _FIG10["branches"]
    s = sub.add_parser(
        "spheroid",
        help="relaxation curve of a compressed spheroid (the seed's Fig. 10 case by default)",
        description="Squeeze a Fung ball between two rigid plates (linear ramp of the total approach, "
        "then hold) with one generalized-Maxwell branch; prints plate force and nominal stress "
        "F / A_mid over time and writes the relaxation curve to a PNG. Defaults: the seed's Fig. 10 case.",
    )
    s.add_argument("--out", default="spheroid.png", help="PNG file for the plot (default: %(default)s)")
    s.add_argument(
        "--radius-um", type=positive(), default=_FIG10["radius"] / UM, help="ball radius in um (default: %(default)g)"
    )
    s.add_argument("--C", type=positive(), default=_FIG10["C"], help="Fung stiffness C in Pa (default: %(default)g)")
    s.add_argument(
        "--alpha", type=nonnegative, default=_FIG10["alpha"], help="Fung exponent alpha >= 0 (default: %(default)g)"
    )
    s.add_argument("--beta", type=nonnegative, default=beta, help="Maxwell energy factor beta (default: %(default)g)")
    s.add_argument("--tau", type=positive(), default=tau, help="relaxation time tau in s (default: %(default)g)")
    s.add_argument(
        "--displacement-um",
        type=positive(),
        default=_FIG10["displacement"] / UM,
        help="total plate approach in um (default: %(default)g)",
    )
    s.add_argument(
        "--ramp-time", type=positive(), default=_FIG10["ramp_time"], help="ramp duration in s (default: %(default)g)"
    )
    s.add_argument(
        "--end-time", type=positive(), default=cases.FIG10_END_TIME, help="end of the hold in s (default: %(default)g)"
    )
    s.add_argument(
        "--equilibrium",
        default="fem",
        choices=["fem", "hertz"],
        help="equilibrium law F_eq: 'fem' (FE-calibrated master curve, default) or 'hertz' (small strain)",
    )
    s.add_argument("--fem", action="store_true", help="also run the finite-element model (slower) and compare")
    return s


def run(args: Namespace) -> None:
    """Run ``tissuemech spheroid`` with parsed arguments."""
    spheroid_table(args)


def spheroid_times(ramp_time: float, end_time: float, n: int = 200) -> np.ndarray:
    """Output times (s): 20 through the ramp, the rest log-spaced through the hold."""
    ramp = np.linspace(0.0, ramp_time, 21)
    hold = np.geomspace(ramp_time, end_time, n - 20)[1:]
    return np.concatenate([ramp, hold])


def _check(args: Namespace) -> str:
    """Validate the options in their own units before anything runs; returns the figure path."""
    out = figure_path("--out", args.out)
    if args.end_time < args.ramp_time:
        raise CLIError(f"--end-time ({args.end_time:g} s) must be >= --ramp-time ({args.ramp_time:g} s)")
    x = args.displacement_um / (2 * args.radius_um)
    if x >= 0.8:
        raise CLIError(
            f"--displacement-um {args.displacement_um:g} is {100 * x:.0f} % of the diameter (2 x --radius-um); "
            "it must be below 80 %"
        )
    if args.equilibrium == "fem":
        from tissuemech.reduced import spheroid

        try:
            mc = spheroid.master_curve()
        except FileNotFoundError:
            raise CLIError(
                "no FE-calibrated table is installed; use --equilibrium hertz or run python -m tissuemech.compare.calibrate"
            ) from None
        if x > mc.x_max * (1 + 1e-12):
            raise CLIError(
                f"--displacement-um {args.displacement_um:g} is {100 * x:.3g} % of the diameter; the FE-calibrated "
                f"table covers up to {100 * mc.x_max:.3g} %: use --equilibrium hertz (small strain) or extend the "
                "table (python -m tissuemech.compare.calibrate --x-max ...)"
            )
        if mc.alpha is not None:
            lo, hi = mc.alpha_range
            if not lo - 1e-12 <= args.alpha <= hi + 1e-12:
                raise CLIError(
                    f"--alpha {args.alpha:g} is outside the FE-calibrated table ({lo:g} <= alpha <= {hi:g}): "
                    "use --equilibrium hertz (small strain) or extend the table (python -m tissuemech.compare.calibrate)"
                )
    return out


def spheroid_table(args: Namespace) -> None:
    """``tissuemech spheroid``: force and nominal stress over time, PNG of the relaxation curve.

    With ``--fem`` the table compares reduced and FE at the FE's own step times (the reduced model is
    evaluated there; nothing is interpolated).
    """
    from tissuemech.reduced import spheroid

    out = _check(args)
    kw = dict(
        radius=args.radius_um * UM,
        C=args.C,
        alpha=args.alpha,
        branches=[(args.beta, args.tau)],
        displacement=args.displacement_um * UM,
        ramp_time=args.ramp_time,
        equilibrium=args.equilibrium,
    )
    t = spheroid_times(args.ramp_time, args.end_time)
    sigma = np.asarray(spheroid.nominal_stress(t, **kw))
    fe = None
    if getattr(args, "fem", False):
        from tissuemech.fem import spheroid as fem_spheroid

        t0 = time.perf_counter()
        fe = fem_spheroid.compress(
            radius=kw["radius"],
            C=args.C,
            alpha=args.alpha,
            branches=kw["branches"],
            displacement=kw["displacement"],
            ramp_time=args.ramp_time,
            end_time=args.end_time,
        )
        print(f"FE run (fem.spheroid.compress, default mesh): {len(fe.time)} steps in {time.perf_counter() - t0:.1f} s")

    print(
        f"Spheroid a0 = {args.radius_um:g} um, C = {args.C:g} Pa, alpha = {args.alpha:g}, "
        f"beta = {args.beta:g}, tau = {args.tau:g} s; approach {args.displacement_um:g} um in "
        f"{args.ramp_time:g} s, held to {args.end_time:g} s; equilibrium: {args.equilibrium}"
    )
    if fe is None:
        picks = [v for v in (0.05, 0.1, 0.2, 1, 10, 50, 100, 200, 400, 800, 1200) if v < args.end_time]
        grid = np.array([v * args.ramp_time / 0.2 if v <= 0.2 else v for v in picks] + [args.end_time])
        show = np.unique(grid[grid <= args.end_time])
    else:
        show = np.asarray(fe.time)[np.asarray(fe.time) > 0]
    F_show = np.asarray(spheroid.force(show, **kw))
    s_show = np.asarray(spheroid.nominal_stress(show, **kw))
    head = f"{'t [s]':>9} {'F [uN]':>10} {'sigma~ [Pa]':>12}"
    if fe is not None:
        head += f" {'FE sigma~ [Pa]':>15} {'reduced/FE - 1':>15}"
        print("(rows: the FE step times)")
    print(head)
    s_fe = np.asarray(fe.nominal_stress)[np.asarray(fe.time) > 0] if fe is not None else None
    for k, ts in enumerate(show):
        row = f"{ts:9.4g} {F_show[k] * 1e6:10.5g} {s_show[k]:12.6g}"  # (fixed decimals read 0.00 in short ramps)
        if s_fe is not None:
            row += f" {s_fe[k]:15.4f} {s_show[k] / s_fe[k] - 1:+15.2e}"
        print(row)
    if s_fe is not None:
        ramp = show <= args.ramp_time * (1 + 1e-12)
        dev = np.abs(s_show / s_fe - 1)
        print(
            f"max |reduced/FE - 1| at the FE step times: {dev[ramp].max():.2e} during the ramp, "
            + (f"{dev[~ramp].max():.2e} in the hold" if (~ramp).any() else "no hold steps")
        )

    from tissuemech.compare.plots.scenes import spheroid_figure

    title = (
        f"Spheroid a0 = {args.radius_um:g} um, C = {args.C:g} Pa, alpha = {args.alpha:g}, beta = {args.beta:g}, "
        f"tau = {args.tau:g} s; {args.displacement_um:g} um in {args.ramp_time:g} s"
    )
    fig = spheroid_figure(
        t, sigma, equilibrium=args.equilibrium, ramp_time=args.ramp_time, end_time=args.end_time, fe=fe, title=title
    )
    save_figure(fig, out)
    print(f"\nwrote {out}")
