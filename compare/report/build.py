r"""``tissuemech report [--out DIR] [--quick]``: the seed's figures, accuracy-vs-speed charts and a
stability map, regenerated from this code into one folder.

Writes into ``DIR`` (default ``tissuemech-report``):

* PNG figures: ``fig3_blastula_von_mises.png``, ``fig4_alpha_sweep.png``, ``fig5_thickness_sweep.png``,
  ``fig8_spheroid_von_mises.png``, ``fig9_mean_von_mises.png``, ``fig10_nominal_stress.png`` (spheroid
  figures only when ``fem.spheroid`` and ``reduced.spheroid`` import), ``accuracy_blastula.png``,
  ``accuracy_spheroid.png``, ``stability_map.png``;
* CSV tables (one per PNG chart and per seed comparison): ``blastula_sets.csv``, ``accuracy_blastula.csv``,
  ``accuracy_spheroid.csv``, ``stability_limit_point.csv``, ``stability_kappa.csv``,
  ``stability_viscous_step.csv``, ``stability_viscous_boundary.csv``, ``stability_stiff_solvers.csv``,
  ``stability_compression.csv``, ``spheroid_seed.csv``, ``seed_comparison.csv``;
* ``report.md`` showing them with the measured numbers and where the reproduction agrees with the
  seed and where it does not; ``summary.json`` (the headline numbers, for tests and scripts).

``--quick``: coarse meshes and fewer levels (under 3 minutes on 2 cores); the default runs the
finer meshes. All timings in one report come from the same run on the same machine.
Programmatic use: ``build(out_dir, quick=False) -> dict`` (the summary).

Each section is a module of this package whose ``section(...)`` returns a ``Section`` (markdown,
figures, tables, summary entries); ``build`` computes them, then writes the files and joins the
markdown in document order: seed comparison, blastula (Figs 3-5), blastula accuracy, spheroid
(Figs 8-10 and its accuracy), stability map. With two processes (the default) the FE runs are shared between
them and the figures are written by the second one (``build``'s docstring).
"""

from __future__ import annotations

import contextlib
import importlib
import json
import pickle
import platform
import time
import traceback
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from tissuemech.compare.report.common import Section
from tissuemech.compare.runcache import Job

__all__ = ["build", "fe_jobs", "FIGURES", "TABLES", "SPHEROID_FIGURES", "SPHEROID_TABLES"]

FIGURES = (
    "fig3_blastula_von_mises.png",
    "fig4_alpha_sweep.png",
    "fig5_thickness_sweep.png",
    "accuracy_blastula.png",
    "stability_map.png",
)
SPHEROID_FIGURES = (
    "fig8_spheroid_von_mises.png",
    "fig9_mean_von_mises.png",
    "fig10_nominal_stress.png",
    "accuracy_spheroid.png",
    "tensiometry.png",
    "time_convergence_spheroid.png",
)
TABLES = (
    "blastula_sets.csv",
    "accuracy_blastula.csv",
    "stability_limit_point.csv",
    "stability_kappa.csv",
    "stability_viscous_step.csv",
    "stability_viscous_boundary.csv",
    "stability_stiff_solvers.csv",
    "seed_comparison.csv",
)
SPHEROID_TABLES = (
    "accuracy_spheroid.csv",
    "time_convergence_spheroid.csv",
    "stability_compression.csv",
    "spheroid_seed.csv",
    "tensiometry_static.csv",
    "tensiometry_hold.csv",
)


def _guarded(
    key: str, fn: Callable[[], Section], *, quick: bool, title: str = "3. Spheroid figures (Figs 8-10)"
) -> Section:
    """Run an optional section (the spheroid, surface tension); a failure is reported in the report, not fatal."""
    try:
        return fn()
    except Exception as exc:
        msg = f"{type(exc).__name__}: {exc}"
        sec = Section(key, quick, summary={f"{key}_error": msg})
        sec.md += [
            f"## {title}: FAILED in this run ({msg[:300]})",
            "",
            "```",
            traceback.format_exc()[-2000:],
            "```",
            "",
        ]
        return sec


