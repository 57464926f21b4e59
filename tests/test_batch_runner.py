"""compare.batch (runner, store, pool): ordered results, stored per point, resume after a kill, executors (process, dask)."""

from __future__ import annotations

import builtins
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
from tissuemech.compare.batch import store as batch_store


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
        "import sys; sys.path.insert(0, %r); import test_batch_runner as t; from tissuemech.compare import batch\n"
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


# ---------------------------------------------------------------- a store that survives corruption and concurrency


def _calls(log: Path) -> int:
    return len(list(log.iterdir()))


def test_key_holds_version_and_code(monkeypatch):
    k = batch.point_key(square, dict(a=1.0))
    monkeypatch.setattr(batch_store, "code_version", lambda: "0.0.0-other")
    assert batch.point_key(square, dict(a=1.0)) != k  # another version of the code: not reused
    monkeypatch.undo()
    monkeypatch.setattr(batch_store, "code_hash", lambda f: "changed")
    assert batch.point_key(square, dict(a=1.0)) != k


@pytest.mark.parametrize("damage", ["truncate", "empty", "garbage", "altered", "foreign", "copied"])
def test_corrupt_file_is_detected_recomputed_and_reported(tmp_path, damage):
    log = tmp_path / "log"
    log.mkdir()
    store = tmp_path / "store"
    pts = [dict(a=float(a), log=str(log)) for a in range(4)]
    ref = batch.run(square, pts, executor="serial", store=store, progress=False)
    victim = store / f"{batch.point_key(square, pts[2])}.npz"
    raw = victim.read_bytes()
    if damage == "truncate":
        victim.write_bytes(raw[: len(raw) // 2])
    elif damage == "empty":
        victim.write_bytes(b"")
    elif damage == "garbage":
        victim.write_bytes(os.urandom(len(raw)))
    elif damage == "foreign":
        np.savez(victim, x=np.zeros(3))  # a valid .npz, but not one of ours
    elif damage == "copied":  # a valid result of another point under this point's name
        victim.write_bytes((store / f"{batch.point_key(square, pts[0])}.npz").read_bytes())
    else:  # a valid file whose numbers were changed afterwards
        with np.load(victim) as z:
            fields = {k: z[k] for k in z.files}
        fields["x"] = fields["x"] + 1.0
        np.savez(victim, **fields)
    with pytest.raises(batch.StoreError, match=str(victim.name)) as info:
        batch.load(victim, key=batch.point_key(square, pts[2]))
    assert str(store) in str(info.value) and "allow_pickle" not in str(info.value)
    before = _calls(log)
    with pytest.warns(batch.StoreWarning, match="recomputing"):
        res = batch.run(square, pts, executor="serial", store=store, progress=False)
    assert _calls(log) - before == 1  # only the damaged point
    assert np.array_equal(res[2].x, ref[2].x)
    assert (store / (victim.name + ".corrupt")).exists()
    assert batch.load(victim)["x"].tolist() == ref[2].x.tolist()


def test_read_only_store_fails_before_computing(tmp_path, monkeypatch):
    log = tmp_path / "log"
    log.mkdir()
    store = tmp_path / "store"
    store.mkdir()
    pts = [dict(a=float(a), log=str(log)) for a in range(3)]
    if os.geteuid() != 0:  # a real read-only folder (root can write anyway, so it is simulated below)
        store.chmod(0o555)
        try:
            with pytest.raises(batch.StoreError, match="not writable"):
                batch.run(square, pts, executor="serial", store=store, progress=False)
        finally:
            store.chmod(0o755)
        assert _calls(log) == 0

    def refuse(file, mode="r", *a, **k):  # writing refused, reading allowed
        if any(c in mode for c in "wax+"):
            raise PermissionError(13, "Permission denied")
        return builtins.open(file, mode, *a, **k)

    monkeypatch.setattr(batch_store, "open", refuse, raising=False)
    with pytest.raises(batch.StoreError, match="not writable"):
        batch.run(square, pts, executor="serial", store=store, progress=False)
    assert _calls(log) == 0  # nothing was computed
    monkeypatch.undo()
    done = batch.run(square, pts, executor="serial", store=store, progress=False)
    monkeypatch.setattr(batch_store, "open", refuse, raising=False)  # all stored: reading needs no write access
    again = batch.run(square, pts, executor="serial", store=store, progress=False)
    assert [float(r.total) for r in again] == [float(r.total) for r in done]


def test_store_that_is_a_file(tmp_path):
    f = tmp_path / "store"
    f.write_text("x")
    with pytest.raises(batch.StoreError, match="not a folder"):
        batch.run(square, POINTS, executor="serial", store=f, progress=False)


def test_stale_lock_of_a_dead_process_is_taken_over(tmp_path):
    store = tmp_path / "store"
    store.mkdir()
    pt = dict(a=2.0)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    lock = store / f"{batch.point_key(square, pt)}.lock"
    lock.write_text(f'{{"pid": {dead.pid}, "host": "{batch_store.HOST}"}}')
    (store / f"{batch.point_key(square, pt)}.npz.{dead.pid}.abc.part").write_bytes(b"half")
    res = batch.run(square, [pt], executor="serial", store=store, progress=False)
    assert float(res[0].total) == 10.0
    assert not lock.exists() and not list(store.glob("*.part"))


def test_a_lock_never_appears_without_its_owner_and_an_ownerless_one_expires(tmp_path, monkeypatch):
    """A batch killed between creating a lock and writing its owner left an EMPTY lock, which no run took over
    before ``stale_after`` (24 h): the rerun of a killed batch hung (seen in CI, test_resume_after_kill).
    Now a lock is created with its owner in it (a written file hard-linked to the lock's name), and a lock
    still without an owner after UNWRITTEN_LOCK_GRACE counts as stale."""
    import json
    import threading

    store = tmp_path / "store"
    store.mkdir()
    lock = store / "k.lock"
    assert batch_store.claim(lock, 24 * 3600.0)
    assert json.loads(lock.read_text())["pid"] == os.getpid()  # the owner is there from the start
    assert not list(store.glob("*.part")) and not batch_store.claim(lock, 24 * 3600.0)  # held: refused
    batch_store.release(lock)
    # an ownerless lock: young = being written (kept), older than the grace = its writer died (taken over)
    lock.write_text("")
    assert not batch_store.lock_is_stale(lock, 24 * 3600.0)
    old = time.time() - batch_store.UNWRITTEN_LOCK_GRACE - 5
    os.utime(lock, (old, old))
    assert batch_store.lock_is_stale(lock, 24 * 3600.0)
    # end to end: a store holding such a lock for a point of the batch finishes and computes that point
    pt = dict(a=3.0)
    empty = store / f"{batch.point_key(square, pt)}.lock"
    empty.write_text("")
    os.utime(empty, (old, old))
    out: list = []
    worker = threading.Thread(
        target=lambda: out.append(batch.run(square, [pt], executor="serial", store=store, progress=False)),
        daemon=True,
    )
    worker.start()
    worker.join(timeout=60)
    assert out, "the batch waited on an ownerless lock"
    assert float(out[0][0].total) == 15.0 and not empty.exists()
    # where the file system refuses hard links, the lock is created exclusively and then filled
    monkeypatch.setattr(batch_store.os, "link", lambda *a: (_ for _ in ()).throw(PermissionError("no hard links")))
    assert batch_store.claim(lock, 24 * 3600.0) and json.loads(lock.read_text())["host"] == batch_store.HOST


WRITER = """
import sys, json
sys.path.insert(0, {tests!r})
import test_batch_runner as t
from tissuemech.compare import batch
if __name__ == "__main__":
    pts = [dict(a=float(a), log={log!r}) for a in range({n})]
    res = batch.run(t.square, pts, executor={ex}, store={store!r}, progress=False)
    ok = all(float(r.total) == 5.0 * p["a"] for r, p in zip(res, pts))
    print(json.dumps(dict(ok=ok, n=len(res))))
"""


@pytest.mark.slow
@pytest.mark.parametrize("executor", ["'serial'", "None"])
def test_concurrent_writers_never_crash_nor_compute_twice(tmp_path, executor):
    """3 runs x 400 points into one store at the same time: every run gets all 400 results, every
    point is computed exactly once, no temporary or lock file is left."""
    n = 400 if executor == "'serial'" else 120
    log = tmp_path / "log"
    log.mkdir()
    store = tmp_path / "store"
    script = tmp_path / "writer.py"
    script.write_text(WRITER.format(tests=str(Path(__file__).parent), log=str(log), n=n, ex=executor, store=str(store)))
    procs = [
        subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        for _ in range(3)
    ]
    outs = [p.communicate(timeout=300) for p in procs]
    for p, (out, err) in zip(procs, outs):
        assert p.returncode == 0, err[-2000:]
        assert '"ok": true' in out and f'"n": {n}' in out
    assert _calls(log) == n  # nothing computed twice
    assert len(list(store.glob("*.npz"))) == n
    assert not list(store.glob("*.part")) and not list(store.glob("*.lock"))


def test_duplicate_points_computed_once(tmp_path):
    log = tmp_path / "log"
    log.mkdir()
    pts = [dict(a=1.0, log=str(log))] * 3 + [dict(a=2.0, log=str(log))]
    res = batch.run(square, pts, executor="serial", store=tmp_path / "s", progress=False)
    assert [float(r.total) for r in res] == [5.0, 5.0, 5.0, 10.0]
    assert _calls(log) == 2


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(points=5), "points"),
        (dict(points=[1, 2]), r"points\[0\]"),
        (dict(points="ab"), "points"),
        (dict(function=3), "function"),
    ],
)
def test_bad_arguments(tmp_path, kw, match):
    args = dict(function=square, points=POINTS, executor="serial", progress=False)
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        batch.run(args.pop("function"), args.pop("points"), **args)


