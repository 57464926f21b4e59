r"""Quasi-static time stepping for rate-dependent (viscoelastic) FE scenes.

Inertia is neglected: with tissue density rho ~ 1e3 kg/m^3 and plate speeds v ~ 50 um / 0.2 s
= 2.5e-4 m/s, the inertial stress rho v^2 ~ 1e3 * (2.5e-4)^2 ~ 6e-5 Pa is ~1e-6 of the 10-1000 Pa
stresses (and the elastic wave transit time a0 sqrt(rho/C) ~ 1 ms is far below the 0.2 s ramp),
so every step is an equilibrium state; time enters only through the Maxwell internal variables
(``fem.viscoelastic``) and the prescribed history delta(t).

Schedule: :func:`ramp_hold_schedule` puts ``n_ramp`` equal steps on the loading ramp (where the
response changes fastest) and ``n_hold`` geometrically growing steps through the hold (the exact
exponential update allows steps far above tau), plus any required output times.
:func:`march` advances through the schedule; a step whose solve raises ``NewtonError`` is halved
(up to ``max_cuts`` times), then the step grows again by ``growth`` per converged sub-step until
the scheduled time is reached. ``too_large(t0, t1)`` (optional) rejects a step before it is tried
(e.g. a cap on the plate displacement per step for arbitrary histories delta(t)).

API: ``ramp_hold_schedule(ramp_time, end_time, *, n_ramp=6, n_hold=20, first_hold=None,
breakpoints=())``, ``march(step, state0, times, *, t0=0.0, max_cuts=10, growth=1.5, too_large=None)``
with ``step(t_old, state_old, t_new, previous) -> (state_new, newton_iterations)`` (``previous`` =
``TimedState(time, state)`` of the step before t_old, or None: for predictors). Returns a list of
``Step(time, state, newton_iterations, wall_time)`` (``fem.stepping``), one per converged (sub)step, or with
``substeps=False`` one per requested time. Times in s.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from typing import TypeVar

import numpy as np

from tissuemech.fem.newton import NewtonError
from tissuemech.fem.stepping import Step, TimedState

log = logging.getLogger(__name__)

S = TypeVar("S")

__all__ = ["Step", "TimedState", "ramp_hold_schedule", "march"]  # Step, TimedState: from fem.stepping


def ramp_hold_schedule(
    ramp_time: float,
    end_time: float,
    *,
    n_ramp: int = 6,
    n_hold: int = 20,
    first_hold: float | None = None,
    breakpoints: Sequence[float] = (),
) -> np.ndarray:
    """Step end times (s): n_ramp equal steps to ramp_time, then n_hold geometric steps to end_time.

    ``first_hold`` is the first hold step (default ramp_time / 2, so the start of the relaxation is
    resolved); ``breakpoints`` (output times) are merged in. The result is sorted, unique and > 0.
    """
    if not (ramp_time > 0 and np.isfinite(ramp_time)):
        raise ValueError(f"ramp_time must be positive (s), got {ramp_time}")
    if not (end_time >= ramp_time and np.isfinite(end_time)):
        raise ValueError(f"end_time must be finite and >= ramp_time = {ramp_time} s, got {end_time}")
    if n_ramp < 1 or n_hold < 1:
        raise ValueError("need at least one ramp step and one hold step")
    t = list(np.linspace(0.0, ramp_time, n_ramp + 1)[1:])
    span = end_time - ramp_time
    if span > 1e-12 * end_time:
        h0 = min(ramp_time / 2 if first_hold is None else float(first_hold), span)
        if n_hold == 1 or h0 >= span:
            t += [end_time]
        else:
            # geometric steps h0 q^k (k < n_hold) summing to span: solve for q by bisection
            # the largest step h0 q^(n_hold - 1) < span bounds q (and keeps q^n_hold finite)
            lo, hi = 1.0, min(1e3, (span / h0) ** (1.0 / (n_hold - 1)))
            f = lambda q: h0 * (q**n_hold - 1) / (q - 1) - span if q > 1 else h0 * n_hold - span
            if f(1.0 + 1e-12) >= 0:  # even equal steps overshoot: use equal steps
                t += list(ramp_time + np.linspace(0, span, n_hold + 1)[1:])
            else:
                for _ in range(200):
                    mid = 0.5 * (lo + hi)
                    lo, hi = (mid, hi) if f(mid) < 0 else (lo, mid)
                q = 0.5 * (lo + hi)
                steps = h0 * q ** np.arange(n_hold)
                t += list(ramp_time + np.cumsum(steps) * span / steps.sum())
    ts = np.unique(np.array(t + [float(b) for b in breakpoints if 0 < b <= end_time]))
    keep = np.r_[True, np.diff(ts) > 1e-12 * max(end_time, 1.0)]
    ts = ts[keep]
    ts[-1] = max(ts[-1], end_time)
    return ts


def march(
    step: Callable[[float, S, float, TimedState[S] | None], tuple[S, int]],
    state0: S,
    times: Sequence[float] | np.ndarray,
    *,
    t0: float = 0.0,
    max_cuts: int = 10,
    growth: float = 1.5,
    too_large: Callable[[float, float], bool] | None = None,
    substeps: bool = True,
) -> list[Step[S]]:
    """Advance from (t0, state0) through every time in ``times`` (s, increasing), halving a failed step.

    ``step(t_old, state_old, t_new, previous) -> (state_new, newton_iterations)`` raises ``NewtonError``
    when it fails; ``previous`` is the ``TimedState`` before t_old (None at the start). Returns one
    ``Step(time, state, newton_iterations, wall_time)`` per converged (sub)step. Raises ``NewtonError``
    (naming the step) after ``max_cuts`` cuts, ValueError for times that do not increase.
    ``substeps=False``: one ``Step`` per requested time only (its newton_iterations and wall_time summed
    over its sub-steps), for callers whose cuts are internal (static load paths).
    """
    out: list[Step[S]] = []
    t_c, s_c = float(t0), state0
    prev: TimedState[S] | None = None
    for target in np.asarray(times, float):
        if target <= t_c:
            raise ValueError(f"step times must increase: {target} s after {t_c} s")
        dt = target - t_c
        cuts = 0
        last_res: list = []
        its_sum, wall_sum = 0, 0.0
        while t_c < target - 1e-12 * max(abs(target), 1.0):
            t_new = min(target, t_c + dt)
            if target - t_new < 1e-9 * dt:
                t_new = target
            if too_large is not None and cuts < max_cuts and too_large(t_c, t_new):
                dt *= 0.5
                cuts += 1
                continue
            w0 = time.perf_counter()
            try:
                s_new, its = step(t_c, s_c, t_new, prev)
            except NewtonError as err:
                cuts += 1
                last_res = err.residuals or last_res
                if cuts > max_cuts:
                    # the step's own label (a time in s, or a load such as "delta = 50 um" for static runs)
                    where = err.load if isinstance(err.load, str) and err.load else f"t = {t_new:.6g} s"
                    raise NewtonError(
                        f"the step to {where} failed after {max_cuts} cuts ({err.args[0].split(' (load level')[0]})",
                        load=where,
                        residuals=err.residuals or last_res,
                        hint=err.hint,
                    ) from None
                dt *= 0.5
                log.debug(
                    "time step %.6g s -> %.6g s failed (%s); cut back to dt = %.3g s", t_c, t_new, err.args[0], dt
                )
                continue
            wall = time.perf_counter() - w0
            its_sum, wall_sum = its_sum + int(its), wall_sum + wall
            if substeps:
                out.append(Step(t_new, s_new, int(its), wall))
            elif t_new == target:
                out.append(Step(t_new, s_new, its_sum, wall_sum))
            prev = TimedState(t_c, s_c)
            t_c, s_c = t_new, s_new
            log.debug("converged t = %.6g s in %d iterations (%.3g s)", t_new, its, wall)
            if cuts:
                dt *= growth
    return out
