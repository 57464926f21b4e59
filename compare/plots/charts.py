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


# marker styles that stay visible when two series coincide: a large hollow one around a small filled one
_STYLES = (
    dict(marker="o", ms=9, mfc="none", mew=1.3),
    dict(marker="s", ms=4),
    dict(marker="^", ms=8, mfc="none"),
    dict(marker="D", ms=4),
    dict(marker="v", ms=8, mfc="none"),
)
_FAIL_STYLES = (dict(marker="+", ms=15, mew=1.5), dict(marker="x", ms=8, mew=1.5))


def _legend_below(ax, ncol: int = 1) -> None:
    """The axis's legend under it, outside the data (constrained layout makes room for it)."""
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=ncol, frameon=False)


def _spread_labels(y: np.ndarray, min_sep: float) -> np.ndarray:
    """Label positions (log10) at least ``min_sep`` apart, as close to ``y`` as the order allows."""
    order = np.argsort(y)
    out = np.array(y, float)
    for k in range(1, len(order)):
        a, b = order[k - 1], order[k]
        out[b] = max(out[b], out[a] + min_sep)
    shift = np.mean(out - y)  # re-centre the stack on the points
    return out - shift


def accuracy_chart(df: pd.DataFrame, *, title: str, floor: float = 1e-16, note: str = ""):
    """Log-log error vs wall time: one marker per method, timing spread as horizontal bars, Pareto front.

    Labels sit to the right of their points, stacked so they never overlap, with a leader line.
    ``df`` columns: method, setting, ``wall_time [s]``, error, pareto and optionally
    ``wall_time min [s]`` / ``wall_time max [s]``.
    """
    plt = _plt()
    fig, ax = plt.subplots(figsize=(9, 6))
    d = df[np.isfinite(df["wall_time [s]"].to_numpy(float)) & np.isfinite(df.error.to_numpy(float))].copy()
    d["err_plot"] = np.maximum(d.error.to_numpy(float), floor)
    markers = iter("osD^vP*X")
    span = np.log10(d.err_plot.max()) - np.log10(d.err_plot.min())
    min_sep = max(0.06 * span, 0.25)  # decades between stacked labels: about one line of text
    labels: list[tuple] = []  # (x, y, label x, text, colour) of every point
    for method, g in d.groupby("method", sort=False):
        x = g["wall_time [s]"].to_numpy(float)
        y = g.err_plot.to_numpy(float)
        right = x.max()  # labels start right of the points and of their timing bars
        if "wall_time min [s]" in g and "wall_time max [s]" in g:
            lo, hi = g["wall_time min [s]"].to_numpy(float), g["wall_time max [s]"].to_numpy(float)
            right = max(right, float(np.nanmax(hi)))
            xerr = np.vstack([x - lo, hi - x])
            (ln,) = ax.plot(x, y, next(markers), ms=7, mfc="none", label=method)
            ax.errorbar(x, y, xerr=np.maximum(xerr, 0), fmt="none", ecolor=ln.get_color(), lw=0.8, capsize=2)
        else:
            (ln,) = ax.plot(x, y, next(markers), ms=7, mfc="none", label=method)
        labels += [(xi, yi, right * 2.5, text, ln.get_color()) for xi, yi, text in zip(x, y, g.setting.astype(str))]
    # stacked over ALL methods: two methods' points at about the same place get labels one line apart
    ly: np.ndarray = 10 ** _spread_labels(np.log10([lab[1] for lab in labels]), min_sep) if labels else np.zeros(0)
    for (xi, yi, lx, text, color), lyi in zip(labels, ly):
        ax.annotate(
            text.replace("mesh ", ""),
            (xi, yi),
            xytext=(lx, lyi),
            textcoords="data",
            fontsize=7,
            color=color,
            va="center",
            arrowprops=dict(arrowstyle="-", color=color, lw=0.5, alpha=0.6),
            bbox=dict(fc="white", ec="none", alpha=0.8, pad=0.3),  # readable over grid and front lines
            zorder=5,
        )
    front = d[d.pareto.astype(bool)].sort_values("wall_time [s]")
    ax.plot(
        front["wall_time [s]"],
        front.err_plot,
        "o-",
        color="r",
        ms=12,
        mfc="none",
        lw=1,
        alpha=0.7,
        label="Pareto front (dominance beyond the timing spread)",
    )
    ax.set_xscale("log")
    ax.set_yscale("log")
    xmin, xmax = d["wall_time [s]"].min(), d["wall_time [s]"].max()
    ax.set_xlim(xmin / 3, max(lab[2] for lab in labels) * 60 if labels else xmax * 150)  # room for the labels
    if len(ly):  # the stacked labels may sit above / below every point: keep them inside the axes
        ys = np.concatenate([d.err_plot.to_numpy(float), ly])
        ax.set_ylim(ys.min() / 3, ys.max() * 3)
    ax.set_xlabel("wall time per solve (s): the fastest of repeated calls after a warm-up; bars: min..max")
    ax.set_ylabel("relative error")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3, which="both")
    # outside the axes: no data point or label can hide behind it
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    if note:
        import textwrap

        fig.text(0.01, 0.01, "\n".join(textwrap.wrap(note, 150)), fontsize=7, va="bottom")
    fig.tight_layout(rect=(0, 0.06 if note else 0, 1, 1))
    return fig


