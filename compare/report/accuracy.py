"""Report section 2: accuracy versus speed for the blastula (reduced quadrature, diffrax, FE meshes); and the
spheroid's convergence in time (:func:`time_convergence`, shown in section 3 next to its mesh convergence)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tissuemech.compare.report.common import Section, md_table


def fe_jobs(quick: bool = False) -> list[tuple[Callable, dict, int]]:
    """The blastula accuracy's FE runs as ``(function, keywords, repeats)`` in the order it asks for them."""
    from tissuemech.compare.studies import accuracy

    return accuracy.blastula_fe_jobs(quick=quick)


def section(*, quick: bool = False) -> Section:
    """Accuracy versus speed, blastula: error against the exact shell vs wall time per method."""
    sec = Section("blastula accuracy", quick)
    from tissuemech.compare.plots import charts
    from tissuemech.compare.studies import accuracy

    df = accuracy.blastula_accuracy(quick=sec.quick)
    sec.table(df, "accuracy_blastula.csv")
    sec.save(
        charts.accuracy_chart(
            df,
            title="Blastula (alpha = 0.2, B = 75 um, p = 200/500/1000 Pa): error vs exact",
            note="FE labels: n_radial x n_circ Q2/P1 elements (kappa = 2.2 GPa: the FE converges to the slightly "
            "compressible shell, ~2e-5 in this error (~5e-6 in stretch) from the incompressible exact one, so its error "
            "stops falling there; 4x8 lies below by a cancellation of the two errors); diffrax labels: Dopri8 relative "
            "tolerance; reduced paths jitted, the fastest of "
            f"{accuracy.reduced_calls(sec.quick)} calls after compile (compile time: 'first call [s]' in the table).",
        ),
        "accuracy_blastula.png",
    )
    fe = df[df.method.str.startswith("FE")]
    ode = df[df.method.str.contains("diffrax")]
    quad = df.iloc[0]
    quad_us = 1e6 * float(quad["wall_time [s]"])
    e_ode = ode.error.to_numpy(float)
    twins = [
        f"{a} and {b}"
        for a, b, ea, eb in zip(ode.setting[:-1], ode.setting[1:], e_ode[:-1], e_ode[1:])
        if abs(ea / eb - 1) < 0.01
    ]
    same = (
        f" ({'; '.join(twins)} give the same error to 1 %, so their markers coincide and both labels point at them)"
        if twins
        else ""
    )
    sec.summary["accuracy_blastula"] = dict(
        fe_errors=fe.error.tolist(),
        fe_stretch_errors=fe.stretch_error.tolist(),
        fe_settings=fe.setting.tolist(),
        fe_wall_s=fe["wall_time [s]"].tolist(),
        quadrature_error=float(df.error.iloc[0]),
        quadrature_wall_s=float(df["wall_time [s]"].iloc[0]),
        ode_errors=df[df.method.str.contains("diffrax")].error.tolist(),
        pareto=df[df.pareto].apply(lambda r: f"{r.method} {r.setting}", axis=1).tolist(),
    )
    sec.md += [
        "## 2. Accuracy versus speed",
        "",
        "### Blastula (error against the exact incompressible shell)",
        "",
        "![accuracy blastula](accuracy_blastula.png)",
        "",
        "The chart shows each method's error against its wall time (log-log; bars: the spread of the repeated "
        "timings; red rings: the Pareto front, no method both more accurate and faster beyond the spread). "
        f"What to conclude: the reduced quadrature path is exact to {quad.error:.0e} in {quad_us:.0f} us"
        + (
            " and dominates every other method here (the front is this one point)"
            if df.pareto.sum() == 1 and bool(quad.pareto)
            else "; on the front: " + "; ".join(f"{r.method} {r.setting}" for r in df[df.pareto].itertuples())
        )
        + "; the diffrax path reaches "
        f"{ode.error.min():.0e} at the tightest tolerance and {ode.error.max():.0e} at the loosest{same}; "
        "the FE falls from "
        f"{fe.error.max():.0e} to {fe.error.min():.0e} over the meshes at {fe['wall_time [s]'].min():.2g}.."
        f"{fe['wall_time [s]'].max():.2g} s and stops falling at the compressibility of kappa = 2.2 GPa.",
        "",
        "error = max over p in {200, 500, 1000} Pa of |p_exact(lambda_a)/p - 1| for the state each method returns "
        "(reduced quadrature: lambda_a from p; diffrax: p from the exact lambda_a; FE: load control, kappa = 2.2 GPa). "
        "wall_time [s]: the fastest of repeated calls after a warm-up (21 for the jitted reduced paths, 3 for FE; "
        "the fastest is the least disturbed by other work on the machine), "
        "wall_time min [s]..wall_time max [s] their spread (a row is Pareto-dominated only by one faster beyond that spread, "
        "so the flags do not move with timing noise inside it); first call [s]: the first call (compile / mesh set-up). "
        "The FE error stops falling at ~5e-6 in stretch: that is the compressibility of "
        "kappa/C = 1.1e7 (kappa = 2.2 GPa), not the mesh (see the kappa stability panel).",
        "",
        md_table(
            df,
            cols=[
                "method",
                "setting",
                "wall_time [s]",
                "wall_time min [s]",
                "wall_time max [s]",
                "first call [s]",
                "error",
                "stretch_error",
                "pareto",
            ],
        ),
        "",
    ]
    return sec


