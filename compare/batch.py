"""Run a function over many parameter points through a ``concurrent.futures`` executor, with resume.

``run(function, points, executor=None, store=path)`` evaluates ``function(**point)`` for each point
(a dict of keyword arguments, SI units). Each result is written to ``store`` the moment its point
finishes, as one ``<key>.npz`` file where ``key`` is a SHA-256 hash of the function's name and the
point's parameters; the file is written to a temporary name and renamed (atomic), so an interrupted
batch (crash, Ctrl-C, killed job) loses nothing that finished and a rerun with the same ``store``
skips every stored point.

Executors: local processes by default (``ProcessPoolExecutor``, 2 workers, "spawn" start so JAX
state is never forked); any ``concurrent.futures.Executor``; a ``dask.distributed.Client`` (its
``get_executor()`` is used; results come back to this process, which writes the store, so workers
need no shared disk); or ``"serial"`` (in-process, for debugging).

Results are returned as :class:`Stored` objects (a dict with attribute access) holding the result's
fields as NumPy arrays: NamedTuples, dataclasses, dicts, scalars and arrays are all accepted.
"""

from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import hashlib
import json
import multiprocessing
import os
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["run", "point_key", "load", "Stored", "BatchError"]


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


def point_key(function: Callable, point: Mapping[str, Any]) -> str:
    """SHA-256 (first 24 hex digits) of the function's qualified name and the point's parameters."""
    text = json.dumps({"f": _name(function), "p": _jsonable(dict(point))}, sort_keys=True)
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


def _save(path: Path, fields: dict[str, np.ndarray], point: Mapping[str, Any]) -> None:
    tmp = path.with_name(path.name + ".part")  # not matched by *.npz until complete
    with open(tmp, "wb") as fh:
        np.savez(fh, __point__=np.asarray(json.dumps(_jsonable(dict(point)))), **fields)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def load(path: str | os.PathLike) -> Stored:
    """Read one stored result file (``<key>.npz``); the point is under ``"__point__"`` (a dict)."""
    with np.load(path, allow_pickle=False) as z:
        out = Stored({k: z[k] for k in z.files if k != "__point__"})
        out["__point__"] = json.loads(str(z["__point__"]))
    return out


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


def _executor(executor: Any) -> tuple[Any, bool]:
    """(executor, owned): owned ones are shut down by run()."""
    if executor is None:
        return cf.ProcessPoolExecutor(max_workers=2, mp_context=multiprocessing.get_context("spawn")), True
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
) -> list[Stored | None]:
    """Evaluate ``function(**point)`` for every point; return the results in the order of ``points``.

    function   a picklable (module-level) function of keyword arguments.
    points     dicts of keyword arguments (SI units).
    executor   None: 2 local processes; "serial"; a concurrent.futures.Executor; a dask Client.
    store      directory for ``<key>.npz`` results; points already there are not recomputed (resume).
    progress   show a tqdm progress bar.
    Failed points are collected; at the end a :class:`BatchError` names them (finished points are
    stored, so a rerun continues), or with ``raise_on_error=False`` their entries are None.
    """
    pts = [dict(p) for p in points]
    keys = [point_key(function, p) for p in pts]
    results: list[Stored | None] = [None] * len(pts)
    folder = Path(store) if store is not None else None
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
        for i, k in enumerate(keys):
            f = folder / f"{k}.npz"
            if f.exists():
                results[i] = load(f)
    todo = [i for i, r in enumerate(results) if r is None]
    failures: dict[int, str] = {}
    if todo:
        from tqdm.auto import tqdm

        ex, owned = _executor(executor)
        bar = tqdm(total=len(pts), initial=len(pts) - len(todo), disable=not progress, desc="batch")
        try:
            futures = {ex.submit(_evaluate, function, pts[i]): i for i in todo}
            done = futures if isinstance(ex, _Serial) else cf.as_completed(futures)
            for fut in done:
                i = futures[fut]
                try:
                    fields = fut.result()
                except Exception as e:
                    failures[i] = f"{type(e).__name__}: {e}"
                    bar.update(1)
                    continue
                if folder is not None:
                    _save(folder / f"{keys[i]}.npz", fields, pts[i])
                results[i] = Stored(fields, __point__=_jsonable(pts[i]))
                bar.update(1)
        finally:
            bar.close()
            if owned:
                ex.shutdown(wait=True, cancel_futures=True)
    if failures and raise_on_error:
        first = min(failures)
        raise BatchError(
            f"{len(failures)} of {len(pts)} points failed (first: point {first} {pts[first]}: "
            f"{failures[first]}). Finished points are stored"
            + (f" in {folder}; rerun with the same store to retry only the failed ones." if folder else "."),
            failures,
        )
    return results
