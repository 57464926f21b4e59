"""Run a function over many parameter points through a ``concurrent.futures`` executor, with resume.

``run(function, points, executor=None, store=path)`` evaluates ``function(**point)`` for each point
(a dict of keyword arguments, SI units). Each result is written to ``store`` the moment its point
finishes, as one ``<key>.npz`` file where ``key`` is a SHA-256 hash of the function's name, a hash of
its source code, the tissuemech version and the point's parameters (results of another version of the
code are never reused). A rerun with the same ``store`` skips every stored point.

The store survives corruption and concurrency:

* every file carries a SHA-256 checksum of its arrays; a truncated, empty, garbage or altered file is
  detected, moved aside to ``<key>.npz.corrupt``, recomputed, and a ``StoreWarning`` says so;
* files are written to a unique temporary name (``<key>.npz.<pid>.<random>.part``) and renamed
  (atomic), so a crash loses nothing that finished and writers never collide;
* a point being computed is claimed by a lock file ``<key>.lock`` (pid and host inside, from the instant it
  exists: a written file hard-linked to the lock's name): a second run into the same store waits for that
  point instead of computing it again; the lock of a dead process (same host) is taken over, so a killed
  batch resumes;
* a store that cannot be written raises :class:`StoreError` before any point is computed.

Executors: local processes by default (``ProcessPoolExecutor``, 2 workers, "spawn" start so JAX
state is never forked, one BLAS thread per worker: threadpoolctl); any ``concurrent.futures.Executor``; a ``dask.distributed.Client`` (its
``get_executor()`` is used; results come back to this process, which writes the store, so workers
need no shared disk); or ``"serial"`` (in-process, for debugging).

Results are returned as :class:`Stored` objects (a dict with attribute access) holding the result's
fields as NumPy arrays: NamedTuples, dataclasses, dicts, scalars and arrays are all accepted.
"""

from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import hashlib
import inspect
import json
import multiprocessing
import os
import socket
import time
import uuid
import warnings
import zipfile
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "run",
    "point_key",
    "load",
    "worker_init",
    "Stored",
    "BatchError",
    "StoreError",
    "StoreWarning",
    "STORE_FORMAT",
]

STORE_FORMAT = 2  # version of the file layout (fields + __point__ + __meta__ with the checksum)


class StoreError(ValueError):
    """The result store cannot be used (not writable, or a stored file is unreadable or altered)."""


class StoreWarning(UserWarning):
    """A stored result was corrupt and is being recomputed."""


class BatchError(RuntimeError):
    """Some points failed; ``failures`` maps point index -> exception text. Finished points are stored."""

    def __init__(self, message: str, failures: dict[int, str]):
        super().__init__(message)
        self.failures = failures


class Stored(dict):
    """A stored result: a dict of NumPy arrays with attribute access (``r.force`` == ``r["force"]``)."""

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


def _jsonable(v: Any) -> Any:
    if isinstance(v, Mapping):
        return {str(k): _jsonable(x) for k, x in sorted(v.items())}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return [_jsonable(x) for x in v.tolist()] if v.ndim else _jsonable(v.item())
    if isinstance(v, (np.floating, float)):
        return float(v)
    if isinstance(v, (np.integer,)):
        return int(v)
    return v


def _name(function: Callable) -> str:
    return f"{getattr(function, '__module__', '?')}.{getattr(function, '__qualname__', repr(function))}"


def _code_hash(function: Callable) -> str:
    """SHA-256 (16 hex digits) of the function's source, '' when it has none (builtins, C code)."""
    try:
        src = inspect.getsource(function)
    except (OSError, TypeError):
        return ""
    return hashlib.sha256(src.encode()).hexdigest()[:16]


def _version() -> str:
    from tissuemech import __version__

    return str(__version__)


def point_key(function: Callable, point: Mapping[str, Any]) -> str:
    """SHA-256 (first 24 hex digits) of the function's qualified name, its source hash, the tissuemech
    version and the point's parameters: results computed by other code are never reused."""
    text = json.dumps(
        {"f": _name(function), "c": _code_hash(function), "v": _version(), "p": _jsonable(dict(point))},
        sort_keys=True,
    )
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def _to_fields(result: Any) -> dict[str, np.ndarray]:
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


