"""Issue 35: the Maxwell history on contact-edge-fitted meshes rebuilt by replay (fem.contact.replayed_history),
and the time convergence of the fast two-branch case it gives."""

import numpy as np
import pytest

from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.contact import FittedEdge, replayed_history
from tissuemech.fem.forms import Assembler, Material
from tissuemech.fem.mesh import fitted_mesh
from tissuemech.fem.spheroid import compress
from tissuemech.fem.stepping import Adaptive, Fixed, lumped_force, lumped_time_error
from tissuemech.fem.timestepping import ramp_hold_schedule

A0 = 500e-6
BETA, TAU = np.array([0.8, 0.3]), np.array([0.05, 20.0])
MAT = Material(1.0, 0.2, 2.2e9 / 150.0)


def _displacements(asm: Assembler, X: np.ndarray, n: int) -> list[np.ndarray]:
    """n growing smooth (non-homogeneous) displacements of the mesh with reference nodes X."""
    out = []
    for k in range(1, n + 1):
        s = 0.02 * k
        x = np.zeros(asm.ndof)
        x[0 : asm.n_u : 2] = s * (0.5 * X[0] + 0.3 * X[0] * X[1] ** 2)
        x[1 : asm.n_u : 2] = -s * (X[1] + 0.2 * X[0] ** 2 * X[1])
        out.append(x)
    return out


def test_replay_on_one_mesh_is_the_plain_update():
    """The history replayed from t = 0 over steps that all lie on one mesh is the step-by-step Maxwell update of
    that mesh (the recursion is the same, only run again): equal to round-off."""
    m = fitted_mesh(A0, 0, 0.2)
    asm = Assembler(m)
    dts = [0.01, 0.02, 0.05, 0.5]
    xs = _displacements(asm, m.X, len(dts))
    plain = ve.initial_state(2, asm.w.shape + (5,))
    path = []
    for x, dt in zip(xs, dts):
        S = asm.iso_S(x, MAT)
        plain = ve.update(plain, BETA, TAU, dt, S)
        path.append((m, x, S, dt))
    got = replayed_history(path, m, MAT, BETA, TAU, smooth=False)
    np.testing.assert_allclose(got.Q, plain.Q, rtol=0, atol=1e-12 * np.abs(plain.Q).max())
    np.testing.assert_array_equal(got.S_iso, plain.S_iso)


def test_replay_across_fitted_meshes_is_exact_for_a_homogeneous_deformation():
    """A homogeneous deformation (S_iso the same at every material point) passed through steps on 4 different
    fitted meshes: the history replayed at a fifth mesh's points is the single-point Maxwell recursion, exactly
    (both the continuous interpolant and the evaluated FE field reproduce a uniform field)."""
    edges = (0.1, 0.15, 0.2, 0.25)
    dts = (0.02, 0.02, 0.04, 0.1)
    target = fitted_mesh(A0, 0, 0.3)
    path, S_one = [], []
    for k, (e, dt) in enumerate(zip(edges, dts)):
        m = fitted_mesh(A0, 0, e)
        asm = Assembler(m)
        x = np.zeros(asm.ndof)
        s = 0.03 * (k + 1)
        x[0 : asm.n_u : 2], x[1 : asm.n_u : 2] = 0.5 * s * m.X[0], -s * m.X[1]
        S = asm.iso_S(x, MAT)
        path.append((m, x, S, dt))
        S_one.append(S[0, 0])
    point = ve.initial_state(2, (1, 1, 5))
    for S, dt in zip(S_one, dts):
        point = ve.update(point, BETA, TAU, dt, np.asarray(S)[None, None])
    for smooth in (True, False):
        got = replayed_history(path, target, MAT, BETA, TAU, smooth=smooth)
        scale = np.abs(point.Q).max()
        assert np.abs(got.Q - point.Q).max() < 1e-10 * scale, smooth
        assert np.abs(got.S_iso - point.S_iso).max() < 1e-10 * np.abs(point.S_iso).max(), smooth


def test_replay_is_the_default_history():
    assert FittedEdge().history == "replay"
    for h in ("points", "transfer", "chain"):
        assert FittedEdge(history=h).history == h


CASE = dict(
    radius=A0,
    C=150.0,
    alpha=0.2,
    branches=[(0.8, 0.05), (0.3, 20.0)],
    displacement=100e-6,
    ramp_time=0.2,
    end_time=1.0,
    n_hold=4,
)
TIMES = (0.1, 0.2)


def _forces(n_ramp: int, level: int) -> np.ndarray:
    r = compress(**CASE, mesh=level, n_ramp=n_ramp, field_times=list(TIMES))
    return np.array([r.force[np.argmin(np.abs(r.time - t))] for t in TIMES])


@pytest.mark.slow
def test_fast_branch_force_converges_in_the_step_with_replay():
    """Issue 35 (tau = 0.05 s on a 0.2 s ramp): with the replayed history successive refinements of the ramp
    change F less and less at every output time (monotone), at an observed order >= 1.5 (a time error, not
    the drift of an interpolated history: "transfer" moved F by +5.2e-3 from 24 to 96 steps at 0.2 s)."""
    F = [_forces(n, 0) for n in (6, 12, 24)]
    d1, d2 = np.abs(F[1] - F[0]), np.abs(F[2] - F[1])
    assert np.all(d2 < d1)
    assert np.all(np.log2(d1 / d2) >= 1.5), np.log2(d1 / d2)


