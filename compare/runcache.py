r"""A content-addressed on-disk cache of FE runs: what does not change between two ``tissuemech report`` runs is
computed once.

:func:`call` ``(fn, kwargs)`` runs ``fn(**kwargs)`` and keeps its result (pickled) with the wall time the run
took, under a key made of everything the result depends on: the function's module and name, every keyword (numbers,
strings, tuples, NumPy arrays by their bytes), the package version and a digest of the source of the FE package
(``tissuemech/fem``) and of the function's own module. A later call with the same key returns the stored result
and the stored wall time (``Timed.cached`` True), so a report made from the cache shows the times of the runs
that made it. Arguments the key cannot represent faithfully (an object whose ``repr`` holds a memory address, a
callable) make the call run uncached.

Where: ``$TISSUEMECH_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/tissuemech/runs`` (default
``~/.cache/tissuemech/runs``); ``tissuemech report --cache-dir DIR`` chooses another, ``--no-cache`` (or
``TISSUEMECH_NO_CACHE=1``) turns it off. Deleting the folder is always safe (:func:`clear`;
``tissuemech report --clear-cache``). Files are written atomically (a temporary file renamed), so two processes
filling the cache at once never read a half-written entry.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import functools
import hashlib
import os
import pickle
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "Timed",
    "Job",
    "call",
    "prefetch",
    "cancel_pending",
    "counts",
    "key",
    "default_dir",
    "configure",
    "settings",
    "clear",
    "code_digest",
    "CACHE_ENV",
]

CACHE_ENV = "TISSUEMECH_CACHE_DIR"
NO_CACHE_ENV = "TISSUEMECH_NO_CACHE"
_STATE: dict[str, Any] = {"dir": None, "enabled": None}  # None: from the environment
_PENDING: dict[str, Any] = {}  # key -> future of a prefetched run (prefetch)
_JOBS: dict[str, tuple[Callable, dict[str, Any], int]] = {}  # key -> the prefetched run's (fn, kwargs, repeats)
_STOLEN: dict[str, Timed] = {}  # key -> a prefetched run this process took back and ran while it waited
_QUEUE: list[tuple[cf.Future, tuple]] = []  # prefetched runs not yet handed to the executor, in its order
_FEED: dict[str, Any] = {}  # the executor runs are handed to, and its free workers
_LOCK = threading.Lock()
Job = tuple  # (fn, kwargs, repeats): one run for prefetch


@dataclass(frozen=True)
class Timed:
    """A run's ``result`` (of the last repeat), the wall seconds of each repeat (``walls``) when it was computed,
    and whether it came from the cache (``cached``); ``wall`` is the first repeat's."""

    result: Any
    walls: tuple[float, ...]
    cached: bool

    @property
    def wall(self) -> float:
        return self.walls[0]