def limit_point_panel(ax, limit: pd.DataFrame) -> None:
    """Relative distance of the largest pressure reached from the exact p_max, per geometry and method.

    Three separate geometries: markers side by side per outer radius (no lines between them); symlog
    y so that the sign (below / past the limit) and the size (1e-6 .. 1e-2) both read.
    """
    bs = sorted(limit["B [um]"].unique())
    methods = list(dict.fromkeys(limit.method))
    width = 0.7 / max(len(methods), 1)
    for k, (method, mk) in enumerate(zip(methods, "so^Dv")):
        g = limit[limit.method == method].set_index("B [um]")
        xs = [bs.index(b) - 0.35 + width * (k + 0.5) for b in g.index]
        ax.plot(xs, g["p reached [Pa]"] / g["p max exact [Pa]"] - 1, mk, ms=8, mfc="none", ls="none", label=method)
    ax.set_yscale("symlog", linthresh=1e-7)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xticks(range(len(bs)), [f"B = {b:g} um" for b in bs])
    ax.set_xlim(-0.6, len(bs) - 0.4)
    ax.set_xlabel("geometry (outer radius B; A = 50 um)")
    ax.set_ylabel("p_reached / p_max,exact - 1 (symlog)")
    ax.set_title("neo-Hookean limit point: load control stops below (< 0),\narc-length passes it", fontsize=9)
    _legend_below(ax, ncol=3)
    ax.grid(alpha=0.3, axis="y")


def kappa_panel(ax, kappa: pd.DataFrame) -> None:
    """Inner-stretch error vs kappa/C, mixed u-p against displacement-only; Newton failures on a top band."""
    ok_all = ~kappa.failed.astype(bool)
    top = 3.0 * float(np.nanmax(kappa.error[ok_all])) if ok_all.any() else 1.0
    for k, (form, g) in enumerate(kappa.groupby("formulation", sort=False)):
        ok = ~g.failed.astype(bool)
        (ln,) = ax.loglog(g.kappa_over_C[ok], g.error[ok], "-", label=form, **_STYLES[k % len(_STYLES)])
        if (~ok).any():
            ax.plot(
                g.kappa_over_C[~ok],
                np.full((~ok).sum(), top),
                color=ln.get_color(),
                ls="none",
                label=f"{form}: Newton failed (no error; drawn on the top band)",
                **_FAIL_STYLES[k % len(_FAIL_STYLES)],
            )
    if (~ok_all).any():
        ax.axhline(top, color="0.6", lw=0.6, ls=":")
        ax.set_ylim(top=top * 3)
    kk = np.geomspace(kappa.kappa_over_C.min(), kappa.kappa_over_C.max(), 50)
    ax.loglog(
        kk,
        1.0 / kk * kappa.error[kappa.formulation == "mixed"].iloc[0] * kappa.kappa_over_C.iloc[0],
        "k:",
        lw=0.8,
        label="~ C/kappa (physical compressibility)",
    )
    ax.set_xlabel("kappa / C (bulk over shear-like modulus, -)")
    ax.set_ylabel("inner-stretch error vs incompressible exact (-)")
    ax.set_title("locking: displacement-only vs mixed u-p\n(alpha = 0.2, B = 75 um)", fontsize=9)
    _legend_below(ax)
    ax.grid(alpha=0.3, which="both")


