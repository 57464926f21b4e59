"""Run a function over many parameter points through a ``concurrent.futures`` executor, with resume.

``run(function, points, executor=None, store=path)`` evaluates ``function(**point)`` for each point
(a dict of keyword arguments, SI units). Each result is written to ``store`` (``compare.batch.store``) the
moment its point finishes; a rerun with the same ``store`` skips every stored point, and points a
concurrent run into the same store is computing are waited for.

Executors: local processes by default (``compare.batch.pool.process_pool``: 2 workers, "spawn" start so JAX
state is never forked, one BLAS thread per worker); any ``concurrent.futures.Executor``; a
``dask.distributed.Client`` (its ``get_executor()`` is used; results come back to this process, which writes
the store, so workers need no shared disk); or ``"serial"`` (in-process, for debugging).

Results are returned as :class:`Stored` objects (a dict with attribute access) holding the result's
fields as NumPy arrays: NamedTuples, dataclasses, dicts, scalars and arrays are all accepted.
"""

from __future__ import annotations

import concurrent.futures as cf
import logging
import os
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from tissuemech.compare.batch.pool import Serial, as_executor, evaluate
from tissuemech.compare.batch.store import (
    Stored,
    StoreError,
    check_writable,
    claim,
    clean_parts,
    describe_owner,
    jsonable,
    load_or_quarantine,
    lock_is_stale,
    point_key,
    release,
    save,
)

__all__ = ["run", "BatchError", "WAIT_REPORT", "WAIT_FIRST"]

log = logging.getLogger(__name__)

WAIT_REPORT = 60.0  # s between warnings while waiting for points another run computes (the first after WAIT_FIRST)
WAIT_FIRST = 10.0


class BatchError(RuntimeError):
    """Some points failed; ``failures`` maps point index -> exception text. Finished points are stored."""

    def __init__(self, message: str, failures: dict[int, str]):
        super().__init__(message)
        self.failures = failures


