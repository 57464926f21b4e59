r"""The seed's figures and the report's charts, as functions of already computed data.

Every function takes results (FE result objects, numpy arrays, ``pandas.DataFrame`` tables from
``compare.accuracy`` / ``compare.stability``) and returns a ``matplotlib.figure.Figure`` (Agg
backend, nothing is shown or saved here; ``compare.report`` saves them). Units on the axes: um, Pa,
s, as in the seed.

Blastula (scene 1): ``fig3`` (von Mises on the deformed wall + exact through-wall profile vs FE),
``fig_stretch_pressure`` (Figs 4 and 5: FE lines, exact markers, the arc-length trace through the
neo-Hookean limit point). Spheroid (scene 2): ``fig8`` (von Mises on the deformed section at two
times), ``fig9`` (mean von Mises vs time), ``fig10`` (nominal stress vs time, FE / reduced / a fit
to a synthetic record). Charts: ``accuracy_chart`` (log-log error vs wall time, Pareto front),
``stability_charts`` (the four/five panels of the stability map).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

UM = 1e-6

__all__ = [
    "fig3",
    "fig_stretch_pressure",
    "fig8",
    "fig9",
    "fig10",
    "accuracy_chart",
    "stability_charts",
    "element_radius",
]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


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


# ---------------------------------------------------------------------------------------------
# Charts
# ---------------------------------------------------------------------------------------------


def accuracy_chart(df: pd.DataFrame, *, title: str, floor: float = 1e-16):
    """Log-log error vs wall time, one marker style per method family, Pareto front joined in red."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.5, 5))
    d = df[np.isfinite(df.wall_s.to_numpy(float)) & np.isfinite(df.error.to_numpy(float))].copy()
    d["err_plot"] = np.maximum(d.error.to_numpy(float), floor)
    markers = iter("osD^vP*X")
    for method, g in d.groupby("method", sort=False):
        ax.plot(g.wall_s, g.err_plot, next(markers), ms=7, mfc="none", label=method)
        for _, r in g.iterrows():
            ax.annotate(
                str(r.setting).replace("mesh ", ""),
                (r.wall_s, r.err_plot),
                textcoords="offset points",
                xytext=(4, 3),
                fontsize=6,
            )
    front = d[d.pareto.astype(bool)].sort_values("wall_s")
    ax.plot(front.wall_s, front.err_plot, "r-", lw=1, alpha=0.7, label="Pareto front")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time per solve (s)")
    ax.set_ylabel("relative error")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def stability_charts(
    *,
    limit: pd.DataFrame,
    kappa: pd.DataFrame,
    viscous: pd.DataFrame,
    stiff: pd.DataFrame,
    compression: pd.DataFrame | None = None,
    tolerance: float = 1e-3,
):
    """The stability map: limit point, locking vs kappa/C, viscous step, stiff solvers, compression depth."""
    plt = _plt()
    fig, axes = plt.subplots(2, 3, figsize=(16, 9))
    ax = axes[0, 0]
    for method, g in limit.groupby("method", sort=False):
        ax.plot(g.B_um, g.p_reached_Pa / g.p_max_exact_Pa, "o-", label=method)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel("outer radius B (um), neo-Hookean")
    ax.set_ylabel("largest pressure reached / exact p_max")
    ax.set_title("limit point: load control stops, arc-length passes")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)

    ax = axes[0, 1]
    for form, g in kappa.groupby("formulation", sort=False):
        ok = ~g.failed.astype(bool)
        (ln,) = ax.loglog(g.kappa_over_C[ok], g.error[ok], "o-", label=form)
        if (~ok).any():
            ax.plot(
                g.kappa_over_C[~ok],
                np.full((~ok).sum(), 1.0),
                "x",
                color=ln.get_color(),
                ms=10,
                label=f"{form}: Newton failed",
            )
    k = np.geomspace(kappa.kappa_over_C.min(), kappa.kappa_over_C.max(), 50)
    ax.loglog(
        k,
        1.0 / k * kappa.error[kappa.formulation == "mixed"].iloc[0] * kappa.kappa_over_C.iloc[0],
        "k:",
        lw=0.8,
        label="~ C/kappa",
    )
    ax.set_xlabel("kappa / C")
    ax.set_ylabel("inner-stretch error vs incompressible exact")
    ax.set_title("locking: displacement-only vs mixed u-p")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")

    ax = axes[0, 2]
    for u, g in viscous.groupby("update", sort=False):
        ax.loglog(g.step_s, np.maximum(g.error, 1e-16), "o-", ms=3, label=u)
    ax.axhline(tolerance, color="r", lw=0.8, label=f"tolerance {tolerance:g}")
    ax.set_ylim(1e-10, 10)
    ax.set_xlabel("time step h (s)  [tau = 200 s, ramp 0.2 s]")
    ax.set_ylabel("max force error / max force")
    ax.set_title("viscoelastic update: largest step keeping 1e-3")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")

    ax = axes[1, 0]
    for s, g in stiff.groupby("solver", sort=False):
        ok = ~g.failed.astype(bool)
        (ln,) = ax.loglog(g.tau_over_ramp[ok], g.steps[ok] + g.rejected[ok], "o-", label=f"{s}")
        if (~ok).any():
            ax.plot(
                g.tau_over_ramp[~ok],
                g.steps[~ok] + g.rejected[~ok],
                "x",
                color=ln.get_color(),
                ms=10,
                label=f"{s}: failed (max_steps)",
            )
    ax.set_xlabel("tau / ramp time")
    ax.set_ylabel("solver steps (accepted + rejected)")
    ax.set_title("stiffness: explicit vs implicit diffrax")
    ax.invert_xaxis()
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")

    ax = axes[1, 1]
    if compression is not None and len(compression):
        ok = compression.converged.astype(bool)
        ax.plot(100 * compression.fraction[ok], compression.force_N[ok] * 1e6, "o-", label="converged")
        if (~ok).any():
            ax.plot(100 * compression.fraction[~ok], np.zeros((~ok).sum()), "rx", ms=10, label="failed")
        ax.axvline(40, color="k", ls=":", lw=0.8, label="target 40 %")
        ax.set_xlabel("total approach / diameter (%)")
        ax.set_ylabel("plate force (uN)")
        ax.legend(fontsize=7)
    else:
        ax.text(0.5, 0.5, "spheroid FE not available", ha="center", va="center", transform=ax.transAxes)
    ax.set_title("static compression depth (spheroid FE)")
    ax.grid(alpha=0.3)
    axes[1, 2].axis("off")
    fig.tight_layout()
    return fig
