"""The two scenes as the command line shows them: tables on stdout, figures as PNG.

Kept apart from ``cli.py`` (argument parsing only) so the report and notebooks can reuse them.
"""

from __future__ import annotations

import time
from argparse import Namespace
from typing import Any

import numpy as np

UM = 1e-6
FIG4 = [("Fig. 4", a, 75.0) for a in (1e-5, 0.1, 0.2, 0.3)]
FIG5 = [("Fig. 5", 0.2, b) for b in (52.0, 60.0, 75.0)]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def blastula_curves(C: float, inner_radius: float, max_pressure: float, step: float) -> list[dict[str, Any]]:
    """Inner/outer stretch at pressures 0..max_pressure for the seed's Fig. 4 and Fig. 5 sets.

    Returns one dict per set with keys figure, alpha, outer_radius (m), pressure (Pa),
    inner_stretch, outer_stretch (NaN past the limit point), limit (p_max, stretch) or None.
    """
    from tissuemech.reduced import blastula

    pressures = np.arange(0.0, max_pressure + 0.5 * step, step)
    out = []
    for fig, alpha, b_um in FIG4 + FIG5:
        geo = dict(inner_radius=inner_radius, outer_radius=b_um * UM)
        lim = blastula.limit_point(**geo, C=C, alpha=alpha)
        ok = pressures < lim[0] if lim is not None else np.ones_like(pressures, bool)
        la = np.full_like(pressures, np.nan)
        if ok.any():
            la[ok] = np.asarray(blastula.inner_stretch(pressures[ok], **geo, C=C, alpha=alpha))
        lb = np.where(ok, np.asarray(blastula.outer_stretch(np.where(ok, la, 1.0), **geo)), np.nan)
        out.append(
            dict(
                figure=fig,
                alpha=alpha,
                outer_radius=b_um * UM,
                pressure=pressures,
                inner_stretch=la,
                outer_stretch=lb,
                limit=lim,
            )
        )
    return out


def _print_blastula(curves: list[dict[str, Any]]) -> None:
    for fig in ("Fig. 4", "Fig. 5"):
        sets = [c for c in curves if c["figure"] == fig]
        heads = [f"a={c['alpha']:g},B={c['outer_radius'] / UM:g}um" for c in sets]
        print(f"\n{fig}: inner / outer stretch (lambda_a / lambda_b); A = 50 um")
        print(f"{'p [Pa]':>8} " + " ".join(f"{h:>19}" for h in heads))
        for i, p in enumerate(sets[0]["pressure"]):
            cells = []
            for c in sets:
                la, lb = c["inner_stretch"][i], c["outer_stretch"][i]
                cells.append(f"{'burst':>19}" if np.isnan(la) else f"{la:9.5f} / {lb:7.5f}")
            print(f"{p:8.1f} " + " ".join(cells))
    print("\nLimit (burst) pressure under load control:")
    for c in curves:
        lim = c["limit"]
        where = f"a={c['alpha']:g}, B={c['outer_radius'] / UM:g} um"
        if lim is None:
            print(f"  {where}: none (p rises monotonically)")
        else:
            print(f"  {where}: p_max = {float(lim[0]):.2f} Pa at lambda_a = {float(lim[1]):.4f}")


