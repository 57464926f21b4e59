"""The AFM relaxation figure: data, fits and residuals for a few curves, and the parameters across all curves."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from tissuemech.compare.plots import pyplot

__all__ = ["relaxation_figure"]


def relaxation_figure(
    one: Sequence[Any], two: Sequence[Any], *, show: Sequence[int] = (0, 1, 2), title: str = ""
) -> Any:
    """Figure with (top) force over time for the curves ``show``: data (grey), the 1-branch fit (blue), the
    2-branch fit (red), the model over the ramp (not fitted, dotted); (middle) their residuals over the hold
    (nN) for both models; (bottom) tau_m and beta_m of the 2-branch fits and tau of the 1-branch fits across all
    curves, and C of both. ``one``/``two``: :class:`tissuemech.compare.afm.fit.CurveFit` lists, same curves."""
    plt = pyplot()
    show = [i for i in show if i < len(one)]
    fig = plt.figure(figsize=(4.0 * max(len(show), 3), 10.0))
    gs = fig.add_gridspec(3, max(len(show), 3), height_ratios=[1.3, 1.0, 1.1])
    for col, i in enumerate(show):
        a, b = one[i], two[i]
        ax = fig.add_subplot(gs[0, col])
        ax.plot(a.ramp_time, a.ramp_force * 1e9, ".", color="0.6", ms=3)
        ax.plot(a.time, a.force * 1e9, ".", color="0.5", ms=3, label="data")
        ax.plot(a.ramp_time, a.ramp_model * 1e9, ":", color="C0")
        ax.plot(b.ramp_time, b.ramp_model * 1e9, ":", color="C3")
        ax.plot(a.time, a.model * 1e9, "-", color="C0", label=f"1 branch (rms {a.rms * 1e9:.1f} nN)")
        ax.plot(b.time, b.model * 1e9, "-", color="C3", label=f"2 branches (rms {b.rms * 1e9:.1f} nN)")
        ax.set(title=a.name, xlabel="time since contact (s)", ylabel="force (nN)")
        ax.legend(fontsize=8)
        ax = fig.add_subplot(gs[1, col])
        ax.axhline(0.0, color="k", lw=0.5)
        ax.plot(
            a.time, a.residual * 1e9, color="C0", lw=1, label=f"1 branch: lag-1 {a.lag1:.2f}, runs z {a.runs_z:.0f}"
        )
        ax.plot(
            b.time, b.residual * 1e9, color="C3", lw=1, label=f"2 branches: lag-1 {b.lag1:.2f}, runs z {b.runs_z:.0f}"
        )
        ax.set(xscale="log", xlabel="time since contact (s)", ylabel="data - fit over the hold (nN)")
        ax.legend(fontsize=8)
    ax = fig.add_subplot(gs[2, 0])
    k = len(two)
    jitter = np.linspace(-0.15, 0.15, k)
    nb = two[0].n_branches
    for m in range(1, nb + 1):
        v = [f.params[f"tau_{m}"] for f in two]
        lo = [f.intervals[f"tau_{m}"][0] for f in two]
        hi = [f.intervals[f"tau_{m}"][1] for f in two]
        ax.errorbar(m + jitter, v, yerr=[np.subtract(v, lo), np.subtract(hi, v)], fmt="o", color="C3", ms=3, lw=0.7)
    v = [f.params["tau"] for f in one]
    ax.errorbar(
        0 + jitter,
        v,
        yerr=[
            np.subtract(v, [f.intervals["tau"][0] for f in one]),
            np.subtract([f.intervals["tau"][1] for f in one], v),
        ],
        fmt="o",
        color="C0",
        ms=3,
        lw=0.7,
    )
    ax.set(
        xticks=range(nb + 1),
        xticklabels=["tau (1 br.)"] + [f"tau_{m} (2 br.)" for m in range(1, nb + 1)],
        yscale="log",
        ylabel="relaxation time (s), 95 % HAC",
        title=f"{k} curves",
    )
    ax = fig.add_subplot(gs[2, 1])
    for m in range(1, nb + 1):
        ax.plot(m + jitter, [f.params[f"beta_{m}"] for f in two], "o", color="C3", ms=3)
    ax.plot(0 + jitter, [f.params["beta"] for f in one], "o", color="C0", ms=3)
    ax.set(
        xticks=range(nb + 1),
        xticklabels=["beta (1 br.)"] + [f"beta_{m}" for m in range(1, nb + 1)],
        ylabel="energy factor beta (-)",
    )
    ax = fig.add_subplot(gs[2, 2])
    ax.plot(0 + jitter, [f.params["C"] for f in one], "o", color="C0", ms=3)
    ax.plot(1 + jitter, [f.params["C"] for f in two], "o", color="C3", ms=3)
    g = one[0].geometry
    ax.set(
        xticks=[0, 1],
        xticklabels=["C (1 br.)", "C (2 br.)"],
        ylabel="C (Pa)",
        title=f"R_p {g['probe_radius'] * 1e6:g} um, a0 {g['radius'] * 1e6:g} um (C ~ R_s^-1/2)",
    )
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
