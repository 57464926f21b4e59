"""Report section 4: the stability map (each method pushed until it fails)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd

from tissuemech.compare import runcache
from tissuemech.compare.report.common import Section, md_table


def _kappa_mesh(quick: bool) -> tuple[int, int]:
    return (4, 8) if quick else (8, 16)


def _compression_settings(quick: bool) -> tuple[tuple[float, ...], str]:
    """(approach fractions, mesh) of the compression-depth panel."""
    if quick:
        return (0.3, 0.5, 0.7, 0.79), "coarse"
    return (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.75, 0.79), "default"


def fe_jobs(quick: bool = False, spheroid: bool = True) -> list[tuple[Callable, dict, int]]:
    """The section's FE runs as ``(function, keywords, repeats)`` in the order it asks for them (kappa map, then the
    compression depth when ``spheroid``): what the report's builder starts ahead on the second core."""
    from tissuemech.compare.studies import stability

    jobs = stability.kappa_jobs(mesh=_kappa_mesh(quick))
    return jobs + (stability.compression_jobs(*_compression_settings(quick)) if spheroid else [])


def stiff_solver_job() -> tuple[Callable, dict, int]:
    """The stiff-solver table (``studies.stability.stiff_solver_map``: three diffrax solvers, each compiled, ~5 s)
    as a job the report's builder starts ahead on the second core."""
    from tissuemech.compare.studies import stability

    return stability.stiff_solver_map, {}, 1


