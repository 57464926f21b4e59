r"""Input checks shared by every public entry point of tissuemech (reduced, fem and compare).

Each check raises :class:`InputError` (a ``ValueError``) with a one-line message that names the
quantity, its unit and the value received, e.g.::

    C (the Fung stiffness, shear modulus / 2) must be positive (in Pa); got -1 Pa
    inner_stretch must be a number or an array of numbers (a/A, dimensionless), not text; got 'abc'

Wrong types (text, None, a bool, a dict...) raise :class:`InputTypeError`, which is both an
``InputError`` (so a ``ValueError``) and a ``TypeError``: ``except ValueError`` catches every bad
input, ``except TypeError`` still catches the type errors.

Values that are JAX tracers (inside ``jit``/``vmap``/``grad``) cannot be inspected: every eager check
returns without a word for them. Their jit-safe twins (``traced_*``) return the same checks of the traced
values as ``(bad, message)`` pairs, which :func:`traced_checks` attaches to a function's result with
``equinox.branched_error_if``: the compiled program raises at run time (a ``JaxRuntimeError`` whose text
holds the message, naming the quantity and its unit; the value itself cannot be printed), for any entry,
also under ``vmap``; ``grad`` passes through. For a concrete value the twins return nothing (the eager
check covers it), so a model calls both.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Sequence
from typing import Any, SupportsInt, cast

import numpy as np

try:  # jax is a core dependency; keep this module importable for pure-NumPy callers anyway
    import jax
    import jax.numpy as jnp
except ImportError:  # pragma: no cover
    jax = None  # type: ignore[assignment]  # optional-module fallback

__all__ = [
    "InputError",
    "InputTypeError",
    "is_traced",
    "as_array",
    "validate_finite",
    "validate_positive",
    "validate_nonnegative",
    "validate_material",
    "validate_radii",
    "validate_branches",
    "validate_int",
    "validate_choice",
    "validate_times",
    "scalar_values",
    "traced_checks",
    "traced_finite",
    "traced_positive",
    "traced_nonnegative",
    "traced_material",
    "traced_radii",
    "traced_branches",
    "traced_times",
]


class InputError(ValueError):
    """A bad input value; the message names the quantity and its unit."""


class InputTypeError(InputError, TypeError):
    """An input of the wrong type (text, None, a bool, a container where a number is needed)."""


def is_traced(*values: Any) -> bool:
    """True if any value is a JAX tracer (inside jit/vmap/grad): checks are then skipped."""
    if jax is None:
        return False
    return any(isinstance(v, jax.core.Tracer) for v in values)


def _unit_phrase(unit: str) -> str:
    return f" (in {unit})" if unit and unit not in ("-", "dimensionless") else (" (dimensionless)" if unit else "")


def _with_unit(x: float, unit: str) -> str:
    return f"{x:g} {unit}" if unit and unit not in ("-", "dimensionless") else f"{x:g}"


def _describe(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def as_array(name: str, value: Any, unit: str = "") -> np.ndarray | None:
    """``value`` as a float64 array (None for traced values), or raise InputTypeError naming ``name``.

    Text, None, bools, complex numbers and ragged or non-numeric containers are refused.
    """
    t = type(value)
    if t is float or t is int:  # the common scalar: skip the type ladder (a bool is not an int here)
        return np.asarray(value, dtype=float)
    if t is np.ndarray and value.dtype.kind in "iuf":
        return value if value.dtype == np.float64 else np.asarray(value, dtype=float)
    if is_traced(value):
        return None
    u = _unit_phrase(unit)
    if value is None:
        raise InputTypeError(f"{name} must be a number{u}; got None")
    if isinstance(value, (str, bytes)):
        raise InputTypeError(f"{name} must be a number or an array of numbers{u}, not text; got {_describe(value)}")
    if isinstance(value, (bool, np.bool_)):
        raise InputTypeError(f"{name} must be a number{u}, not a bool; got {value!r}")
    if isinstance(value, dict):
        raise InputTypeError(f"{name} must be a number or an array of numbers{u}; got a dict {_describe(value)}")
    try:
        raw = np.asarray(value)
    except Exception:
        raise InputTypeError(f"{name} must be a number or an array of numbers{u}; got {_describe(value)}") from None
    if raw.dtype.kind == "c":
        raise InputTypeError(f"{name} must be a real number{u}; got the complex value {_describe(value)}")
    if raw.dtype.kind == "b":
        raise InputTypeError(f"{name} must be a number{u}, not a bool; got {_describe(value)}")
    if raw.dtype.kind in "US":
        raise InputTypeError(f"{name} must be a number or an array of numbers{u}, not text; got {_describe(value)}")
    if raw.dtype.kind not in "iuf":
        try:
            return np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise InputTypeError(f"{name} must be a number or an array of numbers{u}; got {_describe(value)}") from None
    return np.asarray(raw, dtype=float)


def _finite_scalar(value: Any) -> float | None:
    """``value`` as a float if it is a plain finite Python float or int (the fast path), else None."""
    t = type(value)
    if (t is float or t is int) and math.isfinite(value):
        return float(value)
    return None


def scalar_values(*values: Any) -> tuple[list[float], int] | None:
    """The fast path of one-point calls: ``([floats], ndim)`` if every value is a Python float or int
    (not a bool), a NumPy float64 scalar or a real NumPy array with one entry (``ndim``: the largest
    array rank, so the broadcast shape is ``(1,) * ndim``); None otherwise (then the full checks run).
    No value is checked here: a caller tests the floats and takes the full path if any test fails,
    so every message stays that of the full checks."""
    out: list[float] = []
    nd = 0
    for v in values:
        t = type(v)
        if t is float or t is int or t is np.float64:
            out.append(float(v))
        elif t is np.ndarray and v.size == 1 and v.dtype.kind in "fiu":
            out.append(float(v.item()))
            nd = max(nd, v.ndim)
        else:
            return None
    return out, nd


def validate_finite(name: str, value: Any, unit: str = "") -> np.ndarray | None:
    """Raise unless every entry of ``value`` is a finite real number; returns the float array."""
    x = _finite_scalar(value)
    if x is not None:
        return np.asarray(x)
    v = as_array(name, value, unit)
    if v is None:
        return None
    if v.size == 0:
        raise InputError(f"{name} must not be empty{_unit_phrase(unit)}; got {_describe(value)}")
    if not np.isfinite(v).all():
        raise InputError(f"{name} must be a finite number{_unit_phrase(unit)}; got {_describe(value)}")
    return v


def validate_positive(name: str, value: Any, unit: str = "") -> np.ndarray | None:
    """Raise unless every entry of ``value`` is finite and > 0."""
    x = _finite_scalar(value)
    if x is not None and x > 0:
        return np.asarray(x)
    v = validate_finite(name, value, unit)
    if v is not None and (v <= 0).any():
        raise InputError(f"{name} must be positive{_unit_phrase(unit)}; got {_with_unit(float(np.min(v)), unit)}")
    return v


def validate_nonnegative(name: str, value: Any, unit: str = "") -> np.ndarray | None:
    """Raise unless every entry of ``value`` is finite and >= 0."""
    v = validate_finite(name, value, unit)
    if v is not None and np.any(v < 0):
        raise InputError(f"{name} must not be negative{_unit_phrase(unit)}; got {_with_unit(float(np.min(v)), unit)}")
    return v


def validate_material(C: Any, alpha: Any, kappa: Any = None) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Check the Fung parameters: C > 0 (Pa), alpha >= 0 (dimensionless), optional kappa > 0 (Pa).

    Returns (C, alpha) as float64 arrays (None for a traced value), so that callers need not convert twice.
    """
    c = validate_positive("C (the Fung stiffness, shear modulus / 2)", C, "Pa")
    name = "alpha (the Fung stiffening exponent)"
    x = _finite_scalar(alpha)
    v = np.asarray(x) if x is not None else as_array(name, alpha, "dimensionless")
    if v is not None and not (x is not None and x >= 0):
        if v.size == 0 or not np.isfinite(v).all():
            raise InputError(f"{name} must be finite (dimensionless); got {_describe(alpha)}")
        if (v < 0).any():
            raise InputError(f"{name} must be >= 0 (dimensionless, 0 is neo-Hookean); got {np.min(v):g}")
    if kappa is not None:
        validate_positive("kappa (the bulk modulus)", kappa, "Pa")
    return c, v


