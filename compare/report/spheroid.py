"""Report section 3: the seed's spheroid figures (Figs 8-10) and spheroid accuracy versus speed."""

from __future__ import annotations

import functools
import time
from collections.abc import Callable

import numpy as np
import pandas as pd

from tissuemech.compare import cases
from tissuemech.compare.report.common import Section, md_table

FIG89, FIG89_END, FIG89_FIELDS = cases.FIG89, cases.FIG89_END_TIME, cases.FIG89_FIELD_TIMES


def _calibrated_tables(x_max: float, alpha: float, mesh) -> tuple[tuple, tuple, dict]:
    """Equilibrium and midplane tables (x, f), (x, g) from one static FE run (``compare.calibrate``)."""
    from tissuemech.compare.calibrate import _to_master, static_curve

    run = static_curve(alpha=alpha, x_max=x_max, mesh=mesh)
    x = np.linspace(0.0, x_max, 41)
    f, g = _to_master(run, x)
    return (x, f), (x, g), run


def section(*, quick: bool = False, progress: Callable[[str], None] = lambda _: None) -> Section:
    """Figs 8-10 (FE von Mises fields, mean von Mises, nominal stress with a fit) and spheroid accuracy."""
    sec = Section("spheroid", quick)
    progress("spheroid: calibration run (Fig. 10 case)")
    import jax.numpy as jnp

    from tissuemech.compare.fit import relaxation
    from tissuemech.compare.plots import charts
    from tissuemech.compare.plots import seed as figures
    from tissuemech.compare.studies import accuracy
    from tissuemech.fem import spheroid as fes
    from tissuemech.reduced import spheroid as rs

    # ---- Fig. 10 case: accuracy vs speed (FE levels vs the finest, reduced Hertz, reduced calibrated)
    # the reference is the Richardson limit of the three finest levels: 1-3 in both modes (level 0 is not yet
    # in the asymptotic range: over levels 0-2 the quick reference came out on level 2 itself, 1.2e-5 off)
    levels = (1, 2, 3) if quick else (0, 1, 2, 3)
    ref_level = levels[-1]
    fig10 = cases.FIG10
    x10 = fig10["displacement"] / (2 * fig10["radius"])
    t0 = time.perf_counter()
    eq10, mid10, _ = _calibrated_tables(x10, fig10["alpha"], ref_level)
    calib_wall = time.perf_counter() - t0
    # the calibrated law comes from a static run on the REFERENCE mesh itself: its row measures the lumped-
    # relaxation assumption alone, not an independent prediction (labelled so); the shipped table comes from static
    # runs on level 3 (the reference mesh of the study) interpolated in x and alpha
    laws = {
        "hertz": dict(equilibrium="hertz"),
        "calibrated on the reference mesh": dict(equilibrium=eq10, midplane=mid10),
    }
    if rs.DATA_FILE.exists():  # the master curves shipped with the package (python -m tissuemech.compare.calibrate)
        laws["shipped FE table"] = dict(equilibrium="fem")
    progress("spheroid: FE levels and reduced laws (Fig. 10 case)")
    df, fe_runs = accuracy.spheroid_accuracy(meshes=levels, equilibria=laws)
    nel = {m: int(r.mesh.mesh.nelements) for m, r in fe_runs.items()}
    df["setting"] = [
        (f"level {int(st.split()[1])} ({nel[int(st.split()[1])]} el.)" + (" reference" if "reference" in st else ""))
        if str(st).startswith("level ")
        else ("jitted, after compile" if st == "jit" else st)
        for st in df.setting
    ]
    sec.table(df, "accuracy_spheroid.csv")
    sec.save(
        charts.accuracy_chart(
            df,
            title="Spheroid Fig. 10 case: sigma~ at t = 0.2 s and 1500 s vs the Richardson-extrapolated FE",
            floor=1e-8,
            note="FE labels: fem.spheroid mesh level (number of Q2/P1 elements); reduced: the lumped Maxwell model "
            "(jitted, timed after compile); FE: one run per level, mesh set-up included; 'calibrated on the reference "
            "mesh' is not independent of the reference.",
        ),
        "accuracy_spheroid.png",
    )
    ref = fe_runs[ref_level]
    t_ref = ref.time[ref.time > 0]
    t_dense = np.concatenate([np.linspace(0, 0.2, 21)[1:], np.geomspace(0.2, 1500, 80)[1:]])
    hertz = np.asarray(rs.nominal_stress(t_dense, **fig10, equilibrium="hertz"))
    cal = np.asarray(rs.nominal_stress(t_dense, **fig10, equilibrium=eq10, midplane=mid10))
    # synthetic record: the finest FE curve + 1 % multiplicative noise (seeded), fitted with the calibrated law
    rng = np.random.default_rng(0)
    keep = ref.time > 0
    ts, ys = ref.time[keep], ref.nominal_stress[keep] * (1 + 0.01 * rng.standard_normal(keep.sum()))
    model = functools.partial(rs.nominal_stress, midplane=mid10, adjoint="forward")  # calibrated law + midplane
    fit = relaxation(
        [(ts, ys, fig10["displacement"])],
        radius=fig10["radius"],
        ramp_time=fig10["ramp_time"],
        equilibrium=eq10,
        model=model,
        initial=dict(C=100.0, alpha=fig10["alpha"], beta=1.0, tau=50.0),
    )
    pf = fit.params
    fit_curve = np.asarray(
        rs.nominal_stress(
            t_dense,
            radius=fig10["radius"],
            C=pf["C"],
            alpha=pf["alpha"],
            branches=[(pf["beta"], pf["tau"])],
            displacement=fig10["displacement"],
            ramp_time=fig10["ramp_time"],
            equilibrium=eq10,
            midplane=mid10,
        )
    )
    sec.save(
        figures.fig10(
            [
                dict(
                    label=f"FE, finest mesh of the study (level {ref_level}, {nel[ref_level]} elements)",
                    t=ref.time,
                    sigma=ref.nominal_stress,
                    style="ko",
                ),
                dict(
                    label="reduced, Hertz law",
                    t=t_dense,
                    sigma=hertz,
                    style="b--",
                    sigma_at_ref=np.asarray(rs.nominal_stress(t_ref, **fig10, equilibrium="hertz")),
                ),
                dict(
                    label="reduced, law calibrated on the reference mesh",
                    t=t_dense,
                    sigma=cal,
                    style="g-.",
                    sigma_at_ref=np.asarray(rs.nominal_stress(t_ref, **fig10, equilibrium=eq10, midplane=mid10)),
                ),
            ],
            reference=dict(t=t_ref, sigma=ref.nominal_stress[ref.time > 0], label="FE"),
            synthetic=dict(
                t=ts,
                sigma=ys,
                fit_t=t_dense,
                fit_sigma=fit_curve,
                fit_label="fit to the SYNTHETIC record (95 % intervals):\n"
                + ", ".join(
                    f"{n} = {pf[n]:.3g} ({fit.interval_text(n)}){u}"
                    for n, u in (("C", " Pa"), ("alpha", ""), ("beta", ""), ("tau", " s"))
                ),
                fit_at_ref=np.interp(t_ref, t_dense, fit_curve),
            ),
            label="Fig. 10 case: " + cases.describe_spheroid(fig10),
        ),
        "fig10_nominal_stress.png",
    )

    # ---- Figs 8-9 case
    mesh89 = "coarse" if quick else "default"
    progress("spheroid: Figs 8-9 case")
    t0 = time.perf_counter()
    fe89 = fes.compress(**FIG89, end_time=FIG89_END, field_times=FIG89_FIELDS, mesh=mesh89)
    wall89 = time.perf_counter() - t0
    x89 = FIG89["displacement"] / (2 * FIG89["radius"])
    eq89, mid89, static89 = _calibrated_tables(x89, FIG89["alpha"], mesh89)
    sec.save(
        figures.fig8(
            fe89, FIG89_FIELDS, title=f"Fig. 8, Figs 8-9 case: {cases.describe_spheroid(FIG89)}; FE {mesh89} mesh"
        ),
        "fig8_spheroid_von_mises.png",
    )
    # reduced mean von Mises: the FE static mean von Mises at delta(t) times the lumped relaxation factor F/F_eq
    t89 = np.concatenate([np.linspace(0, 0.2, 21)[1:], np.geomspace(0.2, FIG89_END, 60)[1:]])
    st = fes.compress(
        radius=FIG89["radius"],
        C=FIG89["C"],
        alpha=FIG89["alpha"],
        branches=(),
        displacement=FIG89["displacement"],
        ramp_time=1.0,
        end_time=1.0,
        mesh=mesh89,
        static=True,
    )
    delta_t = FIG89["displacement"] * np.minimum(t89 / FIG89["ramp_time"], 1.0)
    F_red = np.asarray(rs.force(t89, **FIG89, equilibrium=eq89))
    F_eq = np.asarray(
        rs.equilibrium_force(
            jnp.asarray(delta_t), radius=FIG89["radius"], C=FIG89["C"], alpha=FIG89["alpha"], equilibrium=eq89
        )
    )
    vm_static = np.interp(delta_t, np.r_[0.0, st.approach], np.r_[0.0, st.mean_von_mises])
    vm_red = vm_static * F_red / F_eq
    sec.save(
        figures.fig9(
            fe89,
            t89,
            vm_red,
            label=f"Fig. 9, Figs 8-9 case: {cases.describe_spheroid(FIG89)} ({mesh89} mesh). Dashed: not an independent "
            "model (FE static field x lumped factor, law calibrated on the same mesh)",
        ),
        "fig9_mean_von_mises.png",
    )

    def row(case, quantity, t, fe, fe_y, red_t, red_y, scale=1.0):
        """One comparison row: the FE curve ``fe_y`` of result ``fe`` and the reduced curve at time t (s)."""
        return dict(
            case=case,
            quantity=quantity,
            fe=float(np.interp(t, fe.time, fe_y)) * scale,
            reduced=float(np.interp(t, red_t, red_y)) * scale,
        )

    static_x_lumped = "(Pa); reduced = FE static x lumped factor"
    seed_rows = [
        row("Figs 8-9", f"mean von Mises at t = 0.2 s {static_x_lumped}", 0.2, fe89, fe89.mean_von_mises, t89, vm_red),
        row(
            "Figs 8-9", f"mean von Mises at t = 1497 s {static_x_lumped}", 1497, fe89, fe89.mean_von_mises, t89, vm_red
        ),
        row(
            "Figs 8-9",
            "plate force at t = 0.2 s (uN); law calibrated on the same mesh",
            0.2,
            fe89,
            fe89.force,
            t89,
            F_red,
            scale=1e6,
        ),
        dict(case="Figs 8-9", quantity="FE wall time (s)", fe=wall89, reduced=np.nan),
        row(
            "Fig. 10",
            "sigma~ at t = 0.2 s (Pa); law calibrated on the reference mesh",
            0.2,
            ref,
            ref.nominal_stress,
            t_dense,
            cal,
        ),
        row(
            "Fig. 10",
            "sigma~ at t = 1500 s (Pa); law calibrated on the reference mesh",
            1500,
            ref,
            ref.nominal_stress,
            t_dense,
            cal,
        ),
        row("Fig. 10", "sigma~ at t = 0.2 s, Hertz law (Pa)", 0.2, ref, ref.nominal_stress, t_dense, hertz),
        dict(case="Fig. 10", quantity="calibration static FE run (s)", fe=calib_wall, reduced=np.nan),
    ]
    for n in fit.names:
        seed_rows.append(
            dict(
                case="Fig. 10 fit (SYNTHETIC)",
                quantity=f"{n} fitted (95 %: {fit.interval_text(n)})",
                fe=np.nan,
                reduced=pf[n],
            )
        )
    sd = pd.DataFrame(seed_rows)
    sd["rel_diff"] = sd.reduced / sd.fe - 1
    sec.table(sd, "spheroid_seed.csv")
    sec.summary["spheroid"] = dict(
        fe_errors=df[df.method.str.startswith("FE")].error.tolist(),
        hertz_error=float(df[df.method == "reduced (hertz)"].error.iloc[0]),
        calibrated_error=float(df[df.method == "reduced (calibrated on the reference mesh)"].error.iloc[0]),
        fit=dict(pf),
        fig89_vm=[seed_rows[0]["fe"], seed_rows[1]["fe"]],
        fig89_wall_s=wall89,
    )
    sec.md += [
        "## 3. The seed's spheroid figures (Figs 8-10)",
        "",
        "![Fig. 8](fig8_spheroid_von_mises.png)",
        "",
        "![Fig. 9](fig9_mean_von_mises.png)",
        "",
        "Fig. 9 dashed line: NOT an independent model. It is the FE static mean von Mises at delta(t) times the "
        "lumped relaxation factor F_reduced(t)/F_eq(delta(t)), with F_eq calibrated by a static run on the same "
        "mesh; it shows that one relaxation factor carries the whole field (agreement to ~1e-5), not a "
        "prediction. Likewise the Figs 8-9 and Fig. 10 rows of the table below use laws calibrated on the FE mesh "
        "they are compared with. Why the lumped model can match the FE this closely: the plates prescribe "
        "the displacement, the body is (nearly) incompressible and the branches act on the isochoric stress, so "
        "multiplying every stress by one factor leaves the deformation unchanged; during the hold the branch "
        "stress only decays (Q = e^{-(t - t_r)/tau} Q(t_r)) and during the short ramp (t_r/tau = 1e-3) it is "
        "nearly beta S_iso. What is left is the compressibility (kappa/C ~ 1e7), t_r/tau and time stepping.",
        "",
        "![Fig. 10](fig10_nominal_stress.png)",
        "",
        "The red dotted curve is a least-squares fit (``compare.fit.relaxation``, FE-calibrated law) to a "
        "SYNTHETIC record (the finest FE curve with 1 % noise, seed 0): there is no measured record in this "
        "repository (the seed's data come from Marmottant et al., Fig. 3, digitised).",
        "",
        md_table(sd),
        "",
        "### Spheroid accuracy versus speed (Fig. 10 case; error vs the Richardson extrapolation of the FE levels)",
        "",
        "![accuracy spheroid](accuracy_spheroid.png)",
        "",
        "error = max over t in {0.2 s, 1500 s} of |sigma~/sigma~_ref - 1|, sigma~_ref the Richardson extrapolation "
        "of the three finest FE levels with their observed order (row 'FE Richardson'); reduced = the lumped Maxwell model "
        "(reduced.spheroid, exact-kernel quadrature path, jitted; wall time after compile). The row 'calibrated on "
        "the reference mesh' uses "
        f"an equilibrium table from one static FE run on the reference mesh ({calib_wall:.1f} s, not counted "
        "in its wall time), so its error measures the lumped-relaxation assumption alone; 'shipped FE table' "
        "uses the package's master curves (reduced/data: static runs on level 3, checked against level 4, and "
        "interpolated in x and alpha) when present. The coarsest level, where it is run, is outside the asymptotic "
        "range of the three the reference comes from: its error need not exceed the next level's.",
        "",
        md_table(df.drop(columns=["reference"], errors="ignore")),
        "",
    ]
    return sec
