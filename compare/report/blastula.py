"""Report section 1: the seed's blastula figures (Figs 3-5) and the table of every set."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pandas as pd

from tissuemech.compare import cases, runcache
from tissuemech.compare.cases import UM
from tissuemech.compare.report.common import Section, md_table

A, C_BL = cases.BLASTULA_INNER_RADIUS, cases.BLASTULA_C


def _set_job(alpha: float, B: float, mesh, max_pressure: float = 1000.0, n: int = 20) -> tuple[Callable, dict, int]:
    """The FE run of one set: load control to max_pressure, or arc-length through a limit point (below it)."""
    from tissuemech.fem.blastula import inflate
    from tissuemech.reduced import blastula as bl

    lim = bl.limit_point(inner_radius=A, outer_radius=B, C=C_BL, alpha=alpha)
    kw: dict[str, Any] = dict(inner_radius=A, outer_radius=B, C=C_BL, alpha=alpha, mesh=mesh)
    if lim is not None and float(lim.pressure) < max_pressure:
        kw.update(pressures=None, method="arclength", max_inner_stretch=1.3 * float(lim.inner_stretch))
    else:
        kw.update(pressures=np.linspace(max_pressure / n, max_pressure, n))
    return inflate, kw, 1


def _fig3_job(mesh) -> tuple[Callable, dict, int]:
    from tissuemech.fem.blastula import inflate

    B, alpha, p = cases.FIG3["outer_radius"], cases.FIG3["alpha"], cases.FIG3["pressure"]
    return (
        inflate,
        dict(inner_radius=A, outer_radius=B, C=C_BL, alpha=alpha, pressures=np.linspace(100, p, 10), mesh=mesh),
        1,
    )


def _mesh(quick: bool) -> str:
    return "default" if quick else "fine"


def fe_jobs(quick: bool = False) -> list[tuple[Callable, dict, int]]:
    """The section's FE runs as ``(function, keywords, repeats)`` in the order it asks for them (Fig. 3, then the
    sets of Figs 4-5): what the report's builder starts ahead on the second core."""
    mesh = _mesh(quick)
    return [_fig3_job(mesh)] + [_set_job(alpha_, B_, mesh) for _, alpha_, B_ in cases.BLASTULA_SETS]


def _blastula_set(alpha: float, B: float, mesh, max_pressure: float = 1000.0, n: int = 20):
    """FE curve of one set (:func:`_set_job`) and its error against the exact shell."""
    from tissuemech.reduced import blastula as bl

    lim = bl.limit_point(inner_radius=A, outer_radius=B, C=C_BL, alpha=alpha)
    run = runcache.call(*_set_job(alpha, B, mesh, max_pressure, n)[:2])  # reused between reports, with its time
    fe, wall = run.result, run.wall
    la = np.linspace(1.0, float(fe.inner_stretch.max()), 300)  # the exact curve, drawn as a line
    geo: dict[str, Any] = dict(inner_radius=A, outer_radius=B)
    p_ex = np.asarray(bl.pressure(la, **geo, C=C_BL, alpha=alpha))
    keep = fe.pressure > 0
    p_fe_ex = np.asarray(bl.pressure(fe.inner_stretch[keep], **geo, C=C_BL, alpha=alpha))
    err = float(np.max(np.abs(p_fe_ex / fe.pressure[keep] - 1)))
    return dict(
        fe=fe,
        exact_p=p_ex,
        exact_inner=la,
        exact_outer=np.asarray(bl.outer_stretch(la, **geo)),
        limit=lim,
        wall=wall,
        error=err,
    )


