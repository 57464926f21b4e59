r"""Loading protocols of the FE scenes: measured histories and their step times, force control by an outer iteration.

:class:`Record` is a measured history (an approach in m or a force in N against time in s): linear between the
samples, held after the last. :func:`record_schedule` gives the step times of a march through it: the samples'
kinks that matter (:func:`kinks`: the Douglas-Peucker simplification of the record to ``tol`` in its value, so a
dense record of 10^5 samples of a few straight pieces gives those pieces' ends, not 10^5 steps), steps that move
the value by at most ``cap`` (the ramp's step), and steps growing geometrically from ``first`` after every kink
(the transients of the Maxwell branches start there). :func:`force_controlled` wraps a scene's one-step function
``step_to(t0, old, t1, prev, d1)`` (the step with the plate at the scaled approach d1, or None: the body without
contact) into a step under a prescribed plate force: a safeguarded secant iteration on d1 (Illinois regula falsi
once bracketed) to ``FORCE_TOL`` of the force. Used by ``fem.spheroid.compress``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import numpy as np

from tissuemech.fem.newton import NewtonError
from tissuemech.fem.stepping import TimedState

log = logging.getLogger(__name__)

__all__ = ["Record", "kinks", "record_schedule", "force_controlled", "FORCE_TOL", "KINK_TOL", "MAX_KINKS"]

S = TypeVar("S")

FORCE_TOL = 1e-7  # |F - F_target| / F_target of a force-controlled step (the fitted-edge force is exact to ~5e-8)
FORCE_MAX_ITER = 20
KINK_TOL = 1e-3  # the kinks that matter: the record's deviation from the steps' straight pieces, in units of cap
MAX_KINKS = 400  # more kinks (a noisy record): the tolerance doubles until they are fewer (a logged warning)


class Record:
    """A measured history value(t): ``times`` (s, from 0, strictly increasing, >= 2 samples) and ``values`` (finite,
    >= 0; ``name`` and ``unit`` name them in errors), linear between the samples and held after the last. Calling it
    at a time t (s) gives the value (float)."""

    def __init__(self, times: Any, values: Any, name: str, unit: str):
        t = np.asarray(times, dtype=float)
        v = np.asarray(values, dtype=float)
        what = f"{name} = (times, {name}s)"
        if t.ndim != 1 or v.shape != t.shape or t.size < 2:
            raise ValueError(
                f"{what} needs two 1-D arrays of equal length >= 2 (s and {unit}); got shapes {t.shape} and {v.shape}"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
            raise ValueError(f"{what}: the times (s) and values ({unit}) must be finite")
        if t[0] != 0.0:
            raise ValueError(f"{what}: the times must start at 0 s (first contact); got {t[0]:g} s")
        if np.any(np.diff(t) <= 0):
            k = int(np.argmax(np.diff(t) <= 0))
            raise ValueError(
                f"{what}: the times must increase strictly (s); sample {k + 1} is at {t[k + 1]:g} s after {t[k]:g} s"
            )
        if np.any(v < 0):
            k = int(np.argmax(v < 0))
            raise ValueError(f"{what}: the values must be >= 0 {unit}; got {v[k]:g} {unit} at t = {t[k]:g} s")
        if v[0] != 0.0:
            raise ValueError(f"{what}: the history must start at 0 {unit} at t = 0 (first contact); got {v[0]:g}")
        self.times, self.values, self.name, self.unit = t, v, name, unit

    def __call__(self, t: float) -> float:
        return float(np.interp(float(t), self.times, self.values))


def kinks(times: np.ndarray, values: np.ndarray, tol: float) -> np.ndarray:
    """Indices of the samples kept by the Douglas-Peucker simplification of the polyline (times, values): between
    consecutive kept samples the record deviates from the straight piece by at most ``tol`` (in the values' unit).
    The first and the last sample are always kept."""
    n = times.size
    keep = np.zeros(n, bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        seg = slice(a + 1, b)
        chord = values[a] + (values[b] - values[a]) * (times[seg] - times[a]) / (times[b] - times[a])
        dev = np.abs(values[seg] - chord)
        k = int(np.argmax(dev))
        if dev[k] > tol:
            m = a + 1 + k
            keep[m] = True
            stack += [(a, m), (m, b)]
    return np.flatnonzero(keep)


def _piece(ta: float, tb: float, first: float, longest: float, growth: float) -> list[float]:
    """Step end times over (ta, tb]: steps first * growth^k, none longer than ``longest``, the fewest that reach tb,
    all scaled down alike to end on tb."""
    span = tb - ta
    h, total, steps = min(first, longest, span), 0.0, []
    while total < span * (1 - 1e-12):
        steps.append(h)
        total += h
        h = min(h * growth, longest)
    out = ta + np.cumsum(np.array(steps) * span / total)
    out[-1] = tb
    return list(out)


def record_schedule(
    record: Record,
    end_time: float,
    *,
    cap: float,
    first: float | None = None,
    growth: float = 1.5,
    breakpoints: Sequence[float] = (),
    tol: float | None = None,
) -> np.ndarray:
    """Step end times (s) through ``record`` to ``end_time``: one at every kink that matters (:func:`kinks` at
    ``tol``, default ``KINK_TOL * cap``; more than ``MAX_KINKS`` of them: the tolerance doubles until they are fewer,
    logged), no step moving the value by more than ``cap``, and within each piece between kinks steps growing by
    ``growth`` from ``first`` (s; default: the shortest step a moving piece needs). ``breakpoints`` (output times)
    are merged in. Past the last sample (held) the steps grow from ``first`` too."""
    if not (cap > 0 and np.isfinite(cap)):
        raise ValueError(f"the step cap must be positive ({record.unit}), got {cap!r}")
    t, v = record.times, record.values
    tol = KINK_TOL * cap if tol is None else float(tol)
    idx = kinks(t, v, tol)
    while idx.size > MAX_KINKS:
        tol *= 2.0
        idx = kinks(t, v, tol)
    if tol > KINK_TOL * cap * 1.5:
        log.warning(
            "the %s record has more than %d kinks at %.3g %s (noise?): steps at its kinks beyond %.3g %s only",
            record.name,
            MAX_KINKS,
            KINK_TOL * cap,
            record.unit,
            tol,
            record.unit,
        )
    tk, vk = t[idx], v[idx]
    keep = tk < end_time
    tk, vk = np.r_[tk[keep], end_time], np.r_[vk[keep], record(end_time)]
    n_move = np.ceil(np.abs(np.diff(vk)) / cap - 1e-9).astype(int)
    longest = np.where(n_move > 0, np.diff(tk) / np.maximum(n_move, 1), np.inf)
    h0 = float(first) if first is not None else float(np.min(longest)) if np.isfinite(longest).any() else end_time
    out: list[float] = []
    for a in range(tk.size - 1):
        out += _piece(float(tk[a]), float(tk[a + 1]), h0, float(longest[a]), growth)
    ts = np.unique(np.array(out + [float(b) for b in breakpoints if 0 < b <= end_time]))
    keep = np.r_[True, np.diff(ts) > 1e-12 * max(end_time, 1.0)]
    return ts[keep]


def force_controlled(
    step_to: Callable[[float, S, float, TimedState[S] | None, float | None], tuple[S, int]],
    force_of: Callable[[S], float],
    approach_of: Callable[[S], float],
    top_of: Callable[[S], float],
    target: Callable[[float], float],
    label: Callable[[float], str],
    stiffness: float,
    tol: float = FORCE_TOL,
    max_iter: int = FORCE_MAX_ITER,
) -> Callable[[float, S, float, TimedState[S] | None], tuple[S, int]]:
    """A step function for ``fem.timestepping.march`` under the prescribed force ``target(t)`` (scaled) from
    ``step_to(t0, old, t1, prev, d1)`` (the step with the plate at the scaled approach d1; None: without contact).

    A target <= 0 gives the free step (the force removed: the approach is then the ball's top, ``top_of``). Else the
    approach d1 with ``force_of(step_to(..., d1)) = target(t1)`` to ``tol`` (relative): the first trial extrapolates
    the last two steps' approaches in time (the first contact: Hertz, f = (32/3) ``stiffness`` x^1.5 above the top),
    the next ones follow the secant of F in u = (d1 - top)^1.5 (Illinois regula falsi once the force is bracketed;
    a trial without contact bounds d1 from below). A step whose iteration does not converge raises ``NewtonError``
    naming its time (s) and force (``label``), so the march cuts it."""

    def step(t0: float, old: S, t1: float, prev: TimedState[S] | None) -> tuple[S, int]:
        f1 = float(target(t1))
        if f1 <= 0.0:
            return step_to(t0, old, t1, prev, None)
        d_old, f_old = approach_of(old), force_of(old)
        # below ``top`` the plate does not touch: the free ball's top, or (in contact) the approach at which the old
        # force would vanish by a relaxed Hertz law, doubled (the secant variable u only; trials never go below it)
        top = top_of(old) if f_old <= 0 else max(d_old - 2.0 * (3.0 * f_old / 32.0) ** (2.0 / 3.0), 0.0)
        u_of = lambda d: max(d - top, 0.0) ** 1.5
        d_of = lambda u: top + max(u, 0.0) ** (2.0 / 3.0)
        f_prev = force_of(prev.state) if prev is not None else 0.0
        if f_old > 0 and prev is not None and f_prev > 0 and t0 > prev.time:
            # the last two steps extrapolated in time, corrected (Hertz-like about the old state) by the target's
            # departure from the extrapolated force (a kink of the force history)
            r_t = (t1 - t0) / (t0 - prev.time)
            d_a = max(d_old + (d_old - approach_of(prev.state)) * r_t, top + 1e-9)
            u_a = u_of(d_a) + (f1 - (f_old + (f_old - f_prev) * r_t)) * u_of(d_old) / f_old
            d_a = d_of(u_a) if u_a > 0 else d_of(u_of(d_old) * f1 / f_old)
        elif f_old > 0:
            d_a = d_of(u_of(d_old) * f1 / f_old)
        else:
            d_a = top + (3.0 * f1 / (32.0 * stiffness)) ** (2.0 / 3.0)
        its_sum = 0
        lo: tuple[float, float] | None = None  # (u, F - f1) with F < f1
        hi: tuple[float, float] | None = None  # with F > f1
        pts: list[tuple[float, float]] = []
        side = 0
        u = u_of(d_a)
        best = None
        failed: NewtonError | None = None
        for _ in range(max_iter):
            u_cur, d = u, d_of(u)
            try:
                st, its = step_to(t0, old, t1, prev, d)
            except NewtonError as err:  # a trial too far (its edge search or Newton failed): halfway back
                failed = err
                ok = [p for p in pts if p[1] != 0.0] or [(u_of(d_old), 0.0)]
                u = 0.5 * (u_cur + min(ok, key=lambda p: abs(p[1]))[0])
                log.debug("force control at %s: the trial x = %.12g failed (%s)", label(t1), d, err.args[0])
                continue
            its_sum += int(its)
            F = force_of(st)
            r = F - f1
            log.debug(
                "force control at %s: x = delta / (2 a0) = %.12g -> F / F_target - 1 = %.3e", label(t1), d, r / f1
            )
            if best is None or abs(r) < abs(best[1]):
                best = (st, r)
            if abs(r) <= tol * f1:
                return st, its_sum
            if r < 0:
                lo = (u, r)
            else:
                hi = (u, r)
            if lo is not None and hi is not None:  # bracketed: Illinois regula falsi
                if r < 0 and side == -1:
                    hi = (hi[0], 0.5 * hi[1])
                elif r > 0 and side == 1:
                    lo = (lo[0], 0.5 * lo[1])
                side = -1 if r < 0 else 1
                (ul, rl), (uh, rh) = lo, hi
                u = ul - rl * (uh - ul) / (rh - rl)
            elif pts and F > 0 and pts[-1][1] != r and pts[-1][0] != u_cur:  # secant through the last two trials
                u1, r1 = pts[-1]
                u_new = u_cur - r * (u_cur - u1) / (r - r1)
                u = u_new if u_new > 0 else 0.5 * u_cur
            elif F > 0:  # one point: Hertz-like, F proportional to u
                u = u * f1 / F
            else:  # no contact at this approach: press further
                u = max(2.0 * u, 3.0 * f1 / (32.0 * stiffness))
            pts.append((u_cur, r))
        raise NewtonError(
            f"the force control did not converge at {label(t1)}: the plate force is {best[1] / f1 + 1:.6g} of the "
            f"target after {max_iter} approaches"
            if best is not None
            else f"the force control failed at {label(t1)}: every trial approach failed ({failed})",
            load=label(t1),
            hint="reduce the time step (more ramp steps) or check that the force history is reachable",
        )

    return step
