"""The result store of ``compare.batch``: one ``<key>.npz`` file per point, verified, written atomically, claimed
by lock files.

``key`` (:func:`point_key`) is a SHA-256 hash of the function's name, a hash of its source code, the
tissuemech version and the point's parameters (results of another version of the code are never reused).

The store survives corruption and concurrency:

* every file carries a SHA-256 checksum of its arrays; a truncated, empty, garbage or altered file is
  detected (:func:`load` raises :class:`StoreError`), moved aside to ``<key>.npz.corrupt``, recomputed, and a
  :class:`StoreWarning` says so (:func:`load_or_quarantine`);
* files are written to a unique temporary name (``<key>.npz.<pid>.<random>.part``) and renamed
  (atomic), so a crash loses nothing that finished and writers never collide (:func:`save`);
* a point being computed is claimed by a lock file ``<key>.lock`` (:func:`claim`; pid and host inside, from the
  instant it exists: a written file hard-linked to the lock's name): a second run into the same store waits for
  that point instead of computing it again; the lock of a dead process (same host) is taken over
  (:func:`lock_is_stale`), so a killed batch resumes;
* a store that cannot be written raises :class:`StoreError` before any point is computed (:func:`check_writable`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import inspect
import json
import os
import socket
import time
import uuid
import warnings
import zipfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "STORE_FORMAT",
    "StoreError",
    "StoreWarning",
    "Stored",
    "point_key",
    "save",
    "load",
    "load_or_quarantine",
    "claim",
    "release",
    "lock_is_stale",
    "check_writable",
    "clean_parts",
    "code_hash",
    "code_version",
    "function_name",
    "jsonable",
    "to_fields",
    "HOST",
    "UNWRITTEN_LOCK_GRACE",
]

STORE_FORMAT = 2  # version of the file layout (fields + __point__ + __meta__ with the checksum)


class StoreError(ValueError):
    """The result store cannot be used (not writable, or a stored file is unreadable or altered)."""


class StoreWarning(UserWarning):
    """A stored result was corrupt and is being recomputed."""


class Stored(dict):
    """A stored result: a dict of NumPy arrays with attribute access (``r.force`` == ``r["force"]``)."""

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


def jsonable(v: Any) -> Any:
    if isinstance(v, Mapping):
        return {str(k): jsonable(x) for k, x in sorted(v.items())}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return [jsonable(x) for x in v.tolist()] if v.ndim else jsonable(v.item())
    if isinstance(v, (np.floating, float)):
        return float(v)
    if isinstance(v, (np.integer,)):
        return int(v)
    return v


def function_name(function: Callable) -> str:
    return f"{getattr(function, '__module__', '?')}.{getattr(function, '__qualname__', repr(function))}"


def code_hash(function: Callable) -> str:
    """SHA-256 (16 hex digits) of the function's source, '' when it has none (builtins, C code)."""
    try:
        src = inspect.getsource(function)
    except (OSError, TypeError):
        return ""
    return hashlib.sha256(src.encode()).hexdigest()[:16]


def code_version() -> str:
    from tissuemech import __version__

    return str(__version__)


def point_key(function: Callable, point: Mapping[str, Any]) -> str:
    """SHA-256 (first 24 hex digits) of the function's qualified name, its source hash, the tissuemech
    version and the point's parameters: results computed by other code are never reused."""
    text = json.dumps(
        {"f": function_name(function), "c": code_hash(function), "v": code_version(), "p": jsonable(dict(point))},
        sort_keys=True,
    )
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def to_fields(result: Any) -> dict[str, np.ndarray]:
    if hasattr(result, "_asdict"):
        d = result._asdict()
    elif dataclasses.is_dataclass(result) and not isinstance(result, type):
        d = {f.name: getattr(result, f.name) for f in dataclasses.fields(result)}
    elif isinstance(result, Mapping):
        d = dict(result)
    else:
        d = {"value": result}
    out = {}
    for k, v in d.items():
        try:
            a = np.asarray(v)
        except Exception:
            continue
        if a.dtype == object:
            continue
        out[str(k)] = a
    return out


