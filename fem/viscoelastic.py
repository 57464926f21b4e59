r"""Generalized Maxwell branches on the isochoric stress (finite strain, Simo 1987 / Holzapfel 2000).

Second Piola-Kirchhoff stress S = S_vol + S_iso + sum_m Q_m with, per branch m (energy factor
beta_m >= 0, dimensionless; relaxation time tau_m > 0, s),

    dQ_m/dt + Q_m / tau_m = beta_m dS_iso/dt.

Time step t_n -> t_{n+1} = t_n + dt, h_m = dt / tau_m, g_m = (1 - e^{-h_m}) / h_m. The update

    Q_m^{n+1} = e^{-h_m} Q_m^n + beta_m g_m (S_iso^{n+1} - S_iso^n)

is exact when S_iso varies linearly in time over the step (and for any dt when S_iso is constant:
the hold of a relaxation test). Inserted in S it gives the algorithmic stress

    S^{n+1} = S_vol + (1 + sum_m beta_m g_m) S_iso^{n+1} + sum_m (e^{-h_m} Q_m^n - beta_m g_m S_iso^n),

i.e. ``fem.forms.Assembler.internal(x, mat, extra_S=..., iso_scale=...)`` with the two terms from
:func:`algorithmic` (the second is fixed during the step, so the tangent is exact). beta = 0 is elastic.
Stresses are in the solver's units (scaled by C); Q_m, S_iso are (n_el, n_qp, 5) arrays (5-comp form).

API: ``MaxwellState(Q, S_iso)`` (immutable), ``initial_state(n_branches, shape)``,
``coefficients(beta, tau, dt) -> (decay, g)``, ``algorithmic(state, beta, tau, dt) -> (iso_scale, extra_S)``,
``update(state, beta, tau, dt, S_iso_new) -> MaxwellState``, ``replay(state, beta, tau, steps)`` (the update
run over a sequence of steps), ``branch_stress(state)`` (sum_m Q_m).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["MaxwellState", "initial_state", "coefficients", "algorithmic", "update", "replay", "branch_stress"]


class MaxwellState(NamedTuple):
    """Internal variables after a converged step: Q (n_branches, n_el, n_qp, 5) and S_iso^n."""

    Q: np.ndarray
    S_iso: np.ndarray


def initial_state(n_branches: int, shape: tuple) -> MaxwellState:
    """Undisturbed state (no branch stress, S_iso = 0 of the reference configuration)."""
    return MaxwellState(np.zeros((n_branches,) + tuple(shape)), np.zeros(tuple(shape)))


def coefficients(beta: np.ndarray, tau: np.ndarray, dt: float):
    """decay_m = e^{-dt/tau_m} and g_m = (1 - e^{-h})/h (-> 1 for h -> 0, to round-off)."""
    if not (dt > 0 and np.isfinite(dt)):
        raise ValueError(f"the time step must be positive and finite, got {dt} s")
    h = dt / np.asarray(tau, float)
    decay = np.exp(-h)
    g = np.where(h < 1e-8, 1.0 - h / 2, -np.expm1(-h) / np.where(h < 1e-8, 1.0, h))
    return decay, g


def algorithmic(state: MaxwellState, beta: np.ndarray, tau: np.ndarray, dt: float):
    """(iso_scale, extra_S) of the step: S = S_vol + iso_scale S_iso^{n+1} + extra_S."""
    beta = np.asarray(beta, float)
    if beta.size == 0:
        return 1.0, None
    decay, g = coefficients(beta, tau, dt)
    bg = beta * g
    # einsum, not tensordot: tensordot over the short branch axis took ~10x longer (30 ms vs 3 ms per call on the
    # default mesh, measured while writing the FE sensitivities)
    extra = np.einsum("m,m...->...", decay, state.Q) - bg.sum() * state.S_iso
    return 1.0 + float(bg.sum()), extra


def update(state: MaxwellState, beta: np.ndarray, tau: np.ndarray, dt: float, S_iso_new: np.ndarray) -> MaxwellState:
    """Branch stresses at t_{n+1} from the converged S_iso^{n+1}."""
    beta = np.asarray(beta, float)
    if beta.size == 0:
        return MaxwellState(state.Q, S_iso_new)
    decay, g = coefficients(beta, tau, dt)
    dS = S_iso_new - state.S_iso
    Q = decay[:, None, None, None] * state.Q + (beta * g)[:, None, None, None] * dS[None]
    return MaxwellState(Q, S_iso_new)


def replay(state: MaxwellState, beta: np.ndarray, tau: np.ndarray, steps) -> MaxwellState:
    """The history after the steps ``steps`` (an iterable of (dt [s], S_iso^{n+1})) from ``state``: :func:`update`
    step by step. The history at a material point is a function of the stress history there only, so it can be
    rebuilt at any points from the deformation of every past step (``fem.contact.replayed_history``)."""
    for dt, S_new in steps:
        state = update(state, beta, tau, dt, S_new)
    return state


def branch_stress(state: MaxwellState) -> np.ndarray:
    """sum_m Q_m (n_el, n_qp, 5)."""
    return state.Q.sum(axis=0)
