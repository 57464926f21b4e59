r"""Plots of a parameter scan (tables from ``compare.scan.spheroid`` / ``compare.scan.blastula``).

Every plotting function takes a scan table (unit-labelled columns, SI values) and returns a
``matplotlib.figure.Figure`` (nothing is shown or saved here; the backend is the caller's: the
``tissuemech scan`` command draws with Agg). Axes show um for
lengths, Pa, s and "-" for dimensionless quantities, as ``compare.figures`` does.

* :func:`summary_map` / :func:`summary_maps`: a summary quantity over two varied parameters, the others
  averaged (or held at chosen values with ``fixed=``), on the design's own grid (grid designs) or on
  bins (random / Latin hypercube designs); FE spot-checks drawn at their design coordinates and
  labelled with their deviation from the reduced model.
* :func:`curve_bundle`: relaxation curves (spheroid, needs ``curves=True``) or pressure-stretch
  curves of the exact shell (blastula), coloured by one parameter.
* :func:`parity_plot`: reduced vs FE at the spot-checks, coloured by the deviation.
* :func:`sensitivity_chart`: which parameter drives which summary (``compare.scan.sensitivities``: exact JAX
  derivatives of the reduced model at points of the design).

Spheroid summaries: ``sigma_peak`` (nominal stress at the end of the ramp), ``sigma_end``,
``relaxed_fraction``, ``t_half``. Blastula: ``inner_stretch`` (at the point's pressure),
``p_limit`` (burst pressure), ``bursts`` (a map of it is the fraction of points that burst).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from tissuemech.compare import scan
from tissuemech.compare.plots import pyplot

__all__ = [
    "SPHEROID_SUMMARIES",
    "BLASTULA_SUMMARIES",
    "axis_label",
    "display_values",
    "summary_map",
    "summary_maps",
    "curve_bundle",
    "parity_plot",
    "sensitivity_chart",
]

SPHEROID_SUMMARIES = scan.SPHEROID_SUMMARIES
BLASTULA_SUMMARIES = scan.BLASTULA_SUMMARIES

# plot labels (symbol, words); units come from scan.UNITS, lengths shown in um
_LABELS = {
    "radius": "radius a0",
    "C": "Fung stiffness C",
    "alpha": "Fung exponent alpha",
    "beta": "energy factor beta",
    "tau": "relaxation time tau",
    "displacement": "plate approach delta",
    "ramp_time": "ramp time t_r",
    "inner_radius": "inner radius A",
    "outer_radius": "outer radius B",
    "pressure": "pressure p",
    "sigma_peak": "stress at end of ramp",
    "sigma_end": "stress at end of hold",
    "relaxed_fraction": "relaxed fraction 1 - end/peak",
    "t_half": "half-relaxation time",
    "inner_stretch": "inner stretch a/A",
    "outer_stretch": "outer stretch b/B",
    "p_limit": "burst (limit) pressure",
    "bursts": "fraction of points that burst",
    "deviation": "deviation reduced vs FE",
}
_DISPLAY = {"m": ("um", 1e6)}  # SI unit -> (shown unit, factor)
_MAX_GRID_LEVELS = 60  # an axis with at most this many distinct values is drawn on its own values


def _unit(name: str) -> str:
    return scan.UNITS.get(name, "-")


def axis_label(name: str) -> str:
    """``"C"`` -> ``"Fung stiffness C (Pa)"``; lengths in um."""
    unit = _unit(name)
    shown = _DISPLAY.get(unit, (unit, 1.0))[0]
    return f"{_LABELS.get(name, name)} ({shown})"


def display_values(table: pd.DataFrame, name: str) -> np.ndarray:
    """Column ``name`` (plain name) in the units the plots show (lengths in um)."""
    factor = _DISPLAY.get(_unit(name), ("", 1.0))[1]
    v = table[scan.column(name)].to_numpy()
    return v.astype(float) * factor


def _check_quantity(table: pd.DataFrame, name: str) -> None:
    if name not in scan.UNITS or scan.column(name) not in table.columns:
        have = [scan.split_column(c)[0] for c in table.columns if table[c].dtype != object]
        raise ValueError(f"{name!r} is not a column of this scan table; it has {have}")


def _axis_bins(v: np.ndarray, log: bool, nbins: int | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """(centres, edges, index of each value, is_grid) for one map axis."""
    levels = np.unique(v)
    f = np.log if log else (lambda a: a)
    finv = np.exp if log else (lambda a: a)
    if levels.size <= _MAX_GRID_LEVELS and nbins is None:
        c = f(levels)
        if c.size == 1:
            edges = np.array([c[0] - 0.5, c[0] + 0.5]) if not log else np.array([c[0] - 0.1, c[0] + 0.1])
        else:
            mid = 0.5 * (c[1:] + c[:-1])
            edges = np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])
        return levels, finv(edges), np.searchsorted(levels, v), True
    nb = nbins or int(np.clip(np.sqrt(v.size / 40.0), 8, 30))  # >= ~40 points per cell on average (2 axes)
    lo, hi = f(levels[0]), f(levels[-1])
    edges = np.linspace(lo, hi, nb + 1)
    idx = np.clip(np.searchsorted(edges, f(v), side="right") - 1, 0, nb - 1)
    return finv(0.5 * (edges[1:] + edges[:-1])), finv(edges), idx, False


def _plain_log_ticks(axis) -> None:
    """Log-axis ticks as plain numbers (20, 50, 100), not 2 x 10^1."""
    import matplotlib as mpl

    fmt = mpl.ticker.FuncFormatter(lambda v, _pos: f"{v:g}")
    axis.set_major_formatter(fmt)
    axis.set_minor_formatter(mpl.ticker.FuncFormatter(lambda v, _pos: f"{v:g}" if f"{v:.1e}"[0] in "25" else ""))


def _select_fixed(table: pd.DataFrame, fixed: Mapping[str, float] | None, log: Sequence[str] | None):
    """Rows of the table at the chosen values of other parameters, and a text saying which."""
    if not fixed:
        return np.ones(len(table), dtype=bool), []
    keep = np.ones(len(table), dtype=bool)
    notes = []
    for k, target in fixed.items():
        _check_quantity(table, k)
        v = display_values(table, k)
        t = float(target) * _DISPLAY.get(_unit(k), ("", 1.0))[1]
        levels = np.unique(v)
        shown = _DISPLAY.get(_unit(k), (_unit(k), 1.0))[0]
        if levels.size <= _MAX_GRID_LEVELS:
            near = levels[np.argmin(np.abs(levels - t))]
            keep &= v == near
            notes.append(f"{k} = {near:.4g} {shown}")
        else:  # scattered design: a band of 10 % of the parameter's range around the value
            lg = scan.is_log_sampled(v, k, log)
            f = np.log if lg else (lambda a: a)
            half = 0.05 * (f(levels[-1]) - f(levels[0]))
            keep &= np.abs(f(v) - f(t)) <= half
            notes.append(f"{k} = {t:.4g} {shown} (+-5 % of its range)")
    if not keep.any():
        raise ValueError(f"no scan point at the fixed values {dict(fixed)}")
    return keep, notes


def summary_map(
    table: pd.DataFrame,
    quantity: str,
    x: str,
    y: str,
    *,
    fixed: Mapping[str, float] | None = None,
    log: Sequence[str] | None = None,
    bins: int | None = None,
    fe: bool = True,
    ax: Any = None,
    cmap: str | None = None,
    color_log: bool | None = None,
):
    """Map of ``quantity`` over parameters ``x`` and ``y`` (plain names), with the FE spot-checks.

    table     a scan table (``scan.spheroid`` / ``scan.blastula``).
    quantity  a summary column, e.g. "sigma_peak", "relaxed_fraction", "t_half", "inner_stretch",
              "p_limit", "bursts" (shown as the fraction of points that burst).
    fixed     parameter -> value (SI units): use only the points at that value (grid: the nearest
              level; scattered designs: a band of +-5 % of the range). Other varied parameters are
              averaged (NaN values, e.g. stretch of a burst shell, are left out of the average; cells
              without a value are grey).
    log       parameters drawn on log axes (default: those positive, spanning >= 20x and sampled
              log-uniformly, i.e. with their median nearer the geometric than the arithmetic middle).
    bins      cells per axis for scattered designs (default sqrt(points / 40), 8..30).
    color_log log colour scale (default: for positive quantities spanning >= 8x, e.g. stretches
              1..9, half-relaxation times over decades of tau).
    fe        draw the FE spot-checks (rows with a ``deviation [-]``) at their (x, y) design
              coordinates (white circles, ``gid="fe-checks"``), each labelled with its deviation in %.
    ax        an Axes to draw on (default: a new figure).
    Returns the Figure. Raises ValueError for unknown columns or x == y.
    """
    plt = pyplot()
    for k in (quantity, x, y):
        _check_quantity(table, k)
    if x == y:
        raise ValueError(f"x and y must be two different parameters; got {x!r} twice")
    keep, notes = _select_fixed(table, fixed, log)
    xv_all, yv_all = display_values(table, x), display_values(table, y)
    xlog, ylog = scan.is_log_sampled(xv_all, x, log), scan.is_log_sampled(yv_all, y, log)
    xc, xe, xi, _ = _axis_bins(xv_all, xlog, bins)
    yc, ye, yi, _ = _axis_bins(yv_all, ylog, bins)
    z = display_values(table, quantity) if quantity != "bursts" else table[scan.column(quantity)].to_numpy(float)
    ok = keep & np.isfinite(z)
    flat = xi[ok] * yc.size + yi[ok]
    total = np.bincount(flat, weights=z[ok], minlength=xc.size * yc.size)
    count = np.bincount(flat, minlength=xc.size * yc.size)
    with np.errstate(invalid="ignore", divide="ignore"):
        Z = np.where(count > 0, total / np.maximum(count, 1), np.nan).reshape(xc.size, yc.size)

    if ax is None:
        fig, ax = plt.subplots(figsize=(5.6, 4.6))
    else:
        fig = ax.figure
    ax.set_facecolor("0.82")  # cells without a value
    if cmap is None:
        cmap = "coolwarm" if quantity == "bursts" else "viridis"
    import matplotlib as mpl

    zf = Z[np.isfinite(Z)]
    if color_log is None:
        color_log = quantity != "bursts" and bool(zf.size and zf.min() > 0 and zf.max() / zf.min() >= 8.0)
    if quantity == "bursts":
        norm = mpl.colors.Normalize(0.0, 1.0)
    elif color_log and zf.size and zf.min() > 0:
        norm = mpl.colors.LogNorm(zf.min(), zf.max())
    else:
        norm = None
    mesh = ax.pcolormesh(xe, ye, Z.T, cmap=cmap, shading="flat", norm=norm)
    mesh.set_gid("map")
    cb = fig.colorbar(mesh, ax=ax)
    cb.set_label(axis_label(quantity) if quantity != "bursts" else "fraction of points that burst (-)")
    if isinstance(norm, mpl.colors.LogNorm):
        _plain_log_ticks(cb.ax.yaxis)
    if xlog:
        ax.set_xscale("log")
        _plain_log_ticks(ax.xaxis)
    if ylog:
        ax.set_yscale("log")
        _plain_log_ticks(ax.yaxis)
    ax.set_xlim(xe[0], xe[-1])
    ax.set_ylim(ye[0], ye[-1])
    ax.set_xlabel(axis_label(x))
    ax.set_ylabel(axis_label(y))
    others = [k for k in scan.varied_parameters(table) if k not in (x, y) and k not in (fixed or {})]
    how = []
    if others:
        how.append("mean over " + ", ".join(others))
    how += notes
    ax.set_title(_LABELS.get(quantity, quantity) + ("\n" + "; ".join(how) if how else ""), fontsize=9)

    if quantity == "bursts" and "pressure" in (x, y) and scan.column("p_limit") in table.columns:
        _limit_line(ax, table, keep, x, y, xc, xi, yc, yi)
    if fe and scan.column("deviation") in table.columns:
        _fe_points(ax, table, x, y)
    return fig


def _limit_line(ax, table, keep, x, y, xc, xi, yc, yi) -> None:
    """Mean burst pressure along the other map axis (blastula maps with pressure as an axis)."""
    p_lim = table[scan.column("p_limit")].to_numpy(float)
    other_c, other_i = (xc, xi) if y == "pressure" else (yc, yi)
    line = np.full(other_c.size, np.nan)
    for j in range(other_c.size):
        sel = keep & (other_i == j) & np.isfinite(p_lim)
        if sel.any():
            line[j] = p_lim[sel].mean()
    if np.isfinite(line).any():
        args = (other_c, line) if y == "pressure" else (line, other_c)
        ax.plot(*args, "k-", lw=1.6, label="burst pressure (exact shell, mean)")
        ax.legend(fontsize=7, loc="upper left")


def _fe_points(ax, table: pd.DataFrame, x: str, y: str) -> None:
    dev = table[scan.column("deviation")].to_numpy(float)
    sel = np.isfinite(dev)
    if not sel.any():
        return
    xv, yv = display_values(table, x)[sel], display_values(table, y)[sel]
    pts = ax.scatter(xv, yv, s=46, facecolor="white", edgecolor="black", linewidth=1.3, zorder=4, clip_on=False)
    pts.set_gid("fe-checks")
    pts.set_label("FE spot-check (deviation)")
    to_axes = ax.transData + ax.transAxes.inverted()
    box = ax.get_window_extent()
    w_pt, h_pt = box.width * 72 / ax.figure.dpi, box.height * 72 / ax.figure.dpi  # panel size in points
    placed: list[tuple[float, float]] = []  # label centres (points in the panel), to step clashes apart
    for a, b, d in zip(xv, yv, dev[sel]):
        fx, fy = to_axes.transform((a, b))
        right = fx > 0.78  # beside the point, on the side that keeps the label inside the panel
        dx = -7 if right else 7
        cx = fx * w_pt + (dx - 17 if right else dx + 17)
        dy = 0
        for k in range(1, 6):  # a label over an earlier one moves a line down (up near the bottom)
            if not any(abs(cx - qx) < 36 and abs(fy * h_pt + dy - qy) < 10 for qx, qy in placed):
                break
            dy = (-10 if fy > 0.15 else 10) * k
        placed.append((cx, fy * h_pt + dy))
        ax.annotate(
            f"{100 * d:.2g}%",
            (a, b),
            textcoords="offset points",
            xytext=(dx, dy),
            ha="right" if right else "left",
            va="center",
            fontsize=7.5,
            zorder=3.9,  # under the markers: a label never hides another spot-check
            annotation_clip=False,
            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8),
        )


def summary_maps(
    table: pd.DataFrame,
    quantities: Sequence[str],
    x: str,
    y: str,
    *,
    title: str | None = None,
    **kwargs: Any,
):
    """One :func:`summary_map` panel per quantity (same x, y, ``fixed``, ``log``...), side by side."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(quantities), figsize=(5.6 * len(quantities), 4.8), squeeze=False)
    for ax, q in zip(axes[0], quantities):
        summary_map(table, q, x, y, ax=ax, **kwargs)
    if title:
        fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    return fig