FIGURE_DPI = 110


def write_figures(out: str | Path, figures: dict[str, Any] | bytes) -> list[str]:
    """Write ``figures`` ({file name: matplotlib figure}, or those pickled) as PNG files into the folder ``out`` and
    close them; returns the names. What the second process runs for the builder once its FE runs are done."""
    from tissuemech.compare.plots import pyplot

    plt = pyplot()
    figs = pickle.loads(figures) if isinstance(figures, bytes) else figures
    for name, fig in figs.items():
        fig.savefig(Path(out) / name, dpi=FIGURE_DPI)
        plt.close(fig)
    return list(figs)


class _FigureWriter:
    """Writes each section's figures as soon as the section is done: in the second process (``pool``) after its
    queued FE runs, the figures pickled here (drawing and compressing a PNG takes ~0.3 s a figure, the second
    process is idle by then), or here when there is no pool. :meth:`finish` writes here what the second process has
    not started (taken back, as the FE runs are) or could not write, and waits for the rest."""

    def __init__(self, out: Path, pool: Any = None):
        self.out, self.pool = out, pool
        self.pending: list[tuple[dict[str, Any], Any]] = []

    def submit(self, figures: dict[str, Any]) -> None:
        if not figures:
            return
        fut = None
        if self.pool is not None:
            with contextlib.suppress(Exception):  # an unpicklable figure, a broken pool: written here at the end
                fut = self.pool.submit(write_figures, str(self.out), pickle.dumps(figures))
        self.pending.append((figures, fut))

    def finish(self) -> None:
        from tissuemech.compare.plots import pyplot

        later = []
        for figures, fut in self.pending:
            if fut is None or fut.cancel():
                write_figures(self.out, figures)
            else:
                later.append((figures, fut))
        for figures, fut in later:
            try:
                fut.result()
            except Exception:  # it failed over there: write them here, where an error reaches the caller
                write_figures(self.out, figures)
            for fig in figures.values():
                pyplot().close(fig)
        self.pending.clear()


def _write(out: Path, sec: Section, written: list[str]) -> None:
    """The section's tables (CSV) into ``out``; its figures' names into ``written`` (:class:`_FigureWriter` writes
    them)."""
    written.extend(sec.figures)
    for name, df in sec.tables.items():
        df.to_csv(out / name, index=False)
        written.append(name)


def build(
    out_dir: str | Path = "tissuemech-report", *, quick: bool = False, progress: bool = True, workers: int = 2
) -> dict:
    """Run every section and write the report folder.

    Args: out_dir the folder (created if missing); quick coarse meshes and fewer levels; progress
    show a progress bar on stderr; workers the processes the FE runs share (2: every section's FE runs
    (:func:`fe_jobs`) are queued at once for a second process through the run cache ``compare.runcache``, in the
    order of :func:`worker_order`, while this one works through the sections in order: a run not yet started there
    when this process reaches it is taken back and run here, and while this process waits for a run in progress
    there it runs the runs queued last; each section's figures are written as soon as the section is done, by the
    second process once its runs are done; 1: one after the other, the figures written at the end).
    Returns the summary dict (also written as ``summary.json``).
    """
    from tissuemech.compare import runcache

    pool = None
    with contextlib.ExitStack() as stack:
        if workers > 1:
            from tissuemech.compare.batch.pool import process_pool

            pool = stack.enter_context(process_pool(workers - 1))
            pool.submit(warm_worker)  # the worker starts and imports the FE while this process lists the jobs
            spheroid = _spheroid_reason() is None
            stack.callback(runcache.cancel_pending)  # before the pool's shutdown: nothing left queued
            late = fe_jobs_late(quick, spheroid, longest_first=True)
            runcache.prefetch(pool, worker_order(fe_jobs_early(quick, spheroid), late))
        return _build(out_dir, quick=quick, progress=progress, pool=pool)