# ---- adaptive steps (fem.stepping.Adaptive, the default of compress) --------------------------------------------

FAST = dict(beta=[0.8, 0.3], tau=[0.05, 20.0])
OUT = [0.05, 0.1, 0.15, 0.2, 1.0, 10.0]


def _hertz(t):
    return np.minimum(np.asarray(t, float) / 0.2, 1.0) ** 1.5


def test_fixed_is_the_ramp_hold_schedule():
    got = Fixed(n_ramp=8, n_hold=12).schedule(0.2, 100.0, breakpoints=[0.05, 3.0], **FAST)
    np.testing.assert_array_equal(got, ramp_hold_schedule(0.2, 100.0, n_ramp=8, n_hold=12, breakpoints=[0.05, 3.0]))


def test_lumped_force_is_exact_for_a_linear_load_and_relaxes_in_the_hold():
    """The Maxwell update is exact for a load linear in time over each step: on a linear ramp F = F_eq +
    beta tau F_eq' (1 - e^{-t/tau}) at any step; held after, the branch decays as e^{-(t - t_r)/tau}."""
    beta, tau, tr = 0.7, 0.3, 1.0
    load = lambda t: np.minimum(np.asarray(t, float) / tr, 1.0)
    t = np.array([0.1, 0.4, 1.0, 1.7, 3.0])
    q_r = beta * tau / tr * (1 - np.exp(-tr / tau))
    want = np.where(t <= tr, t / tr + beta * tau / tr * (1 - np.exp(-t / tau)), 1.0 + q_r * np.exp(-(t - tr) / tau))
    np.testing.assert_allclose(lumped_force(t, load, [beta], [tau]), want, rtol=1e-13)


def test_adaptive_keeps_the_base_steps_for_slow_branches():
    """Fig. 10's branch (tau = 200 s on a 0.2 s ramp): the base schedule is already fine, nothing is added."""
    base = Fixed().schedule(0.2, 200.0)
    np.testing.assert_array_equal(Adaptive().schedule(0.2, 200.0, beta=[0.8], tau=[200.0]), base)
    np.testing.assert_array_equal(Adaptive().schedule(0.2, 200.0), base)  # elastic


def test_adaptive_meets_its_tolerance_and_tightening_it_converges_at_second_order():
    """Fast branch (tau = ramp / 4): the estimated time error of the lumped force is below tol at every step,
    far below the default 6 ramp steps' (1.1e-2), and the true error (against a 100x finer run) at the output
    times falls ~ N^-2 with the ramp step count N."""
    fine = np.unique(np.r_[np.linspace(0, 0.2, 20001)[1:], np.geomspace(0.2, 200.0, 4000), OUT])
    F_fine = lumped_force(fine, _hertz, **FAST)
    ref = np.array([F_fine[np.argmin(np.abs(fine - t))] for t in OUT])
    fixed = Fixed().schedule(0.2, 200.0, breakpoints=OUT)
    assert np.abs(lumped_time_error(fixed, _hertz, **FAST)).max() > 1e-2
    errs, n_ramp = [], []
    for tol in (4e-4, 1e-4):
        ts = Adaptive(tol=tol).schedule(0.2, 200.0, breakpoints=OUT, **FAST)
        assert set(OUT) <= set(ts.tolist())
        est = lumped_time_error(ts, _hertz, **FAST)
        assert np.abs(est).max() <= tol
        F = lumped_force(ts, _hertz, **FAST)
        errs.append(np.array([F[np.argmin(np.abs(ts - t))] for t in OUT]) / ref - 1)
        n_ramp.append(int(np.sum(ts <= 0.2)))
    assert np.all(np.abs(errs[0][:4]) < 4e-4) and np.all(np.abs(errs[1][:4]) < 1e-4)
    order = np.log(np.abs(errs[0][:4] / errs[1][:4])) / np.log(n_ramp[1] / n_ramp[0])
    assert np.all((order > 1.6) & (order < 2.6)), order


def test_step_strategies_reject_bad_settings():
    with pytest.raises(ValueError, match="n_ramp"):
        Fixed(n_ramp=0)
    with pytest.raises(ValueError, match="tol"):
        Adaptive(tol=0.0)
    with pytest.raises(ValueError, match="stepping="):
        compress(**CASE, mesh=0, n_ramp=6, stepping=Adaptive())


def test_compress_reports_its_steps():
    """The default stepping of a time run is Adaptive(); the step count is in parameters["n_steps"]."""
    kw = {k: v for k, v in CASE.items() if k != "n_hold"}
    r = compress(**{**kw, "branches": [(0.8, 200.0)], "end_time": 0.3}, mesh=0)
    assert r.parameters["stepping"] == Adaptive()
    base = Fixed().schedule(0.2, 0.3)  # tau = 200 s: the base steps, unchanged
    assert r.parameters["n_steps"] == r.time.size == base.size
    np.testing.assert_allclose(r.time, base)