def run(
    function: Callable[..., Any],
    points: Iterable[Mapping[str, Any]],
    *,
    executor: Any = None,
    store: str | os.PathLike | None = None,
    progress: bool = True,
    raise_on_error: bool = True,
    poll: float = 0.05,
    stale_after: float = 24 * 3600.0,
) -> list[Stored | None]:
    """Evaluate ``function(**point)`` for every point; return the results in the order of ``points``.

    function   a picklable (module-level) function of keyword arguments.
    points     dicts of keyword arguments (SI units).
    executor   None: 2 local processes; "serial"; a concurrent.futures.Executor; a dask Client.
    store      directory for ``<key>.npz`` results; points already there are not recomputed (resume).
               A stored file is used only if it is intact and the result of this function (name and source),
               point and tissuemech version; others (damaged, or copied from another point) are moved aside and
               recomputed (with a ``StoreWarning`` naming the file); points claimed by a concurrent run into the
               same store are waited for, not recomputed (logged: which point, which process holds it).
    progress   show a tqdm progress bar.
    poll       seconds between looks at points another run is computing.
    stale_after  seconds after which a lock of a process on another host counts as abandoned (locks of
               dead processes on this host are taken over at once).
    Failed points are collected; at the end a :class:`BatchError` names them (finished points are
    stored, so a rerun continues), or with ``raise_on_error=False`` their entries are None.
    Raises :class:`StoreError` before computing anything if the store cannot be written, and (naming the
    store and the file) when a stored file cannot be read or a result cannot be written (full disk).
    """
    if not callable(function):
        raise ValueError(f"function must be a callable of keyword arguments; got {function!r}")
    if isinstance(points, (str, bytes, Mapping)) or not isinstance(points, Iterable):
        raise ValueError(f"points must be a sequence of dicts of keyword arguments; got {type(points).__name__}")
    pts = []
    j: int | None  # a point index here, first_of.get(...) below
    for j, p in enumerate(points):
        if not isinstance(p, Mapping):
            raise ValueError(f"points[{j}] must be a dict of keyword arguments; got {p!r}")
        pts.append(dict(p))
    keys = [point_key(function, p) for p in pts]
    results: list[Stored | None] = [None] * len(pts)
    folder = Path(store) if store is not None else None
    if folder is not None:
        if folder.exists() and not folder.is_dir():
            raise StoreError(f"store {folder} exists and is not a folder")
        for i, k in enumerate(keys):
            results[i] = load_or_quarantine(folder / f"{k}.npz", k)
    todo = [i for i, r in enumerate(results) if r is None]
    failures: dict[int, str] = {}
    if not todo:
        return results
    if folder is not None:
        check_writable(folder)
        clean_parts(folder)
    from tqdm.auto import tqdm

    first_of: dict[str, int] = {}  # one computation per distinct key (duplicate points share it)
    for i in todo:
        first_of.setdefault(keys[i], i)
    pending = [first_of[k] for k in dict.fromkeys(keys[i] for i in todo)]
    ex, owned = as_executor(executor)
    window = 1 if isinstance(ex, Serial) else max(4, 2 * (getattr(ex, "_max_workers", 4) or 4))
    bar = tqdm(total=len(pts), initial=len(pts) - len(todo), disable=not progress, desc="batch")
    held: set[str] = set()
    try:
        waiting: list[int] = []  # points another run holds: looked at again later
        announced: set[str] = set()  # keys whose wait was logged
        next_report = time.monotonic() + WAIT_FIRST
        futures: dict[Any, int] = {}
        queue = list(pending)

        def submit_next() -> None:
            while queue and len(futures) < window:
                i = queue.pop(0)
                if folder is not None:
                    f = folder / f"{keys[i]}.npz"
                    got = load_or_quarantine(f, keys[i])
                    if got is not None:  # finished meanwhile by a concurrent run
                        results[i] = got
                        bar.update(1)
                        continue
                    lock = folder / f"{keys[i]}.lock"
                    if not claim(lock, stale_after):
                        waiting.append(i)
                        if keys[i] not in announced:
                            announced.add(keys[i])
                            log.info(
                                "point %d %s is being computed by %s: waiting for it", i, pts[i], describe_owner(lock)
                            )
                        continue
                    got = load_or_quarantine(f, keys[i])  # finished between the look and the claim
                    if got is not None:
                        release(lock)
                        results[i] = got
                        bar.update(1)
                        continue
                    held.add(keys[i])
                futures[ex.submit(evaluate, function, pts[i])] = i

        def collect(fut) -> None:
            i = futures.pop(fut)
            try:
                fields = fut.result()
            except Exception as e:
                failures[i] = f"{type(e).__name__}: {e}"
            else:
                if folder is not None:
                    save(folder / f"{keys[i]}.npz", fields, pts[i], function)
                results[i] = Stored(fields, __point__=jsonable(pts[i]))
            finally:
                if folder is not None and keys[i] in held:
                    release(folder / f"{keys[i]}.lock")
                    held.discard(keys[i])
            bar.update(1)

        while queue or futures or waiting:
            submit_next()
            if futures:
                if isinstance(ex, Serial):
                    collect(next(iter(futures)))
                else:
                    done, _ = cf.wait(list(futures), timeout=poll if waiting else None, return_when=cf.FIRST_COMPLETED)
                    for fut in done:
                        collect(fut)
                continue
            if waiting:  # nothing of our own in flight: look at the points others hold
                assert folder is not None  # only a store's locks put points in waiting
                still = []
                for i in waiting:
                    got = load_or_quarantine(folder / f"{keys[i]}.npz", keys[i])
                    if got is not None:
                        results[i] = got
                        bar.update(1)
                    elif (folder / f"{keys[i]}.lock").exists() and not lock_is_stale(
                        folder / f"{keys[i]}.lock", stale_after
                    ):
                        still.append(i)
                    else:  # the other run gave up (failed point, or died): compute it here
                        queue.append(i)
                waiting[:] = still
                if waiting and time.monotonic() > next_report:
                    next_report = time.monotonic() + WAIT_REPORT
                    lock = folder / f"{keys[waiting[0]]}.lock"
                    log.warning(
                        "still waiting for %d point(s) another run is computing in store %s (point %d: %s)",
                        len(waiting),
                        folder,
                        waiting[0],
                        describe_owner(lock),
                    )
                if waiting and not queue:
                    time.sleep(poll)
    finally:
        bar.close()
        if folder is not None:
            for k in held:
                release(folder / f"{k}.lock")
        if owned:
            ex.shutdown(wait=True, cancel_futures=True)
    for i in range(len(pts)):  # duplicates of a computed point share its result
        if results[i] is None and i not in failures:
            j = first_of.get(keys[i])
            if j is not None and j != i:
                if j in failures:
                    failures[i] = failures[j]
                else:
                    results[i] = results[j]
    if failures and raise_on_error:
        first = min(failures)
        raise BatchError(
            f"{len(failures)} of {len(pts)} points failed (first: point {first} {pts[first]}: "
            f"{failures[first]}). Finished points are stored"
            + (f" in {folder}; rerun with the same store to retry only the failed ones." if folder else "."),
            failures,
        )
    return results
