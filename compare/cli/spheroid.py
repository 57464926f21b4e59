"""``tissuemech spheroid``: relaxation curve (force, nominal stress) of a compressed spheroid, PNG plot."""

from __future__ import annotations

import argparse
import time
from argparse import Namespace
from typing import Any

import numpy as np

from tissuemech.compare import cases
from tissuemech.compare.cases import UM
from tissuemech.compare.cli.common import nonnegative, positive, save_figure

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


def spheroid_table(args: Namespace) -> None:
    """``tissuemech spheroid``: force and nominal stress over time, PNG of the relaxation curve."""
    from tissuemech.reduced import spheroid

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
    force = np.asarray(spheroid.force(t, **kw))
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
        print(f"FE run: {len(fe.time)} steps in {time.perf_counter() - t0:.1f} s")

    print(
        f"Spheroid a0 = {args.radius_um:g} um, C = {args.C:g} Pa, alpha = {args.alpha:g}, "
        f"beta = {args.beta:g}, tau = {args.tau:g} s; approach {args.displacement_um:g} um in "
        f"{args.ramp_time:g} s, held to {args.end_time:g} s; equilibrium: {args.equilibrium}"
    )
    show = [t_ for t_ in (0.05, 0.1, 0.2, 1, 10, 50, 100, 200, 400, 800, 1200, args.end_time) if t_ <= args.end_time]
    head = f"{'t [s]':>8} {'F [uN]':>10} {'sigma~ [Pa]':>12}"
    print(head + (f" {'FE sigma~ [Pa]':>15}" if fe is not None else ""))
    for ts in show:
        row = f"{ts:8.2f} {np.interp(ts, t, force) * 1e6:10.4f} {np.interp(ts, t, sigma):12.4f}"
        if fe is not None:
            row += f" {np.interp(ts, fe.time, fe.nominal_stress):15.4f}"
        print(row)

    from tissuemech.compare.plots.scenes import spheroid_figure

    fig = spheroid_figure(
        t, sigma, equilibrium=args.equilibrium, ramp_time=args.ramp_time, end_time=args.end_time, fe=fe
    )
    save_figure(fig, args.out)
    print(f"\nwrote {args.out}")
