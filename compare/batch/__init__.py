"""Run a function over many parameter points, with a resumable store: locally, on a dask cluster, or as job arrays.

    from tissuemech.compare import batch
    results = batch.run(batch.fe_spheroid, points, executor=None, store="store-dir")

* :mod:`.runner`: :func:`run` (ordered results, failures collected in :class:`BatchError`);
* :mod:`.store`: one ``<key>.npz`` per point (:func:`point_key`, :func:`load`), verified, written atomically,
  claimed by lock files;
* :mod:`.pool`: the one local process pool (:func:`process_pool`, :func:`worker_init`);
* :mod:`.points`: the FE point functions, one per scene (:func:`fe_spheroid`, :func:`fe_blastula`);
* :mod:`.cluster`: cluster recipes (:func:`worker_env`, :func:`pin_threads`, :func:`jobqueue_cluster`);
* :mod:`.jobs`: scheduler-free job arrays (:func:`read_points`, :func:`chunk`, :func:`array_index`,
  :func:`collect`, :func:`resolve_function`).

The command ``tissuemech batch run|collect``: ``compare.cli.batch``.
"""

from __future__ import annotations

from tissuemech.compare.batch import points
from tissuemech.compare.batch.cluster import jobqueue_cluster, pin_threads, worker_env
from tissuemech.compare.batch.jobs import (
    UserFunctionWarning,
    array_index,
    array_task,
    chunk,
    collect,
    read_points,
    resolve_function,
)
from tissuemech.compare.batch.points import FUNCTIONS, fe_blastula, fe_spheroid
from tissuemech.compare.batch.pool import process_pool, worker_init
from tissuemech.compare.batch.runner import BatchError, run
from tissuemech.compare.batch.store import (
    STORE_FORMAT,
    CorruptResultError,
    Stored,
    StoreError,
    StoreWarning,
    load,
    point_key,
)

__all__ = [
    "run",
    "point_key",
    "load",
    "worker_init",
    "process_pool",
    "Stored",
    "BatchError",
    "StoreError",
    "StoreWarning",
    "CorruptResultError",
    "UserFunctionWarning",
    "STORE_FORMAT",
    "points",
    "fe_spheroid",
    "fe_blastula",
    "FUNCTIONS",
    "worker_env",
    "pin_threads",
    "jobqueue_cluster",
    "read_points",
    "chunk",
    "array_index",
    "array_task",
    "collect",
    "resolve_function",
]