def _color_map(values: np.ndarray, name: str, log: Sequence[str] | None):
    import matplotlib as mpl

    lg = scan.is_log_sampled(values, name, log)
    lo, hi = float(np.min(values)), float(np.max(values))
    if hi <= lo:
        hi = lo + (abs(lo) or 1.0) * 1e-9
    norm = mpl.colors.LogNorm(lo, hi) if lg else mpl.colors.Normalize(lo, hi)
    return mpl.cm.ScalarMappable(norm=norm, cmap="plasma")


def curve_bundle(
    table: pd.DataFrame,
    color_by: str,
    *,
    max_curves: int | None = None,
    seed: int = 0,
    log: Sequence[str] | None = None,
    max_pressure: float | None = None,
    ax: Any = None,
):
    """Curves coloured by parameter ``color_by``: up to ``max_curves`` points of the design, picked at random
    (default 100 relaxation curves, 40 pressure-stretch curves).

    Spheroid: the nominal-stress relaxation curves of the table (needs ``curves=True``), against log time.
    Blastula: pressure vs inner stretch of the exact shell for the design's (A, B, C, alpha)
    combinations, from p = 0 to ``max_pressure`` (Pa; default: the largest scanned pressure); each
    curve ends where the shell bursts (limit point, marked x).
    Returns the Figure. Raises ValueError if the curves are missing or ``color_by`` is unknown.
    """
    import matplotlib as mpl

    plt = pyplot()
    _check_quantity(table, color_by)
    scene = scan.scene_of(table)
    rng = np.random.default_rng(seed)
    if ax is None:
        if scene == "spheroid":
            fig, (ax, ax_n) = plt.subplots(1, 2, figsize=(12.5, 4.6))
        else:
            fig, ax = plt.subplots(figsize=(6.8, 4.6))
            ax_n = None
    else:
        fig, ax_n = ax.figure, None
    if scene == "spheroid":
        if "sigma [Pa]" not in table.columns or "time [s]" not in table.attrs:
            raise ValueError("curve_bundle needs the curves: run scan.spheroid(..., curves=True)")
        rows = np.sort(rng.choice(len(table), size=min(max_curves or 100, len(table)), replace=False))
        cv = display_values(table, color_by)
        sm = _color_map(cv, color_by, log)
        t = np.asarray(table.attrs["time [s]"], dtype=float)
        pos = t > 0
        curves = table["sigma [Pa]"].to_numpy()
        for i in rows[np.argsort(cv[rows])]:
            s_i = np.asarray(curves[i])[pos]
            ax.plot(t[pos], s_i, "-", lw=0.9, alpha=0.75, color=sm.to_rgba(cv[i]))
            if ax_n is not None:
                ax_n.plot(t[pos], s_i / np.max(s_i), "-", lw=0.9, alpha=0.75, color=sm.to_rgba(cv[i]))
        for a in (ax, ax_n) if ax_n is not None else (ax,):
            a.set_xscale("log")
            a.set_xlabel("time since first contact t (s)")
            a.grid(alpha=0.3, which="both")
        ax.set_ylabel("nominal stress F / A_mid (Pa)")
        ax.set_title(f"relaxation curves: {rows.size} of {len(table)}, coloured by {color_by}", fontsize=10)
        if ax_n is not None:
            ax_n.set_ylabel("stress / its peak (-)")
            ax_n.set_title("the same, divided by the peak (the relaxation shape)", fontsize=10)
    else:
        import jax.numpy as jnp

        from tissuemech.reduced import blastula as red

        names = ("inner_radius", "outer_radius", "C", "alpha")
        combos = table[[scan.column(k) for k in names]].drop_duplicates().to_numpy(float)
        pick = np.sort(rng.choice(len(combos), size=min(max_curves or 40, len(combos)), replace=False))
        combos = combos[pick]
        p_top = float(max_pressure or table[scan.column("pressure")].max())
        if not p_top > 0:
            given = "max_pressure" if max_pressure else "the largest pressure of the table"
            raise ValueError(
                f"the pressure-stretch curves run from 0 Pa up to a positive pressure; {given} is {p_top:.4g} Pa"
            )
        p = np.linspace(0.0, p_top, 160)
        padded = np.concatenate([combos, np.repeat(combos[:1], 40 - len(combos) % 40 if len(combos) % 40 else 0, 0)])
        A, B, C, al = (jnp.asarray(padded[:, j])[:, None] for j in range(4))  # one shape: solver compiled once
        la = np.asarray(
            red.inner_stretch_solve(jnp.asarray(p)[None, :], inner_radius=A, outer_radius=B, C=C, alpha=al)[0]
        )[: len(combos)]
        lim = red.limit_point(inner_radius=A[:, 0], outer_radius=B[:, 0], C=C[:, 0], alpha=al[:, 0])
        if lim is None:  # only for one scalar shell without a limit point; these are arrays (NaN: none)
            raise ValueError("the limit points of the blastula curves could not be computed")
        lim_pressure = np.asarray(lim.pressure)[: len(combos)]
        lim_stretch = np.asarray(lim.inner_stretch)[: len(combos)]
        # a shell with a limit point has no equilibrium above it: the curve ends there (the solve would return the
        # re-stiffening branch beyond the limit stretch, drawn as broken fragments)
        past = np.isfinite(lim_pressure)[:, None] & (
            (p[None, :] > lim_pressure[:, None]) | (la > lim_stretch[:, None] * (1 + 1e-9))
        )
        la = np.where(past, np.nan, la)
        j = list(names).index(color_by) if color_by in names else None
        if j is None:
            raise ValueError(f"blastula curves are coloured by one of {list(names)}; got {color_by!r}")
        factor = _DISPLAY.get(_unit(color_by), ("", 1.0))[1]
        cv = combos[:, j] * factor
        sm = _color_map(cv, color_by, log)
        for i in np.argsort(cv):
            col = sm.to_rgba(cv[i])
            ax.plot(la[i], p, "-", lw=1.0, alpha=0.8, color=col)
            pl, ll = float(lim_pressure[i]), float(lim_stretch[i])
            if np.isfinite(pl) and pl <= p_top:
                ax.plot(ll, pl, "x", color=col, ms=6, mew=1.5)
        ax.set_xlabel("inner stretch a/A (-)")
        ax.set_ylabel("pressure p (Pa)")
        ax.set_title(
            f"pressure-stretch curves (exact shell): {len(combos)} design{'s' if len(combos) > 1 else ''}"
            + (f", coloured by {color_by}" if np.ptp(cv) > 0 else "")
            + "\n"
            "x: limit point (the shell bursts above it)",
            fontsize=10,
        )
    ax.grid(alpha=0.3, which="both")
    if np.ptp(cv) > 0:  # (one value of the colouring parameter: no scale to show)
        cb = fig.colorbar(sm, ax=ax_n if ax_n is not None else ax)
        cb.set_label(axis_label(color_by))
        if isinstance(sm.norm, mpl.colors.LogNorm):
            _plain_log_ticks(cb.ax.yaxis)
    fig.tight_layout()
    return fig


