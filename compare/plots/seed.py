r"""The seed's figures, as functions of already computed data.

Every function takes results (FE result objects, numpy arrays) and returns a
``matplotlib.figure.Figure`` (Agg backend, nothing is shown or saved here; ``compare.report``
saves them). Units on the axes: um, Pa, s, as in the seed.

Blastula (scene 1): ``fig3`` (von Mises on the deformed section, a zoom on the wall, the reference
section, the exact through-wall profile vs FE), ``fig_stretch_pressure`` (Figs 4 and 5: exact lines,
FE steps as markers from the unloaded state, the arc-length trace through the neo-Hookean limit point).
Fields are drawn smooth on the curved Q2 geometry (:mod:`.fields`). Spheroid (scene 2): ``fig8`` (von Mises on the deformed section at two
times), ``fig9`` (mean von Mises vs time), ``fig10`` (nominal stress vs time, FE / reduced / a fit
to a synthetic record). The report's charts are in :mod:`tissuemech.compare.plots.charts`.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from tissuemech.compare.cases import UM
from tissuemech.compare.plots import pyplot as _plt

__all__ = [
    "fig3",
    "fig_stretch_pressure",
    "fig8",
    "fig9",
    "fig10",
    "element_radius",
    "elastic_von_mises_at",
    "reference_points",
]


def element_radius(mesh) -> np.ndarray:
    """Reference radius (m) of each element's corner centroid, sqrt(R^2 + Z^2) (spherical shell)."""
    p = mesh.mesh.p[:, mesh.mesh.t[:4]].mean(axis=1)
    return np.hypot(p[0], p[1]) * mesh.length_scale


def elastic_von_mises_at(mesh, displacement: np.ndarray, ref_points: np.ndarray, *, C: float, alpha: float):
    """Von Mises stress (Pa) of an ELASTIC FE state at given points of every element: (n_el, n_points).

    mesh: an ``fem.mesh.AxiMesh`` (Q2); displacement: (N, 2) nodal displacement (m); ref_points: (2, n)
    points of the reference square [0, 1]^2; C (Pa), alpha: the Fung law. The deformation gradient comes
    from the Q2 displacement at each point and the stress from ``fem.constitutive`` (the engine's law):
    von Mises depends only on the stress deviator, which in the mixed form is the isochoric stress's (the
    pressure field adds a multiple of the identity), so it is the FE field itself, not an average (the
    results store element means). Not for viscoelastic states (their branch stresses are history).
    """
    from skfem import CellBasis

    from tissuemech.fem import constitutive as cm

    pts = np.asarray(ref_points, float)
    basis = CellBasis(mesh.mesh, mesh.basis.elem, quadrature=(pts, np.full(pts.shape[1], 1.0 / pts.shape[1])))
    L = mesh.length_scale
    u = np.asarray(displacement, float) / L  # scaled like the mesh coordinates
    ur, uz = basis.interpolate(u[:, 0]), basis.interpolate(u[:, 1])
    R = np.asarray(basis.global_coordinates())[0]  # (nel, n) scaled
    on_axis = R < 1e-12 * max(float(np.max(R)), 1.0)
    hoop = 1.0 + np.where(on_axis, ur.grad[0], np.asarray(ur) / np.where(on_axis, 1.0, R))
    f = np.stack([1.0 + ur.grad[0], ur.grad[1], uz.grad[0], 1.0 + uz.grad[1], hoop], axis=-1)
    P, _ = cm.iso_stress(f, C, alpha)
    return cm.von_mises(cm.cauchy(f, P))


# ---------------------------------------------------------------------------------------------
# Blastula
# ---------------------------------------------------------------------------------------------


