"""Scheduler-free FE batches for job arrays: ``tissuemech batch run`` / ``tissuemech batch collect``.

A points table (CSV, one column per keyword argument of the function, SI units) is split into
``--chunks N`` interleaved chunks (point k belongs to chunk k mod N); each array task computes one
chunk into a shared store folder (``compare.batch``: one ``<key>.npz`` per point, written atomically, so
tasks never collide and a rerun skips finished points); ``collect`` gathers the stored results into one
table (the points plus every scalar result field; ``stored`` says which points are done)::

    tissuemech batch run points.csv --store /scratch/run1 --index $SLURM_ARRAY_TASK_ID --chunks 50
    tissuemech batch collect points.csv --store /scratch/run1 --out table.csv

``--index`` defaults to the array index of SLURM (``SLURM_ARRAY_TASK_ID``), PBS (``PBS_ARRAY_INDEX``,
``PBS_ARRAYID``), SGE (``SGE_TASK_ID``, 1-based) or LSF (``LSB_JOBINDEX``, 1-based). ``--function``:
``fe-spheroid`` (default; :func:`fe_spheroid`), ``fe-blastula`` (:func:`fe_blastula`) or
``module:function`` (a module-level function of keyword arguments; ``run`` and ``collect`` must name the
same one, its name is part of the store keys). Threads: ``--threads T`` (default 1) pins BLAS and XLA
to T threads per process (:func:`worker_env`); ``--workers W`` > 0 evaluates the chunk on W spawned
local processes, 0 (default) in this process.

API: ``add_parser(subparsers)``, ``run(args)``, ``main(argv)`` (``python -m tissuemech.compare.batch_cli``),
``chunk(n_points, index, chunks)``, ``read_points(path)``, ``collect(points, store, function)``,
``worker_env(threads)``, ``pin_threads(threads)``, ``jobqueue_cluster(system, ...)`` (dask-jobqueue),
``resolve_function(spec)``, ``fe_spheroid``, ``fe_blastula``.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any

__all__ = [
    "add_parser",
    "run",
    "main",
    "chunk",
    "read_points",
    "collect",
    "worker_env",
    "pin_threads",
    "jobqueue_cluster",
    "resolve_function",
    "fe_spheroid",
    "fe_blastula",
    "FUNCTIONS",
]

log = logging.getLogger(__name__)

_ARRAY_INDEX = (
    ("SLURM_ARRAY_TASK_ID", 0),
    ("PBS_ARRAY_INDEX", 0),
    ("PBS_ARRAYID", 0),
    ("SGE_TASK_ID", 1),
    ("LSB_JOBINDEX", 1),
)


def worker_env(threads: int = 1) -> dict[str, str]:
    """Environment variables that pin BLAS (OpenMP, OpenBLAS, MKL, BLIS, Accelerate) and XLA's CPU
    backend to ``threads`` threads per process: pass them to worker processes (dask ``LocalCluster(env=...)``,
    ``dask_jobqueue`` ``job_script_prologue``) so that W workers on W cores do not oversubscribe them.
    Raises ValueError unless ``threads`` is a positive integer."""
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads (per worker process) must be a positive integer, got {threads!r}")
    n = str(threads)
    env = {k: n for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")}
    env["VECLIB_MAXIMUM_THREADS"] = n
    env["NUMEXPR_NUM_THREADS"] = n
    xla = f"--xla_cpu_multi_thread_eigen={'true' if threads > 1 else 'false'} intra_op_parallelism_threads={n}"
    env["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + xla).strip()
    return env


def pin_threads(threads: int = 1) -> dict[str, str]:
    """Set :func:`worker_env` in ``os.environ`` (inherited by processes started afterwards; BLAS of this
    process only if it is not loaded yet) and return it."""
    env = worker_env(threads)
    os.environ.update(env)
    return env


_JOBQUEUE = {
    "slurm": "SLURMCluster",
    "pbs": "PBSCluster",
    "sge": "SGECluster",
    "lsf": "LSFCluster",
    "htcondor": "HTCondorCluster",
}


def jobqueue_cluster(
    system: str, *, cores: int, memory: str, walltime: str, threads_per_worker: int = 1, **kwargs: Any
):
    """A dask-jobqueue cluster whose jobs each run ``cores // threads_per_worker`` pinned workers.

    system              "slurm", "pbs", "sge", "lsf" or "htcondor" (needs ``pip install tissuemech[cluster]``).
    cores, memory       per job (e.g. 8, "16GB"); walltime per job ("02:00:00").
    threads_per_worker  threads of each worker; BLAS and XLA are pinned to it (:func:`worker_env`) by
                        exports prepended to ``job_script_prologue``.
    kwargs              passed on (``queue``, ``account``, ``job_extra_directives``, ``job_script_prologue``
                        lines to run after the exports, e.g. activating the environment, ...).
    Scale it with ``cluster.scale(jobs=n)`` and pass ``dask.distributed.Client(cluster)`` as the executor of
    ``compare.batch.run``. Raises ValueError for an unknown system or cores not divisible by the threads,
    ImportError without dask-jobqueue.
    """
    if system.lower() not in _JOBQUEUE:
        raise ValueError(f"system must be one of {sorted(_JOBQUEUE)}, got {system!r}")
    if cores < 1 or threads_per_worker < 1 or cores % threads_per_worker:
        raise ValueError(
            f"cores per job ({cores}) must be a positive multiple of threads_per_worker ({threads_per_worker})"
        )
    import dask_jobqueue

    env = worker_env(threads_per_worker)
    prologue = [f"export {k}='{v}'" for k, v in env.items()] + list(kwargs.pop("job_script_prologue", []))
    cls = getattr(dask_jobqueue, _JOBQUEUE[system.lower()])
    return cls(
        cores=cores,
        processes=cores // threads_per_worker,
        memory=memory,
        walltime=walltime,
        job_script_prologue=prologue,
        **kwargs,
    )


def fe_spheroid(
    *,
    radius: float = 500e-6,
    C: float,
    alpha: float,
    beta: float,
    tau: float,
    displacement: float,
    ramp_time: float = 0.2,
    end_time: float = 1500.0,
    mesh: Any = "default",
) -> dict:
    """One FE compression-relaxation (``fem.spheroid.compress``, one Maxwell branch), SI units.

    Returns the curves ``time`` [s], ``force`` [N], ``nominal_stress`` [Pa] and the scalars
    ``sigma_peak`` and ``sigma_end`` [Pa] (largest and last nominal stress), ``steps``."""
    from tissuemech.fem import spheroid

    r = spheroid.compress(
        radius=radius,
        C=C,
        alpha=alpha,
        branches=[(beta, tau)] if beta > 0 else [],
        displacement=displacement,
        ramp_time=ramp_time,
        end_time=end_time,
        mesh=int(mesh) if isinstance(mesh, float) and mesh.is_integer() else mesh,
    )
    s = r.nominal_stress
    return dict(
        time=r.time,
        force=r.force,
        nominal_stress=s,
        sigma_peak=float(s.max()),
        sigma_end=float(s[-1]),
        steps=len(r.time),
    )


def fe_blastula(
    *, inner_radius: float = 50e-6, outer_radius: float, C: float, alpha: float, pressure: float, mesh: Any = "default"
) -> dict:
    """One FE inflation (``fem.blastula.inflate``) to ``pressure`` (Pa), SI units; returns the scalars
    ``inner_stretch`` and ``outer_stretch`` [-] and ``newton_iterations``."""
    from tissuemech.fem import blastula

    r = blastula.inflate(
        inner_radius=inner_radius, outer_radius=outer_radius, C=C, alpha=alpha, pressures=[pressure], mesh=mesh
    )
    return dict(
        inner_stretch=float(r.inner_stretch[-1]),
        outer_stretch=float(r.outer_stretch[-1]),
        newton_iterations=int(r.newton_iterations.sum()),
    )


FUNCTIONS: dict[str, Callable[..., Any]] = {"fe-spheroid": fe_spheroid, "fe-blastula": fe_blastula}


def resolve_function(spec: str) -> Callable[..., Any]:
    """A name of :data:`FUNCTIONS` or ``module:function``; raises ValueError if it cannot be found."""
    if spec in FUNCTIONS:
        return FUNCTIONS[spec]
    mod, sep, name = spec.partition(":")
    if not sep or not mod or not name:
        raise ValueError(f"--function must be one of {sorted(FUNCTIONS)} or 'module:function', got {spec!r}")
    try:
        obj: Any = importlib.import_module(mod)
        for part in name.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError) as exc:
        raise ValueError(f"--function {spec!r} not found: {exc}") from None
    if not callable(obj):
        raise ValueError(f"--function {spec!r} is not callable")
    return obj


_SI_UNITS = {"", "-", "1", "m", "s", "Pa", "N", "kg", "J"}  # units a points-table header may state


def read_points(path: str | os.PathLike) -> list[dict[str, Any]]:
    """The points of a CSV table (header = keyword names; numbers in SI units), one dict per row, with
    Python ints/floats/strings (integral columns stay ints). Raises ValueError for an empty table."""
    import pandas as pd

    df = pd.read_csv(path)
    if df.empty:
        raise ValueError(f"{path}: the points table has no rows")
    names = []
    for c in map(str, df.columns):  # 'C [Pa]' -> 'C'; the numbers must be SI: a unit is checked, not dropped
        name, _, unit = c.partition(" [")
        unit = unit.rstrip("]").strip()
        if unit not in _SI_UNITS:
            raise ValueError(
                f"{path}: column {c!r}: the points are passed as they are, in SI units ({', '.join(sorted(_SI_UNITS - {''}))}); "
                f"convert the column to SI and name it so (e.g. 'C [Pa]', 'radius [m]')"
            )
        names.append(name.strip())
    df.columns = names
    return [{k: (v.item() if hasattr(v, "item") else v) for k, v in row.items()} for row in df.to_dict("records")]


def chunk(n_points: int, index: int, chunks: int) -> list[int]:
    """Indices of the points in chunk ``index`` of ``chunks`` (interleaved: k with k mod chunks == index).
    Raises ValueError unless 0 <= index < chunks."""
    if chunks < 1:
        raise ValueError(f"--chunks must be >= 1, got {chunks}")
    if not 0 <= index < chunks:
        raise ValueError(f"--index must be in 0..{chunks - 1} (the chunk number), got {index}")
    return list(range(index, n_points, chunks))


def _array_index() -> int | None:
    for name, base in _ARRAY_INDEX:
        v = os.environ.get(name)
        if v not in (None, "", "undefined"):
            try:
                return int(v) - base
            except ValueError:
                raise ValueError(f"{name}={v!r} is not an integer array index") from None
    return None


def collect(points: Sequence[dict], store: str | os.PathLike, function: Callable[..., Any]):
    """DataFrame: the points, ``stored`` (bool) and every scalar field of the stored results (NaN where
    not stored yet); curves (arrays) stay in the store (``compare.batch.load``)."""
    from pathlib import Path

    import numpy as np
    import pandas as pd

    from tissuemech.compare import batch

    rows = []
    for p in points:
        f = Path(store) / f"{batch.point_key(function, p)}.npz"
        row: dict[str, Any] = dict(p)
        row["stored"] = f.exists()
        if f.exists():
            r = batch.load(f)
            for k, v in r.items():
                if k != "__point__" and np.ndim(v) == 0 and k not in p:
                    row[k] = v.item() if hasattr(v, "item") else v
        rows.append(row)
    return pd.DataFrame(rows)


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``batch run`` and ``batch collect`` to the ``tissuemech`` subcommands; returns the parser."""
    b = sub.add_parser(
        "batch",
        help="FE batches for job arrays: compute one chunk of a points table into a store, collect a table",
        description="Scheduler-free FE batches: 'batch run' computes chunk --index of --chunks of the points "
        "table into --store (resumable), 'batch collect' gathers the stored results into one table.",
    )
    bs = b.add_subparsers(dest="batch_command", metavar="{run,collect}")
    for name in ("run", "collect"):
        s = bs.add_parser(name, help="compute one chunk" if name == "run" else "gather the stored results")
        s.add_argument("points", help="CSV table of points (one column per keyword argument, SI units)")
        s.add_argument("--store", required=True, help="shared folder of the results (<key>.npz per point)")
        s.add_argument(
            "--function",
            default="fe-spheroid",
            help="fe-spheroid (default), fe-blastula or module:function (the same for run and collect)",
        )
        if name == "run":
            s.add_argument("--index", type=int, default=None, help="chunk number 0..N-1 (default: the job-array index)")
            s.add_argument("--chunks", type=int, default=1, help="number of chunks N (default: 1)")
            s.add_argument("--threads", type=int, default=1, help="BLAS/XLA threads per process (default: 1)")
            s.add_argument(
                "--workers", type=int, default=0, help="local processes for the chunk (default 0: in-process)"
            )
        else:
            s.add_argument("--out", default=None, help="CSV file for the table (default: print it)")
    return b


