"""Helpers the benchmark suites share: timing a jitted call, printing rows as an aligned table."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np


def jit_timed(fn: Callable, *args, repeats: int = 3) -> tuple[float, float, object]:
    """(compile seconds, best seconds per call, result) of jax.jit(fn)(*args)."""
    import jax

    t0 = time.perf_counter()
    compiled = jax.jit(fn).lower(*args).compile()
    t_compile = time.perf_counter() - t0
    out = jax.block_until_ready(compiled(*args))
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = jax.block_until_ready(compiled(*args))
        best = min(best, time.perf_counter() - t0)
    return t_compile, best, out


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def print_rows(rows: list[dict]) -> None:
    """Print dict rows as a ``|``-separated table with the union of their keys as columns."""
    keys: list[str] = []
    for r in rows:
        for k in r:
            if k not in keys:
                keys.append(k)
    widths = {k: max(len(k), *(len(_fmt(r.get(k, ""))) for r in rows)) for k in keys}
    print(" | ".join(k.ljust(widths[k]) for k in keys))
    print("-|-".join("-" * widths[k] for k in keys))
    for r in rows:
        print(" | ".join(_fmt(r.get(k, "")).ljust(widths[k]) for k in keys))