def fig3(
    result: Any,
    profile: Any,
    *,
    pressure: float,
    alpha: float,
    outer_radius: float,
    inner_stretch: float | None = None,
    C: float = 200.0,
    n_sub: int = 6,
):
    """Seed Fig. 3: von Mises in the inflated wall, four panels with one colour scale.

    (a) the deformed quarter section (the wall is thin at this stretch: the box marks the zoom),
    (b) the zoom on the deformed wall at 45 degrees, where the through-thickness gradient shows,
    (c) the same field on the reference section (R, Z), (d) the exact through-wall profile against
    the FE. result: ``fem.blastula`` result at the final pressure (elastic); profile:
    ``reduced.blastula.profiles`` at the exact inner stretch (R in m, von_mises in Pa); C (Pa).

    The colours are the FE field itself, evaluated at ``n_sub`` x ``n_sub`` points per element
    (:func:`elastic_von_mises_at`), not the stored element means (which average the steep through-wall
    gradient and miss the wall values); the colour scale spans the FE field and the exact profile, so
    both extrema are on it (the colour-bar label gives both ranges).
    """
    from matplotlib.patches import Rectangle

    from tissuemech.compare.plots.fields import draw_field, subgrid

    plt = _plt()
    fig, axes = plt.subplots(2, 2, figsize=(11, 9.5), layout="constrained")
    (a0, a1), (a2, a3) = axes
    mesh, vm = result.mesh, np.asarray(result.von_mises)
    R_prof, vm_prof = np.asarray(profile.R).ravel(), np.asarray(profile.von_mises).ravel()
    ref = subgrid(n_sub)
    vm_pts = elastic_von_mises_at(mesh, result.displacement, ref, C=C, alpha=alpha)  # (nel, (n_sub+1)^2)
    lo, hi = min(float(vm_pts.min()), float(vm_prof.min())), max(float(vm_pts.max()), float(vm_prof.max()))
    A = mesh.length_scale
    la = float(result.inner_stretch[-1]) if inner_stretch is None else inner_stretch
    lb = float(result.outer_stretch[-1])
    a, b = la * A / UM, lb * outer_radius / UM
    coll = draw_field(a0, mesh, result.displacement, vm_pts, vmin=lo, vmax=hi, n_sub=n_sub)
    rc, w = 0.5 * (a + b), max(1.6 * (b - a), 2.0)
    cx, cy = rc / np.sqrt(2), rc / np.sqrt(2)
    a0.add_patch(Rectangle((cx - w, cy - w), 2 * w, 2 * w, fill=False, ec="r", lw=1.2))
    a0.set_title(f"(a) deformed section, p = {pressure / 1e3:g} kPa (wall {b - a:.1f} um thick)", fontsize=9)
    draw_field(a1, mesh, result.displacement, vm_pts, vmin=lo, vmax=hi, n_sub=n_sub)
    a1.set_xlim(cx - w, cx + w)
    a1.set_ylim(cy - w, cy + w)
    a1.set_title("(b) zoom on the deformed wall (red box in (a))", fontsize=9)
    draw_field(a2, mesh, None, vm_pts, vmin=lo, vmax=hi, n_sub=n_sub)
    a2.set_title(
        f"(c) the same field on the reference section\n(A = {A / UM:g} um, B = {outer_radius / UM:g} um)", fontsize=9
    )
    for ax, xl, yl in ((a0, "r (um)", "z (um)"), (a1, "r (um)", "z (um)"), (a2, "R (um)", "Z (um)")):
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
    fig.colorbar(coll, ax=[a0, a1], label="von Mises stress (Pa)", shrink=0.9)
    fig.colorbar(coll, ax=[a2], label="von Mises stress (Pa)", shrink=0.9)
    a3.plot(R_prof / UM, vm_prof, "k-", lw=1.5, label="exact (incompressible shell)", zorder=3)
    r_pts = np.hypot(*reference_points(mesh, ref)) * A / UM
    a3.plot(
        r_pts.ravel(), vm_pts.ravel(), ".", ms=2, color="C0", alpha=0.5, label="FE field at points (drawn in (a)-(c))"
    )
    a3.plot(element_radius(mesh) / UM, vm, "s", ms=5, mfc="none", color="C1", label="FE element means (stored)")
    a3.set_xlabel("reference radius R (um)")
    a3.set_ylabel("von Mises stress |sigma_theta - sigma_r| (Pa)")
    a3.set_title("(d) through-wall profile (not in the seed)", fontsize=9)
    a3.grid(alpha=0.3)
    a3.legend(fontsize=8, loc="upper right")
    fig.suptitle(
        f"Fig. 3: blastula at p = {pressure:g} Pa, alpha = {alpha:g}, C = {C:g} Pa; inner stretch {la:.4f}, "
        f"outer {lb:.4f}\ncolours: the FE field at {n_sub + 1} x {n_sub + 1} points per element, "
        f"{vm_pts.min():.0f}..{vm_pts.max():.0f} Pa (exact {vm_prof.min():.0f}..{vm_prof.max():.0f} Pa; "
        "one scale spans both)",
        fontsize=10,
    )
    return fig


