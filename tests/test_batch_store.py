"""compare.batch.store: a stored file is served only for its own point and code, errors name the store and the
file, a failed write leaves nothing, locks name their owner by pid, start time and boot."""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from tissuemech.compare import batch
from tissuemech.compare.batch import store


def triple(*, a: float) -> dict:
    return {"y": 3.0 * a, "curve": a * np.arange(4.0)}


def other(*, a: float) -> dict:
    return {"y": -a}


def _stored(tmp_path, points, function=triple):
    folder = tmp_path / "store"
    batch.run(function, points, executor="serial", store=folder, progress=False)
    return folder


def test_a_valid_file_under_another_points_key_is_refused(tmp_path):
    """A valid result of point A copied under the key of point B was served as B's result."""
    folder = _stored(tmp_path, [dict(a=1.0), dict(a=2.0)])
    key_a, key_b = (batch.point_key(triple, dict(a=a)) for a in (1.0, 2.0))
    shutil.copy(folder / f"{key_a}.npz", folder / f"{key_b}.npz")
    with pytest.raises(store.CorruptResultError) as info:
        store.load(folder / f"{key_b}.npz", key=key_b)
    msg = str(info.value)
    assert str(folder) in msg and f"{key_b}.npz" in msg and "a=1.0" in msg and "not of the point requested" in msg
    assert float(store.load(folder / f"{key_b}.npz")["y"]) == 3.0  # without a key: the file itself is sound
    # the batch recomputes B (with a warning naming the file) and serves the right number
    with pytest.warns(batch.StoreWarning, match=f"{key_b}.npz holds the result of"):
        res = batch.run(triple, [dict(a=2.0)], executor="serial", store=folder, progress=False)
    assert float(res[0].y) == 6.0 and (folder / f"{key_b}.npz.corrupt").exists()


def test_a_result_of_another_function_or_version_is_refused(tmp_path, monkeypatch):
    folder = _stored(tmp_path, [dict(a=1.0)], function=other)
    key_other = batch.point_key(other, dict(a=1.0))
    key = batch.point_key(triple, dict(a=1.0))
    shutil.copy(folder / f"{key_other}.npz", folder / f"{key}.npz")
    with pytest.raises(store.CorruptResultError, match="holds the result of .*other"):
        store.load(folder / f"{key}.npz", key=key)
    monkeypatch.setattr(store, "code_version", lambda: "0.0.0-other")  # a file of the released version ...
    new_key = batch.point_key(other, dict(a=1.0))
    shutil.copy(folder / f"{key_other}.npz", folder / f"{new_key}.npz")
    with pytest.raises(store.CorruptResultError, match="tissuemech"):  # ... is not one of this version
        store.load(folder / f"{new_key}.npz", key=new_key)


def test_garbage_names_the_store_and_file_without_numpy_advice(tmp_path):
    folder = _stored(tmp_path, [dict(a=1.0)])
    f = folder / f"{batch.point_key(triple, dict(a=1.0))}.npz"
    f.write_bytes(b"\x80\x04garbage, not a zip" * 50)  # looks like a pickle to numpy
    with pytest.raises(store.CorruptResultError) as info:
        store.load(f)
    msg = str(info.value)
    assert f"store {folder}" in msg and f.name in msg and "allow_pickle" not in msg


def test_a_read_error_names_the_file_and_keeps_it(tmp_path, monkeypatch):
    folder = _stored(tmp_path, [dict(a=1.0)])
    f = folder / f"{batch.point_key(triple, dict(a=1.0))}.npz"

    def refuse(*a, **k):
        raise PermissionError(errno.EACCES, "Permission denied")

    monkeypatch.setattr(store, "open", refuse, raising=False)
    with pytest.raises(store.StoreError, match="cannot be read: Permission denied") as info:
        batch.run(triple, [dict(a=1.0)], executor="serial", store=folder, progress=False)
    assert not isinstance(info.value, store.CorruptResultError) and f.name in str(info.value)
    assert f.exists() and not list(folder.glob("*.corrupt"))  # an unreadable file is not damaged: not moved


def test_a_full_disk_names_the_store_and_leaves_no_file(tmp_path, monkeypatch):
    folder = tmp_path / "store"

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(store.os, "fsync", full)
    with pytest.raises(store.StoreError) as info:
        batch.run(triple, [dict(a=1.0)], executor="serial", store=folder, progress=False)
    msg = str(info.value)
    assert f"store {folder}" in msg and ".npz" in msg and "disk is full" in msg
    assert not list(folder.glob("*.npz")) and not list(folder.glob("*.part")) and not list(folder.glob("*.lock"))


def test_a_lock_names_its_owner_by_pid_start_time_and_boot(tmp_path):
    lock = tmp_path / "k.lock"
    assert store.claim(lock, 24 * 3600.0)
    info = json.loads(lock.read_text())
    assert info["pid"] == os.getpid() and info["boot"] == store.BOOT_ID
    assert info["start"] == store.process_start(os.getpid())
    assert store.owner_alive(info) is True and not store.lock_is_stale(lock, 24 * 3600.0)
    assert f"process {os.getpid()}" in store.describe_owner(lock)
    store.release(lock)


@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="process start times from /proc (Linux)")
def test_a_reused_pid_or_a_reboot_makes_a_lock_stale(tmp_path):
    """A lock whose pid now belongs to another process (started later) or was written before a reboot is stale,
    although a process with that pid runs."""
    lock = tmp_path / "k.lock"
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        start = store.process_start(live.pid)
        assert start is not None
        owner = dict(pid=live.pid, host=store.HOST, boot=store.BOOT_ID, start=start)
        lock.write_text(json.dumps(owner))
        assert not store.lock_is_stale(lock, 24 * 3600.0)  # the owner runs
        lock.write_text(json.dumps(dict(owner, start=start - 1)))  # same pid, another process
        assert store.lock_is_stale(lock, 24 * 3600.0)
        if store.BOOT_ID:
            lock.write_text(json.dumps(dict(owner, boot="another-boot")))
            assert store.lock_is_stale(lock, 24 * 3600.0)
    finally:
        live.kill()
        live.wait()
