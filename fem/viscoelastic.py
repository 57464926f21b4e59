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

Viscoelastic liquids. The seed's branches are energy factors of the long-time (relaxed) Fung stiffness C,
beta_m = C_m / C, which needs C > 0. A material may instead give each branch its own stiffness,
:class:`Branch` (C_m [Pa], tau_m [s]), and then have no long-time modulus at all (C_inf = 0: a Maxwell
liquid, whose stress relaxes completely under held plates so that only a surface tension holds the shape).
The engine then scales stresses by a reference modulus that is never zero, C_ref = C_inf if C_inf > 0 (the
seed's scaling: (beta, tau) and Branch spellings give the same numbers, bit for bit for (beta, tau)) and
C_ref = sum_m C_m if C_inf = 0, and the long-time term carries the weight w = C_inf / C_ref (1 or 0):

    S = S_vol + w S_iso + sum_m Q_m,     dQ_m/dt + Q_m / tau_m = beta_m dS_iso/dt,  beta_m = C_m / C_ref,

with the algorithmic factor iso_scale = w + sum_m beta_m g_m (``algorithmic(..., long_time=w)``).
:func:`relative_branches` makes (C_ref, w, beta, tau) from (C_inf, branches).
Stresses are in the solver's units (scaled by C); Q_m, S_iso are (n_el, n_qp, 5) arrays (5-comp form).

API: ``MaxwellState(Q, S_iso)`` (immutable), ``initial_state(n_branches, shape)``,
``coefficients(beta, tau, dt) -> (decay, g)``, ``algorithmic(state, beta, tau, dt, long_time=1) -> (iso_scale,
extra_S)``, ``Branch(modulus, tau)``, ``relative_branches(C, branches) -> RelativeBranches``,
``update(state, beta, tau, dt, S_iso_new) -> MaxwellState``, ``replay(state, beta, tau, steps)`` (the update
run over a sequence of steps), ``branch_stress(state)`` (sum_m Q_m).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from tissuemech.reduced.validation import validate_branches, validate_positive

__all__ = [
    "MaxwellState",
    "initial_state",
    "coefficients",
    "algorithmic",
    "update",
    "replay",
    "branch_stress",
    "Branch",
    "RelativeBranches",
    "relative_branches",
]


class Branch(NamedTuple):
    """A Maxwell branch given by its own Fung stiffness ``modulus`` C_m (Pa, > 0) and relaxation time ``tau``
    (s, > 0); E_m = 6 C_m is its small-strain Young's modulus and eta_m = E_m tau_m / 3 its viscosity."""

    modulus: float
    tau: float


class RelativeBranches(NamedTuple):
    """The branches in the engine's units: stresses scaled by ``reference`` (Pa, > 0), the long-time term's
    weight ``long_time`` = C_inf / reference (1 for a solid, 0 for a liquid), ``beta`` = C_m / reference and
    ``tau`` (s) per branch (arrays)."""

    reference: float
    long_time: float
    beta: np.ndarray
    tau: np.ndarray


def relative_branches(C: float, branches) -> RelativeBranches:
    """(C_ref, w, beta, tau) of a material with the long-time Fung stiffness ``C`` (Pa, >= 0) and ``branches``,
    each ``Branch(modulus [Pa], tau [s])`` or the seed's ``(beta, tau)`` (an energy factor of C: only with C > 0).

    C > 0: C_ref = C, w = 1, beta_m = C_m / C for a ``Branch`` (a solid; the seed's scaling). C = 0 (a Maxwell
    liquid): every branch a ``Branch``, at least one, C_ref = sum_m C_m, w = 0, beta_m = C_m / C_ref (sum 1).
    Raises ValueError naming the quantity and its unit (negative or non-finite numbers, C = 0 without moduli,
    a factor with C = 0)."""
    C = float(C)
    if not (np.isfinite(C) and C >= 0):
        raise ValueError(f"C (the long-time Fung stiffness C_inf) must be finite and >= 0 Pa, got {C!r}")
    branches = () if branches is None else tuple(branches)
    factors = iter(validate_branches([b for b in branches if not isinstance(b, Branch)]))  # the seed's spelling
    beta, tau = [], []
    for k, b in enumerate(branches):
        if isinstance(b, Branch):
            validate_positive(f"modulus (the Fung stiffness C_m of branch {k})", b.modulus, "Pa")
            validate_positive(f"tau (relaxation time of branch {k})", b.tau, "s")
            if C > 0:
                beta.append(float(b.modulus) / C)
            else:
                beta.append(float(b.modulus))  # divided by C_ref below
            tau.append(float(b.tau))
            continue
        if C == 0:
            raise ValueError(
                f"branch {k} is an energy factor (beta, tau) of the long-time stiffness C, which is 0 Pa here: give "
                "a liquid's branches by their moduli, Branch(modulus=C_m [Pa], tau=tau_m [s])"
            )
        f, t = next(factors)
        beta.append(float(f))
        tau.append(float(t))
    if C > 0:
        return RelativeBranches(C, 1.0, np.array(beta), np.array(tau))
    if not beta:
        raise ValueError(
            "C = 0 Pa (no long-time modulus: a liquid) needs at least one Maxwell branch, "
            "Branch(modulus=C_m [Pa], tau=tau_m [s]): a material with no modulus at all has no shape"
        )
    ref = float(sum(beta))
    return RelativeBranches(ref, 0.0, np.array(beta) / ref, np.array(tau))


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


def algorithmic(state: MaxwellState, beta: np.ndarray, tau: np.ndarray, dt: float, long_time: float = 1.0):
    """(iso_scale, extra_S) of the step: S = S_vol + iso_scale S_iso^{n+1} + extra_S, iso_scale = long_time +
    sum_m beta_m g_m (``long_time``: the weight of the long-time term, 1 for a solid, 0 for a liquid)."""
    beta = np.asarray(beta, float)
    if beta.size == 0:
        return long_time, None
    decay, g = coefficients(beta, tau, dt)
    bg = beta * g
    # einsum, not tensordot: tensordot over the short branch axis took ~10x longer (30 ms vs 3 ms per call on the
    # default mesh, measured while writing the FE sensitivities)
    extra = np.einsum("m,m...->...", decay, state.Q) - bg.sum() * state.S_iso
    return long_time + float(bg.sum()), extra


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