def reference_points(mesh, ref: np.ndarray) -> np.ndarray:
    """Scaled reference coordinates (2, n_el, n) of the points ``ref`` of every element (Q2 map)."""
    from skfem import CellBasis

    basis = CellBasis(mesh.mesh, mesh.basis.elem, quadrature=(ref, np.full(ref.shape[1], 1.0 / ref.shape[1])))
    return np.asarray(basis.global_coordinates())


def fig_stretch_pressure(
    sets: Sequence[Mapping[str, Any]], *, title: str, limit_trace: Any = None, limit: tuple[float, float] | None = None
):
    """Seed Figs 4/5: inner (left) and outer (right) stretch vs pressure; exact lines, FE markers.

    sets         dicts with label, fe (FE result: pressure, inner_stretch, outer_stretch), exact_p (Pa),
                 exact_inner, exact_outer (dense arrays from the unloaded state, drawn as lines)
    limit_trace  an FE arc-length result through the neo-Hookean limit point (drawn in black)
    limit        (p_max Pa, lambda_a at the limit) of the exact solution, marked
    Every FE series starts at the unloaded state (stretch 1, p = 0), which the FE also satisfies.
    """
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.2), sharey=True, layout="constrained")
    for s in sets:
        fe = s["fe"]
        p_fe = np.r_[0.0, fe.pressure]
        (ln,) = axes[0].plot(s["exact_inner"], s["exact_p"], "-", lw=1.3, label=f"{s['label']}")
        axes[0].plot(np.r_[1.0, fe.inner_stretch], p_fe, "o", color=ln.get_color(), ms=3.5, mfc="none")
        axes[1].plot(s["exact_outer"], s["exact_p"], "-", lw=1.3, color=ln.get_color())
        axes[1].plot(np.r_[1.0, fe.outer_stretch], p_fe, "o", color=ln.get_color(), ms=3.5, mfc="none")
    if limit_trace is not None:
        axes[0].plot(
            limit_trace.inner_stretch, limit_trace.pressure, "k.-", lw=0.8, ms=3, label="neo-Hookean, FE arc-length"
        )
        axes[1].plot(limit_trace.outer_stretch, limit_trace.pressure, "k.-", lw=0.8, ms=3)
    if limit is not None:
        axes[0].plot(limit[1], limit[0], "r*", ms=12, label=f"limit point {limit[0]:.2f} Pa (exact)")
    axes[0].set_xlabel("inner stretch a/A")
    axes[1].set_xlabel("outer stretch b/B")
    axes[0].set_ylabel("pressure p (Pa)")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.set_ylim(bottom=0)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(
        handles,
        labels,
        fontsize=8,
        loc="outside lower center",
        ncol=min(len(labels), 6),
        title="lines: exact; circles: FE steps (both panels)",
        title_fontsize=8,
        frameon=False,
    )
    fig.suptitle("\n".join(textwrap.wrap(title, 120)), fontsize=10)
    return fig


# ---------------------------------------------------------------------------------------------
# Spheroid
# ---------------------------------------------------------------------------------------------


