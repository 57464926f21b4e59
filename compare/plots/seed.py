r"""The seed's figures, as functions of already computed data.

Every function takes results (FE result objects, numpy arrays) and returns a
``matplotlib.figure.Figure`` (Agg backend, nothing is shown or saved here; ``compare.report``
saves them). Units on the axes: um, Pa, s, as in the seed.

Blastula (scene 1): ``fig3`` (von Mises on the deformed wall + exact through-wall profile vs FE),
``fig_stretch_pressure`` (Figs 4 and 5: FE lines, exact markers, the arc-length trace through the
neo-Hookean limit point). Spheroid (scene 2): ``fig8`` (von Mises on the deformed section at two
times), ``fig9`` (mean von Mises vs time), ``fig10`` (nominal stress vs time, FE / reduced / a fit
to a synthetic record). The report's charts are in :mod:`tissuemech.compare.plots.charts`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from tissuemech.compare.cases import UM
from tissuemech.compare.plots import pyplot as _plt

__all__ = ["fig3", "fig_stretch_pressure", "fig8", "fig9", "fig10", "element_radius"]


def element_radius(mesh) -> np.ndarray:
    """Reference radius (m) of each element's corner centroid, sqrt(R^2 + Z^2) (spherical shell)."""
    p = mesh.mesh.p[:, mesh.mesh.t[:4]].mean(axis=1)
    return np.hypot(p[0], p[1]) * mesh.length_scale


# ---------------------------------------------------------------------------------------------
# Blastula
# ---------------------------------------------------------------------------------------------


def fig3(result: Any, profile: Any, *, pressure: float, alpha: float, outer_radius: float):
    """Seed Fig. 3: von Mises on the deformed wall (left) and the exact through-wall profile vs FE (right).

    result   ``fem.blastula`` result at the final pressure (element means of von Mises, Pa)
    profile  ``reduced.blastula.profiles`` at the exact inner stretch (R in m, von_mises in Pa)
    """
    plt = _plt()
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(11, 4.6))
    result.plot(ax=a0)
    a0.set_title(f"FE von Mises, p = {pressure / 1e3:g} kPa, alpha = {alpha:g}, B = {outer_radius / UM:g} um")
    R = np.asarray(profile.R).ravel() / UM
    a1.plot(R, np.asarray(profile.von_mises).ravel(), "k-", label="exact (incompressible shell)")
    a1.plot(
        element_radius(result.mesh) / UM,
        result.von_mises,
        "o",
        ms=4,
        mfc="none",
        label="FE element means (all elements)",
    )
    a1.set_xlabel("reference radius R (um)")
    a1.set_ylabel("von Mises stress |sigma_theta - sigma_r| (Pa)")
    a1.set_title("through-wall profile (not in the seed)")
    a1.grid(alpha=0.3)
    a1.legend(fontsize=8)
    fig.tight_layout()
    return fig


def fig_stretch_pressure(
    sets: Sequence[Mapping[str, Any]], *, title: str, limit_trace: Any = None, limit: tuple[float, float] | None = None
):
    """Seed Figs 4/5: inner and outer stretch vs pressure; FE lines, exact markers.

    sets         dicts with label, fe (FE result: pressure, inner_stretch, outer_stretch),
                 exact_p (Pa), exact_inner, exact_outer (arrays)
    limit_trace  an FE arc-length result through the neo-Hookean limit point (drawn in black)
    limit        (p_max Pa, lambda_a at the limit) of the exact solution, marked
    """
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4), sharey=True)
    for s in sets:
        (ln,) = axes[0].plot(s["fe"].inner_stretch, s["fe"].pressure, "-", label=f"{s['label']} FE")
        axes[0].plot(s["exact_inner"], s["exact_p"], "o", color=ln.get_color(), ms=4, mfc="none")
        axes[1].plot(s["fe"].outer_stretch, s["fe"].pressure, "-", color=ln.get_color(), label=f"{s['label']} FE")
        axes[1].plot(s["exact_outer"], s["exact_p"], "o", color=ln.get_color(), ms=4, mfc="none")
    if limit_trace is not None:
        axes[0].plot(limit_trace.inner_stretch, limit_trace.pressure, "k-", lw=1.2, label="neo-Hookean FE arc-length")
        axes[1].plot(limit_trace.outer_stretch, limit_trace.pressure, "k-", lw=1.2)
    if limit is not None:
        axes[0].plot(limit[1], limit[0], "r*", ms=12, label=f"limit point {limit[0]:.2f} Pa (exact)")
    axes[0].set_xlabel("inner stretch a/A")
    axes[1].set_xlabel("outer stretch b/B")
    axes[0].set_ylabel("pressure p (Pa)")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, title="lines: FE, circles: exact", title_fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------------------------------------