def checksum(fields: Mapping[str, np.ndarray], point_json: str) -> str:
    h = hashlib.sha256(point_json.encode())
    for k in sorted(fields):
        a = np.ascontiguousarray(fields[k])
        h.update(f"{k}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def save(path: Path, fields: dict[str, np.ndarray], point: Mapping[str, Any], function: str = "") -> None:
    point_json = json.dumps(jsonable(dict(point)))
    meta = dict(
        format=STORE_FORMAT,
        tissuemech=code_version(),
        function=function,
        sha256=checksum(fields, point_json),
        written=time.time(),
    )
    # a unique temporary name per writer: concurrent writers of one key never collide (not matched by *.npz)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.{uuid.uuid4().hex[:12]}.part")
    try:
        with open(tmp, "wb") as fh:
            np.savez(fh, __point__=np.asarray(point_json), __meta__=np.asarray(json.dumps(meta)), **fields)  # type: ignore[arg-type]  # numpy stubs: savez **kwds typed as bool
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def load(path: str | os.PathLike) -> Stored:
    """Read one stored result file (``<key>.npz``); the point is under ``"__point__"`` (a dict).

    Raises :class:`StoreError` (naming the file) when it is truncated, empty, not a result file, or
    its numbers do not match the checksum written with them.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            files = set(z.files)
            if "__point__" not in files or "__meta__" not in files:
                raise StoreError(f"result file {path} is not a tissuemech store file (no __point__/__meta__)")
            point_json = str(z["__point__"])
            meta = json.loads(str(z["__meta__"]))
            fields = {k: z[k] for k in z.files if k not in ("__point__", "__meta__")}
    except StoreError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError) as exc:
        raise StoreError(f"result file {path} is unreadable (truncated, empty or not an .npz): {exc}") from None
    if meta.get("sha256") != checksum(fields, point_json):
        raise StoreError(f"result file {path} does not match its checksum (its numbers were altered or damaged)")
    out = Stored(fields)
    out["__point__"] = json.loads(point_json)
    return out


def load_or_quarantine(path: Path) -> Stored | None:
    """The stored result, or None if absent; a corrupt file is moved aside (with a StoreWarning)."""
    if not path.exists():
        return None
    try:
        return load(path)
    except StoreError as exc:
        if not path.exists():  # replaced meanwhile by a concurrent writer: read it again
            return load_or_quarantine(path) if path.exists() else None
        try:
            os.replace(path, path.with_name(path.name + ".corrupt"))
        except OSError:
            pass
        warnings.warn(f"{exc}; recomputing this point", StoreWarning, stacklevel=3)
        return None


# ---------------------------------------------------------------- per-point claims (lock files)

HOST = socket.gethostname()


def pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


UNWRITTEN_LOCK_GRACE = 60.0  # s: a lock file still without content after this lost its writer (see claim)


def lock_is_stale(lock: Path, stale_after: float) -> bool:
    try:
        text = lock.read_text()
        age = time.time() - lock.stat().st_mtime
    except OSError:
        return False  # just removed: look again later
    try:
        info = json.loads(text) if text.strip() else None
    except ValueError:
        info = None
    if not isinstance(info, dict):
        # no owner written in it: a writer that died between creating and filling it (only where the store's
        # file system has no hard links, or a lock of an older version); the writer fills it within
        # microseconds, so after the grace period nobody will
        return age > UNWRITTEN_LOCK_GRACE
    if info.get("host") == HOST and isinstance(info.get("pid"), int):
        return not pid_alive(info["pid"])
    return age > stale_after


_RUN_ID = uuid.uuid4().hex


def claim(lock: Path, stale_after: float) -> bool:
    """Create ``lock`` exclusively (True), or False if a live process holds it; stale locks are taken over.

    The lock appears with its owner (pid, host) already in it (:func:`place_lock`), so a process killed at any
    instant never leaves a lock without an owner."""
    owner = json.dumps({"pid": os.getpid(), "host": HOST, "run": _RUN_ID, "time": time.time()})
    part = lock.with_name(f"{lock.name}.{os.getpid()}.{uuid.uuid4().hex[:12]}.part")  # clean_parts' pattern
    part.write_text(owner)
    try:
        for _ in range(2):
            try:
                place_lock(lock, part, owner)
            except FileExistsError:
                if not lock_is_stale(lock, stale_after):
                    return False
                lock.unlink(missing_ok=True)
                continue
            return True
        return False
    finally:
        part.unlink(missing_ok=True)


def place_lock(lock: Path, part: Path, owner: str) -> None:
    """Make ``lock`` exist holding ``owner``, or raise FileExistsError: a hard link of ``part`` (which holds
    ``owner``) to the lock's name, atomic; where the file system refuses hard links, an exclusive create and
    then the write (a lock left empty there counts as stale after ``UNWRITTEN_LOCK_GRACE``)."""
    try:
        os.link(part, lock)
        return
    except FileExistsError:
        raise
    except OSError:
        pass
    fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    with os.fdopen(fd, "w") as fh:
        fh.write(owner)


def release(lock: Path) -> None:
    try:
        lock.unlink()
    except FileNotFoundError:
        pass


def check_writable(folder: Path) -> None:
    """Raise StoreError unless files can be created in ``folder`` (checked before any point is computed)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".write-probe.{os.getpid()}.{uuid.uuid4().hex[:8]}"
        with open(probe, "wb") as fh:
            fh.write(b"ok")
        probe.unlink()
    except OSError as exc:
        raise StoreError(
            f"store {folder} is not writable ({exc.strerror or exc}); give a folder this process can write to, "
            "or store=None"
        ) from None


def clean_parts(folder: Path) -> None:
    """Remove temporary files left by dead writers on this host (``<key>.npz.<pid>.<rand>.part``)."""
    for part in folder.glob("*.part"):
        bits = part.name.split(".")
        try:
            pid = int(bits[-3])
        except (IndexError, ValueError):
            continue
        if not pid_alive(pid):
            part.unlink(missing_ok=True)