def fig8(result: Any, times: Sequence[float], *, title: str = ""):
    """Seed Fig. 8: von Mises on the deformed full section (the FE quarter mirrored) at the field times.

    One panel per time with one colour scale (the relaxation shows as a colour change), smooth on
    the curved Q2 geometry, the two rigid plates drawn at z = +-(a0 - delta(t)/2).
    """
    from tissuemech.compare.plots.fields import draw_field

    plt = _plt()
    fig, axes = plt.subplots(1, len(times), figsize=(5.6 * len(times), 4.2), layout="constrained")
    axes = np.atleast_1d(axes)
    fields = [result.field_at(t) for t in times]
    lo = float(min(np.min(f.von_mises) for f in fields))
    hi = float(max(np.max(f.von_mises) for f in fields))
    a0 = result.mesh.length_scale / UM
    coll = None
    for ax, f in zip(axes, fields):
        coll = draw_field(ax, result.mesh, f.displacement, f.von_mises, mirror=True, vmin=lo, vmax=hi)
        d = float(np.interp(f.time, result.time, result.approach)) / UM
        zp = a0 - d / 2
        half = 1.35 * a0
        for sgn in (1, -1):
            ax.fill_between([-half, half], sgn * zp, sgn * (zp + 0.06 * a0), color="0.55", lw=0)
        ax.set_xlim(-half, half)
        ax.set_ylim(-(zp + 0.1 * a0), zp + 0.1 * a0)
        ax.set_xlabel("r (um)")
        ax.set_ylabel("z (um)")
        ax.set_title(f"t = {f.time:g} s: approach {d:.0f} um, plates at z = +-{zp:.0f} um", fontsize=9)
    fig.colorbar(
        coll,
        ax=list(axes),
        label="von Mises stress (Pa)\n(element means averaged to nodes)",
        shrink=0.85,
    )
    note = f"colours: FE element means averaged to the nodes, element means {lo:.0f}..{hi:.0f} Pa over both times"
    fig.suptitle("\n".join([*textwrap.wrap(title, 120), note]), fontsize=10)
    return fig


def fig9(
    fe: Any,
    reduced_t: np.ndarray | None = None,
    reduced_vm: np.ndarray | None = None,
    *,
    label: str = "",
    reduced_label: str = "FE static mean x reduced relaxation factor (hybrid, not independent)",
):
    """Seed Fig. 9: volume-averaged von Mises vs time (ramp, left; relaxation, right, log time).

    The title is wrapped to the figure's width and the legend sits below the panels (off the data).
    """
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), layout="constrained")
    ramp_end = float(fe.parameters.get("ramp_time", 0.2)) if getattr(fe, "parameters", None) else 0.2
    for ax, sel in zip(axes, (fe.time <= ramp_end * 1.0001, fe.time >= ramp_end * 0.9999)):
        ax.plot(fe.time[sel], fe.mean_von_mises[sel], "o", ms=5, mfc="none", label="FE (transient run), every step")
        if reduced_t is not None and reduced_vm is not None:
            rs = (reduced_t <= ramp_end * 1.0001) if ax is axes[0] else (reduced_t >= ramp_end * 0.9999)
            ax.plot(reduced_t[rs], reduced_vm[rs], "k--", lw=1.2, label=reduced_label)
        ax.set_xlabel("time t (s)")
        ax.set_ylabel("volume-averaged von Mises stress (Pa)")
        ax.grid(alpha=0.3)
    axes[0].set_xlim(0, ramp_end * 1.02)
    axes[0].set_ylim(bottom=0)
    axes[1].set_xscale("log")
    axes[0].set_title("ramp", fontsize=9)
    axes[1].set_title("relaxation (hold, log time)", fontsize=9)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(
        handles, ["\n".join(textwrap.wrap(t, 90)) for t in labels], fontsize=8, loc="outside lower center", ncol=2
    )
    fig.suptitle("\n".join(textwrap.wrap(label, 110)), fontsize=10)
    return fig


