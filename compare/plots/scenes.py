"""The plots of ``tissuemech blastula`` and ``tissuemech spheroid`` (each returns a Figure; the CLI saves it)."""

from __future__ import annotations

from typing import Any

import numpy as np

from tissuemech.compare.cases import UM
from tissuemech.compare.plots import pyplot as _plt

__all__ = ["blastula_figure", "spheroid_figure"]


def blastula_figure(
    curves: list[dict[str, Any]], *, C: float, inner_radius: float, max_pressure: float, fem_runs: dict
):
    """Pressure-stretch curves of the Fig. 4 (left) and Fig. 5 (right) sets: exact lines, FE markers.

    curves: ``cli.blastula.blastula_curves`` output; C (Pa); inner_radius (m); max_pressure (Pa), the
    top of the plotted pressure range; fem_runs: {(alpha, outer_radius): FE result} (may be empty).
    Each exact curve runs from (1, 0) to max_pressure, or past the limit point to 1.6 x its stretch.
    """
    from tissuemech.reduced import blastula

    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.3), sharey=True)
    for ax, name in zip(axes, ("Fig. 4", "Fig. 5")):
        for c in (c for c in curves if c["figure"] == name):
            label = f"alpha={c['alpha']:g}" if name == "Fig. 4" else f"B={c['outer_radius'] / UM:g} um"
            geo = dict(inner_radius=inner_radius, outer_radius=c["outer_radius"], C=C, alpha=c["alpha"])
            lim = c["limit"]
            if lim is None or float(lim.pressure) >= max_pressure:
                at_top = np.isclose(c["pressure"][-1], max_pressure, rtol=1e-12, atol=0.0)
                la_top = (  # the table's last row when it is max_pressure (no one-point program to compile)
                    float(c["inner_stretch"][-1])
                    if at_top and np.isfinite(c["inner_stretch"][-1])
                    else float(blastula.inner_stretch(max_pressure, **geo))
                )
            else:
                la_top = 1.6 * float(lim.inner_stretch)
            la = np.linspace(1.0, la_top, 300)  # (300 points: the compiled program of the report's curves)
            p = np.asarray(blastula.pressure(la, **geo))
            keep = p <= max_pressure * 1.0001
            (line,) = ax.plot(la[keep], p[keep], label=label + " (inner)")
            lb = np.asarray(blastula.outer_stretch(la, inner_radius=inner_radius, outer_radius=c["outer_radius"]))
            ax.plot(lb[keep], p[keep], "--", color=line.get_color(), lw=1)
            if lim is not None and float(lim.pressure) < max_pressure:
                ax.plot(float(lim.inner_stretch), float(lim.pressure), "kx", ms=8)
                ax.annotate(
                    f"limit {float(lim.pressure):.0f} Pa",
                    (float(lim.inner_stretch), float(lim.pressure)),
                    textcoords="offset points",
                    xytext=(5, 5),
                    fontsize=8,
                )
            run = fem_runs.get((c["alpha"], c["outer_radius"]))
            if run is not None:
                ax.plot(run.inner_stretch, run.pressure, "o", color=line.get_color(), ms=3, mfc="none")
        ax.set_xlabel("stretch (solid: inner a/A, dashed: outer b/B)")
        ax.set_title(f"{name}" + (" (circles: FE)" if fem_runs else ""))
        ax.set_ylim(0, max_pressure * 1.05)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_ylabel("pressure p [Pa]")
    fig.suptitle(f"Blastula inflation: exact incompressible Fung shell, A = {inner_radius / UM:g} um, C = {C:g} Pa")
    fig.tight_layout()
    return fig


def spheroid_figure(t, sigma, *, equilibrium: str, ramp_time: float, end_time: float, fe: Any = None, title: str = ""):
    """Nominal stress vs time: the ramp (left, linear time) and the relaxation (right, log time).

    t (s), sigma (Pa): the reduced curve; fe: an FE result with ``time`` and ``nominal_stress`` or None.
    """
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax in axes:
        ax.plot(t, sigma, "k-", label=f"reduced ({equilibrium})")
        if fe is not None:
            ax.plot(fe.time, fe.nominal_stress, "o", ms=3, mfc="none", label="FE")
        ax.set_xlabel("time t [s]")
        ax.grid(alpha=0.3)
    axes[0].set_xlim(0, 3 * ramp_time)
    axes[0].set_title("ramp")
    axes[1].set_xscale("log")
    axes[1].set_xlim(ramp_time / 10, end_time)
    axes[1].set_title("relaxation (log time)")
    axes[0].set_ylabel("nominal stress F / A_mid [Pa]")
    axes[0].legend()
    fig.suptitle(title or "Spheroid compression-relaxation")
    fig.tight_layout()
    return fig