def _checksum(fields: Mapping[str, np.ndarray], point_json: str) -> str:
    h = hashlib.sha256(point_json.encode())
    for k in sorted(fields):
        a = np.ascontiguousarray(fields[k])
        h.update(f"{k}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _save(path: Path, fields: dict[str, np.ndarray], point: Mapping[str, Any], function_name: str = "") -> None:
    point_json = json.dumps(_jsonable(dict(point)))
    meta = dict(
        format=STORE_FORMAT,
        tissuemech=_version(),
        function=function_name,
        sha256=_checksum(fields, point_json),
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
    if meta.get("sha256") != _checksum(fields, point_json):
        raise StoreError(f"result file {path} does not match its checksum (its numbers were altered or damaged)")
    out = Stored(fields)
    out["__point__"] = json.loads(point_json)
    return out


def _load_or_quarantine(path: Path) -> Stored | None:
    """The stored result, or None if absent; a corrupt file is moved aside (with a StoreWarning)."""
    if not path.exists():
        return None
    try:
        return load(path)
    except StoreError as exc:
        if not path.exists():  # replaced meanwhile by a concurrent writer: read it again
            return _load_or_quarantine(path) if path.exists() else None
        try:
            os.replace(path, path.with_name(path.name + ".corrupt"))
        except OSError:
            pass
        warnings.warn(f"{exc}; recomputing this point", StoreWarning, stacklevel=3)
        return None


# ---------------------------------------------------------------- per-point claims (lock files)

_HOST = socket.gethostname()


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


UNWRITTEN_LOCK_GRACE = 60.0  # s: a lock file still without content after this lost its writer (see _claim)


def _lock_is_stale(lock: Path, stale_after: float) -> bool:
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
    if info.get("host") == _HOST and isinstance(info.get("pid"), int):
        return not _pid_alive(info["pid"])
    return age > stale_after


_RUN_ID = uuid.uuid4().hex


def _claim(lock: Path, stale_after: float) -> bool:
    """Create ``lock`` exclusively (True), or False if a live process holds it; stale locks are taken over.

    The lock appears with its owner (pid, host) already in it (:func:`_place`), so a process killed at any
    instant never leaves a lock without an owner."""
    owner = json.dumps({"pid": os.getpid(), "host": _HOST, "run": _RUN_ID, "time": time.time()})
    part = lock.with_name(f"{lock.name}.{os.getpid()}.{uuid.uuid4().hex[:12]}.part")  # _clean_parts' pattern
    part.write_text(owner)
    try:
        for _ in range(2):
            try:
                _place(lock, part, owner)
            except FileExistsError:
                if not _lock_is_stale(lock, stale_after):
                    return False
                lock.unlink(missing_ok=True)
                continue
            return True
        return False
    finally:
        part.unlink(missing_ok=True)


def _place(lock: Path, part: Path, owner: str) -> None:
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


def _release(lock: Path) -> None:
    try:
        lock.unlink()
    except FileNotFoundError:
        pass


def _check_writable(folder: Path) -> None:
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


def _clean_parts(folder: Path) -> None:
    """Remove temporary files left by dead writers on this host (``<key>.npz.<pid>.<rand>.part``)."""
    for part in folder.glob("*.part"):
        bits = part.name.split(".")
        try:
            pid = int(bits[-3])
        except (IndexError, ValueError):
            continue
        if not _pid_alive(pid):
            part.unlink(missing_ok=True)


def _evaluate(function: Callable, point: dict) -> dict[str, np.ndarray]:
    return _to_fields(function(**point))


class _Serial:
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


_BLAS_LIMIT: list = []  # the worker's threadpoolctl limit, kept alive for the worker's life


def worker_init() -> None:
    """Worker start-up of the process pools of ``run`` (default executor) and ``tissuemech batch``: one
    BLAS thread per worker (pass it as ``initializer=`` to a pool of your own). The FE gains nothing from a
    second BLAS thread on its small dense blocks, and 2 workers x 2 OpenBLAS threads on 2 cores made a
    6-run Fig. 10 batch 1.4-2.0x slower (13.0-14.3 s vs 7.1-9.1 s with one thread each:
    ``python notes/batch_blas_threads.py``)."""
    from threadpoolctl import threadpool_limits

    _BLAS_LIMIT.append(threadpool_limits(limits=1, user_api="blas"))


def _executor(executor: Any) -> tuple[Any, bool]:
    """(executor, owned): owned ones are shut down by run()."""
    if executor is None:
        pool = cf.ProcessPoolExecutor(
            max_workers=2, mp_context=multiprocessing.get_context("spawn"), initializer=worker_init
        )
        return pool, True
    if executor == "serial":
        return _Serial(), True
    if hasattr(executor, "get_executor"):  # dask.distributed.Client
        return executor.get_executor(), False
    if isinstance(executor, cf.Executor):
        return executor, False
    raise ValueError(
        "executor must be None (2 local processes), 'serial', a concurrent.futures.Executor "
        f"or a dask.distributed.Client; got {executor!r}"
    )


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
               Corrupt files are recomputed (with a ``StoreWarning``); points claimed by a concurrent
               run into the same store are waited for, not recomputed.
    progress   show a tqdm progress bar.
    poll       seconds between looks at points another run is computing.
    stale_after  seconds after which a lock of a process on another host counts as abandoned (locks of
               dead processes on this host are taken over at once).
    Failed points are collected; at the end a :class:`BatchError` names them (finished points are
    stored, so a rerun continues), or with ``raise_on_error=False`` their entries are None.
    Raises :class:`StoreError` before computing anything if the store cannot be written.
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
            results[i] = _load_or_quarantine(folder / f"{k}.npz")
    todo = [i for i, r in enumerate(results) if r is None]
    failures: dict[int, str] = {}
    if not todo:
        return results
    if folder is not None:
        _check_writable(folder)
        _clean_parts(folder)
    from tqdm.auto import tqdm

    first_of: dict[str, int] = {}  # one computation per distinct key (duplicate points share it)
    for i in todo:
        first_of.setdefault(keys[i], i)
    pending = [first_of[k] for k in dict.fromkeys(keys[i] for i in todo)]
    name = _name(function)
    ex, owned = _executor(executor)
    window = 1 if isinstance(ex, _Serial) else max(4, 2 * (getattr(ex, "_max_workers", 4) or 4))
    bar = tqdm(total=len(pts), initial=len(pts) - len(todo), disable=not progress, desc="batch")
    held: set[str] = set()
    try:
        waiting: list[int] = []  # points another run holds: looked at again later
        futures: dict[Any, int] = {}
        queue = list(pending)

        def submit_next() -> None:
            while queue and len(futures) < window:
                i = queue.pop(0)
                if folder is not None:
                    f = folder / f"{keys[i]}.npz"
                    got = _load_or_quarantine(f)
                    if got is not None:  # finished meanwhile by a concurrent run
                        results[i] = got
                        bar.update(1)
                        continue
                    lock = folder / f"{keys[i]}.lock"
                    if not _claim(lock, stale_after):
                        waiting.append(i)
                        continue
                    got = _load_or_quarantine(f)  # finished between the look and the claim
                    if got is not None:
                        _release(lock)
                        results[i] = got
                        bar.update(1)
                        continue
                    held.add(keys[i])
                futures[ex.submit(_evaluate, function, pts[i])] = i

        def collect(fut) -> None:
            i = futures.pop(fut)
            try:
                fields = fut.result()
            except Exception as e:
                failures[i] = f"{type(e).__name__}: {e}"
            else:
                if folder is not None:
                    _save(folder / f"{keys[i]}.npz", fields, pts[i], name)
                results[i] = Stored(fields, __point__=_jsonable(pts[i]))
            finally:
                if folder is not None and keys[i] in held:
                    _release(folder / f"{keys[i]}.lock")
                    held.discard(keys[i])
            bar.update(1)

        while queue or futures or waiting:
            submit_next()
            if futures:
                if isinstance(ex, _Serial):
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
                    got = _load_or_quarantine(folder / f"{keys[i]}.npz")
                    if got is not None:
                        results[i] = got
                        bar.update(1)
                    elif (folder / f"{keys[i]}.lock").exists() and not _lock_is_stale(
                        folder / f"{keys[i]}.lock", stale_after
                    ):
                        still.append(i)
                    else:  # the other run gave up (failed point, or died): compute it here
                        queue.append(i)
                waiting[:] = still
                if waiting and not queue:
                    time.sleep(poll)
    finally:
        bar.close()
        if folder is not None:
            for k in held:
                _release(folder / f"{k}.lock")
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