def viscous_step_panel(ax, viscous: pd.DataFrame, tolerance: float = 1e-3) -> None:
    """Force error of each viscoelastic update formula vs the time step."""
    for k, (u, g) in enumerate(viscous.groupby("update", sort=False)):
        ax.loglog(g["step [s]"], np.maximum(g.error, 1e-16), "-", label=u, **_STYLES[k % len(_STYLES)])
    ax.axhline(tolerance, color="r", lw=0.8, label=f"tolerance {tolerance:g}")
    ax.set_ylim(1e-10, 10)
    ax.set_xlabel("time step h (s)  [tau = 200 s, ramp 0.2 s]")
    ax.set_ylabel("max force error / max force (-)")
    ax.set_title("viscoelastic update: largest step keeping 1e-3\n(one Maxwell branch, exact solution)", fontsize=9)
    _legend_below(ax, ncol=2)
    ax.grid(alpha=0.3, which="both")


def stiff_solver_panel(ax, stiff: pd.DataFrame) -> None:
    """Accepted + rejected diffrax steps vs tau / ramp time, explicit against implicit.

    Explicit solvers that nearly coincide (Tsit5 and Dopri5 take nearly as many steps) stay visible: a large hollow
    marker around a small filled one, and '+' around 'x' where they gave up.
    """
    for k, (name, g) in enumerate(stiff.groupby("solver", sort=False)):
        ok = ~g.failed.astype(bool)
        (ln,) = ax.loglog(
            g.tau_over_ramp[ok], g.steps[ok] + g.rejected[ok], "-", label=f"{name}", **_STYLES[k % len(_STYLES)]
        )
        if (~ok).any():
            ax.plot(
                g.tau_over_ramp[~ok],
                g.steps[~ok] + g.rejected[~ok],
                color=ln.get_color(),
                ls="none",
                label=f"{name}: gave up (steps taken when max_steps was hit)",
                **_FAIL_STYLES[k % len(_FAIL_STYLES)],
            )
    ax.set_xlabel("tau / ramp time (-)")
    ax.set_ylabel("solver steps (accepted + rejected)")
    ax.set_title("stiffness: explicit vs implicit diffrax\n(same ODE, rtol = atol = 1e-8)", fontsize=9)
    ax.invert_xaxis()
    _legend_below(ax, ncol=2)
    ax.grid(alpha=0.3, which="both")