def fig10(
    curves: Sequence[Mapping[str, Any]],
    synthetic: Mapping[str, Any] | None = None,
    *,
    label: str = "",
    reference: Mapping[str, Any] | None = None,
    ramp_time: float = 0.2,
    linthresh: float = 1e-3,
):
    """Seed Fig. 10: nominal stress sigma~ = F / A_mid vs time, and each model's deviation from the FE.

    curves     dicts with label, t (s), sigma (Pa), style (matplotlib format string); optionally
               sigma_at_ref (the curve at ``reference["t"]``) for the deviation panel, and top=False to
               draw the curve in the deviation panel only
    synthetic  dict with t, sigma (the noisy synthetic record), fit_t, fit_sigma, fit_label, fit_at_ref
    reference  dict with t, sigma, label: what the bottom panels divide by (the FE)
    linthresh  the deviation panels are symlog in %: linear within +-linthresh %, so that deviations
               of 1e-5 and of 10 % both read
    The fit is drawn as a solid red line; one legend for all panels sits below them, off the data.
    """
    plt = _plt()
    rows = 2 if reference is not None else 1
    fig, axes = plt.subplots(
        rows, 2, figsize=(11.5, 4.0 * rows + 1.4), squeeze=False, sharex="col", layout="constrained"
    )
    for col, log in enumerate((False, True)):
        ax = axes[0, col]
        for c in curves:
            if c.get("top", True):
                ax.plot(c["t"], c["sigma"], c.get("style", "-"), label=c["label"], ms=4, mfc="none", lw=1.4)
        if synthetic is not None:
            ax.plot(
                synthetic["t"],
                synthetic["sigma"],
                ".",
                color="0.6",
                ms=3,
                label="SYNTHETIC record (FE + 1 % noise)",
                zorder=0,
            )
            ax.plot(synthetic["fit_t"], synthetic["fit_sigma"], "r-", lw=0.9, label=synthetic["fit_label"])
        ax.set_ylabel("nominal stress F / A_mid (Pa)")
        ax.grid(alpha=0.3)
        if log:
            ax.set_xscale("log")
        else:
            ax.set_xlim(0, 3 * ramp_time)
        if reference is not None:
            bx = axes[1, col]
            for c in curves:
                if c.get("sigma_at_ref") is not None:
                    (ln,) = bx.plot(
                        reference["t"],
                        100 * (np.asarray(c["sigma_at_ref"]) / reference["sigma"] - 1),
                        c.get("style", "-"),
                        ms=4,
                        mfc="none",
                        lw=1.2,
                        label=c["label"],
                    )
                    if not c.get("top", True) and col == 0:  # only here: give it a legend entry
                        ax.plot([], [], c.get("style", "-"), ms=4, mfc="none", label=c["label"])
            if synthetic is not None and synthetic.get("fit_at_ref") is not None:
                bx.plot(
                    reference["t"],
                    100 * (np.asarray(synthetic["fit_at_ref"]) / reference["sigma"] - 1),
                    "r-",
                    lw=0.9,
                    label="fit",
                )
            bx.axhline(0, color="k", lw=0.6)
            bx.set_yscale("symlog", linthresh=linthresh)
            bx.set_ylabel(f"model / {reference.get('label', 'FE')} - 1 (%)\n(symlog, linear within +-{linthresh:g} %)")
            bx.grid(alpha=0.3)
            bx.set_xlabel("time t (s)")
            if log:
                bx.set_xscale("log")
        else:
            ax.set_xlabel("time t (s)")
    axes[0, 0].set_title("ramp and early hold", fontsize=9)
    axes[0, 1].set_title("relaxation (log time)", fontsize=9)
    if reference is not None:
        axes[1, 0].set_title("deviation from the FE at every FE step", fontsize=9)
        axes[1, 1].set_title("deviation from the FE at every FE step (log time)", fontsize=9)
    # one legend for both columns, below the panels: the fit's label is long and must not cover data
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=7, loc="outside lower center", ncol=2, frameon=False)
    fig.suptitle("\n".join(textwrap.wrap(label, 120)), fontsize=10)
    return fig