def section(traces: dict, *, quick: bool = False, progress: Callable[[str], None] = lambda _: None) -> Section:
    """Figs 3-5: von Mises through the wall at 1 kPa, the alpha and thickness sweeps (FE vs exact).

    traces: FE arc-length results through the neo-Hookean limit point keyed by B in um (from
    ``studies.stability.limit_point_map``); the B = 75 um one is drawn in Fig. 5.
    """
    sec = Section("blastula", quick)
    from tissuemech.compare.plots import seed as figures
    from tissuemech.reduced import blastula as bl

    mesh = _mesh(sec.quick)
    progress("blastula: Fig. 3")
    # Fig. 3
    B, alpha, p = cases.FIG3["outer_radius"], cases.FIG3["alpha"], cases.FIG3["pressure"]
    run3 = runcache.call(*_fig3_job(mesh)[:2])
    fe, wall3 = run3.result, run3.wall  # the run's time, also when it comes from the cache (compare.runcache)
    la = float(bl.inner_stretch(p, inner_radius=A, outer_radius=B, C=C_BL, alpha=alpha))
    prof = bl.profiles(la, inner_radius=A, outer_radius=B, C=C_BL, alpha=alpha, n=200)
    R_el = figures.element_radius(fe.mesh)
    vm_ex = np.interp(R_el, np.asarray(prof.R), np.asarray(prof.von_mises))
    vm_err = float(np.max(np.abs(fe.von_mises - vm_ex)) / np.max(np.asarray(prof.von_mises)))
    la_err = abs(float(fe.inner_stretch[-1]) / la - 1)
    # the FE field at points (what Fig. 3 colours): its extrema and its error against the exact profile
    from tissuemech.compare.plots.fields import subgrid

    pts = subgrid(6)
    vm_pts = figures.elastic_von_mises_at(fe.mesh, fe.displacement, pts, C=C_BL, alpha=alpha)
    R_pts = np.hypot(*figures.reference_points(fe.mesh, pts)) * A  # the shell mesh is scaled by A
    vm_pts_err = float(np.max(np.abs(vm_pts - np.interp(R_pts, np.asarray(prof.R), np.asarray(prof.von_mises)))))
    vm_pts_err /= float(np.max(np.asarray(prof.von_mises)))
    sec.save(figures.fig3(fe, prof, pressure=p, alpha=alpha, outer_radius=B, C=C_BL), "fig3_blastula_von_mises.png")
    sec.summary["fig3"] = dict(
        mesh=str(mesh),
        inner_stretch_fe=float(fe.inner_stretch[-1]),
        inner_stretch_exact=la,
        stretch_rel_err=la_err,
        von_mises_rel_err=vm_err,
        wall_s=wall3,
        von_mises_range_Pa=[float(fe.von_mises.min()), float(fe.von_mises.max())],
        von_mises_field_range_Pa=[float(vm_pts.min()), float(vm_pts.max())],
        von_mises_field_rel_err=vm_pts_err,
        exact_von_mises_range_Pa=[float(np.min(prof.von_mises)), float(np.max(prof.von_mises))],
    )

    rows: list[dict[str, Any]] = []
    sets4: list[dict[str, Any]] = []
    sets5: list[dict[str, Any]] = []
    progress("blastula: Figs 4-5 (7 sets)")
    for fig, alpha_, B_ in cases.BLASTULA_SETS:
        b = B_ / UM
        s = _blastula_set(alpha_, B_, mesh)
        s["label"] = f"alpha={alpha_:g}" if fig == "Fig. 4" else f"B={b:g} um"
        (sets4 if fig == "Fig. 4" else sets5).append(s)
        lim = s["limit"]
        rows.append(
            dict(
                figure=fig,
                alpha=alpha_,
                B_um=b,
                method=s["fe"].method,
                steps=len(s["fe"].pressure),
                final_pressure_Pa=float(s["fe"].pressure[-1]),
                final_inner_stretch=float(s["fe"].inner_stretch[-1]),
                final_outer_stretch=float(s["fe"].outer_stretch[-1]),
                max_rel_pressure_err=s["error"],
                limit_p_Pa=np.nan if lim is None else float(lim.pressure),
                limit_stretch=np.nan if lim is None else float(lim.inner_stretch),
                wall_s=s["wall"],
            )
        )
    df = pd.DataFrame(rows).rename(
        columns={
            "B_um": "B [um]",
            "final_pressure_Pa": "final pressure [Pa]",
            "limit_p_Pa": "limit pressure [Pa]",
            "wall_s": "wall_time [s]",
        }
    )
    sec.table(df, "blastula_sets.csv")
    sec.summary["blastula_sets_max_err"] = float(df.max_rel_pressure_err.max())
    lim75 = bl.limit_point(inner_radius=A, outer_radius=cases.FIG4_OUTER_RADIUS, C=C_BL, alpha=cases.NEO_HOOKEAN_ALPHA)
    assert lim75 is not None, "the neo-Hookean shell has a limit point"
    f4_err = float(df[df.figure == "Fig. 4"].max_rel_pressure_err.max())
    f5 = df[df.figure == "Fig. 5"].sort_values("B [um]")
    f5_err, f5_la = float(f5.max_rel_pressure_err.max()), f5.final_inner_stretch.to_numpy(float)
    sec.save(
        figures.fig_stretch_pressure(
            sets4,
            title="Fig. 4: B = 75 um, alpha sweep (neo-Hookean traced through its limit point by arc-length)",
            limit=(float(lim75[0]), float(lim75[1])),
        ),
        "fig4_alpha_sweep.png",
    )
    sec.save(
        figures.fig_stretch_pressure(
            sets5,
            title="Fig. 5: alpha = 0.2, thickness sweep (black: neo-Hookean B = 75 um arc-length)",
            limit_trace=traces.get(75.0),
        ),
        "fig5_thickness_sweep.png",
    )
    sec.md += [
        "## 1. The seed's blastula figures (Figs 3-5)",
        "",
        "![Fig. 3](fig3_blastula_von_mises.png)",
        "",
        f"**Fig. 3** shows the von Mises stress in the wall of the inflated blastula (alpha = 0.2, B = 75 um, "
        f"p = 1 kPa; {mesh} mesh, {len(fe.von_mises)} elements, {wall3:.2f} s): (a) the deformed quarter section, "
        "(b) a zoom on the thin deformed wall, (c) the same field on the reference section, where the "
        "through-wall gradient is visible, (d) the through-wall profile against the exact incompressible shell. "
        "The colours are the FE field itself at 7 x 7 points per element (the deformation gradient of the Q2 "
        "displacement through the engine's constitutive law), on a scale that spans both it and the exact "
        f"profile: FE {vm_pts.min():.0f}..{vm_pts.max():.0f} Pa, exact {float(np.min(prof.von_mises)):.0f}.."
        f"{float(np.max(prof.von_mises)):.0f} Pa, the peak at the inner wall. What to conclude: the FE field "
        f"follows the exact profile within {vm_pts_err:.1e} of the peak at every point, and the inner stretch "
        f"within {la_err:.1e} (FE {fe.inner_stretch[-1]:.6f}, exact {la:.6f}); the stress falls by a factor "
        f"{float(np.max(prof.von_mises)) / float(np.min(prof.von_mises)):.0f} through the wall. The element means "
        f"that the FE result stores ({fe.von_mises.min():.0f}..{fe.von_mises.max():.0f} Pa, squares in (d)) "
        "average this steep gradient over each element and do not reach the wall values; they match the exact "
        f"profile at the element centres within {vm_err:.1e} of the peak.",
        "",
        "![Fig. 4](fig4_alpha_sweep.png)",
        "",
        f"**Fig. 4** shows the inner (left) and outer (right) stretch against the pressure for B = 75 um and alpha "
        f"in {{{', '.join(f'{a:g}' for a in cases.FIG4_ALPHAS)}}}: lines the exact shell, circles the FE steps from "
        "the unloaded state. What to conclude: the stiffening exponent alpha removes the limit point; the "
        f"neo-Hookean shell (alpha = 1e-5) has one at p_max = {float(lim75[0]):.2f} Pa (red star, inner stretch "
        f"{float(lim75[1]):.3f}), which load control cannot pass and the FE arc-length trace follows through; "
        f"the FE steps lie on the exact lines within {f4_err:.1e} in pressure (worst set; every set in the table "
        "below).",
        "",
        "![Fig. 5](fig5_thickness_sweep.png)",
        "",
        f"**Fig. 5** shows the same for alpha = 0.2 and B in {{{', '.join(f'{b / UM:g}' for b in cases.FIG5_OUTER_RADII)}}}"
        " um, with the neo-Hookean B = 75 um arc-length trace in black for contrast. What to conclude: a thinner "
        "wall inflates further at a given pressure (the inner stretch at 1 kPa goes from "
        f"{f5_la[0]:.2f} at B = {cases.FIG5_OUTER_UM[0]:g} um to {f5_la[-1]:.2f} at B = {cases.FIG5_OUTER_UM[-1]:g} um) "
        f"but alpha = 0.2 keeps every curve monotone (no limit point); FE within {f5_err:.1e} of the exact pressure.",
        "",
        "Every set (lines exact, circles the FE steps from the unloaded state): `blastula_sets.csv`; error = max over the FE steps of "
        "|p_exact(lambda_a,FE)/p_FE - 1|.",
        "",
        md_table(
            df,
            cols=[
                "figure",
                "alpha",
                "B [um]",
                "method",
                "steps",
                "final pressure [Pa]",
                "final_inner_stretch",
                "max_rel_pressure_err",
                "limit pressure [Pa]",
                "limit_stretch",
                "wall_time [s]",
            ],
        ),
        "",
    ]
    return sec