def blastula_table(args: Namespace) -> None:
    """``tissuemech blastula``: table of the Fig. 4/5 sets, limit pressures, PNG plot."""
    from tissuemech.reduced import blastula

    A = args.inner_radius_um * UM
    curves = blastula_curves(args.C, A, args.max_pressure, args.step)
    _print_blastula(curves)
    fem_runs = _blastula_fem(curves, args.C, A) if getattr(args, "fem", False) else {}

    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.3), sharey=True)
    for ax, name in zip(axes, ("Fig. 4", "Fig. 5")):
        for c in (c for c in curves if c["figure"] == name):
            label = f"alpha={c['alpha']:g}" if name == "Fig. 4" else f"B={c['outer_radius'] / UM:g} um"
            lim = c["limit"]
            la_top = 4.0 if lim is None else 2.2 * float(lim[1])
            la = np.linspace(1.0, la_top, 400)
            geo = dict(inner_radius=A, outer_radius=c["outer_radius"])
            p = np.asarray(blastula.pressure(la, **geo, C=args.C, alpha=c["alpha"]))
            keep = p <= args.max_pressure * 1.02
            (line,) = ax.plot(la[keep], p[keep], label=label + " (inner)")
            lb = np.asarray(blastula.outer_stretch(la, **geo))
            ax.plot(lb[keep], p[keep], "--", color=line.get_color(), lw=1)
            if lim is not None:
                ax.plot(float(lim[1]), float(lim[0]), "kx", ms=8)
                ax.annotate(
                    f"limit {float(lim[0]):.0f} Pa",
                    (float(lim[1]), float(lim[0])),
                    textcoords="offset points",
                    xytext=(5, 5),
                    fontsize=8,
                )
            run = fem_runs.get((c["alpha"], c["outer_radius"]))
            if run is not None:
                ax.plot(run.inner_stretch, run.pressure, "o", color=line.get_color(), ms=3, mfc="none")
        ax.set_xlabel("stretch (solid: inner a/A, dashed: outer b/B)")
        ax.set_title(f"{name}" + (" (markers: FE)" if fem_runs else ""))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_ylabel("pressure p [Pa]")
    fig.suptitle("Blastula inflation: exact incompressible Fung shell, A = 50 um, C = %g Pa" % args.C)
    fig.tight_layout()
    fig.savefig(args.out, dpi=130)
    plt.close(fig)
    print(f"\nwrote {args.out}")


def _blastula_fem(curves: list[dict[str, Any]], C: float, A: float) -> dict:
    """Run the FE blastula for every set (load control to the table's pressures below any limit)."""
    from tissuemech.fem import blastula as fem_blastula

    runs = {}
    print("\nFE check (fem.blastula.inflate, default mesh, kappa = 2.2 GPa):")
    for c in curves:
        ok = ~np.isnan(c["inner_stretch"])
        ps = c["pressure"][ok][1:]
        t0 = time.perf_counter()
        run = fem_blastula.inflate(inner_radius=A, outer_radius=c["outer_radius"], C=C, alpha=c["alpha"], pressures=ps)
        wall = time.perf_counter() - t0
        exact = np.interp(run.pressure, c["pressure"][ok], c["inner_stretch"][ok])
        err = np.max(np.abs(run.inner_stretch / exact - 1.0))
        print(
            f"  alpha={c['alpha']:g}, B={c['outer_radius'] / UM:g} um: {len(run.pressure)} steps in "
            f"{wall:.2f} s, max |FE/exact - 1| of inner stretch = {err:.1e}"
        )
        runs[(c["alpha"], c["outer_radius"])] = run
    return runs


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

    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax in axes:
        ax.plot(t, sigma, "k-", label=f"reduced ({args.equilibrium})")
        if fe is not None:
            ax.plot(fe.time, fe.nominal_stress, "o", ms=3, mfc="none", label="FE")
        ax.set_xlabel("time t [s]")
        ax.grid(alpha=0.3)
    axes[0].set_xlim(0, 3 * args.ramp_time)
    axes[0].set_title("ramp")
    axes[1].set_xscale("log")
    axes[1].set_xlim(args.ramp_time / 10, args.end_time)
    axes[1].set_title("relaxation (log time)")
    axes[0].set_ylabel("nominal stress F / A_mid [Pa]")
    axes[0].legend()
    fig.suptitle("Spheroid compression-relaxation (seed Fig. 10 case by default)")
    fig.tight_layout()
    fig.savefig(args.out, dpi=130)
    plt.close(fig)
    print(f"\nwrote {args.out}")
