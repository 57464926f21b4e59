"""Cluster recipes: thread pinning of worker processes and dask-jobqueue clusters (SLURM, PBS, SGE, LSF, HTCondor).

:func:`worker_env` gives the environment variables that pin BLAS and XLA to T threads per process; pass them to
workers (dask ``LocalCluster(env=...)``, a job script). :func:`jobqueue_cluster` is plain dask-jobqueue with that
pinning added. Use the cluster through ``dask.distributed.Client(cluster)`` as the executor of ``compare.batch.run``.
"""

from __future__ import annotations

import os
from typing import Any

__all__ = ["worker_env", "pin_threads", "jobqueue_cluster", "JOBQUEUE_SYSTEMS"]


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


JOBQUEUE_SYSTEMS = {
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
    if system.lower() not in JOBQUEUE_SYSTEMS:
        raise ValueError(f"system must be one of {sorted(JOBQUEUE_SYSTEMS)}, got {system!r}")
    if cores < 1 or threads_per_worker < 1 or cores % threads_per_worker:
        raise ValueError(
            f"cores per job ({cores}) must be a positive multiple of threads_per_worker ({threads_per_worker})"
        )
    import dask_jobqueue

    env = worker_env(threads_per_worker)
    prologue = [f"export {k}='{v}'" for k, v in env.items()] + list(kwargs.pop("job_script_prologue", []))
    cls = getattr(dask_jobqueue, JOBQUEUE_SYSTEMS[system.lower()])
    return cls(
        cores=cores,
        processes=cores // threads_per_worker,
        memory=memory,
        walltime=walltime,
        job_script_prologue=prologue,
        **kwargs,
    )
