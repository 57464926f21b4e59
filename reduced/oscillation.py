r"""Oscillation: the dynamic stiffness of the lumped generalized-Maxwell spheroid (JAX, SI units).

A ball held at the approach delta_0 (m) long enough for its branches to relax, then driven by a small sinusoidal
approach delta(t) = delta_0 + eps sin(omega t), omega = 2 pi f. The lumped law of :mod:`tissuemech.reduced.spheroid`,

    F = F_eq(delta) + sum_m q_m,   dq_m/dt = -q_m / tau_m + beta_m dF_eq(delta)/dt,

linearised about delta_0 (F_eq(delta) = F_eq(delta_0) + k_eq (delta - delta_0), k_eq = dF_eq/ddelta at delta_0),
has the steady response F - F_eq(delta_0) = Re[K*(omega) eps e^{i omega t}] (with eps e^{i omega t} for the
sinusoid) with the complex stiffness

    K*(omega) = k_eq (1 + sum_m beta_m i omega tau_m / (1 + i omega tau_m)),

so the storage and loss stiffnesses (N/m) are

    K'  = k_eq (1 + sum_m beta_m (omega tau_m)^2 / (1 + (omega tau_m)^2)),
    K'' = k_eq sum_m beta_m omega tau_m / (1 + (omega tau_m)^2),

K' rising from k_eq (omega -> 0, relaxed) to k_eq (1 + sum beta) (omega -> inf, instantaneous), K'' peaking near
omega = 1 / tau_m, the loss tangent K'' / K' independent of the equilibrium law. k_eq is the delta-derivative of
the equilibrium law (``equilibrium=``, as :func:`tissuemech.reduced.spheroid.force`: "fem", "hertz", a table, a
callable or a law object; ``jax.jvp``). Checked against the FE (``fem.spheroid.compress`` driven by a sampled
sinusoid, amplitude and phase of the steady force fitted): ``python -m tissuemech.compare.bench.fem_protocols``.

Broadcasts over array parameters and works under jit / vmap / grad; eager calls validate the inputs (ValueError
naming the quantity and its unit).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from tissuemech.reduced.spheroid import as_equilibrium_law
from tissuemech.reduced.validation import (
    is_traced,
    validate_branches,
    validate_material,
    validate_nonnegative,
    validate_positive,
)

__all__ = ["dynamic_stiffness", "equilibrium_stiffness"]


def equilibrium_stiffness(approach: Any, *, radius: Any, C: Any, alpha: Any, equilibrium: Any = "fem") -> jnp.ndarray:
    """k_eq = dF_eq / ddelta (N/m) of the equilibrium law at the total approach ``approach`` (m)."""
    law = as_equilibrium_law(equilibrium)
    x = jnp.asarray(approach, dtype=jnp.float64) / (2.0 * jnp.asarray(radius, dtype=jnp.float64))

    def one(xx, r, c, a):
        f = law.curve(alpha=a, radius=r, C=c)
        _, df = jax.jvp(f, (xx,), (jnp.ones_like(xx),))
        return c * r * df / 2.0  # d(C a0^2 f(x)) / d delta with x = delta / (2 a0)

    args = jnp.broadcast_arrays(x, *(jnp.asarray(v, dtype=jnp.float64) for v in (radius, C, alpha)))
    flat = [a.reshape(-1) for a in args]
    return jax.vmap(one)(*flat).reshape(args[0].shape)


def dynamic_stiffness(
    frequency: Any,
    *,
    radius: Any,
    C: Any,
    alpha: Any,
    branches: Sequence[tuple[Any, Any]] = (),
    approach: Any,
    equilibrium: Any = "fem",
) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(storage K', loss K'') in N/m of a small sinusoidal approach of ``frequency`` (Hz, >= 0, any shape) about the
    relaxed compression ``approach`` (m, 0 < approach < 2 radius) of the lumped spheroid (module docstring).

    radius (m), C (Pa), alpha (-): the ball; branches [(beta_m, tau_m [s]), ...]; equilibrium: the law of
    :func:`tissuemech.reduced.spheroid.force`. Output shape: frequency's shape broadcast with the parameters'."""
    br = validate_branches(branches)
    if not is_traced(frequency, radius, C, alpha, approach, *(v for b in br for v in b)):
        validate_nonnegative("frequency (of the oscillation)", frequency, "Hz")
        validate_positive("radius (of the ball)", radius, "m")
        validate_material(C, alpha)
        validate_positive("approach (the held compression delta_0)", approach, "m")
        if np.any(np.asarray(approach) >= 2.0 * np.asarray(radius)):
            raise ValueError("approach (the held compression delta_0, m) must be below the diameter 2 * radius")
    k = equilibrium_stiffness(approach, radius=radius, C=C, alpha=alpha, equilibrium=equilibrium)
    w = 2.0 * jnp.pi * jnp.asarray(frequency, dtype=jnp.float64)
    storage = jnp.ones_like(w)
    loss = jnp.zeros_like(w)
    for beta, tau in br:
        wt = w * jnp.asarray(tau, dtype=jnp.float64)
        b = jnp.asarray(beta, dtype=jnp.float64)
        storage = storage + b * wt**2 / (1.0 + wt**2)
        loss = loss + b * wt / (1.0 + wt**2)
    return k * storage, k * loss