def warm_worker() -> None:
    """A second process's first task: import what its FE runs need (~2-3 s), so that it overlaps this process's
    listing of the jobs (whose limit points compile a JAX program) instead of following it."""
    with contextlib.suppress(Exception):  # an import error is the run's to report, where it is imported again
        import tissuemech.fem.blastula
        import tissuemech.fem.spheroid  # noqa: F401


def worker_order(early: list[Job], late: list[Job]) -> list[Job]:
    """The second process's order of the FE runs: the last sections' runs (``late``: spheroid, surface tension) first
    and in the order this process will ask for them, then the first sections' runs (``early``) from the back.

    This process reaches the spheroid section ~20 s in (quick) and needs its runs one after the other from its
    first line on (the calibration run, then the levels): run in that order they are ready when asked for (run
    from the back, the first one asked for came last: this process waited ~4 s for it); meanwhile this process
    works through the early sections from the front and takes back their runs the second has not started (the two
    meet in the middle)."""
    return list(late) + list(early)[::-1]


def fe_jobs_late(quick: bool = False, spheroid: bool = True, longest_first: bool = False) -> list[Job]:
    """The spheroid and surface-tension sections' FE runs (none without ``spheroid``), in the order they are asked for
    (``longest_first``: the spheroid's convergence-in-time runs longest first, see ``report.spheroid.fe_jobs``); an
    optional section whose jobs cannot be listed (an import error) is left out: it runs, or fails, in place."""
    jobs: list[Job] = []
    if spheroid:
        for name in ("spheroid", "tension"):
            try:
                module = importlib.import_module(f"tissuemech.compare.report.{name}")
                jobs += (
                    module.fe_jobs(quick, longest_first=longest_first) if name == "spheroid" else module.fe_jobs(quick)
                )
            except Exception:  # reported by the section itself (_guarded)
                continue
    return jobs


def fe_jobs(quick: bool = False, spheroid: bool = True) -> list[tuple[Callable, dict, int]]:
    """Every section's FE runs as ``(function, keywords, repeats)``, in the order the builder asks for them
    (stability map, blastula figures, blastula accuracy, then with ``spheroid`` the spheroid section and surface
    tension). The limit-point runs are not listed (their load-control sweeps end in an expected ``LimitPointError``);
    an optional section whose jobs cannot be listed (an import error) is left out: it runs, or fails, in place."""
    return fe_jobs_early(quick, spheroid) + fe_jobs_late(quick, spheroid)


def fe_jobs_early(quick: bool = False, spheroid: bool = True) -> list[Job]:
    """The stability map's, blastula figures' and blastula accuracy's FE runs (the stability map's compression depth
    with ``spheroid``), in the order they are asked for."""
    from tissuemech.compare.report import accuracy, blastula, stability

    return stability.fe_jobs(quick, spheroid=spheroid) + blastula.fe_jobs(quick) + accuracy.fe_jobs(quick)


def _spheroid_reason() -> str | None:
    from tissuemech.compare.studies.accuracy import spheroid_available

    return spheroid_available()


