r"""The one converged-step type of every path-following loop: load control, arc-length and time stepping.

``Step(time, state, newton_iterations, wall_time)``: ``time`` is where the step ends on its path: a time
(s) for ``fem.timestepping.march``, the (scaled) load for ``fem.continuation.load_control`` and
``arc_length``; ``state`` what the step converged to (``Step[S]``: the state type of the loop; the unknown
vector ``np.ndarray`` for load control and arc-length); ``newton_iterations`` (summed over the sub-steps
to a requested load), ``wall_time`` (s). Aliases: ``load`` (= time), ``x`` (= state), ``solution`` (a
``NewtonResult`` of the state, load control's field of release 0.1), ``t``, ``iterations``, ``wall_s``.
``TimedState(time, state)``: a converged state and its time, the ``previous`` argument of a step function.

Step-size strategies of a time run (the ``stepping=`` argument of ``fem.spheroid.compress``, in the style of
diffrax's step-size controllers): ``Fixed(n_ramp=6, n_hold=20)``, ``n_ramp`` equal ramp steps and ``n_hold``
geometrically growing hold steps (``fem.timestepping.ramp_hold_schedule``); ``Adaptive(tol=2e-4)``, the same
steps refined where the Maxwell update's time error needs it (issue 35). Both have ``schedule(ramp_time,
end_time, *, beta, tau, load=None, breakpoints=())`` -> the step end times (s).

How ``Adaptive`` chooses: the time error of the FE's Maxwell update (``fem.viscoelastic``: exact for an
isochoric stress linear in time over the step, 2nd order otherwise) is estimated on the lumped recursion of the
same update for the plate force, F = F_eq + sum_m q_m with q_m^{n+1} = e^{-h_m} q_m^n + beta_m g_m
(F_eq^{n+1} - F_eq^n), F_eq = ``load(t)`` (default the Hertz shape (t / ramp_time)^1.5, capped at the ramp's
end): a scalar recursion, microseconds per step. A step controller marches it from t = 0 inside each interval
of the ``base`` (``Fixed``) schedule, with step doubling (one step against two half steps) as the local
error e_m of branch m, and accepts a step h ending at t when sum_m e_m min(tau_m, t) / h <= eps max(F(t), floor
max F) (the error a step leaves, times the number of steps over which it survives: the branch's memory
min(tau_m, t) / h); it never takes a step longer than the base interval it lies in and lands on every base
node, so a run whose base schedule is already fine (slow branches: Fig. 10, tau = 200 s) keeps it unchanged.
Then the whole schedule is checked: the lumped force's global relative error at every step time
(``lumped_time_error``: against the same recursion on 4x finer steps, Richardson order 2), normalised by
max(F(t), floor max F); while it exceeds ``tol``, eps shrinks and the march is redone. The FE's own time error
follows the lumped one closely (measured, fast two-branch case of issue 35, level 1, against its own
time-converged force, n_ramp 24 / 48: FE -8.2e-4 / -2.1e-4 at t = 0.05 s, -2.9e-4 / -7.2e-5 at 0.1 s,
-1.0e-4 / -2.6e-5 at 0.2 s; lumped -7.6e-4 / -1.9e-4, -2.6e-4 / -6.4e-5, -6.7e-5 / -1.7e-5), so the default
``tol`` = 2e-4 keeps the FE's time error within ~5e-4 (``python -m tissuemech.compare.bench.fem_time --adaptive``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Generic, NamedTuple, TypeVar

import numpy as np

from tissuemech.fem.newton import NewtonResult

__all__ = ["Step", "TimedState", "Fixed", "Adaptive", "lumped_force", "lumped_time_error"]

S = TypeVar("S")


class Step(NamedTuple, Generic[S]):
    """One converged step of a path-following loop (see the module docstring)."""

    time: float  # s (time stepping) or the scaled load (load control, arc-length): where the step ends
    state: S  # the converged state (the unknown vector for load control and arc-length)
    newton_iterations: int
    wall_time: float  # s spent on this step (all its sub-steps)

    @property
    def load(self) -> float:
        """The (scaled) load of a load-control or arc-length step (= ``time``)."""
        return self.time

    @property
    def x(self) -> S:
        """The converged state (= ``state``; the unknown vector on load and arc-length paths)."""
        return self.state

    @property
    def solution(self) -> NewtonResult:
        """``NewtonResult(state, newton_iterations, [])`` (load control's field of release 0.1)."""
        return NewtonResult(self.state, self.newton_iterations, [])  # type: ignore[arg-type]

    # the names of release 0.1 (read-only aliases)
    @property
    def t(self) -> float:
        return self.time

    @property
    def iterations(self) -> int:
        return self.newton_iterations

    @property
    def wall_s(self) -> float:
        return self.wall_time


class TimedState(NamedTuple, Generic[S]):
    """A converged state and its time (s): the ``previous`` argument of a step function."""

    time: float
    state: S


# ---- step-size strategies of time runs ------------------------------------------------------------------------


def _hertz_ramp(ramp_time: float) -> Callable[[np.ndarray], np.ndarray]:
    """The default equilibrium-force shape of a linear ramp to ``ramp_time`` held after: (min(t / ramp_time, 1))^1.5."""
    return lambda t: np.minimum(np.asarray(t, float) / ramp_time, 1.0) ** 1.5


def _branches(beta, tau) -> tuple[np.ndarray, np.ndarray]:
    beta, tau = np.atleast_1d(np.asarray(beta, float)), np.atleast_1d(np.asarray(tau, float))
    if beta.shape != tau.shape or np.any(beta < 0) or np.any(~(tau > 0)) or not np.all(np.isfinite(tau)):
        raise ValueError(f"branches need beta >= 0 and tau > 0 (s) of one length, got beta {beta}, tau {tau}")
    return beta, tau


def _lumped_step(q: np.ndarray, beta: np.ndarray, tau: np.ndarray, h: float, dF: float) -> np.ndarray:
    """One step of the lumped Maxwell recursion (``fem.viscoelastic.update`` on a scalar): q_m^{n+1}."""
    r = h / tau
    g = np.where(r < 1e-8, 1.0 - r / 2, -np.expm1(-r) / np.where(r < 1e-8, 1.0, r))
    return np.exp(-r) * q + beta * g * dF


def lumped_force(times, load: Callable, beta, tau) -> np.ndarray:
    """The lumped force F = F_eq + sum_m q_m at ``times`` (s, increasing, > 0) from t = 0, by the FE's Maxwell update
    (``fem.viscoelastic.update``) applied to F_eq = ``load(t)`` (any unit; ``load(0)`` is the start)."""
    beta, tau = _branches(beta, tau)
    ts = np.asarray(times, float)
    F_eq = np.asarray(load(np.r_[0.0, ts]), float)
    q = np.zeros(beta.size)
    out = np.empty(ts.size)
    t0 = 0.0
    for k, t in enumerate(ts):
        q = _lumped_step(q, beta, tau, float(t - t0), float(F_eq[k + 1] - F_eq[k]))
        out[k] = F_eq[k + 1] + q.sum()
        t0 = float(t)
    return out


def lumped_time_error(times, load: Callable, beta, tau, *, floor: float = 0.05) -> np.ndarray:
    """Estimated global relative time error of the lumped force on the steps ``times`` (s) at each of them:
    (F_h - F_{h/4}) 16/15 (Richardson, order 2) with F_{h/4} the same recursion on every step cut in 4,
    over max(|F(t)|, floor max |F|) (so the first steps, where F -> 0, are measured against the force's scale)."""
    ts = np.asarray(times, float)
    t_prev = np.r_[0.0, ts[:-1]]
    fine = (t_prev[:, None] + (ts - t_prev)[:, None] * np.arange(1, 5)[None, :] / 4).ravel()
    F = lumped_force(ts, load, beta, tau)
    Ff = lumped_force(fine, load, beta, tau)[3::4]
    scale = np.maximum(np.abs(Ff), floor * np.abs(Ff).max())
    return (F - Ff) * (16.0 / 15.0) / scale


@dataclass(frozen=True)
class Fixed:
    """``n_ramp`` equal ramp steps and ``n_hold`` geometrically growing hold steps, the first ``first_hold`` long
    (s; default ramp_time / 2): ``fem.timestepping.ramp_hold_schedule``. The schedule of release 0.1."""

    n_ramp: int = 6
    n_hold: int = 20
    first_hold: float | None = None

    def __post_init__(self):
        for name in ("n_ramp", "n_hold"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"{name} (a number of time steps) must be an integer >= 1, got {v!r}")

    def schedule(
        self, ramp_time: float, end_time: float, *, beta=(), tau=(), load: Callable | None = None, breakpoints=()
    ) -> np.ndarray:
        """Step end times (s); ``beta``, ``tau``, ``load`` are not used (the signature of ``Adaptive.schedule``)."""
        from tissuemech.fem.timestepping import ramp_hold_schedule  # timestepping imports this module

        return ramp_hold_schedule(
            ramp_time,
            end_time,
            n_ramp=int(self.n_ramp),
            n_hold=int(self.n_hold),
            first_hold=self.first_hold,
            breakpoints=breakpoints,
        )


@dataclass(frozen=True)
class Adaptive:
    """The ``base`` schedule refined so that the estimated time error of the Maxwell update is below ``tol``
    (relative, of the plate force, at every step time; see the module docstring). ``floor``: errors are measured
    against max(F(t), floor max F); ``max_steps``: a ValueError beyond it (a tol too tight for the branches)."""

    tol: float = 2e-4
    base: Fixed = field(default_factory=Fixed)
    floor: float = 0.05
    max_steps: int = 5000

    def __post_init__(self):
        if not (0 < self.tol < 1):
            raise ValueError(f"tol (a relative error of the force) must be in (0, 1), got {self.tol!r}")
        if not (0 < self.floor <= 1):
            raise ValueError(f"floor (a fraction of the largest force) must be in (0, 1], got {self.floor!r}")
        if not isinstance(self.base, Fixed):
            raise ValueError(f"base must be a Fixed schedule, got {self.base!r}")

    def schedule(
        self,
        ramp_time: float,
        end_time: float,
        *,
        beta=(),
        tau=(),
        load: Callable | None = None,
        breakpoints: Sequence[float] = (),
    ) -> np.ndarray:
        """Step end times (s) for the branches (beta_m, tau_m [s]) under the equilibrium force shape ``load(t)``
        (default the Hertz shape of a linear ramp to ``ramp_time``); elastic runs (no branch) get the base."""
        base = self.base.schedule(ramp_time, end_time, breakpoints=breakpoints)
        beta, tau = _branches(beta, tau)
        if beta.size == 0 or not np.any(beta > 0):
            return base
        shape = _hertz_ramp(float(ramp_time)) if load is None else load
        F_scale = float(np.abs(lumped_force(base, shape, beta, tau)).max())
        # the local tolerance eps scaled until the estimated global error is 0.6-1 tol (it is ~ eps: 2nd order)
        eps, best = self.tol, None
        for _ in range(12):
            ts = self._march(base, shape, beta, tau, eps, F_scale)
            err = float(np.abs(lumped_time_error(ts, shape, beta, tau, floor=self.floor)).max())
            if err <= self.tol:
                if best is None or ts.size < best.size:
                    best = ts
                if err >= 0.6 * self.tol or np.array_equal(ts, base):
                    return best
            elif best is not None:
                return best
            eps *= 0.8 * self.tol / max(err, 1e-3 * self.tol)
        if best is not None:
            return best
        raise ValueError(f"Adaptive(tol={self.tol:g}) did not reach its tolerance (estimated error {err:.2g})")

    def _march(self, base: np.ndarray, load: Callable, beta, tau, eps: float, F_scale: float) -> np.ndarray:
        """The controller's step end times for the local tolerance eps (see the module docstring)."""
        out: list[float] = []
        t, q, Fe = 0.0, np.zeros(beta.size), float(load(np.array([0.0]))[0])
        h_ctrl = float(base[0])  # the controller's proposal (a step clipped at a base node leaves it)
        for b in base:
            while t < b - 1e-12 * b:
                rest = b - t
                while True:
                    hs = rest if h_ctrl >= rest else (rest / 2 if rest < 2 * h_ctrl else h_ctrl)
                    F1, Fm = (float(v) for v in load(np.array([t + hs, t + hs / 2])))
                    one = _lumped_step(q, beta, tau, hs, F1 - Fe)
                    two = _lumped_step(_lumped_step(q, beta, tau, hs / 2, Fm - Fe), beta, tau, hs / 2, F1 - Fm)
                    E = float(np.sum(np.abs(one - two) * (4.0 / 3.0) * np.minimum(tau, t + hs) / hs))
                    allowed = eps * max(abs(F1 + one.sum()), self.floor * F_scale)
                    ratio = float(np.sqrt(allowed / E)) if E > 1e-300 else 5.0
                    if E <= allowed:
                        break
                    h_ctrl = hs * max(0.2, 0.9 * ratio)
                t = b if hs == rest else t + hs
                q, Fe = one, F1
                out.append(t)
                if len(out) > self.max_steps:
                    raise ValueError(
                        f"Adaptive(tol={self.tol:g}) needs more than max_steps = {self.max_steps} steps for the "
                        f"branches tau = {tau} s: loosen tol or raise max_steps"
                    )
                grown = hs * min(5.0, max(0.2, 0.9 * ratio))
                h_ctrl = max(grown, h_ctrl) if hs < h_ctrl else grown
        return np.array(out)
