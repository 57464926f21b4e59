r"""The one converged-step type of every path-following loop: load control, arc-length and time stepping.

``Step(time, state, newton_iterations, wall_time)``: ``time`` is where the step ends on its path: a time
(s) for ``fem.timestepping.march``, the (scaled) load for ``fem.continuation.load_control`` and
``arc_length``; ``state`` what the step converged to (``Step[S]``: the state type of the loop; the unknown
vector ``np.ndarray`` for load control and arc-length); ``newton_iterations`` (summed over the sub-steps
to a requested load), ``wall_time`` (s). Aliases: ``load`` (= time), ``x`` (= state), ``solution`` (a
``NewtonResult`` of the state, load control's field of release 0.1), ``t``, ``iterations``, ``wall_s``.
``TimedState(time, state)``: a converged state and its time, the ``previous`` argument of a step function.
"""

from __future__ import annotations

from typing import Generic, NamedTuple, TypeVar

from tissuemech.fem.newton import NewtonResult

__all__ = ["Step", "TimedState"]

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