def validate_radii(inner_radius: Any, outer_radius: Any) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Check a hollow sphere: 0 < inner_radius < outer_radius (both in m).

    Returns the two radii as float64 arrays (None for a traced value)."""
    a = validate_positive("inner_radius", inner_radius, "m")
    b = validate_positive("outer_radius", outer_radius, "m")
    if a is not None and b is not None and not (a.ndim == 0 and b.ndim == 0 and float(a) < float(b)):
        try:
            thin = (a >= b).any()
        except ValueError:
            raise InputError(
                f"inner_radius (shape {a.shape}) and outer_radius (shape {b.shape}) must broadcast (in m)"
            ) from None
        if thin:
            raise InputError(
                "inner_radius must be smaller than outer_radius (the wall needs a positive "
                f"thickness); got inner {np.max(a):g} m >= outer {np.min(b):g} m"
            )
    return a, b


def validate_branches(branches: Iterable[Sequence[float]] | None) -> tuple[tuple[Any, Any], ...]:
    """Normalise generalized-Maxwell branches to a tuple of (beta, tau) and check them.

    ``beta`` (dimensionless energy factor) must be >= 0 and ``tau`` (relaxation time, s) > 0.
    ``None`` or an empty sequence means purely elastic.
    """
    if branches is None:
        return ()
    if isinstance(branches, (str, bytes, dict)) or not isinstance(branches, Iterable):
        raise InputTypeError(
            "branches must be a sequence of (beta, tau) pairs (energy factor, relaxation time in s), "
            f"e.g. [(0.4, 200.0)]; got {_describe(branches)}"
        )
    out = []
    for k, br in enumerate(branches):
        if isinstance(br, (str, bytes)):
            raise InputTypeError(f"branch {k}: each viscoelastic branch is a pair (beta, tau); got {br!r}")
        try:
            beta, tau = br
        except (TypeError, ValueError):
            raise InputTypeError(f"branch {k}: each viscoelastic branch is a pair (beta, tau); got {br!r}") from None
        validate_nonnegative(f"beta (energy factor of branch {k})", beta, "dimensionless")
        validate_positive(f"tau (relaxation time of branch {k})", tau, "s")
        out.append((beta, tau))
    return tuple(out)


def validate_int(name: str, value: Any, minimum: int | None = None, maximum: int | None = None) -> int:
    """``value`` as a Python int; raises unless it is a whole number within [minimum, maximum]."""
    if isinstance(value, (bool, np.bool_)) or value is None or isinstance(value, (str, bytes)):
        raise InputTypeError(f"{name} must be a whole number; got {_describe(value)}")
    if isinstance(value, numbers.Integral):
        n = int(value)
    elif isinstance(value, numbers.Real) and np.isfinite(float(value)) and float(value).is_integer():
        n = int(cast(SupportsInt, value))  # numbers.Real has no __int__ in the stubs
    else:
        raise InputTypeError(f"{name} must be a whole number; got {_describe(value)}")
    if minimum is not None and n < minimum:
        raise InputError(f"{name} must be at least {minimum}; got {n}")
    if maximum is not None and n > maximum:
        raise InputError(f"{name} must be at most {maximum}; got {n}")
    return n


def validate_choice(name: str, value: Any, choices: Sequence[str]) -> str:
    """Raise unless ``value`` is one of the strings ``choices``."""
    if not isinstance(value, str) or value not in choices:
        opts = ", ".join(repr(c) for c in choices)
        raise InputError(f"{name} must be one of {opts}; got {_describe(value)}")
    return value


def validate_times(
    name: str, t: Any, *, unit: str = "s", ascending: bool = False, strictly: bool = False, ndim1: bool = False
) -> np.ndarray | None:
    """Output times: a non-empty array of finite values >= 0 (``unit``); optionally 1-D and ascending."""
    v = validate_finite(name, t, unit)
    if v is None:
        return None
    if ndim1 and v.ndim != 1:
        raise InputError(f"{name} must be a 1-D array of times{_unit_phrase(unit)}; got shape {v.shape}")
    if np.any(v < 0):
        raise InputError(f"{name} must be >= 0{_unit_phrase(unit)}; got {_with_unit(float(np.min(v)), unit)}")
    if ascending:
        d = np.diff(v.ravel())
        if np.any(d < 0) or (strictly and np.any(d == 0)):
            i = int(np.flatnonzero(d < 0)[0] if np.any(d < 0) else np.flatnonzero(d == 0)[0])
            order = "strictly increasing" if strictly else "in ascending order"
            raise InputError(
                f"{name} must be {order}{_unit_phrase(unit)}; entry {i + 1} ({v.ravel()[i + 1]:g}) follows "
                f"{v.ravel()[i]:g}"
            )
    return v


# ---------------------------------------------------------------- jit-safe twins (equinox.error_if)

_TRACED = " (checked at run time: a traced value cannot be printed)"
Checks = list[tuple[Any, str]]  # (bad, message) pairs: bad a boolean array, True where the input is refused


def traced_checks(out: Any, checks: Sequence[tuple[Any, str]]) -> Any:
    """``out`` (an array or a pytree of arrays: a function's result) with the ``(bad, message)`` checks attached as
    one run-time check (``equinox.branched_error_if``): the compiled program raises the message of the first pair
    with any True entry (a ``JaxRuntimeError`` holding it). Under vmap the check reduces over the batch; grad passes
    through. Attach the checks to what a function returns, so that they run whenever a result is used (a check on
    an unused value is dropped by the compiler). Every pair concrete: raises :class:`InputError` at once instead."""
    if not checks:
        return out
    anys = [jnp.any(jnp.asarray(bad)) for bad, _ in checks]
    if not is_traced(*anys):
        for flag, (_, message) in zip(anys, checks):
            if bool(flag):
                raise InputError(message)
        return out
    import equinox as eqx  # here, not at import: equinox costs a command that never traces ~0.1-0.4 s to import

    flags = jnp.stack(anys)
    out = jax.tree_util.tree_map(lambda v: v if isinstance(v, jax.Array) else jnp.asarray(v), out)
    return eqx.branched_error_if(out, jnp.any(flags), jnp.argmax(flags), [m + _TRACED for _, m in checks])


def traced_finite(name: str, value: Any, unit: str = "") -> Checks:
    """Twin of :func:`validate_finite`: the run-time check of a traced value (none for a concrete one: the eager
    check covers it), for :func:`traced_checks`."""
    if not is_traced(value):
        return []
    return [(~jnp.isfinite(value), f"{name} must be a finite number{_unit_phrase(unit)}")]


def traced_positive(name: str, value: Any, unit: str = "") -> Checks:
    """Twin of :func:`validate_positive` (finite and > 0) for a traced value."""
    if not is_traced(value):
        return []
    v = jnp.asarray(value)
    return [(~(v > 0) | ~jnp.isfinite(v), f"{name} must be positive{_unit_phrase(unit)} and finite")]


def traced_nonnegative(name: str, value: Any, unit: str = "") -> Checks:
    """Twin of :func:`validate_nonnegative` (finite and >= 0) for a traced value."""
    if not is_traced(value):
        return []
    v = jnp.asarray(value)
    return [(~(v >= 0) | ~jnp.isfinite(v), f"{name} must not be negative{_unit_phrase(unit)}")]


def traced_material(C: Any, alpha: Any) -> Checks:
    """Twin of :func:`validate_material` (C > 0 in Pa, alpha >= 0, both finite) for traced values."""
    out = traced_positive("C (the Fung stiffness, shear modulus / 2)", C, "Pa")
    if is_traced(alpha):
        a = jnp.asarray(alpha)
        message = "alpha (the Fung stiffening exponent) must be >= 0 (dimensionless, 0 is neo-Hookean) and finite"
        out.append((~(a >= 0) | ~jnp.isfinite(a), message))
    return out


def traced_radii(inner_radius: Any, outer_radius: Any) -> Checks:
    """Twin of :func:`validate_radii` (0 < inner_radius < outer_radius, in m) for traced values."""
    if not is_traced(inner_radius, outer_radius):
        return []
    a, b = jnp.asarray(inner_radius), jnp.asarray(outer_radius)
    return [
        (~(a > 0) | ~jnp.isfinite(a), "inner_radius must be positive (in m) and finite"),
        (~(b > 0) | ~jnp.isfinite(b), "outer_radius must be positive (in m) and finite"),
        (~(a < b), "inner_radius must be smaller than outer_radius (the wall needs a positive thickness, in m)"),
    ]


def traced_branches(branches: Sequence[tuple[Any, Any]]) -> Checks:
    """Twin of :func:`validate_branches` (beta >= 0, tau > 0 in s) for the traced entries of checked branches."""
    out: Checks = []
    for k, (beta, tau) in enumerate(branches):
        out += traced_nonnegative(f"beta (energy factor of branch {k})", beta, "dimensionless")
        out += traced_positive(f"tau (relaxation time of branch {k})", tau, "s")
    return out


def traced_times(name: str, t: Any, *, unit: str = "s", ascending: bool = False) -> Checks:
    """Twin of :func:`validate_times` for traced times: finite, >= 0 (and ascending when asked)."""
    if not is_traced(t):
        return []
    v = jnp.asarray(t)
    out = [(~jnp.isfinite(v) | (v < 0), f"{name} must be finite and >= 0{_unit_phrase(unit)}")]
    if ascending:
        out.append((jnp.diff(v.ravel()) < 0, f"{name} must be in ascending order{_unit_phrase(unit)}"))
    return out
