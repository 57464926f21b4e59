r"""Viscoelastic thick shell: inflation history a(t) of an incompressible Fung sphere with
generalized-Maxwell branches, under an internal pressure history p(t).

Model (exact under incompressibility and spherical symmetry; the S-based form of physics.md)
-----------------------------------------------------------------------------------------------
A material point at reference radius R has hoop stretch l(R, t), with
l^3 = 1 + (lambda_a^3 - 1) (A/R)^3, and F = diag(l^-2, l, l) in the fixed (r, theta, phi) axes, so
the principal axes never rotate and every tensor below is diagonal. The isochoric second
Piola-Kirchhoff stress S_iso = 2 W'(I1) (I - I1/3 C^-1), C = F^T F, has the components

    S_rr = 2 W'(I1) (1 - I1 l^4 / 3)   = -(4/3) W'(I1) expm1(6 log l),
    S_tt = 2 W'(I1) (1 - I1 l^-2 / 3)  = -(2/3) W'(I1) expm1(-6 log l),

and every branch m (energy factor beta_m, relaxation time tau_m) carries an internal stress
Q_m = diag(Q_rr, Q_tt, Q_tt) with (Simo 1987 / Holzapfel 2000, physics.md)

    dQ_m/dt + Q_m / tau_m = beta_m dS_iso/dt      (componentwise; Q_m = 0 at rest).

The Cauchy stress sigma = F (S_iso + sum Q_m - p_h C^-1) F^T gives, with the hydrostatic
p_h cancelling,

    sigma_theta - sigma_r = 2 W'(I1) (l^2 - l^-4) + sum_m (l^2 Q_tt,m - l^-4 Q_rr,m).

Radial equilibrium d sigma_r/dr = 2 (sigma_theta - sigma_r)/r with sigma_r(b) = 0 and
dr/r = d(log R) / l^3 gives the pressure balance (an algebraic constraint)

    p(t) = P(lambda_a, Q) = int_{log A}^{log B} 2 (sigma_theta - sigma_r) / l^3 d(log R).

This is not the "Cauchy-stress lumped" Maxwell form (a relaxing (sigma_theta - sigma_r)); the two
differ at finite strain through the push-forward factors l^2, l^-4 (which change while Q relaxes).
For an instantaneous load the internal stresses jump to Q_m = beta_m S_iso, i.e. the shell
responds as an elastic one with C_inst = (1 + sum beta_m) C; for t >> tau it relaxes to the
elastic curve with C (reduced.blastula).

Numerics
--------
Internal variables live at ``N_NODES`` Gauss-Legendre points in u = log R through the wall (the
pressure integrand is smooth in u; 16 points give the elastic pressure to ~1e-13). The index-1 DAE
(states Q, algebraic lambda_a) is reduced to an ODE for y = (lambda_a, Q) by differentiating the
constraint: dp/dt = dP/dlambda_a dlambda_a/dt + sum dP/dQ . dQ/dt with dQ/dt = -Q/tau +
beta dS_iso/dlambda_a dlambda_a/dt, so

    dlambda_a/dt = [dp/dt + sum_m dP/dQ_m . Q_m/tau_m] / [dP/dlambda_a + sum_m beta_m dP/dQ_m . dS_iso/dlambda_a],

the denominator being the instantaneous tangent stiffness (zero at the instantaneous limit point:
the shell bursts). The partial derivatives come from jax.jvp of P, so nothing is hand-derived twice.
The relaxation times may be much shorter than the history (stiff): the L-stable ESDIRK solver
``diffrax.Kvaerno5`` with a PID step-size controller (rtol = atol = 1e-10 by default) handles both
regimes; the ramp end is passed as a jump time. Stresses are scaled by C inside the solver.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from tissuemech.reduced import blastula
from tissuemech.reduced.material import dW_dI1
from tissuemech.reduced.validation import (
    is_traced,
    traced_branches,
    traced_checks,
    traced_finite,
    traced_material,
    traced_positive,
    traced_radii,
    validate_branches,
    validate_finite,
    validate_int,
    validate_material,
    validate_positive,
    validate_radii,
    validate_times,
)

__all__ = ["inflate", "Inflation", "N_NODES"]

Array = Any
N_NODES = 16
_XN, _WN = np.polynomial.legendre.leggauss(N_NODES)


class Inflation(NamedTuple):
    """Inflation history at the requested times ``t`` (s): inner stretch a/A and outer stretch b/B."""

    t: Array
    inner_stretch: Array
    outer_stretch: Array


def _node_stretch(la, rho):
    """Hoop stretch log l at nodes with rho = (A/R)^3: l^3 = 1 + (lambda_a^3 - 1) rho (no cancellation)."""
    return jnp.log1p(jnp.expm1(3.0 * jnp.log(la)) * rho) / 3.0


def _s_iso(la, rho, alpha):
    """(S_rr, S_tt) / C of the isochoric 2nd Piola-Kirchhoff stress at the nodes, and log l."""
    sl = _node_stretch(la, rho)
    l2 = jnp.exp(2.0 * sl)
    I1 = 2.0 * l2 + jnp.exp(-4.0 * sl)
    w1 = dW_dI1(I1, 1.0, alpha)
    return -(4.0 / 3.0) * w1 * jnp.expm1(6.0 * sl), -(2.0 / 3.0) * w1 * jnp.expm1(-6.0 * sl)


def _pressure_over_C(la, q_rr, q_tt, rho, wu, alpha):
    """P(lambda_a, Q)/C = sum_k w_k 2 (sigma_theta - sigma_r)_k / l_k^3 (Gauss in u = log R)."""
    sl = _node_stretch(la, rho)
    l2 = jnp.exp(2.0 * sl)
    lm4 = jnp.exp(-4.0 * sl)
    I1 = 2.0 * l2 + lm4
    elastic = 2.0 * dW_dI1(I1, 1.0, alpha) * (l2 - lm4)
    viscous = jnp.sum(l2 * q_tt - lm4 * q_rr, axis=0)
    return jnp.sum(wu * 2.0 * (elastic + viscous) * jnp.exp(-3.0 * sl))


def _geometry(inner_radius, outer_radius):
    A = jnp.asarray(inner_radius, dtype=jnp.float64)
    B = jnp.asarray(outer_radius, dtype=jnp.float64)
    uA, uB = jnp.log(A), jnp.log(B)
    u = 0.5 * (uA + uB) + 0.5 * (uB - uA) * jnp.asarray(_XN)
    wu = 0.5 * (uB - uA) * jnp.asarray(_WN)
    rho = jnp.exp(3.0 * (uA - u))  # (A/R)^3
    return rho, wu


class _Ramp(eqx.Module):
    """p(t) = p0 min(t / ramp_time, 1) in Pa (ramp_time = 0: a step at t = 0)."""

    p0: Array
    ramp_time: Array

    def __call__(self, t):
        safe = jnp.where(self.ramp_time > 0, self.ramp_time, 1.0)
        return jnp.where(self.ramp_time > 0, self.p0 * jnp.minimum(t / safe, 1.0), self.p0 + 0.0 * t)


def _rates(t, y, args):
    """(d y/dt, instantaneous tangent dP/dlambda_a / C) of the constraint-differentiated DAE."""
    p_fun, C, rho, wu, alpha, beta, tau = args
    la, q_rr, q_tt = y
    P = lambda la_, qr, qt: _pressure_over_C(la_, qr, qt, rho, wu, alpha)
    _, dS = jax.jvp(lambda la_: _s_iso(la_, rho, alpha), (la,), (jnp.ones_like(la),))
    relax_rr = -q_rr / tau[:, None]
    relax_tt = -q_tt / tau[:, None]
    zero_q = jnp.zeros_like(q_rr)
    _, dP_la = jax.jvp(P, (la, q_rr, q_tt), (jnp.ones_like(la), zero_q, zero_q))
    _, dP_relax = jax.jvp(P, (la, q_rr, q_tt), (jnp.zeros_like(la), relax_rr, relax_tt))
    dq_rr_dla = beta[:, None] * dS[0][None, :]
    dq_tt_dla = beta[:, None] * dS[1][None, :]
    _, dP_inst = jax.jvp(P, (la, q_rr, q_tt), (jnp.zeros_like(la), dq_rr_dla, dq_tt_dla))
    _, dp_dt = jax.jvp(p_fun, (t,), (jnp.ones_like(t),))
    tangent = dP_la + dP_inst
    dla = (dp_dt / C - dP_relax) / tangent
    return (dla, relax_rr + dq_rr_dla * dla, relax_tt + dq_tt_dla * dla), tangent


def _rhs(t, y, args):
    return _rates(t, y, args)[0]


def _burst(t, y, args, **kwargs):
    """Event function: the instantaneous tangent stiffness falls to 1e-3 of its unloaded value
    8 (1 + sum beta)(1 - (A/B)^3) C; at zero the shell passes its limit point and bursts."""
    ref = 1e-3 * 8.0 * (1.0 + jnp.sum(args[5])) * _wall_factor(args)
    return _rates(t, y, args)[1] - ref


def _wall_factor(args):
    """1 - (A/B)^3 from the node data: the small-strain tangent is 8 (1 + sum beta)(1 - (A/B)^3)."""
    wu = args[3]
    log_B_over_A = jnp.sum(wu)  # the u-weights sum to log(B/A)
    return -jnp.expm1(-3.0 * log_B_over_A)


def inflate(
    t: Array,
    *,
    pressure: float | Callable[[Array], Array],
    inner_radius: float,
    outer_radius: float,
    C: float | Array,
    alpha: float | Array,
    branches: Sequence[tuple[float, float]] | None,
    ramp_time: float | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_steps: int = 100_000,
) -> Inflation:
    r"""Inflation history of the viscoelastic shell (see the module docstring for the model).

    t             output times in s (>= 0, ascending); the shell is at rest (unloaded) before t = 0.
    pressure      a number p0 (Pa): ramped linearly from 0 to p0 over ``ramp_time`` s and then held
                  (``ramp_time=None``: a step applied at t = 0, i.e. the instantaneous response first);
                  or a JAX-traceable function p(t) in Pa (use jax.numpy); p(0) != 0 acts as a step at 0.
    inner_radius, outer_radius   A < B in m;  C > 0 in Pa;  alpha >= 0.
    branches      sequence of (beta_m, tau_m): energy factor (>= 0) and relaxation time (s, > 0);
                  None or () is purely elastic.
    Returns ``Inflation(t, inner_stretch, outer_stretch)``. Raises RuntimeError (with the time
    reached and a hint) when the integration fails, e.g. when the shell creeps past its limit point;
    ValueError (naming the quantity and unit) for bad inputs, e.g. a pressure history p(t) that is not
    finite at some time. Under jit/vmap/grad (traced inputs) the checks of the radii, C, alpha, the branches,
    ramp_time, the pressure and a pressure history raise at run time (``equinox.error_if``, the eager message
    without the value); a failed solve, a shell that bursts (at once or later), or output times that are
    negative, non-finite or not ascending give NaN stretches (the NaN flag).
    """
    validate_radii(inner_radius, outer_radius)
    validate_material(C, alpha)
    br = validate_branches(branches)
    validate_positive("rtol (relative tolerance of the ODE solver)", rtol, "dimensionless")
    validate_positive("atol (absolute tolerance of the ODE solver)", atol, "dimensionless")
    validate_int("max_steps (of the ODE solver)", max_steps, minimum=1)
    if not is_traced(t):
        tn = validate_times("t (output times, t = 0 is when loading starts)", t, unit="s", ascending=True)
        if tn is not None and tn.ndim != 1:
            raise ValueError(f"t (output times) must be a 1-D array of times in s; got shape {tn.shape}")
    t = jnp.asarray(t, dtype=jnp.float64)
    if ramp_time is not None:
        validate_positive("ramp_time", ramp_time, "s")
    # traced values: the same checks at run time (equinox.error_if on the result; concrete ones were checked above)
    checks = [] if ramp_time is None else traced_positive("ramp_time", ramp_time, "s")
    checks += traced_radii(inner_radius, outer_radius) + traced_material(C, alpha) + traced_branches(br)
    if callable(pressure):
        p_fun = pressure
        jumps = None
        if not is_traced(t) and not _closes_over_tracers(pressure):
            _check_pressure_history(pressure, np.asarray(t))
        else:
            checks += _traced_pressure_history(pressure, t)
    else:
        validate_finite("pressure", pressure, "Pa")
        if not is_traced(pressure) and np.ndim(pressure) != 0:
            raise ValueError(
                f"pressure must be a single number in Pa (or a callable p(t)); got shape {np.shape(pressure)}"
            )
        tr = 0.0 if ramp_time is None else ramp_time
        checks += traced_finite("pressure", pressure, "Pa")
        p_fun = _Ramp(jnp.asarray(pressure, dtype=jnp.float64), jnp.asarray(tr, dtype=jnp.float64))
        jumps = None if ramp_time is None else jnp.asarray([tr], dtype=jnp.float64)
    C = jnp.asarray(C, dtype=jnp.float64)
    alpha = jnp.asarray(alpha, dtype=jnp.float64)
    beta = jnp.asarray([b for b, _ in br] or [0.0], dtype=jnp.float64)
    tau = jnp.asarray([s for _, s in br] or [1.0], dtype=jnp.float64)
    la, lb = _solve(t, p_fun, jumps, inner_radius, outer_radius, C, alpha, beta, tau, rtol, atol, max_steps)
    la, lb = traced_checks((la, lb), checks)
    return Inflation(t, la, lb)


def _closes_over_tracers(history: Callable) -> bool:
    """Whether a pressure history returns traced values at t = 0 (it closes over the user's traced values)."""
    try:
        return is_traced(history(jnp.zeros(())))
    except Exception:  # the eager check reports it with its message
        return False


def _traced_pressure_history(pressure: Callable, t: Array) -> list[tuple[Any, str]]:
    """The run-time twin of :func:`_check_pressure_history`: p(t) finite at the output times and 257 even times up
    to the last."""
    tt = jnp.ravel(t)
    probe = jnp.concatenate([tt, jnp.linspace(0.0, 1.0, 257) * jnp.max(tt)])
    p = jax.vmap(pressure)(probe)
    return [(~jnp.isfinite(p), "pressure history p(t) must be finite (in Pa)")]


def _check_pressure_history(pressure: Callable, t: np.ndarray) -> None:
    """Eager check of a pressure history p(t): finite numbers (Pa) at the output times and between them."""
    probe = np.union1d(t.ravel(), np.linspace(0.0, float(np.max(t)), 257))
    try:
        p = np.asarray(jax.vmap(pressure)(jnp.asarray(probe)), dtype=float)
    except Exception as exc:
        raise ValueError(f"pressure (a callable p(t) in Pa) failed when called on the output times: {exc}") from None
    if p.shape != probe.shape:
        raise ValueError(f"pressure (a callable p(t) in Pa) must return one number per time; got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        bad = probe[~np.isfinite(p)][0]
        raise ValueError(
            f"pressure history p(t) must be finite (in Pa); it is {p[~np.isfinite(p)][0]} at t = {bad:g} s"
        )


def _solve(t, p_fun, jumps, inner_radius, outer_radius, C, alpha, beta, tau, rtol, atol, max_steps):
    import diffrax

    rho, wu = _geometry(inner_radius, outer_radius)
    # state at t = 0+: instantaneous (glassy) response to p(0), C_inst = (1 + sum beta) C
    C_inst = C * (1.0 + jnp.sum(beta))
    p_start = p_fun(jnp.asarray(0.0))
    la0, ok0 = blastula.inner_stretch_solve(
        p_start, inner_radius=inner_radius, outer_radius=outer_radius, C=C_inst, alpha=alpha
    )
    if not is_traced(la0) and not bool(ok0):
        raise ValueError(
            f"the initial pressure {float(p_start):g} Pa exceeds what the shell can hold even instantaneously "
            f"(C_inst = {float(C_inst):g} Pa): it bursts at once; ramp the pressure up or lower it"
        )
    s_rr, s_tt = _s_iso(la0, rho, alpha)
    y0 = (la0, beta[:, None] * s_rr[None, :], beta[:, None] * s_tt[None, :])
    controller = diffrax.PIDController(
        rtol=jnp.asarray(rtol, dtype=jnp.float64), atol=jnp.asarray(atol, dtype=jnp.float64)
    )
    if jumps is not None:
        controller = diffrax.ClipStepSizeController(controller, jump_ts=jumps)
    # inside jit the times cannot be checked: a non-monotonic, negative or non-finite t would make
    # diffrax fail with an XLA callback error; integrate over a monotone copy and flag the result NaN
    t_bad = jnp.any(~jnp.isfinite(t)) | jnp.any(t < 0) | jnp.any(jnp.diff(t) < 0)
    t = jax.lax.cummax(jnp.clip(jnp.where(jnp.isfinite(t), t, 0.0), 0.0, None))
    t1 = t[-1]
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(_rhs),
        diffrax.Kvaerno5(),
        t0=0.0,
        t1=jnp.maximum(t1, 1e-300),
        dt0=None,
        y0=y0,
        args=(p_fun, C, rho, wu, alpha, beta, tau),
        saveat=diffrax.SaveAt(ts=t, t1=True),
        stepsize_controller=controller,
        event=diffrax.Event(_burst),
        max_steps=max_steps,
        throw=False,
    )
    la = sol.ys[0][:-1]
    burst = sol.result == diffrax.RESULTS.event_occurred
    if not is_traced(la):
        if bool(burst):
            ts, ys = np.asarray(sol.ts), np.asarray(sol.ys[0])
            i = int(np.flatnonzero(np.isfinite(ts))[-1])  # diffrax saves the event time after the last output
            raise RuntimeError(
                f"the shell bursts at t = {ts[i]:.6g} s (inner stretch {ys[i]:.6g}): "
                "its instantaneous stiffness has dropped to zero, so under this pressure history it "
                "creeps past its limit point and inflates without bound. Hint: compare the held "
                "pressure with reduced.blastula.limit_point for the relaxed material (C) and the "
                "instantaneous one ((1 + sum beta) C)."
            )
        if sol.result != diffrax.RESULTS.successful or not np.all(np.isfinite(np.asarray(la))):
            good = np.asarray(la)[np.isfinite(np.asarray(la))]
            last = f"; last finite inner stretch {good[-1]:.6g}" if good.size else ""
            raise RuntimeError(
                f"viscoelastic inflation failed before t = {float(t1):g} s ({sol.result}){last}. "
                "Hint: tighten or loosen rtol/atol, raise max_steps, or check that the pressure "
                "function is smooth and JAX-traceable."
            )
    else:
        la = jnp.where((sol.result == diffrax.RESULTS.successful) & ~t_bad, la, jnp.nan)
    lb = (
        blastula.outer_stretch(la, inner_radius=inner_radius, outer_radius=outer_radius)
        if not is_traced(la)
        else jnp.exp(
            jnp.log1p(jnp.expm1(3.0 * jnp.log(la)) * (jnp.asarray(inner_radius) / jnp.asarray(outer_radius)) ** 3) / 3.0
        )
    )
    return la, lb
