"""fem.stepping / timestepping / continuation: one Step type, schedules and cut-backs, load control, arc-length."""

import numpy as np
import pytest
import scipy.sparse as sp

from tissuemech.fem.continuation import LimitPointError, arc_length, load_control
from tissuemech.fem.newton import NewtonError, newton
from tissuemech.fem.stepping import Step
from tissuemech.fem.timestepping import march, ramp_hold_schedule


def test_arc_length_passes_a_limit_point_and_load_control_stops_there():
    """lam(x) = x exp(-x) has a maximum 1/e at x = 1: Riks passes it, load control reports it."""

    def fun(x, lam):
        return (np.array([x[0] * np.exp(-x[0]) - lam]), sp.csr_matrix([[(1 - x[0]) * np.exp(-x[0])]]), np.array([-1.0]))

    path = arc_length(fun, np.array([0.0]), 0.0, 0.05, stop=lambda x, lam: x[0] >= 2.0, rtol=1e-12)
    xs = np.array([p[1][0] for p in path])
    lams = np.array([p[0] for p in path])
    assert np.allclose(lams, xs * np.exp(-xs), atol=1e-12)  # every point is an equilibrium
    assert xs[-1] >= 2.0 and lams[-1] < lams.max()  # on the falling branch
    assert abs(lams.max() - np.exp(-1)) < 2e-3

    def solve(lam, guess):
        return newton(
            lambda x: fun(x, lam)[:2],
            guess,
            rtol=1e-12,
            xtol=1e-12,
            load=lam,
            admissible=lambda x: "past the maximum" if x[0] > 1.5 else None,
        )

    with pytest.raises(LimitPointError) as ei:
        load_control(solve, np.linspace(0.05, 0.5, 10), np.array([0.0]), monitor=lambda x: x[0])
    assert np.exp(-1) - 0.05 < ei.value.last_converged <= np.exp(-1) < ei.value.load


def test_schedule_and_cutback():
    t = ramp_hold_schedule(0.2, 1500.0, n_ramp=5, n_hold=10, breakpoints=[0.05, 700.0])
    assert np.isclose(t[-1], 1500.0) and np.all(np.diff(t) > 0)
    assert np.any(np.isclose(t, 0.05)) and np.any(np.isclose(t, 700.0)) and np.any(np.isclose(t, 0.2))
    hold = np.diff(t[t >= 0.2])
    assert hold[-1] > 50 * hold[0]  # geometric growth through the hold
    calls = []

    def step(t0, s, t1, prev):  # fails for steps longer than 0.3
        calls.append((t0, t1))
        if t1 - t0 > 0.3:
            raise NewtonError("too big", load=t1)
        return s + (t1 - t0), 2

    out = march(step, 0.0, [1.0, 2.0])
    assert np.isclose(out[-1].t, 2.0) and np.isclose(out[-1].state, 2.0)
    assert all(b - a <= 0.3 + 1e-12 for a, b in zip([0.0] + [s.t for s in out[:-1]], [s.t for s in out]))
    with pytest.raises(NewtonError, match="failed after"):
        march(step, 0.0, [1.0], max_cuts=1)


def test_one_step_type_for_every_path_and_requested_times_only():
    """march, load_control and arc_length all return ``Step`` (time/load, state/x, iterations, wall time);
    ``substeps=False`` returns one Step per requested time with the iterations of its sub-steps summed."""

    def step(t0, s, t1, prev):  # fails for steps longer than 0.3
        if t1 - t0 > 0.3:
            raise NewtonError("too big", load=t1)
        return s + (t1 - t0), 2

    every = march(step, 0.0, [1.0, 2.0])
    only = march(step, 0.0, [1.0, 2.0], substeps=False)
    assert [s.time for s in only] == [1.0, 2.0] and len(every) > 2
    assert sum(s.newton_iterations for s in only) == sum(s.newton_iterations for s in every)
    assert only[-1].state == every[-1].state and only[-1].x == only[-1].state

    def fun(x, lam):  # x + x^3 = lam
        return np.array([x[0] + x[0] ** 3 - lam]), sp.csr_matrix([[1 + 3 * x[0] ** 2]]), np.array([-1.0])

    solve = lambda lam, g: newton(lambda x: fun(x, lam)[:2], g, rtol=1e-13, xtol=1e-13)
    loads = load_control(solve, [0.5, 2.0], np.array([0.0]))
    arcs = arc_length(fun, np.array([0.0]), 0.0, 0.5, stop=lambda x, lam: lam >= 1.0, rtol=1e-12)
    for s in (*loads, *arcs, *only):
        assert isinstance(s, Step) and s.load == s.time
    assert loads[-1].solution.x is loads[-1].x and loads[-1].solution.iterations == loads[-1].newton_iterations
    assert abs(loads[-1].x[0] + loads[-1].x[0] ** 3 - 2.0) < 1e-12
