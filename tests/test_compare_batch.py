"""compare.batch: ordered results, stored per point, resume after a kill, executors (process, dask)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pytest

from tissuemech.compare import batch


class Out(NamedTuple):
    x: np.ndarray
    total: float


def square(*, a: float, n: int = 3, log: str | None = None, delay: float = 0.0) -> Out:
    """Toy 'simulation': records each call in `log` (a folder) so recomputation is visible."""
    if log is not None:
        Path(log, f"{a!r}-{os.getpid()}-{time.time_ns()}").touch()
    time.sleep(delay)
    x = a * np.arange(n, dtype=float) ** 2
    return Out(x, float(x.sum()))


def fails_on_three(*, a: float) -> dict:
    if a == 3.0:
        raise RuntimeError("Newton did not converge at load step 7 (residual 1e-3)")
    return {"y": a + 1.0}


POINTS = [dict(a=float(a)) for a in range(6)]


def test_serial_results_ordered_and_exact(tmp_path):
    res = batch.run(square, POINTS, executor="serial", store=tmp_path, progress=False)
    for p, r in zip(POINTS, res):
        assert np.array_equal(r.x, p["a"] * np.arange(3.0) ** 2)
        assert float(r.total) == 5.0 * p["a"]
    assert len(list(tmp_path.glob("*.npz"))) == len(POINTS)
    stored = batch.load(next(tmp_path.glob("*.npz")))
    assert set(stored) == {"x", "total", "__point__"}


def test_key_depends_on_parameters_and_function():
    k = batch.point_key(square, dict(a=1.0))
    assert k == batch.point_key(square, dict(a=1.0))
    assert k == batch.point_key(square, {"a": np.float64(1.0)})
    assert k != batch.point_key(square, dict(a=1.0 + 1e-15))
    assert k != batch.point_key(fails_on_three, dict(a=1.0))


def test_failures_named_and_others_stored(tmp_path):
    with pytest.raises(batch.BatchError, match="point 3") as info:
        batch.run(fails_on_three, POINTS, executor="serial", store=tmp_path, progress=False)
    assert set(info.value.failures) == {3}
    assert "load step 7" in str(info.value)
    assert len(list(tmp_path.glob("*.npz"))) == 5
    res = batch.run(fails_on_three, POINTS, executor="serial", store=tmp_path, progress=False, raise_on_error=False)
    assert res[3] is None and float(res[4].y) == 5.0


def test_process_pool_default(tmp_path):
    log = tmp_path / "log"
    log.mkdir()
    pts = [dict(a=float(a), log=str(log)) for a in range(4)]
    res = batch.run(square, pts, store=tmp_path / "s", progress=False)  # 2 spawned processes
    assert [float(r.total) for r in res] == [5.0 * a for a in range(4)]
    pids = {f.name.split("-")[1] for f in log.iterdir()}
    assert str(os.getpid()) not in pids


@pytest.mark.parametrize("executor", ["serial", "processes"])
def test_resume_after_kill(tmp_path, executor):
    """Kill a running batch (its whole process group) mid-way; the rerun computes only the missing
    points; results equal an uninterrupted run."""
    log = tmp_path / "log"
    log.mkdir()
    store = tmp_path / "store"
    pts = [dict(a=float(a), log=str(log), delay=0.25) for a in range(10)]
    ex = "'serial'" if executor == "serial" else "None"
    code = (
        "import sys; sys.path.insert(0, %r); import test_compare_batch as t; from tissuemech.compare import batch\n"
        "if __name__ == '__main__': batch.run(t.square, %r, executor=%s, store=%r, progress=False)"
        % (str(Path(__file__).parent), pts, ex, str(store))
    )
    script = tmp_path / "job.py"
    script.write_text(code)
    proc = subprocess.Popen([sys.executable, str(script)], start_new_session=True)
    t0 = time.time()
    while len(list(store.glob("*.npz"))) < 3 and time.time() - t0 < 60:
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)  # the job and its worker processes
    proc.wait()
    time.sleep(0.2)
    done = len(list(store.glob("*.npz")))
    assert 3 <= done < len(pts), "the kill must land mid-batch"
    calls_before = len(list(log.iterdir()))
    res = batch.run(square, pts, executor="serial", store=store, progress=False)
    recomputed = len(list(log.iterdir())) - calls_before
    assert recomputed == len(pts) - done  # nothing stored was recomputed
    ref = [square(a=p["a"]) for p in pts]  # uninterrupted results (the delay does not change them)
    for r, q in zip(res, ref):
        assert np.array_equal(r.x, q.x) and float(r.total) == float(q.total)
    assert not list(store.glob("*.tmp.npz"))


def test_dask_local_cluster(tmp_path):
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster,
        distributed.Client(cluster) as client,
    ):
        res = batch.run(square, POINTS, executor=client, store=tmp_path, progress=False)
    assert [float(r.total) for r in res] == [5.0 * p["a"] for p in POINTS]
    again = batch.run(square, POINTS, executor="serial", store=tmp_path, progress=False)
    assert [float(r.total) for r in again] == [float(r.total) for r in res]


def test_bad_executor():
    with pytest.raises(ValueError, match="executor"):
        batch.run(square, POINTS, executor="cloud", progress=False)
