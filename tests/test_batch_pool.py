"""compare.batch.pool: the one local process pool: one BLAS thread per worker, workers end with their parent."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tissuemech.compare import batch


def blas_threads(*, a: float) -> dict:
    """The BLAS thread counts this process runs with (threadpoolctl), one per loaded BLAS library."""
    from threadpoolctl import threadpool_info

    return dict(threads=np.array([i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]))


def test_default_pool_workers_run_one_blas_thread(tmp_path):
    """The default process pool limits every worker to one BLAS thread (2 workers x 2 OpenBLAS threads on
    2 cores oversubscribe the machine)."""
    res = batch.run(blas_threads, [dict(a=float(a)) for a in range(2)], store=tmp_path / "s", progress=False)
    assert all(r.threads.size >= 1 and np.all(r.threads == 1) for r in res)


def test_the_pool_is_refused_a_bad_size():
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="workers"):
            batch.process_pool(bad)


PARENT = """
import os, sys, time
sys.path.insert(0, {tests!r})
import test_batch_pool as t
from tissuemech.compare import batch
if __name__ == "__main__":
    pool = batch.process_pool(2)
    futures = [pool.submit(t.report_pid_and_sleep, folder={folder!r}) for _ in range(2)]
    time.sleep(600)
"""


def report_pid_and_sleep(*, folder: str) -> None:
    Path(folder, str(os.getpid())).touch()
    time.sleep(600)


def test_a_killed_parent_takes_its_workers_with_it(tmp_path):
    """Workers of the pool end themselves when their parent is killed (SIGKILL: no cleanup in the parent), instead
    of computing on as orphans."""
    pids = tmp_path / "pids"
    pids.mkdir()
    script = tmp_path / "parent.py"
    script.write_text(PARENT.format(tests=str(Path(__file__).parent), folder=str(pids)))
    parent = subprocess.Popen([sys.executable, str(script)], start_new_session=True)
    t0 = time.time()
    while len(list(pids.iterdir())) < 2 and time.time() - t0 < 120:
        time.sleep(0.05)
    workers = [int(p.name) for p in pids.iterdir()]
    assert len(workers) == 2, "the workers did not start"
    parent.kill()  # the parent only, not its process group
    parent.wait()

    def alive(pid: int) -> bool:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        return (
            Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] != "Z" if Path("/proc").exists() else True
        )

    t0 = time.time()
    while any(alive(p) for p in workers) and time.time() - t0 < 30:
        time.sleep(0.1)
    left = [p for p in workers if alive(p)]
    for p in left:  # do not leave them behind if the test fails
        os.kill(p, signal.SIGKILL)
    assert not left, f"workers {left} outlived their killed parent"
