"""The one local process pool of ``compare.batch`` (and of ``tissuemech scan --fe-workers``,
``tissuemech batch run --workers``), its worker initialiser, and the executors ``run`` accepts.

:func:`process_pool` starts ``workers`` processes with the "spawn" start method (JAX state is never
forked), each initialised by :func:`worker_init` (one BLAS thread per worker).
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from tissuemech.compare.batch.store import to_fields

__all__ = ["worker_init", "watch_parent", "process_pool", "as_executor", "evaluate", "Serial", "DEFAULT_WORKERS"]

DEFAULT_WORKERS = 2
PARENT_POLL = 0.5  # s between a worker's looks at its parent process

_BLAS_LIMIT: list = []  # the worker's threadpoolctl limit, kept alive for the worker's life


def worker_init() -> None:
    """Worker start-up of :func:`process_pool` (pass it as ``initializer=`` to a pool of your own):

    * one BLAS thread per worker. The FE gains nothing from a second BLAS thread on its small dense blocks, and
      2 workers x 2 OpenBLAS threads on 2 cores made a 6-run Fig. 10 batch 1.4-2.0x slower (13.0-14.3 s vs
      7.1-9.1 s with one thread each);
    * the worker ends itself when its parent process is gone (killed, even by SIGKILL), within
      ``PARENT_POLL`` s, so a killed batch leaves no worker computing on."""
    from threadpoolctl import threadpool_limits

    _BLAS_LIMIT.append(threadpool_limits(limits=1, user_api="blas"))
    watch_parent()


def watch_parent(poll: float = PARENT_POLL) -> threading.Thread:
    """Start a daemon thread that ends this process (``os._exit``) once its parent process is gone (the process is
    then re-parented, and ``os.getppid()`` changes). Returns the thread."""
    parent = os.getppid()

    def watch() -> None:
        while True:
            time.sleep(poll)
            if os.getppid() != parent:
                os._exit(70)  # EX_SOFTWARE: no cleanup, nobody is left to report to

    t = threading.Thread(target=watch, name="tissuemech-parent-watch", daemon=True)
    t.start()
    return t


def process_pool(workers: int = DEFAULT_WORKERS) -> cf.ProcessPoolExecutor:
    """``workers`` local processes ("spawn" start, :func:`worker_init`). Raises ValueError unless ``workers`` >= 1."""
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers (local processes) must be a whole number >= 1; got {workers!r}")
    return cf.ProcessPoolExecutor(
        max_workers=workers, mp_context=multiprocessing.get_context("spawn"), initializer=worker_init
    )


def evaluate(function: Callable, point: dict) -> dict[str, np.ndarray]:
    """``function(**point)`` as the fields the store writes (what a worker runs for one point)."""
    return to_fields(function(**point))


class Serial:
    """In-process 'executor': each point is evaluated when its result is asked for (so results are
    stored one by one, as with real workers)."""

    def submit(self, fn, /, *args, **kwargs):
        return _Lazy(fn, args, kwargs)

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        pass


class _Lazy:
    def __init__(self, fn, args, kwargs):
        self.call = (fn, args, kwargs)

    def result(self):
        fn, args, kwargs = self.call
        return fn(*args, **kwargs)


def as_executor(executor: Any) -> tuple[Any, bool]:
    """(executor, owned) for ``run``'s ``executor=``: None (:func:`process_pool` of 2 workers), "serial", a
    ``concurrent.futures.Executor`` or a ``dask.distributed.Client``; owned ones are shut down by ``run``."""
    if executor is None:
        return process_pool(DEFAULT_WORKERS), True
    if isinstance(executor, str) and executor == "serial":
        return Serial(), True
    if hasattr(executor, "get_executor"):  # dask.distributed.Client
        return executor.get_executor(), False
    if isinstance(executor, cf.Executor):
        return executor, False
    raise ValueError(
        "executor must be None (2 local processes), 'serial', a concurrent.futures.Executor "
        f"or a dask.distributed.Client; got {executor!r}"
    )