def _build(out_dir: str | Path, *, quick: bool, progress: bool, pool: Any = None) -> dict:
    from tqdm.auto import tqdm

    import tissuemech.reduced  # noqa: F401  (float64 JAX)
    from tissuemech.compare import runcache
    from tissuemech.compare.report import accuracy, blastula, seed_comparison, spheroid, stability, tension
    from tissuemech.compare.studies import stability as stability_study
    from tissuemech.compare.studies.accuracy import spheroid_available

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    runcache.counts(reset=True)
    reason = spheroid_available()
    done: dict[str, Section] = {}
    figures = _FigureWriter(out, pool)  # each section's figures are written as soon as it is done
    bar = tqdm(total=13 if reason is None else 7, desc="tissuemech report", disable=not progress, unit="step")

    def step(label: str) -> None:  # one tick per milestone inside the sections, so long stages show progress
        bar.set_postfix_str(label)
        bar.update(1)

    summary: dict[str, Any] = {"quick": quick}
    written: list[str] = []
    # wall and CPU seconds of this process per section (FE runs taken from the cache or from the second process
    # count where they are collected, with the wait for them)
    times: dict[str, dict[str, float]] = {}

    @contextlib.contextmanager
    def timed(name: str) -> Iterator[None]:
        w0, c0 = time.perf_counter(), time.process_time()
        try:
            yield
        finally:
            times[name] = {"wall_s": time.perf_counter() - w0, "cpu_s": time.process_time() - c0}

    step("limit point: load control, arc-length, exact (3 geometries)")
    with timed("limit point"):
        limit = stability_study.limit_point_map(mesh="default")
    with timed("stability map"):
        done["stability map"] = stability.section(limit, quick=quick, spheroid_reason=reason, progress=step)
    figures.submit(done["stability map"].figures)
    with timed("blastula figures"):
        done["blastula figures"] = blastula.section(limit[1], quick=quick, progress=step)
    figures.submit(done["blastula figures"].figures)
    step("blastula accuracy")
    with timed("blastula accuracy"):
        done["blastula accuracy"] = accuracy.section(quick=quick)
    figures.submit(done["blastula accuracy"].figures)
    if reason is None:
        with timed("spheroid figures + accuracy"):
            done["spheroid figures + accuracy"] = _guarded(
                "spheroid", lambda: spheroid.section(quick=quick, progress=step), quick=quick
            )
        figures.submit(done["spheroid figures + accuracy"].figures)
        with timed("surface tension"):
            done["surface tension"] = _guarded(
                "tension", lambda: tension.section(quick=quick, progress=step), quick=quick, title="5. Surface tension"
            )
        figures.submit(done["surface tension"].figures)
    for sec in done.values():
        summary.update(sec.summary)
    step("seed comparison, writing")
    bar.close()
    done["seed comparison"] = seed_comparison.section(limit[0], summary, quick=quick)
    summary.update(done["seed comparison"].summary)
    figures.submit(done["seed comparison"].figures)
    if reason is not None:
        done["spheroid figures + accuracy"] = Section(
            "spheroid",
            quick,
            md=[f"## 3. Spheroid figures (Figs 8-10) and spheroid accuracy: not available ({reason})", ""],
        )
    order = ["seed comparison", "blastula figures", "blastula accuracy", "spheroid figures + accuracy", "stability map"]
    order += ["surface tension"] * ("surface tension" in done)
    md: list[str] = []
    with timed("writing figures and tables"):
        for key in order:
            _write(out, done[key], written)
            md += done[key].md
        figures.finish()
    total = time.perf_counter() - t_start
    summary["total_wall_s"] = total
    summary["section_times"] = times
    summary["fe_runs"] = runcache.counts()  # where the FE runs came from: cache, second process, this one
    summary["spheroid_available"] = reason is None
    summary["files"] = sorted(set(written) | {"report.md", "summary.json"})  # every file this run writes
    head = [
        "# tissuemech report" + (" (quick)" if quick else ""),
        "",
        f"Made by `tissuemech report --out {out}{' --quick' if quick else ''}` in {total:.0f} s on "
        f"{platform.machine()} / {platform.system()} (shared CPU: timings are pessimistic; all in this run). "
        "CSV tables next to this file hold every number shown.",
        "",
    ]
    (out / "report.md").write_text("\n".join(head + md) + "\n")
    (out / "summary.json").write_text(json.dumps(json_safe(summary), indent=1, allow_nan=False))
    return summary


def json_safe(o: Any) -> Any:
    """``o`` with numpy scalars/arrays as Python values and NaN / +-inf as None (JSON ``null``)."""
    if isinstance(o, dict):
        return {str(k): json_safe(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [json_safe(v) for v in o]
    if isinstance(o, np.ndarray):
        return json_safe(o.tolist())
    if isinstance(o, (np.bool_, bool)):
        return bool(o)
    if isinstance(o, (np.integer, int)):
        return int(o)
    if isinstance(o, (np.floating, float)):
        v = float(o)
        return v if np.isfinite(v) else None
    if o is None or isinstance(o, str):
        return o
    return str(o)