def time_convergence(sec: Section) -> list[str]:
    """The spheroid's convergence in time (fast two-branch case): table, chart and text added to ``sec`` (its
    ``quick`` picks level 0 and three fixed step counts); returns the markdown lines."""
    from tissuemech.compare.plots import charts
    from tissuemech.compare.studies import accuracy

    df = accuracy.spheroid_time_convergence(quick=sec.quick)
    level = df.attrs["level"]
    sec.table(df, "time_convergence_spheroid.csv")
    sec.save(
        charts.time_convergence_chart(
            df,
            title=f"Spheroid, tau = 0.05 s on a 0.2 s ramp (level {level}): F at t = 0.05, 0.1, 0.2 s vs the "
            "time-converged FE",
        ),
        "time_convergence_spheroid.png",
    )
    fx, ad = df[df.method == "FE fixed"], df[df.method == "FE adaptive"]
    ref = df[df.method == "FE Richardson"].setting.iloc[0]
    sec.summary["time_convergence_spheroid"] = dict(
        level=level,
        fixed=dict(zip(fx.ramp_steps.astype(int).tolist(), fx.error.tolist())),
        adaptive={r.setting: dict(ramp_steps=int(r.ramp_steps), error=r.error) for r in ad.itertuples()},
    )
    e, n = fx.error.to_numpy(float), fx.ramp_steps.to_numpy(float)
    order = float(np.log(e[-2] / e[-1]) / np.log(n[-1] / n[-2]))
    adaptive_text = "; ".join(
        f"Adaptive({st}) takes {int(n)} ramp steps and is within {e:.1e} (lumped estimate {le:.1e})"
        for st, n, e, le in zip(ad.setting, ad.ramp_steps, ad.error, ad["lumped estimate"])
    )
    return [
        f"### Spheroid convergence in time (fast Maxwell branch, level {level})",
        "",
        "![time convergence spheroid](time_convergence_spheroid.png)",
        "",
        "The mesh convergence above is for a slow branch (tau = 200 s), where the time step hardly matters. With a "
        "branch a quarter of the ramp (issue 35: a0 = 500 um, C = 150 Pa, alpha = 0.2, branches (0.8, 0.05 s) and "
        "(0.3, 20 s), 100 um in 0.2 s) the time step does: the chart shows F / F_ref - 1 at t = 0.05, 0.1, 0.2 s "
        f"against the level's own time-converged force (Richardson of fixed {ref}) versus the ramp step count. "
        f"What to conclude: fixed steps converge (from {fx.error.iloc[0]:.1e} with {fx.setting.iloc[0]}, release "
        f"0.1's default, to {fx.error.iloc[-1]:.1e} with {fx.setting.iloc[-1]}; observed order of the worst error "
        f"{order:.2f}, 2 in the asymptotic range); the default adaptive steps (``fem.stepping.Adaptive``) put them where "
        f"the Maxwell update needs them: {adaptive_text}. The lumped estimate (dashed, the scalar recursion "
        "Adaptive controls) follows the FE's error, which is why a microsecond estimate can choose the steps. "
        "Full study: `tissuemech bench fem-time --adaptive` (level 1: the default tol = 2e-4 is within 7.5e-5 at "
        "every output time).",
        "",
        md_table(df),
        "",
    ]
