"""``tissuemech batch run|collect``: scheduler-free FE batches for job arrays.

A points table (CSV, one column per keyword argument of the function, SI units) is split into
``--chunks N`` interleaved chunks (point k belongs to chunk k mod N); each array task computes one
chunk into a shared store folder (``compare.batch``: one ``<key>.npz`` per point, written atomically, so
tasks never collide and a rerun skips finished points); ``collect`` gathers the stored results into one
table (the points plus every scalar result field; ``stored`` says which points are done)::

    tissuemech batch run points.csv --store /scratch/run1 --index $SLURM_ARRAY_TASK_ID --chunks 50
    tissuemech batch collect points.csv --store /scratch/run1 --out table.csv

``--index`` defaults to the array index of SLURM (``SLURM_ARRAY_TASK_ID``), PBS (``PBS_ARRAY_INDEX``,
``PBS_ARRAYID``), SGE (``SGE_TASK_ID``, 1-based) or LSF (``LSB_JOBINDEX``, 1-based). ``--function``:
``fe-spheroid`` (default; ``compare.batch.fe_spheroid``), ``fe-blastula`` (``compare.batch.fe_blastula``) or
``module:function`` (a module-level function of keyword arguments; ``run`` and ``collect`` must name the
same one, its name is part of the store keys). Threads: ``--threads T`` (default 1) pins BLAS and XLA
to T threads per process (``compare.batch.worker_env``); ``--workers W`` > 0 evaluates the chunk on W spawned
local processes (``compare.batch.process_pool``), 0 (default) in this process.

Wiring: ``add_parser(subparsers)``, ``run(args)``, ``main(argv)`` (``python -m tissuemech.compare.cli.batch``).
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tissuemech.compare.batch import (
    BatchError,
    StoreWarning,
    UserFunctionWarning,
    array_task,
    chunk,
    collect,
    pin_threads,
    process_pool,
    read_points,
    resolve_function,
)
from tissuemech.compare.batch import run as run_batch

__all__ = ["add_parser", "run", "main"]

log = logging.getLogger(__name__)


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
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserFunctionWarning)
        function = resolve_function(args.function)
    for w in caught:
        print(f"tissuemech batch: warning: {w.message}", file=sys.stderr)
    points = read_points(args.points)
    if cmd == "collect":
        if not Path(args.store).exists():  # a mistyped --store reads like a batch not started yet: say which
            print(f"tissuemech batch: warning: store {args.store} does not exist: no point is stored", file=sys.stderr)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", StoreWarning)
            table = collect(points, args.store, function)
        for w in caught:
            print(f"tissuemech batch: warning: {w.message}", file=sys.stderr)
        if args.out:
            _write_csv(table, Path(args.out))
            print(f"wrote {args.out}: {int(table['stored'].sum())} of {len(table)} points stored")
        else:
            print(table.to_string(index=False))
        return 0

    pin_threads(args.threads)
    source = "--index"
    if args.index is not None:
        index = args.index
    else:
        task = array_task()
        if task is None:
            raise ValueError("--index not given and no job-array index (SLURM_ARRAY_TASK_ID, PBS_ARRAY_INDEX, ...) set")
        index, source = task
    if source != "--index" and not 0 <= index < args.chunks:
        raise ValueError(
            f"{source}={os.environ[source]} is chunk {index} (0-based), but --chunks {args.chunks} has chunks "
            f"0..{args.chunks - 1}: give --chunks the number of array tasks"
        )
    mine = chunk(len(points), index, args.chunks)
    executor: Any = "serial"
    if args.workers < 0:
        raise ValueError(f"--workers must be >= 0, got {args.workers}")
    if args.workers > 0:
        executor = process_pool(args.workers)
    log.info("chunk %d of %d: %d of %d points into %s", index, args.chunks, len(mine), len(points), args.store)
    failures: dict[int, str] = {}
    try:
        run_batch(
            function,
            [points[i] for i in mine],
            executor=executor,
            store=args.store,
            progress=False,
        )
    except BatchError as exc:  # the finished points are stored; the reasons of the others are here
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


def _write_csv(table: Any, path: Path) -> None:
    """``table`` as CSV at ``path``, written to a temporary file next to it and renamed: a failed write (full disk)
    leaves no truncated table. Raises ValueError naming the file."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.part")
    try:
        table.to_csv(tmp, index=False)
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise ValueError(f"--out {path}: cannot write the table ({exc.strerror or exc})") from None


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tissuemech.compare.cli.batch run|collect ...`` (the same as ``tissuemech batch ...``)."""
    p = argparse.ArgumentParser(prog="tissuemech")
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