def test_a_wait_says_what_it_waits_for(tmp_path, caplog):
    """A point claimed by another live process is waited for, and the log says for what and whom."""
    import json
    import threading

    folder = tmp_path / "store"
    folder.mkdir()
    pt = dict(a=4.0)
    key = batch.point_key(square, pt)
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        owner = dict(pid=holder.pid, host=batch_store.HOST, boot=batch_store.BOOT_ID, time=time.time())
        owner["start"] = batch_store.process_start(holder.pid)
        (folder / f"{key}.lock").write_text(json.dumps(owner))
        out: list = []
        with caplog.at_level("INFO", logger="tissuemech.compare.batch.runner"):
            worker = threading.Thread(
                target=lambda: out.append(batch.run(square, [pt], executor="serial", store=folder, progress=False)),
                daemon=True,
            )
            worker.start()
            t0 = time.time()
            while "waiting for it" not in caplog.text and time.time() - t0 < 30:
                time.sleep(0.05)
            holder.kill()  # the owner dies: the wait ends, the point is computed here
            holder.wait()
            worker.join(timeout=60)
        assert f"process {holder.pid} on host {batch_store.HOST}" in caplog.text and "a': 4.0" in caplog.text
        assert out and float(out[0][0].total) == 20.0
    finally:
        holder.kill()
        holder.wait()
