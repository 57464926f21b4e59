r"""Compiled programs of the reduced models, and the XLA options of small eager calls.

A command such as ``tissuemech blastula`` spends most of its first run compiling: each model core (the
blastula's limit point, inverse, pressure) is one XLA program, compiled once per process (or read from JAX's
persistent program cache). For a call with a few points the program runs for microseconds to milliseconds and
its compilation takes hundreds of milliseconds, so :func:`small_call` compiles eager calls of up to ~1000 points
with XLA's CPU fusion emitters off (:data:`SMALL_CALL_COMPILER_OPTIONS`: the same run time there, less compile
time) and calls of one point also at XLA's lowest backend optimisation level (:data:`ONE_POINT_COMPILER_OPTIONS`:
up to a few tens of microseconds more per call, compiled in ~40 % of the time).
``python -m tissuemech.compare.bench.reduced_blastula --compile`` prints the compile and run times of each.
Large calls keep XLA's defaults (the fusion emitters make a limit-point search over 2e5 shells ~2x faster), and
so does every core staged into a user's ``jax.jit``/``vmap``/``grad`` (a nested program cannot take compiler
options: it is compiled with the user's program). On other backends than CPU the options are not used.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import jax

__all__ = ["ONE_POINT_COMPILER_OPTIONS", "SMALL_CALL_COMPILER_OPTIONS", "small_call"]

SMALL_CALL_COMPILER_OPTIONS: dict[str, Any] = {"xla_cpu_use_fusion_emitters": False}
ONE_POINT_COMPILER_OPTIONS: dict[str, Any] = {**SMALL_CALL_COMPILER_OPTIONS, "xla_backend_optimization_level": 0}


def _top_level() -> bool:
    """True outside any JAX trace (an eager call). JAX has no public test for it: where its private trace
    context is missing (another JAX version) this says False, and calls simply use the default program."""
    try:
        from jax._src import core as jax_core

        return bool(jax_core.trace_ctx.is_top_level())
    except (ImportError, AttributeError):  # pragma: no cover - depends on the JAX version
        return False


@functools.cache
def _cpu() -> bool:
    return jax.default_backend() == "cpu"


@functools.cache
def _variant(core: Callable, static_argnums: tuple[int, ...], one_point: bool) -> Callable:
    options = ONE_POINT_COMPILER_OPTIONS if one_point else SMALL_CALL_COMPILER_OPTIONS
    return jax.jit(core.__wrapped__, static_argnums=static_argnums, compiler_options=options)  # type: ignore[attr-defined]


def small_call(core: Callable, static_argnums: tuple[int, ...] = (), one_point: bool = False) -> Callable:
    """The program a small eager call of ``core`` (a ``jax.jit`` function) runs: outside any trace on CPU,
    ``core`` compiled with :data:`ONE_POINT_COMPILER_OPTIONS` (``one_point``: every input has one point) or
    :data:`SMALL_CALL_COMPILER_OPTIONS` (up to ~1000 points); else ``core`` itself. ``static_argnums`` are those
    ``core`` was jitted with. The same operations as ``core``, compiled differently: the values agree to rounding
    (a few units of 1e-16 relative)."""
    if _cpu() and _top_level():
        return _variant(core, static_argnums, one_point)
    return core