def parity_plot(table: pd.DataFrame, *, ax: Any = None):
    """Reduced vs FE at the FE spot-checks, coloured by the deviation (%); the diagonal and +-5 % lines.

    Spheroid: stress at the end of the ramp (circles) and of the hold (squares), Pa.
    Blastula: inner stretch a/A (-). Raises ValueError if the table has no FE spot-check.
    """
    plt = pyplot()
    scene = scan.scene_of(table)
    if scan.column("deviation") not in table.columns or not table[scan.column("deviation")].notna().any():
        raise ValueError("the table has no FE spot-checks (run the scan with fe_checks=k)")
    sel = table[scan.column("deviation")].notna().to_numpy()
    dev = 100 * table.loc[sel, scan.column("deviation")].to_numpy(float)
    if ax is None:
        fig, ax = plt.subplots(figsize=(5.8, 5.0))
    else:
        fig = ax.figure
    pairs = (
        [("sigma_peak", "fe_sigma_peak", "o", "end of ramp"), ("sigma_end", "fe_sigma_end", "s", "end of hold")]
        if scene == "spheroid"
        else [("inner_stretch", "fe_inner_stretch", "o", "inner stretch")]
    )
    import matplotlib as mpl

    # a log scale from 0.01 % (pale) to 10 % (black), so parity plots of different scans compare, widened to
    # the true extrema of this scan (a deviation below 0.01 % is shown as it is, not clipped to the pale end)
    floor = min(1e-2, max(float(np.nanmin(dev)), 1e-8)) if np.isfinite(dev).any() else 1e-2
    norm = mpl.colors.LogNorm(floor, max(10.0, float(np.nanmax(dev))))
    lo, hi = np.inf, -np.inf
    sc = None
    for red_name, fe_name, marker, label in pairs:
        r = table.loc[sel, scan.column(red_name)].to_numpy(float)
        f = table.loc[sel, scan.column(fe_name)].to_numpy(float)
        sc = ax.scatter(
            f, r, c=np.maximum(dev, floor), cmap="magma_r", norm=norm, marker=marker, s=60, edgecolor="k", label=label
        )
        fin = np.isfinite(f) & np.isfinite(r)
        if fin.any():
            lo, hi = min(lo, f[fin].min(), r[fin].min()), max(hi, f[fin].max(), r[fin].max())
    if not np.isfinite(lo):
        lo, hi = 0.0, 1.0
    pad = 0.05 * (hi - lo) if hi > lo else 0.05 * abs(hi) + 1e-12
    g = np.array([lo - pad, hi + pad])
    ax.plot(g, g, "k-", lw=0.9, label="reduced = FE")
    ax.plot(g, 1.05 * g, "k:", lw=0.8, label="+-5 %")
    ax.plot(g, 0.95 * g, "k:", lw=0.8)
    ax.set_xlim(*g)
    ax.set_ylim(*g)
    ax.set_aspect("equal")
    unit = "Pa" if scene == "spheroid" else "-"
    what = "nominal stress" if scene == "spheroid" else "inner stretch a/A"
    ax.set_xlabel(f"FE {what} ({unit})")
    ax.set_ylabel(f"reduced {what} ({unit})")
    ax.set_title(f"reduced vs FE at {int(sel.sum())} spot-checks (largest deviation {dev.max():.2g} %)", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    cb = fig.colorbar(sc, ax=ax)
    cb.set_label("deviation: largest |reduced/FE - 1| at the point (%)")
    fig.tight_layout()
    return fig


def sensitivity_chart(sens: pd.DataFrame, *, title: str | None = None):
    """Heat map of :func:`sensitivities`: rows summaries, columns parameters, colour the share (%),
    each cell labelled with the share and the direction (+: the summary grows with the parameter)."""
    plt = pyplot()
    qs = list(dict.fromkeys(sens["quantity"]))
    ps = list(dict.fromkeys(sens["parameter"]))
    S = sens.pivot(index="quantity", columns="parameter", values="share [-]").loc[qs, ps].to_numpy(float)
    D = sens.pivot(index="quantity", columns="parameter", values="direction").loc[qs, ps].to_numpy(float)
    n_pts = sens.groupby("quantity", sort=False)["points"].first().loc[qs].to_numpy()
    fig, ax = plt.subplots(figsize=(1.25 * len(ps) + 3.8, 0.75 * len(qs) + 2.2))
    im = ax.imshow(100 * S, cmap="Blues", vmin=0, vmax=100, aspect="auto")
    for i in range(len(qs)):
        for j in range(len(ps)):
            if np.isfinite(S[i, j]):
                sign = "" if S[i, j] < 0.005 else ("+" if D[i, j] > 0 else ("-" if D[i, j] < 0 else ""))
                ax.text(
                    j,
                    i,
                    f"{sign}{100 * S[i, j]:.0f}%",
                    ha="center",
                    va="center",
                    fontsize=9,
                    color="white" if S[i, j] > 0.55 else "black",
                )
    ax.set_xticks(range(len(ps)))
    ax.set_xticklabels([axis_label(k) for k in ps], rotation=25, ha="right", fontsize=8)
    ax.set_yticks(range(len(qs)))
    ax.set_yticklabels([f"{axis_label(q)}\n[{n} points]" for q, n in zip(qs, n_pts)], fontsize=8)
    cb = fig.colorbar(im, ax=ax)
    cb.set_label("share of mean |dy/du| (%)")
    ax.set_title(
        title
        or "which parameter drives which summary\n"
        "exact JAX derivatives, parameters scaled to their scan range (sign: direction)",
        fontsize=9,
    )
    fig.tight_layout()
    return fig
