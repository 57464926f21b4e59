r"""The report's charts: accuracy against wall time and the stability map, one function per panel.

Inputs are the ``pandas.DataFrame`` tables of :mod:`tissuemech.compare.studies.accuracy` and
:mod:`tissuemech.compare.studies.stability`; each ``*_panel(ax, ...)`` draws one panel on a
matplotlib axis, and ``accuracy_chart`` / ``stability_charts`` assemble figures (Agg backend,
nothing is shown or saved here).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from tissuemech.compare.plots import pyplot as _plt

__all__ = [
    "accuracy_chart",
    "stability_charts",
    "limit_point_panel",
    "kappa_panel",
    "viscous_step_panel",
    "stiff_solver_panel",
    "compression_panel",
]


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


def limit_point_panel(ax, limit: pd.DataFrame) -> None:
    """Largest pressure reached / exact p_max per outer radius and method (neo-Hookean limit point)."""
    for method, g in limit.groupby("method", sort=False):
        ax.plot(g.B_um, g.p_reached_Pa / g.p_max_exact_Pa, "o-", label=method)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel("outer radius B (um), neo-Hookean")
    ax.set_ylabel("largest pressure reached / exact p_max")
    ax.set_title("limit point: load control stops, arc-length passes")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)


def kappa_panel(ax, kappa: pd.DataFrame) -> None:
    """Inner-stretch error vs kappa/C, mixed u-p against displacement-only."""
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


def viscous_step_panel(ax, viscous: pd.DataFrame, tolerance: float = 1e-3) -> None:
    """Force error of each viscoelastic update formula vs the time step."""
    for u, g in viscous.groupby("update", sort=False):
        ax.loglog(g.step_s, np.maximum(g.error, 1e-16), "o-", ms=3, label=u)
    ax.axhline(tolerance, color="r", lw=0.8, label=f"tolerance {tolerance:g}")
    ax.set_ylim(1e-10, 10)
    ax.set_xlabel("time step h (s)  [tau = 200 s, ramp 0.2 s]")
    ax.set_ylabel("max force error / max force")
    ax.set_title("viscoelastic update: largest step keeping 1e-3")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")


def stiff_solver_panel(ax, stiff: pd.DataFrame) -> None:
    """Accepted + rejected diffrax steps vs tau / ramp time, explicit against implicit."""
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


def compression_panel(ax, compression: pd.DataFrame | None) -> None:
    """Static compression depth: plate force vs total approach / diameter."""
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
    limit_point_panel(axes[0, 0], limit)
    kappa_panel(axes[0, 1], kappa)
    viscous_step_panel(axes[0, 2], viscous, tolerance)
    stiff_solver_panel(axes[1, 0], stiff)
    compression_panel(axes[1, 1], compression)
    axes[1, 2].axis("off")
    fig.tight_layout()
    return fig