def default_dir() -> Path:
    """``$TISSUEMECH_CACHE_DIR``, else ``$XDG_CACHE_HOME/tissuemech/runs`` (``~/.cache/tissuemech/runs``)."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "tissuemech" / "runs"


def _enabled() -> bool:
    if _STATE["enabled"] is not None:
        return bool(_STATE["enabled"])
    return os.environ.get(NO_CACHE_ENV, "") in ("", "0")


def _folder() -> Path:
    return Path(_STATE["dir"]) if _STATE["dir"] is not None else default_dir()


def configure(folder: str | Path | None = None, enabled: bool | None = None) -> None:
    """Set the cache folder (None: :func:`default_dir`) and whether it is used (None: from ``TISSUEMECH_NO_CACHE``),
    for this process and the worker processes started after it (through the environment)."""
    _STATE["dir"] = None if folder is None else str(folder)
    _STATE["enabled"] = enabled
    if folder is not None:
        os.environ[CACHE_ENV] = str(folder)
    if enabled is not None:
        os.environ[NO_CACHE_ENV] = "" if enabled else "1"


@contextlib.contextmanager
def settings(folder: str | Path | None = None, enabled: bool | None = None) -> Iterator[None]:
    """:func:`configure` within a ``with`` block (the previous settings and environment restored after it)."""
    saved = dict(_STATE), {k: os.environ.get(k) for k in (CACHE_ENV, NO_CACHE_ENV)}
    configure(folder, enabled)
    try:
        yield
    finally:
        _STATE.update(saved[0])
        for k, v in saved[1].items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def code_digest(module: str = "") -> str:
    """sha256 of the package version and the source of ``tissuemech/fem`` (and of ``module``'s file, if given)."""
    import importlib

    import tissuemech

    fem_file = importlib.import_module("tissuemech.fem").__file__ or ""
    return _digest(tissuemech.__version__, module, str(Path(fem_file).parent))


_DIGESTS: dict[tuple, str] = {}


def _digest(version: str, module: str, fem_dir: str) -> str:
    import importlib

    files = sorted(Path(fem_dir).glob("*.py"))
    if module:
        f = getattr(importlib.import_module(module), "__file__", None)
        if f:
            files.append(Path(f))
    stamp = tuple((str(f), f.stat().st_mtime_ns, f.stat().st_size) for f in files)
    k = (version, module, stamp)
    if k not in _DIGESTS:
        h = hashlib.sha256(version.encode())
        for f in files:
            h.update(f.name.encode())
            h.update(f.read_bytes())
        _DIGESTS[k] = h.hexdigest()
    return _DIGESTS[k]


class _Uncacheable(Exception):
    pass


def _canonical(v: Any) -> Any:
    """A value the key can hash: numbers, strings, None, tuples/lists/dicts of them, arrays by their bytes."""
    if v is None or isinstance(v, (bool, str)):
        return v
    if isinstance(v, (int, np.integer)):
        return ("int", int(v))
    if isinstance(v, (float, np.floating)):
        return ("float", float(v).hex())
    if isinstance(v, np.ndarray) or type(v).__module__.startswith("jax"):
        a = np.ascontiguousarray(np.asarray(v))
        return ("array", a.dtype.str, a.shape, hashlib.sha256(a.tobytes()).hexdigest())
    if isinstance(v, (tuple, list)):
        return (type(v).__name__, tuple(_canonical(x) for x in v))
    if isinstance(v, dict):
        return ("dict", tuple(sorted((str(k), _canonical(x)) for k, x in v.items())))
    if callable(v):
        raise _Uncacheable(f"a callable argument ({v!r})")
    r = repr(v)
    if " at 0x" in r:
        raise _Uncacheable(f"an argument without a faithful text form ({r[:60]})")
    return ("repr", type(v).__module__, type(v).__qualname__, r)


def key(fn: Callable, kwargs: dict[str, Any]) -> str:
    """The cache key (hex sha256) of ``fn(**kwargs)``; raises ValueError for arguments it cannot represent."""
    try:
        parts = (fn.__module__, fn.__qualname__, _canonical(kwargs), code_digest(fn.__module__))
    except _Uncacheable as exc:
        raise ValueError(f"not cacheable: {exc}") from None
    return hashlib.sha256(repr(parts).encode()).hexdigest()


def _job_key(fn: Callable, kwargs: dict[str, Any], repeats: int) -> str | None:
    try:
        return key(fn, {"kwargs": kwargs, "repeats": repeats})
    except ValueError:
        return None


def call(fn: Callable, kwargs: dict[str, Any], *, repeats: int = 1) -> Timed:
    """``fn(**kwargs)`` through the cache (module doc), run ``repeats`` times when computed (timing studies keep the
    fastest); the wall times are the runs', measured when they ran. A run :func:`prefetch` started in another
    process is waited for (or, not yet started there, taken back and run here)."""
    repeats = max(int(repeats), 1)
    k = _job_key(fn, kwargs, repeats) if (_enabled() or _PENDING or _STOLEN) else None
    if k and k in _STOLEN:
        _count("taken back")
        timed = _STOLEN.pop(k)
        _count("cached" if timed.cached else "run here")
        return timed
    fut = _PENDING.pop(k, None) if k else None
    if k:
        _JOBS.pop(k, None)
    if fut is not None:
        if not fut.cancel():
            while not fut.done() and _steal_one():  # running over there: do the last queued run here meanwhile
                pass
            try:
                timed = fut.result()
                _count("prefetched" if not timed.cached else "cached")
                return timed
            except Exception:  # the run failed over there: run it here, where its error reaches the caller
                _count("failed in the other process")
        else:
            _count("taken back")
    timed = _cached_run(fn, kwargs, repeats)
    _count("cached" if timed.cached else "run here")
    return timed


def _steal_one() -> bool:
    """Take back the prefetched run that would start last over there (not started yet) and run it here, keeping its
    result for the :func:`call` that asks for it: while this process waits for a run in progress in the other one,
    both work (the runs asked for last are the farthest from starting there). False where none is left to take."""
    for k in reversed(list(_PENDING)):
        fut = _PENDING[k]
        if fut.cancel():
            del _PENDING[k]
            fn, kwargs, repeats = _JOBS.pop(k)
            try:
                _STOLEN[k] = _cached_run(fn, kwargs, repeats)
            except Exception:  # its own call runs it again, where the error reaches that caller
                pass
            return True
    return False


_COUNTS: dict[str, int] = {}


def _count(what: str) -> None:
    _COUNTS[what] = _COUNTS.get(what, 0) + 1


def counts(reset: bool = False) -> dict[str, int]:
    """How the runs :func:`call` returned were obtained in this process: "cached" (read from the cache), "prefetched"
    (computed by :func:`prefetch`'s executor), "run here", and how many prefetched runs were "taken back" (not yet
    started there) or "failed in the other process" (then run here too). ``reset``: start counting anew."""
    out = dict(_COUNTS)
    if reset:
        _COUNTS.clear()
    return out


def _cached_run(fn: Callable, kwargs: dict[str, Any], repeats: int) -> Timed:
    """The cache lookup and run of :func:`call`, without the prefetched runs (what :func:`prefetch` submits: a
    worker THREAD sharing this process's pending table would otherwise wait for its own future)."""
    repeats = max(int(repeats), 1)
    k = _job_key(fn, kwargs, repeats) if _enabled() else None
    path = _folder() / k[:2] / f"{k}.pkl" if k else None
    if path is not None and path.exists():
        try:
            with open(path, "rb") as f:
                result, walls = pickle.load(f)
            return Timed(result, tuple(float(w) for w in walls), True)
        except Exception:  # a damaged or foreign entry: recompute and overwrite
            pass
    walls = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn(**kwargs)
        walls.append(time.perf_counter() - t0)
    if path is not None:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            with open(tmp, "wb") as f:
                pickle.dump((result, walls), f, protocol=pickle.HIGHEST_PROTOCOL)
            os.replace(tmp, path)
        except Exception:  # unpicklable result, read-only or full disk: the run stands, uncached
            with contextlib.suppress(OSError):
                tmp.unlink()
    return Timed(result, tuple(walls), False)


def prefetch(executor: Any, jobs: list[Job], *, workers: int = 1) -> int:
    """Start ``jobs`` (``(fn, kwargs, repeats)``, in the order given) on ``executor`` (e.g. one worker process on the
    second core: ``compare.batch.pool.process_pool(1)``) unless the cache holds them; a later :func:`call` of the same
    run collects it. Returns the number queued.

    The runs are handed to the executor one per free worker (``workers``: how many it runs at once), the rest wait
    here: a run not yet handed over can always be taken back (an executor's own queue marks the runs it has
    accepted as running, and a process pool accepts one more than it runs)."""
    n = 0
    for fn, kwargs, repeats in jobs:
        k = _job_key(fn, kwargs, max(int(repeats), 1))
        if k is None or k in _PENDING:
            continue
        if _enabled() and (_folder() / k[:2] / f"{k}.pkl").exists():
            continue
        fut: cf.Future = cf.Future()
        _PENDING[k] = fut
        _JOBS[k] = (fn, kwargs, repeats)
        with _LOCK:
            _QUEUE.append((fut, (fn, kwargs, repeats)))
        n += 1
    with _LOCK:
        _FEED["executor"] = executor
        _FEED["free"] = _FEED.get("free", 0) + max(int(workers), 1)
    _feed()
    return n


def _feed() -> None:
    """Hand the next queued runs to the executor while it has a free worker (runs taken back are skipped)."""
    while True:
        with _LOCK:
            if _FEED.get("free", 0) <= 0 or not _QUEUE:
                return
            fut, job = _QUEUE.pop(0)
            if not fut.set_running_or_notify_cancel():  # taken back (cancelled) before it was handed over
                continue
            _FEED["free"] -= 1
            executor = _FEED["executor"]
        try:
            inner = executor.submit(_cached_run, *job)
        except Exception as exc:  # the executor is shut down or broken: the caller runs it itself
            fut.set_exception(exc)
            with _LOCK:
                _FEED["free"] += 1
            continue
        inner.add_done_callback(functools.partial(_handed_back, fut))


def _handed_back(fut: cf.Future, inner: cf.Future) -> None:
    """The executor finished a run: its result (or error) to the run's own future, then the next run to the worker."""
    try:
        fut.set_result(inner.result())
    except BaseException as exc:  # the error, a cancellation included, goes to the caller of call
        fut.set_exception(exc if isinstance(exc, Exception) else RuntimeError(repr(exc)))
    with _LOCK:
        _FEED["free"] = _FEED.get("free", 0) + 1
    _feed()


def cancel_pending() -> None:
    """Forget the prefetched runs nobody asked for (cancelling those not started)."""
    with _LOCK:
        queued = [fut for fut, _ in _QUEUE]
        _QUEUE.clear()
        _FEED.clear()
    for fut in queued + list(_PENDING.values()):
        fut.cancel()
    _PENDING.clear()
    _JOBS.clear()
    _STOLEN.clear()


def clear(folder: str | Path | None = None) -> int:
    """Delete the cache's entries (``folder``, default the folder in use); returns how many were removed."""
    root = Path(folder) if folder is not None else _folder()
    n = 0
    if root.is_dir():
        for p in root.glob("*/*.pkl"):
            with contextlib.suppress(OSError):
                p.unlink()
                n += 1
    return n
