"""tissuemech report: the folder it promises, and the physics in its numbers.

The session fixture ``quick_report`` (conftest.py) runs ``build(..., quick=True)`` once (about 1.5
minutes on 2 cores); these tests check every figure and table, then the numbers in them.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tissuemech.compare import report


def _csv(out: Path, name: str) -> pd.DataFrame:
    return pd.read_csv(out / name)


@pytest.mark.slow
def test_every_promised_file_exists_and_is_not_empty(quick_report):
    out, summary = quick_report
    names = list(report.FIGURES) + list(report.TABLES) + ["report.md", "summary.json"]
    if summary["spheroid_available"]:
        assert "spheroid_error" not in summary, summary.get("spheroid_error")
        assert "tension_error" not in summary, summary.get("tension_error")
        names += list(report.SPHEROID_FIGURES) + list(report.SPHEROID_TABLES)
    for n in names:
        p = out / n
        assert p.is_file() and p.stat().st_size > 0, n
        if n.endswith(".png"):
            assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and p.stat().st_size > 10_000, n
        if n.endswith(".csv"):
            assert len(_csv(out, n)) > 0, n
    md = (out / "report.md").read_text()
    for n in names:
        if n.endswith(".png"):
            assert f"({n})" in md, f"report.md does not show {n}"
    assert json.loads((out / "summary.json").read_text())["quick"] is True


@pytest.mark.slow
def test_report_states_the_seed_burst_disagreement(quick_report):
    out, _ = quick_report
    md = (out / "report.md").read_text()
    assert "197.41 Pa" in md and "90.06 Pa" in md and "19.44 Pa" in md
    seed = _csv(out, "seed_comparison.csv")
    row = seed[seed.claim.str.contains("B = 75")].iloc[0]
    assert row.agrees == "NO"


@pytest.mark.slow
def test_blastula_accuracy_numbers(quick_report):
    out, _ = quick_report
    df = _csv(out, "accuracy_blastula.csv")
    fe = df[df.method.str.startswith("FE")]
    assert len(fe) == 4
    # every FE level but the coarsest 1x2 is within 1e-4 of the exact inner stretch
    assert (fe.stretch_error.iloc[1:] < 1e-4).all()
    assert (fe.error.iloc[2:] < 1e-4).all()
    quad = df[df.method == "reduced quadrature"].iloc[0]
    assert quad.error < 1e-12 and bool(quad.pareto)
    ode = df[df.method.str.contains("diffrax")].set_index("setting")
    assert ode.loc["rtol=1e-10", "error"] < 1e-10
    assert ode.loc["rtol=1e-10", "error"] < ode.loc["rtol=1e-06", "error"] < ode.loc["rtol=1e-03", "error"]
    sets = _csv(out, "blastula_sets.csv")
    assert sets.max_rel_pressure_err.max() < 2e-3


@pytest.mark.slow
def test_limit_point_map(quick_report):
    out, _ = quick_report
    lim = _csv(out, "stability_limit_point.csv")
    exact = {52.0: 19.44, 60.0: 90.06, 75.0: 197.41}
    for b, p in exact.items():
        g = lim[lim["B [um]"] == b].set_index("method")
        assert g.loc["reduced (exact)", "p reached [Pa]"] == pytest.approx(p, abs=0.006)
        arc = g.loc["FE arc-length"]
        assert abs(arc.rel_err_p) < 5e-3 and bool(arc.passed_limit)
        lc = g.loc["FE load control"]
        assert -5e-3 < lc.rel_err_p <= 1e-9 and not bool(lc.passed_limit)


@pytest.mark.slow
def test_kappa_map_mixed_beats_displacement(quick_report):
    out, _ = quick_report
    k = _csv(out, "stability_kappa.csv")
    top = k[k.kappa_over_C == k.kappa_over_C.max()].set_index("formulation")
    assert k.kappa_over_C.max() == pytest.approx(1e7)
    assert top.loc["mixed", "error"] < 1e-5
    assert bool(top.loc["displacement", "failed"]) or top.loc["displacement", "error"] > 100 * top.loc["mixed", "error"]
    # mixed: the error is the physical compressibility ~ C/kappa, falling tenfold per decade
    m = k[(k.formulation == "mixed") & (k.kappa_over_C <= 1e5)].sort_values("kappa_over_C")
    assert np.all(np.diff(np.log10(m.error)) < -0.9)


@pytest.mark.slow
def test_viscous_and_stiff_maps(quick_report):
    out, _ = quick_report
    b = _csv(out, "stability_viscous_boundary.csv").set_index("update")
    assert b.loc["exact-linear", "largest ok step [s]"] >= 100 * b.loc["backward Euler", "largest ok step [s]"]
    assert 0.1 < b.loc["backward Euler", "largest ok step [s]"] < 10
    s = _csv(out, "stability_stiff_solvers.csv")
    imp = s[s.solver == "Kvaerno5"]
    assert not imp.failed.any() and imp.steps.max() < 500
    exp = s[s.solver == "Tsit5"].sort_values("tau_over_ramp", ascending=False)
    assert bool(exp.failed.iloc[-1])
    ok = exp[~exp.failed]
    assert np.all(np.diff(ok.steps) > 0)


@pytest.mark.slow
def test_spheroid_numbers(quick_report):
    out, summary = quick_report
    assert summary["spheroid_available"], "the report left out its spheroid section (fem.spheroid / reduced.spheroid)"
    acc = _csv(out, "accuracy_spheroid.csv")
    fe = acc[acc.method.str.startswith("FE")]
    assert fe.error.iloc[:-1].max() < 0.02
    cal = acc[acc.method == "reduced (calibrated on the reference mesh)"].iloc[0]
    assert cal.error < 1e-3
    hertz = acc[acc.method == "reduced (hertz)"].iloc[0]
    assert 0.02 < hertz.error < 0.3  # Hertz is a small-strain law: off by ~10 % at 5 % compression
    fit = summary["spheroid"]["fit"]
    assert fit["tau"] == pytest.approx(200.0, rel=0.15) and fit["beta"] == pytest.approx(0.4, rel=0.15)
    comp = _csv(out, "stability_compression.csv")
    # the seed's 30 % converges; beyond it the fitted-mesh contact may fail, and then says how
    assert comp[comp.converged].fraction.max() >= 0.3
    failed = comp[~comp.converged]
    assert failed.failure.notna().all() and (failed.fraction > 0.3).all()


def test_accuracy_chart_keeps_every_label_inside_the_axes():
    """The stacked labels of an accuracy chart may sit above the highest point (four FE meshes near one error):
    the y-range takes them in, so no label runs into the title or out of the figure."""
    from tissuemech.compare.plots import charts, pyplot

    df = pd.DataFrame(
        dict(
            method=["FE"] * 6 + ["reduced"],
            setting=[f"mesh {n}x{2 * n}" for n in (2, 4, 8, 16, 24, 32)] + ["quadrature"],
            error=[1.2e-4, 1.1e-4, 1.05e-4, 1e-4, 1e-4, 1e-4, 3e-15],
            pareto=[False] * 6 + [True],
        )
    )
    df["wall_time [s]"] = [0.07, 0.06, 0.2, 1.0, 3.0, 6.0, 6e-5]
    fig = charts.accuracy_chart(df, title="t")
    ax = fig.axes[0]
    lo, hi = ax.get_ylim()
    ys = [a.xyann[1] for a in ax.texts if hasattr(a, "xyann")]
    assert len(ys) == 7 and max(ys) > 1.2e-4 * 10  # the six FE labels stack above their points
    assert all(lo <= y <= hi for y in ys)
    pyplot().close(fig)


def test_fe_jobs_list_every_prefetched_run_once_and_cacheable():
    """The builder's job list (what the second process starts ahead, in reverse): every run has a cache key, the
    spheroid section's runs (accuracy levels, Figs 8-9, time convergence) and the tension sweep are in it, and without
    the spheroid nothing of the spheroid is."""
    from tissuemech.compare import runcache
    from tissuemech.compare.report.build import fe_jobs
    from tissuemech.compare.studies.accuracy import time_convergence_jobs

    jobs = fe_jobs(quick=True)
    keys = [runcache.key(fn, {"kwargs": kw, "repeats": r}) for fn, kw, r in jobs]  # raises if one is not cacheable
    names = {f"{fn.__module__}.{fn.__name__}" for fn, _, _ in jobs}
    assert {"tissuemech.fem.spheroid.compress", "tissuemech.fem.blastula.inflate"} <= names
    assert {"tissuemech.compare.calibrate.static_curve", "tissuemech.compare.studies.tensiometry.sweep"} <= names
    tc = [runcache.key(fn, {"kwargs": kw, "repeats": r}) for fn, kw, r in time_convergence_jobs(quick=True)]
    assert len(tc) == 4 and set(tc) <= set(keys)
    assert len(set(keys)) >= len(keys) - 1  # Fig. 3's run is also one of the Fig. 4 sets
    bare = fe_jobs(quick=True, spheroid=False)
    assert not {f"{fn.__module__}.{fn.__name__}" for fn, _, _ in bare} & {
        "tissuemech.fem.spheroid.compress",
        "tissuemech.compare.calibrate.static_curve",
    }


def test_the_second_process_runs_the_last_sections_first_and_in_order():
    """The second process's queue: the spheroid and tension runs first, in the order the builder asks for them (so the
    first one asked for is ready first), then the earlier sections' runs from the back (the builder takes those back
    from the front: the two meet in the middle)."""
    from tissuemech.compare import runcache
    from tissuemech.compare.report.build import fe_jobs, fe_jobs_early, fe_jobs_late, worker_order

    assert worker_order([1, 2, 3], ["a", "b"]) == ["a", "b", 3, 2, 1]
    early, late = fe_jobs_early(quick=True), fe_jobs_late(quick=True)
    assert early and late
    key = lambda jobs: [runcache.key(fn, {"kwargs": kw, "repeats": r}) for fn, kw, r in jobs]
    assert key(fe_jobs(quick=True)) == key(early) + key(late)
    assert {f"{fn.__module__}.{fn.__name__}" for fn, _, _ in late} >= {
        "tissuemech.compare.calibrate.static_curve",
        "tissuemech.compare.studies.tensiometry.sweep",
    }
    assert fe_jobs_late(quick=True, spheroid=False) == []


def test_figures_written_by_the_second_process_are_the_figures_drawn_here(tmp_path):
    """The builder's figure writer: figures sent (pickled) to another executor come out as the same PNG bytes as
    figures written here; without an executor, and where the executor fails, they are written here."""
    import concurrent.futures as cf

    from tissuemech.compare.plots import pyplot
    from tissuemech.compare.report.build import _FigureWriter, write_figures

    plt = pyplot()

    def figs():
        fig, ax = plt.subplots(figsize=(3, 2))
        ax.plot([0, 1, 2], [1, 0, 2], "k-o", label="a curve")
        ax.legend()
        return {"curve.png": fig}

    (tmp_path / "here").mkdir()
    assert write_figures(tmp_path / "here", figs()) == ["curve.png"]
    reference = (tmp_path / "here" / "curve.png").read_bytes()
    for name, pool in (("pool", cf.ThreadPoolExecutor(1)), ("none", None), ("broken", cf.ThreadPoolExecutor(1))):
        out = tmp_path / name
        out.mkdir()
        if name == "broken":
            pool.shutdown()  # submit raises: written here at the end
        writer = _FigureWriter(out, pool)
        writer.submit(figs())
        writer.finish()
        assert (out / "curve.png").read_bytes() == reference, name
        if pool is not None:
            pool.shutdown()