def section(
    limit: tuple[pd.DataFrame, dict],
    *,
    quick: bool = False,
    spheroid_reason: str | None = None,
    progress: Callable[[str], None] = lambda _: None,
) -> Section:
    """Stability map: limit point, locking vs kappa/C, viscous step, stiff solvers, compression depth.

    limit: ``studies.stability.limit_point_map()`` output (computed once by the builder, shared with
    the blastula section); spheroid_reason: why the spheroid FE is unavailable, or None.
    """
    sec = Section("stability", quick)
    from tissuemech.compare.plots import charts
    from tissuemech.compare.studies import stability

    lim, traces = limit
    progress("stability: locking vs kappa/C")
    kap = stability.kappa_map(mesh=_kappa_mesh(sec.quick))
    progress("stability: viscous step, stiff solvers")
    visc, bounds = stability.viscous_step_map(
        np.geomspace(1e-2 if sec.quick else 1e-3, 1500.0, 24 if sec.quick else 34)
    )
    stiff = runcache.call(*stiff_solver_job()[:2]).result  # computed ahead by the builder's second process
    comp = None
    if spheroid_reason is None:
        progress("stability: compression depth")
        comp = stability.compression_map(*_compression_settings(sec.quick))
        sec.table(comp, "stability_compression.csv")
    for df, name in (
        (lim, "stability_limit_point.csv"),
        (kap, "stability_kappa.csv"),
        (visc, "stability_viscous_step.csv"),
        (bounds, "stability_viscous_boundary.csv"),
        (stiff, "stability_stiff_solvers.csv"),
    ):
        sec.table(df, name)
    sec.save(
        charts.stability_charts(limit=lim, kappa=kap, viscous=visc, stiff=stiff, compression=comp), "stability_map.png"
    )

    k7 = kap[kap.kappa_over_C == kap.kappa_over_C.max()].set_index("formulation")
    sec.summary["stability"] = dict(
        limit={
            f"{r['method']}|{r['B [um]']:g}": dict(
                p=r["p reached [Pa]"], rel=r["rel_err_p"], passed=bool(r["passed_limit"])
            )
            for r in lim.to_dict("records")
        },
        kappa_max=float(kap.kappa_over_C.max()),
        kappa_error_mixed=float(k7.loc["mixed", "error"]),
        kappa_error_displacement=float(k7.loc["displacement", "error"]),
        kappa_displacement_failed=bool(k7.loc["displacement", "failed"]),
        viscous={
            r["update"]: dict(
                step=r["largest ok step [s]"],
                error=r["error_at_boundary"],
                limited_by_range=bool(r["limited_by_range"]),
            )
            for r in bounds.to_dict("records")
        },
        stiff={
            f"{r.solver}|{r.tau_over_ramp:g}": dict(
                steps=int(r.steps), rejected=int(r.rejected), failed=bool(r.failed), error=r.error
            )
            for r in stiff.itertuples()
        },
        compression=None
        if comp is None
        else dict(
            largest_converged=float(comp[comp.converged].fraction.max()) if comp.converged.any() else 0.0,
            tried=comp.fraction.tolist(),
            ended_by=(comp.failure[~comp.converged].iloc[0] if (~comp.converged).any() else "not reached"),
        ),
    )
    lc = lim[lim.method == "FE load control"]
    sec.md += [
        "## 4. Stability map: each method pushed until it fails",
        "",
        "![stability map](stability_map.png)",
        "",
        _map_caption(lim, kap, bounds, stiff, comp),
        "",
        "### Neo-Hookean limit point (alpha = 1e-5, default mesh)",
        "",
        "Load control (`fem.blastula.inflate`, adaptive cut-back) runs one sweep fixed in advance for every B "
        "(60 geometric steps from 1 Pa to 1 kPa; it is not told the exact limit) and stops just below the limit "
        "with a `LimitPointError`: p_reached is its last converged load and stretch_reached the FE inner stretch "
        "there, both from the FE alone. Arc-length passes the limit (its p_reached: the maximum of the trace by a "
        "parabola through the three steps around it; stretch_reached: where the trace ends). The exact columns "
        "(`reduced.blastula.limit_point`, closed form; `inner_stretch` raises `ValueError` above it) are only "
        "compared with afterwards.",
        "",
        md_table(
            lim,
            cols=[
                "B [um]",
                "method",
                "p reached [Pa]",
                "stretch_reached",
                "p max exact [Pa]",
                "stretch_limit_exact",
                "rel_err_p",
                "passed_limit",
                "wall_time [s]",
            ],
            floatfmt=".6g",
        ),
        "",
        f"### Locking: kappa/C from 1e2 to 1e7 (alpha = 0.2, B = 75 um, mesh {(4, 8) if sec.quick else (8, 16)})",
        "",
        "Error = max |lambda_a,FE / lambda_a,exact - 1| at p = 250, 500 Pa against the INCOMPRESSIBLE exact shell, "
        "so it includes the true compressibility effect (~C/kappa, shared by both) plus locking.",
        "",
        md_table(kap, cols=["formulation", "kappa_over_C", "error", "failed", "wall_time [s]"]),
        "",
        "### Viscoelastic update formulas (lumped Maxwell branch, beta = 1.2, tau = 200 s, ramp 0.2 s, hold to 1500 s)",
        "",
        "Error = max over the steps of |F_n - F(t_n)| / max F against the exact solution (Dawson-integral closed "
        "form). Uniform step h in the hold, the ramp split into ceil(t_r/h) steps.",
        "",
        md_table(bounds),
        "",
        "### Explicit vs implicit diffrax (same ODE with tau << ramp; rtol = atol = 1e-8, max_steps = 20000)",
        "",
        md_table(stiff.drop(columns=["note"])),
        "",
    ]
    if comp is not None:
        sec.md += [
            "### Static compression depth (spheroid FE, alpha = 0.2, C = 200 Pa; stops at the first failure)",
            "",
            _compression_text(comp),
            "",
            md_table(comp),
            "",
        ]
    else:
        sec.md += [f"### Static compression depth: not available ({spheroid_reason})", ""]
    sec.summary["limit_load_control_Pa"] = {f"{r['B [um]']:g}": r["p reached [Pa]"] for r in lc.to_dict("records")}
    sec.data.update(limit=lim, traces=traces)
    return sec


def _compression_text(comp: pd.DataFrame) -> str:
    """Say what ended the push: a failure of the method (and how), or the model's stated cap."""
    ok = comp[comp.converged]
    top = f"{100 * ok.fraction.max():.0f} %" if len(ok) else "none"
    bad = comp[~comp.converged]
    if not len(bad):
        return f"Every approach tried converged (largest {top} of the diameter); no failure was reached."
    first = bad.iloc[0]
    nodal = ""
    if "nodal_contact_states" in comp and (ok.nodal_contact_states > 0).any():
        f0 = 100 * ok[ok.nodal_contact_states > 0].fraction.min()
        nodal = (
            f" From {f0:.0f} % on, the states beyond about 48 % of the diameter (the contact edge past the fitted range) use "
            "node-by-node contact on the last fitted mesh (logged; `result.parameters['contact']`), with the ~1e-3 "
            "edge quantisation of nodal contact."
        )
    if first.failure == "refused (cap)":
        return (
            f"Every approach tried below the cap converged (largest {top} of the diameter).{nodal} The push ends at "
            f"{100 * first.fraction:.0f} % because `fem.spheroid.compress` refuses an approach of 80 % of the "
            "diameter or more up front (the ball would be squeezed below 20 % of its height; the model is not "
            "meant for that): the cap, not a failure of the method, ends this map. Not shown: how the method "
            "would fail beyond it."
        )
    return (
        f"Converged up to {top} of the diameter;{nodal} at {100 * first.fraction:.0f} % it fails by "
        f"**{first.failure}** ({first.note})."
    )