def compression_panel(ax, compression: pd.DataFrame | None, seed_depth: float = 0.3, cap: float = 0.8) -> None:
    """Static compression depth: plate force vs total approach / diameter, how the push ended."""
    if compression is not None and len(compression):
        ok = compression.converged.astype(bool)
        ax.plot(100 * compression.fraction[ok], compression["force [N]"][ok] * 1e6, "o-", label="converged")
        bad = compression[~ok]
        if len(bad):
            ax.plot(100 * bad.fraction, np.zeros(len(bad)), "rx", ms=10, mew=1.5, ls="none", label="not converged")
        for _, r in bad.iterrows():
            ax.annotate(
                f"{r.failure}",
                (100 * r.fraction, 0.0),
                textcoords="offset points",
                xytext=(-8, 10),
                ha="right",
                fontsize=7,
                color="r",
            )
        ax.axvline(100 * seed_depth, color="k", ls=":", lw=0.8, label=f"seed: static runs to {100 * seed_depth:.0f} %")
        ax.axvline(
            100 * cap, color="r", ls="--", lw=0.8, label=f"fem.spheroid refuses >= {100 * cap:.0f} % (stated cap)"
        )
        ax.set_xlim(min(100 * compression.fraction.min(), 100 * seed_depth) - 5, 100 * cap + 5)
        _legend_below(ax, ncol=2)
    else:
        ax.text(0.5, 0.5, "spheroid FE not available", ha="center", va="center", transform=ax.transAxes)
    ax.set_xlabel("total approach / diameter (%)")
    ax.set_ylabel("plate force (uN)")
    ax.set_title(
        "static compression depth (spheroid FE, alpha = 0.2,\nC = 200 Pa): pushed to failure or cap", fontsize=9
    )
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
    """The stability map: limit point, locking vs kappa/C, viscous step, stiff solvers, compression depth.

    Five panels (three above, two centred below; no empty one), each legend under its panel, off the data.
    """
    plt = _plt()
    fig = plt.figure(figsize=(16, 10.5))
    # fixed spacing (not constrained layout, which collapses with wide legends): room under each row for its
    # legends, which sit below their panels
    axes = fig.subplot_mosaic(
        "AABBCC;.DDEE.",
        gridspec_kw=dict(left=0.06, right=0.985, top=0.91, bottom=0.14, hspace=0.68, wspace=1.3),
    )
    limit_point_panel(axes["A"], limit)
    kappa_panel(axes["B"], kappa)
    viscous_step_panel(axes["C"], viscous, tolerance)
    stiff_solver_panel(axes["D"], stiff)
    compression_panel(axes["E"], compression)
    fig.suptitle("Stability map: each method pushed until it fails (tables: stability_*.csv)", fontsize=11)
    return fig


def time_convergence_chart(df: pd.DataFrame, *, title: str):
    """Log-log error vs ramp steps of a time-convergence table (``compare.studies.accuracy.spheroid_time_convergence``):
    the FE with fixed steps (one line per output time, and their max), the FE with adaptive steps (markers, labelled
    with their tol) and the lumped recursion's estimate of the same error (dashed)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 6.5), layout="constrained")
    fx = df[df.method == "FE fixed"]
    ad = df[df.method == "FE adaptive"]
    cols = [c for c in df.columns if c.startswith("error ") and c.endswith(" s")]
    for c in cols:
        ax.loglog(fx.ramp_steps, np.abs(fx[c].to_numpy(float)), "-", lw=1, alpha=0.6, label=f"FE fixed, t = {c[6:]}")
    ax.loglog(fx.ramp_steps, fx.error, "k-o", ms=5, label="FE fixed, max over the times")
    ax.loglog(fx.ramp_steps, fx["lumped estimate"], "k--", lw=1, label="lumped estimate (fixed), max")
    ax.loglog(ad.ramp_steps, ad.error, "rs", ms=8, mfc="none", label="FE adaptive, max")
    ax.loglog(ad.ramp_steps, ad["lumped estimate"], "r+", ms=9, label="lumped estimate (adaptive)")
    for r in ad.itertuples():
        ax.annotate(str(r.setting), (r.ramp_steps, r.error), textcoords="offset points", xytext=(6, 6), fontsize=8)
    n = fx.ramp_steps.to_numpy(float)
    if n.size:
        e0 = float(fx.error.iloc[0])
        ax.loglog(n, e0 * (n / n[0]) ** -2.0, ":", color="grey", label="slope -2")
    ax.set_xlabel("ramp steps")
    ax.set_ylabel("|F / F_ref - 1|")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    _legend_below(ax, ncol=2)
    return fig