# Spheroid
# ---------------------------------------------------------------------------------------------


def fig8(result: Any, times: Sequence[float]):
    """Seed Fig. 8: von Mises on the deformed quarter section at the stored field times (one panel each)."""
    plt = _plt()
    fig, axes = plt.subplots(1, len(times), figsize=(5.5 * len(times), 4.6))
    axes = np.atleast_1d(axes)
    for ax, t in zip(axes, times):
        result.plot_von_mises(t, ax=ax)
    # one colour scale for all panels, so the relaxation is visible as a colour change
    vms = [result.field_at(t).von_mises for t in times]
    lo, hi = float(min(v.min() for v in vms)), float(max(v.max() for v in vms))
    for ax in axes:
        for coll in ax.collections:
            coll.set_clim(lo, hi)
    fig.tight_layout()
    return fig


def fig9(fe: Any, reduced_t: np.ndarray | None = None, reduced_vm: np.ndarray | None = None, *, label: str = ""):
    """Seed Fig. 9: volume-averaged von Mises vs time (ramp, left; relaxation, right, log time)."""
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    ramp_end = float(fe.parameters.get("ramp_time", 0.2)) if getattr(fe, "parameters", None) else 0.2
    for ax, sel in zip(axes, (fe.time <= ramp_end * 1.0001, fe.time >= ramp_end * 0.9999)):
        ax.plot(fe.time[sel], fe.mean_von_mises[sel], "o-", ms=3, label="FE")
        if reduced_t is not None:
            rs = (reduced_t <= ramp_end * 1.0001) if ax is axes[0] else (reduced_t >= ramp_end * 0.9999)
            ax.plot(reduced_t[rs], reduced_vm[rs], "k--", label="reduced (lumped relaxation x FE static mean)")
        ax.set_xlabel("time t (s)")
        ax.grid(alpha=0.3)
    axes[1].set_xscale("log")
    axes[0].set_title("ramp")
    axes[1].set_title("relaxation (hold)")
    axes[0].set_ylabel("volume-averaged von Mises stress (Pa)")
    axes[0].legend(fontsize=8)
    fig.suptitle(label)
    fig.tight_layout()
    return fig


def fig10(curves: Sequence[Mapping[str, Any]], synthetic: Mapping[str, Any] | None = None, *, label: str = ""):
    """Seed Fig. 10: nominal stress sigma~ = F / A_mid vs time.

    curves     dicts with label, t (s), sigma (Pa), style (matplotlib format string)
    synthetic  dict with t, sigma (the noisy synthetic record), fit_t, fit_sigma, fit_label
    """
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, log in zip(axes, (False, True)):
        for c in curves:
            ax.plot(c["t"], c["sigma"], c.get("style", "-"), label=c["label"], ms=3)
        if synthetic is not None:
            ax.plot(synthetic["t"], synthetic["sigma"], ".", color="0.5", label="SYNTHETIC record (FE + 1 % noise)")
            ax.plot(synthetic["fit_t"], synthetic["fit_sigma"], "r:", lw=1.5, label=synthetic["fit_label"])
        ax.set_xlabel("time t (s)")
        ax.set_ylabel("nominal stress F / A_mid (Pa)")
        ax.grid(alpha=0.3)
        if log:
            ax.set_xscale("log")
    axes[0].legend(fontsize=7)
    fig.suptitle(label)
    fig.tight_layout()
    return fig
