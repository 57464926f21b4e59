"""Helpers the benchmark suites share: the machine line, timing a jitted call, printing rows as an aligned table."""

from __future__ import annotations

import os
import time
from collections.abc import Callable

import numpy as np


def machine_line() -> str:
    """The load and this box's speed right now, for a benchmark's header: the load average (1, 5, 15 min), the
    CPU count, a pure-Python loop of 1e6 additions and 1e4 NumPy ufunc calls on 288 floats (the blastula 4x8
    mesh's quadrature points: the per-call overhead that dominates the small FE runs), both in ms, min of 3.

    The shared box's speed moves by up to ~3x between days (the same commit's runs): figures from different
    runs compare through these two numbers, ratios within one run need neither."""

    def best(fn) -> float:
        ts = []
        for _ in range(3):
            t = time.perf_counter()
            fn()
            ts.append(time.perf_counter() - t)
        return 1e3 * min(ts)

    def loop() -> None:
        s = 0
        for i in range(1_000_000):
            s += i

    a = np.linspace(1.0, 2.0, 288)

    def calls() -> None:
        for _ in range(10_000):
            np.multiply(a, a)

    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    return (
        f"load average (1, 5, 15 min): {load} on {os.cpu_count()} CPUs; box speed: Python loop of 1e6 additions "
        f"{best(loop):.0f} ms, 1e4 NumPy calls on 288 floats {best(calls):.1f} ms"
    )


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