def run(args: argparse.Namespace) -> int:
    """Run ``tissuemech batch run|collect`` from parsed arguments; returns the exit code (0; 1 if points
    of the chunk failed). Raises ValueError for bad arguments (the CLI prints them as one line)."""
    cmd = getattr(args, "batch_command", None)
    if cmd not in ("run", "collect"):
        raise ValueError("batch needs a subcommand: 'run' or 'collect'")
    function = resolve_function(args.function)
    points = read_points(args.points)
    if cmd == "collect":
        table = collect(points, args.store, function)
        if args.out:
            table.to_csv(args.out, index=False)
            print(f"wrote {args.out}: {int(table['stored'].sum())} of {len(table)} points stored")
        else:
            print(table.to_string(index=False))
        return 0

    pin_threads(args.threads)
    index = args.index if args.index is not None else _array_index()
    if index is None:
        raise ValueError("--index not given and no job-array index (SLURM_ARRAY_TASK_ID, PBS_ARRAY_INDEX, ...) set")
    mine = chunk(len(points), index, args.chunks)
    from tissuemech.compare import batch

    executor: Any = "serial"
    if args.workers < 0:
        raise ValueError(f"--workers must be >= 0, got {args.workers}")
    if args.workers > 0:
        import concurrent.futures as cf
        import multiprocessing

        executor = cf.ProcessPoolExecutor(
            args.workers, mp_context=multiprocessing.get_context("spawn"), initializer=batch.worker_init
        )
    log.info("chunk %d of %d: %d of %d points into %s", index, args.chunks, len(mine), len(points), args.store)
    failures: dict[int, str] = {}
    try:
        batch.run(
            function,
            [points[i] for i in mine],
            executor=executor,
            store=args.store,
            progress=False,
        )
    except batch.BatchError as exc:  # the finished points are stored; the reasons of the others are here
        failures = exc.failures
    finally:
        if args.workers > 0:
            executor.shutdown()
    failed = sorted(mine[k] for k in failures)
    print(f"chunk {index}/{args.chunks}: {len(mine) - len(failed)} of {len(mine)} points stored in {args.store}")
    if failed:
        print(f"failed points (rows of {args.points}, 0-based): {failed}", file=sys.stderr)
        for k in sorted(failures)[:10]:
            print(f"  row {mine[k]}: {failures[k]}", file=sys.stderr)
        print(
            "a rerun with the same store retries only these (one that failed on its inputs fails again: fix the row)",
            file=sys.stderr,
        )
        return 1
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tissuemech.compare.batch_cli run|collect ...`` (the same as ``tissuemech batch ...``)."""
    p = argparse.ArgumentParser(prog="python -m tissuemech.compare.batch_cli")
    sub = p.add_subparsers(dest="command")
    add_parser(sub)
    args = p.parse_args(["batch", *(sys.argv[1:] if argv is None else argv)])
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    try:
        return run(args)
    except (ValueError, OSError) as exc:
        print(f"tissuemech batch: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
