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
import errno
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
    "CorruptResultError",
    "StoreWarning",
    "Stored",
    "point_key",
    "save",
    "load",
    "load_or_quarantine",
    "describe",
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
    "BOOT_ID",
    "process_start",
    "lock_owner",
    "owner_alive",
    "describe_owner",
    "UNWRITTEN_LOCK_GRACE",
]

STORE_FORMAT = 3  # version of the file layout (fields + __point__ + __meta__: key, function, code, version, checksum)


class StoreError(ValueError):
    """The result store cannot be used (not writable, or a stored file is unreadable or altered)."""


class CorruptResultError(StoreError):
    """A stored result file is damaged, not a result file, or the result of another point or version of the code."""


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


def checksum(fields: Mapping[str, np.ndarray], point_json: str, identity: str = "") -> str:
    """SHA-256 of a result: its fields (names, dtypes, shapes, bytes), its point (JSON) and its identity (the JSON
    of key, function, code hash and version; format 3)."""
    h = hashlib.sha256(point_json.encode())
    h.update(identity.encode())
    for k in sorted(fields):
        a = np.ascontiguousarray(fields[k])
        h.update(f"{k}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _identity(meta: Mapping[str, Any]) -> str:
    return json.dumps({k: meta.get(k) for k in ("key", "function", "code", "tissuemech")}, sort_keys=True)


def _key_of(meta: Mapping[str, Any], point: Any) -> str:
    """The key of a stored result, recomputed from what it says it is (function, code, version, point)."""
    text = json.dumps(
        {"f": meta.get("function"), "c": meta.get("code"), "v": meta.get("tissuemech"), "p": point}, sort_keys=True
    )
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def _describe(meta: Mapping[str, Any], point: Any) -> str:
    text = ", ".join(f"{k}={v!r}" for k, v in point.items()) if isinstance(point, dict) else repr(point)
    if len(text) > 160:
        text = text[:157] + "..."
    return f"{meta.get('function') or 'an unnamed function'} at ({text}), tissuemech {meta.get('tissuemech')}"


def save(path: Path, fields: dict[str, np.ndarray], point: Mapping[str, Any], function: Callable) -> None:
    """Write the result ``fields`` of ``function(**point)`` to ``path`` (``<store>/<key>.npz``) with its identity
    (key, function, code hash, version) and checksum: to a unique temporary file first, then renamed (atomic), so a
    failed write (full disk) leaves no truncated result. Raises :class:`StoreError` naming the store and file."""
    point_json = json.dumps(jsonable(dict(point)))
    meta: dict[str, Any] = dict(
        format=STORE_FORMAT,
        key=point_key(function, point),
        function=function_name(function),
        code=code_hash(function),
        tissuemech=code_version(),
        written=time.time(),
    )
    meta["sha256"] = checksum(fields, point_json, _identity(meta))
    # a unique temporary name per writer: concurrent writers of one key never collide (not matched by *.npz)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.{uuid.uuid4().hex[:12]}.part")
    try:
        with open(tmp, "wb") as fh:
            np.savez(fh, __point__=np.asarray(point_json), __meta__=np.asarray(json.dumps(meta)), **fields)  # type: ignore[arg-type]  # numpy stubs: savez **kwds typed as bool
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        why = exc.strerror or str(exc)
        hint = " (the disk is full: free space or give another store)" if exc.errno == errno.ENOSPC else ""
        raise StoreError(f"store {path.parent}: cannot write result file {path.name}: {why}{hint}") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def load(path: str | os.PathLike, *, key: str | None = None) -> Stored:
    """Read one stored result file (``<key>.npz``); the point is under ``"__point__"`` (a dict).

    key  the key the file must hold (:func:`point_key` of the requested function and point): the file's function,
         code hash, tissuemech version and point must hash to it (a valid result of another point, function or
         version of the code copied under this name is refused).
    Raises :class:`CorruptResultError` (naming the store and the file) when it is truncated, empty, not a result
    file, altered (checksum) or, with ``key``, the result of something else; :class:`StoreError` when it cannot be
    read (permissions, I/O error).
    """
    path = Path(path)
    where = f"store {path.parent}: result file {path.name}"
    try:
        fh = open(path, "rb")
    except OSError as exc:
        raise StoreError(f"{where} cannot be read: {exc.strerror or exc}") from None
    try:
        with fh, np.load(fh, allow_pickle=False) as z:
            files = set(z.files)
            if "__point__" not in files or "__meta__" not in files:
                raise CorruptResultError(f"{where} is not a tissuemech result (an .npz without __point__/__meta__)")
            point_json = str(z["__point__"])
            meta = json.loads(str(z["__meta__"]))
            fields = {k: z[k] for k in z.files if k not in ("__point__", "__meta__")}
            point = json.loads(point_json)
    except CorruptResultError:
        raise
    except OSError as exc:
        if exc.errno is not None:  # the disk, not the content
            raise StoreError(f"{where} cannot be read: {exc.strerror or exc}") from None
        raise CorruptResultError(
            f"{where} is unreadable: truncated, empty or not an .npz written by compare.batch"
        ) from None
    except (ValueError, EOFError, zipfile.BadZipFile, KeyError, TypeError):  # numpy: "... allow_pickle=False" etc.
        raise CorruptResultError(
            f"{where} is unreadable: truncated, empty or not an .npz written by compare.batch"
        ) from None
    if not isinstance(meta, dict):
        raise CorruptResultError(f"{where} is not a tissuemech result (its metadata is not a record)")
    identity = _identity(meta) if meta.get("format", 0) >= 3 else ""
    if meta.get("sha256") != checksum(fields, point_json, identity):
        raise CorruptResultError(f"{where} does not match its checksum (its numbers were altered or damaged)")
    if key is not None:
        if meta.get("format", 0) < 3:
            raise CorruptResultError(
                f"{where} was written by an older store format ({meta.get('format')}) that does not record what it "
                "belongs to; it cannot be verified"
            )
        if meta.get("key") != key or _key_of(meta, point) != key:
            raise CorruptResultError(
                f"{where} holds the result of {_describe(meta, point)}, not of the point requested (key {key})"
            )
    out = Stored(fields)
    out["__point__"] = point
    return out


def load_or_quarantine(path: Path, key: str | None = None) -> Stored | None:
    """The stored result (verified against ``key``, see :func:`load`), or None if absent; a corrupt or foreign file
    is moved aside to ``<name>.corrupt`` (with a :class:`StoreWarning`). Read errors raise :class:`StoreError`."""
    if not path.exists():
        return None
    try:
        return load(path, key=key)
    except CorruptResultError as exc:
        if not path.exists():  # replaced meanwhile by a concurrent writer: read it again
            return load_or_quarantine(path, key) if path.exists() else None
        try:
            os.replace(path, path.with_name(path.name + ".corrupt"))
        except OSError:
            pass
        warnings.warn(f"{exc}; moved aside to {path.name}.corrupt, recomputing this point", StoreWarning, stacklevel=3)
        return None


def describe(folder: str | os.PathLike) -> dict[str, int]:
    """What a store holds: function name -> number of result files (unreadable files under ``"(unreadable)"``)."""
    out: dict[str, int] = {}
    for f in sorted(Path(folder).glob("*.npz")):
        try:
            with np.load(f, allow_pickle=False) as z:
                name = str(json.loads(str(z["__meta__"])).get("function") or "(unnamed)")
        except Exception:
            name = "(unreadable)"
        out[name] = out.get(name, 0) + 1
    return out


# ---------------------------------------------------------------- per-point claims (lock files)

HOST = socket.gethostname()


def _boot_id() -> str:
    """This machine's boot id (Linux: a new one at every boot), '' where there is none."""
    try:
        return Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    except OSError:
        return ""


def process_start(pid: int) -> int | None:
    """Start time of process ``pid`` (clock ticks since boot, Linux ``/proc/<pid>/stat``), None where unknown: with
    the pid it names one process (a pid is reused by later processes, its start time is not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
        return int(stat[stat.rindex(")") + 2 :].split()[19])
    except (OSError, ValueError, IndexError):
        return None


BOOT_ID = _boot_id()


def pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


UNWRITTEN_LOCK_GRACE = 60.0  # s: a lock file still without content after this lost its writer (see claim)


def lock_owner(lock: Path) -> dict[str, Any] | None:
    """The owner a lock file names (pid, host, boot, start, run, time), None if it has none (or is gone)."""
    try:
        text = lock.read_text()
        info = json.loads(text) if text.strip() else None
    except (OSError, ValueError):
        return None
    return info if isinstance(info, dict) else None


def owner_alive(info: Mapping[str, Any]) -> bool | None:
    """Whether the process a lock names still runs: True/False on this host (same host and boot, the pid alive and,
    where recorded, started at the recorded time: a reused pid is another process); None for another host."""
    if info.get("host") != HOST or not isinstance(info.get("pid"), int):
        return None
    if info.get("boot") and BOOT_ID and info["boot"] != BOOT_ID:
        return False  # this machine rebooted since: every process of before is gone
    if not pid_alive(info["pid"]):
        return False
    start = info.get("start")
    if isinstance(start, int):
        now = process_start(info["pid"])
        if now is not None and now != start:
            return False  # the pid belongs to a later process
    return True


def lock_is_stale(lock: Path, stale_after: float) -> bool:
    """Whether ``lock`` was abandoned: its owner (this host) no longer runs (:func:`owner_alive`), an owner on another
    host has held it longer than ``stale_after`` s, or it has had no owner for ``UNWRITTEN_LOCK_GRACE`` s."""
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
    alive = owner_alive(info)
    if alive is not None:
        return not alive
    return age > stale_after


def describe_owner(lock: Path) -> str:
    """Who holds ``lock``, in words (for messages about waiting on it)."""
    info = lock_owner(lock)
    if info is None:
        return f"lock {lock} (no owner written yet)"
    since = info.get("time")
    when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(since)) if isinstance(since, (int, float)) else "?"
    return f"process {info.get('pid')} on host {info.get('host')} since {when} (lock {lock})"


_RUN_ID = uuid.uuid4().hex


def claim(lock: Path, stale_after: float) -> bool:
    """Create ``lock`` exclusively (True), or False if a live process holds it; stale locks are taken over.

    The lock appears with its owner (pid, host) already in it (:func:`place_lock`), so a process killed at any
    instant never leaves a lock without an owner."""
    pid = os.getpid()
    owner = json.dumps(
        {"pid": pid, "host": HOST, "boot": BOOT_ID, "start": process_start(pid), "run": _RUN_ID, "time": time.time()}
    )
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