def _map_caption(
    lim: pd.DataFrame, kap: pd.DataFrame, bounds: pd.DataFrame, stiff: pd.DataFrame, comp: pd.DataFrame | None
) -> str:
    """What the five panels of the stability map show and what to conclude, with the numbers."""
    lc, arc = lim[lim.method == "FE load control"], lim[lim.method == "FE arc-length"]
    k7 = kap[kap.kappa_over_C == kap.kappa_over_C.max()].set_index("formulation")
    disp = kap[kap.formulation == "displacement"]
    disp_ok = disp[~disp.failed.astype(bool)]
    mixed = kap[kap.formulation == "mixed"].set_index("kappa_over_C").error
    ratio = disp_ok.error.to_numpy(float) / mixed.reindex(disp_ok.kappa_over_C).to_numpy(float)
    worst_disp = disp_ok.iloc[int(np.nanargmax(ratio))] if len(disp_ok) and np.isfinite(ratio).any() else None
    worst_ratio = float(np.nanmax(ratio)) if worst_disp is not None else np.nan
    b = bounds.set_index("update")
    steps = "; ".join(f"{u}: {r['largest ok step [s]']:.3g} s" for u, r in b.iterrows())
    gave_up = stiff[stiff.failed.astype(bool)]
    imp = stiff[~stiff.solver.isin(gave_up.solver.unique())] if len(gave_up) else stiff
    exp_ok = stiff[stiff.solver.isin(gave_up.solver.unique()) & ~stiff.failed.astype(bool)]
    n_exp = exp_ok.steps + exp_ok.rejected
    exp_lo, exp_hi = (int(n_exp.min()), int(n_exp.max())) if len(exp_ok) else (0, 0)
    text = (
        "The map has five panels, each method pushed until it fails. "
        f"**Limit point** (top left): load control stops below the exact neo-Hookean limit by "
        f"{lc.rel_err_p.abs().min():.1e}..{lc.rel_err_p.abs().max():.1e} (relative) for the three shells, never past "
        f"it; arc-length passes it on every shell ({int(arc.passed_limit.astype(bool).sum())} of {len(arc)}) and "
        f"finds p_max within {arc.rel_err_p.abs().max():.1e}. "
        f"**Locking** (top middle): the mixed u-p error follows the physical compressibility C/kappa down to "
        f"{k7.loc['mixed', 'error']:.1e} at kappa/C = {kap.kappa_over_C.max():.0e}; the displacement-only form "
        + (
            f"locks (at kappa/C = {worst_disp.kappa_over_C:.0e} its error is {worst_disp.error:.1e}, "
            f"{worst_ratio:.0f} times the mixed form's)"
            if worst_disp is not None
            else "locks"
        )
        + (
            " and its Newton fails at kappa/C = "
            + ", ".join(f"{v:.0e}" for v in disp[disp.failed.astype(bool)].kappa_over_C)
            + " (crosses on the top band)"
            if disp.failed.astype(bool).any()
            else ""
        )
        + ": use the mixed form (the default). "
        f"**Viscoelastic update** (top right): the largest time step keeping the force within 1e-3 is {steps} "
        "(tau = 200 s): the exponential (exact-linear) update is the one to use. "
        f"**Stiffness** (bottom left): the explicit solvers' step count grows from {exp_lo} to {exp_hi} as tau / "
        "ramp falls, and "
        + (
            f"they give up (max_steps) from tau / ramp = {gave_up.tau_over_ramp.max():.0e} on "
            "(Tsit5 and Dopri5 take nearly as many steps as each other: their markers overlap, a large hollow one "
            "around a small filled one); "
            if len(gave_up)
            else "none gave up; "
        )
        + f"the implicit {', '.join(imp.solver.unique())} stays below {int((imp.steps + imp.rejected).max())} steps. "
    )
    if comp is not None:
        text += "**Compression depth** (bottom right): " + _compression_text(comp)
    return text
