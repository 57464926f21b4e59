"""Report section 5: surface tension: what the tensiometry formula reads from a compressed aggregate."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd

from tissuemech.compare.report.common import Section, md_table


def fe_jobs(quick: bool = False) -> list[tuple[Callable, dict, int]]:
    """The section's FE runs as ``(function, keywords, repeats)`` in the order it asks for them (the static sweep,
    then one hold per ``HOLD_NUMBERS``): what the report's builder starts ahead on the second core."""
    from tissuemech.compare.studies import tensiometry as T

    mesh = 0 if quick else 1
    numbers = (0.2, 1.0, 5.0, 20.0) if quick else T.NUMBERS
    return [(T.sweep, dict(numbers=tuple(numbers), mesh=mesh), 1)] + [
        (T.hold_series, dict(number=n, mesh=mesh), 1) for n in T.HOLD_NUMBERS
    ]


def section(*, quick: bool = False, progress: Callable[[str], None] = lambda _: None) -> Section:
    """The formula gamma_app = F / (pi R3^2 (1/R1 + 1/R2)) on FE aggregates (``compare.studies.tensiometry``):
    elastic ones against gamma / (C a0) and relaxing ones against the time since compression."""
    from tissuemech.compare import runcache
    from tissuemech.compare.plots.tension import tensiometry_figure
    from tissuemech.compare.studies import tensiometry as T

    sec = Section("tension", quick)
    progress("surface tension: tensiometry formula")
    (fn, kw, _), *holds = fe_jobs(quick)
    points = runcache.call(fn, kw).result  # reused between reports
    static = T.table(points)
    hold = pd.concat([runcache.call(f, k).result for f, k, _ in holds], ignore_index=True)
    sec.table(static, "tensiometry_static.csv")
    sec.table(hold, "tensiometry_hold.csv")
    sec.save(tensiometry_figure(static, hold, tau=T.TAU), "tensiometry.png")
    thr = T.threshold(points, 0.05)
    wide = hold.pivot(index="time [s]", columns="gamma/(C_inf a0)", values="gamma_app/gamma").reset_index()
    wide.columns = ["time [s]"] + [f"{c:g}" for c in wide.columns[1:]]
    last = hold.groupby("gamma/(C_inf a0)")["gamma_app/gamma"].last()
    sec.summary["tensiometry"] = {
        "number_within_5pct": thr,
        "hold_final_ratio": {f"{k:g}": float(v) for k, v in last.items()},
    }
    sec.md += [
        "## 5. Surface tension: the tensiometry formula on FE aggregates",
        "",
        "Parallel-plate tensiometry reads the tissue surface tension as gamma_app = F / (pi R3^2 (1/R1 + 1/R2)), "
        "exact for a liquid drop at rest (`tissuemech.reduced.drop`). Here it is applied to FE aggregates "
        f"(`compare.studies.tensiometry`, S180 numbers: a0 = {T.A0 * 1e6:g} um, gamma = {T.GAMMA * 1e3:g} mN/m, "
        f"10 % compression, mesh level {kw['mesh']}, node-by-node contact), radii read from the FE profile as from a side "
        "view. Left: elastic aggregates at rest; right: an aggregate of instantaneous E0 = "
        f"{T.E0:g} Pa relaxing through one Maxwell branch (tau = 3 eta / E0 = {T.TAU:g} s for eta = {T.ETA:g} Pa s) "
        "to the long-time modulus C_inf = gamma / (number a0), plates held.",
        "",
        "![tensiometry](tensiometry.png)",
        "",
        md_table(static, cols=["gamma/(C a0)", "gamma_app/gamma", "F/F_drop"]),
        "",
        (
            f"Within 5 % from gamma / (C a0) = {thr:.3g} on (interpolated in the sweep)."
            if np.isfinite(thr)
            else "Within 5 % at no number of this sweep."
        )
        + f" After the hold (t = "
        f"{hold['time [s]'].max():g} s) the relaxing aggregates read "
        + ", ".join(f"{v:.3g} (number {k:g})" for k, v in last.items())
        + " of the true gamma.",
        "",
        "gamma_app / gamma of the relaxing aggregates (rows: time since the compression started; columns: "
        "gamma / (C_inf a0)):",
        "",
        md_table(wide, floatfmt=".3g"),
        "",
        "The formula is within 5 % only where the elastic stress has relaxed to a long-time modulus well below "
        "gamma / a0; right after the compression it overestimates gamma several-fold whatever the long-time "
        "modulus, and it approaches its long-time value only after a few tau. Tables: `tensiometry_static.csv`, "
        "`tensiometry_hold.csv`.",
        "",
    ]
    return sec
