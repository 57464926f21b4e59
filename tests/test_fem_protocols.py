"""Issue 34, FE side: measured approach histories, unloading with contact loss, force control (creep and recovery)
of ``fem.spheroid.compress`` and the step schedule of dense records (``fem.protocols``)."""

from __future__ import annotations

import numpy as np
import pytest

from tissuemech.fem.protocols import Record, kinks, record_schedule
from tissuemech.fem.spheroid import compress

A0 = 500e-6
MAT = dict(radius=A0, C=150.0, alpha=0.2)


# ---- the step schedule of a measured record ---------------------------------------------------------------------
def test_dense_record_steps_at_its_kinks_only():
    """10^5 samples of a ramp-hold-unload-hold polyline: the steps land on its 4 kinks, move the approach by at most
    the cap, and number a few dozen (not one per sample)."""
    knots_t, knots_v = [0.0, 1.0, 5.0, 5.5, 20.0], [0.0, 40e-6, 40e-6, 10e-6, 10e-6]
    t = np.union1d(np.linspace(0.0, 20.0, 100_001), knots_t)
    rec = Record(t, np.interp(t, knots_t, knots_v), "approach", "m")
    assert list(t[kinks(rec.times, rec.values, 1e-12)]) == knots_t
    cap = 40e-6 / 6
    ts = record_schedule(rec, 20.0, cap=cap)
    assert ts.size < 60 and ts[-1] == 20.0
    assert all(np.min(np.abs(ts - k)) < 1e-12 for k in knots_t[1:])
    v = np.interp(np.r_[0.0, ts], knots_t, knots_v)
    assert np.max(np.abs(np.diff(v))) <= cap * (1 + 1e-9)


def test_noisy_record_is_capped_with_a_warning(caplog):
    """A record of white noise on a ramp: the kink tolerance grows until at most MAX_KINKS remain (logged)."""
    from tissuemech.fem.protocols import MAX_KINKS

    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 10.0, 20_001)
    v = np.clip(4e-6 * t + 1e-7 * rng.standard_normal(t.size), 0.0, None)
    v[0] = 0.0
    ts = record_schedule(Record(t, v, "approach", "m"), 10.0, cap=40e-6 / 6)
    assert ts.size <= 3 * MAX_KINKS
    assert "kinks" in caplog.text


@pytest.mark.parametrize(
    "kw, msg",
    [
        (dict(displacement=50e-6, force=1e-6), "exactly one of displacement= .* and force="),
        (dict(), "exactly one of .* got neither"),
        (dict(force=1e-6, static=True), "static=True needs the final approach"),
        (dict(displacement=([0.1, 1.0], [0.0, 1e-6])), "start at 0 s"),
        (dict(displacement=([0.0, 1.0, 1.0], [0.0, 1e-6, 2e-6])), "increase strictly"),
        (dict(displacement=([0.0, 1.0], [0.0, -1e-6])), ">= 0 m"),
        (dict(force=([0.0, 1.0], [1e-6, 1e-6])), "start at 0 N"),
        (dict(force=lambda t: -1e-6 * t), ">= 0 .the plates only push"),
        (dict(force=-1e-6), "force"),
        (dict(force=([0.0, 1.0], [0.0, 0.0])), "0 throughout"),
    ],
)
def test_protocol_inputs_are_checked(kw, msg):
    kw = {"ramp_time": 0.2, "end_time": 1.0, **kw} if "static" not in kw else {"ramp_time": 0.2, **kw}
    with pytest.raises(ValueError, match=msg):
        compress(**MAT, mesh="coarse", **kw)


# ---- force control ---------------------------------------------------------------------------------------------
def test_force_control_reproduces_displacement_control():
    """The force history of a displacement-controlled relaxation, prescribed: the same step times, and at every step
    the approach the displacement run had (to the force tolerance, 1e-7, and the edge tolerance): the outer iteration
    solves the same states."""
    kw = dict(**MAT, branches=[(0.4, 2.0)], ramp_time=0.2, end_time=4.0, mesh="coarse", n_hold=6)
    d = compress(**kw, displacement=40e-6)
    f = compress(**kw, force=lambda t: float(np.interp(t, np.r_[0.0, d.time], np.r_[0.0, d.force])))
    assert np.array_equal(f.time, d.time)
    assert np.max(np.abs(f.approach / d.approach - 1)) < 1e-6
    assert np.max(np.abs(f.force / d.force - 1)) < 2e-7
    assert f.parameters["control"] == "force" and f.in_contact.all()


@pytest.fixture(scope="module")
def creep_recovery():
    """A force of 4 uN ramped in 0.2 s, held to 3 s, removed by 3.2 s, then nothing to 8 s (tau = 0.5 s)."""
    return compress(
        **MAT,
        branches=[(0.6, 0.5)],
        force=([0.0, 0.2, 3.0, 3.2, 8.0], [0.0, 4e-6, 4e-6, 0.0, 0.0]),
        mesh="coarse",
        n_ramp=4,
    )


@pytest.mark.slow
def test_creep_approach_grows_under_a_held_force(creep_recovery):
    r = creep_recovery
    hold = (r.time >= 0.2 - 1e-12) & (r.time <= 3.0 + 1e-12)
    assert np.allclose(r.force[hold], 4e-6, rtol=1e-6)
    a = r.approach[hold]
    assert np.all(np.diff(a) > 0)
    # one branch: from the instantaneous F_eq^-1(F / (1 + beta)) toward the relaxed F_eq^-1(F), ~(1.6)^(2/3) = 1.37
    assert 1.2 < a[-1] / a[0] < 1.37
    assert np.all(r.force >= 0)


@pytest.mark.slow
def test_recovery_after_the_force_is_removed(creep_recovery):
    """Force 0 from 3.2 s: the plates lose the ball (flagged, force exactly 0), its top recovers toward the undeformed
    ball (approach -> 0, monotone) with the branch's time."""
    r = creep_recovery
    off = r.time >= 3.2 - 1e-12
    assert not r.in_contact[off].any() and r.in_contact[~off].all()
    assert np.all(r.force[off] == 0.0)
    assert r.parameters["contact_lost"] == (pytest.approx(3.2),) and r.parameters["contact_regained"] == ()
    a = r.approach[off]
    assert np.all(np.diff(a) < 0) and a[-1] < 0.01 * r.approach[r.time <= 3.0][-1]
    assert set(np.array(r.parameters["contact"])[off]) == {"none"}


# ---- measured histories: unloading, contact lost and regained ---------------------------------------------------
@pytest.mark.slow
def test_unloading_faster_than_recovery_loses_and_regains_contact():
    """The plates retract faster than the ball recovers (tau = 1 s): the force falls to exactly 0 (never negative),
    ``in_contact`` says when, and the contact comes back when the plates press again (fitted edges again)."""
    r = compress(
        **MAT,
        branches=[(0.5, 1.0)],
        displacement=([0.0, 1.0, 2.0, 2.2, 4.0, 5.0, 6.0], [0.0, 40e-6, 40e-6, 0.0, 0.0, 30e-6, 30e-6]),
        mesh="coarse",
    )
    assert np.all(r.force >= 0)
    lost, back = r.parameters["contact_lost"], r.parameters["contact_regained"]
    assert len(lost) == 1 and 2.0 < lost[0] <= 2.2 and len(back) == 1 and 4.0 < back[0] < 5.0
    gone = ~r.in_contact
    assert np.all(r.force[gone] == 0.0) and np.all(r.min_gap[gone] >= 0)
    assert np.all(r.in_contact[r.time >= 5.0 - 1e-12])
    assert r.parameters["contact"][-1] == "fitted"
    # before the loss the force still falls with the plates; at 5-6 s the ball relaxes again under the held plates
    held = r.time >= 5.0 - 1e-12
    assert np.all(np.diff(r.force[held]) < 0)


def test_measured_history_kinks_are_steps_and_follow_the_record():
    """A dense measured ramp-hold record gives the ramp-hold run's forces (same kinks: the record's steps are the
    ramp's equal steps in approach; the hold's steps differ, so compare at the ramp's end and by interpolation)."""
    kw = dict(**MAT, branches=[(0.4, 2.0)], mesh="coarse")
    t = np.union1d(np.linspace(0.0, 4.0, 4001), [0.2])
    r = compress(**kw, displacement=(t, 40e-6 * np.clip(t / 0.2, 0.0, 1.0)), n_ramp=6)
    d = compress(**kw, displacement=40e-6, ramp_time=0.2, end_time=4.0, n_ramp=6)  # Fixed: 6 equal ramp steps
    assert r.parameters["control"] == "displacement" and r.time[-1] == 4.0
    ramp = r.time <= 0.2 + 1e-12
    assert np.allclose(r.time[ramp], d.time[: ramp.sum()], rtol=1e-12)
    assert np.allclose(r.force[ramp], d.force[: ramp.sum()], rtol=1e-9)
    assert r.time.size < 40
    assert np.interp(4.0, r.time, r.force) == pytest.approx(d.force[-1], rel=2e-3)


# ---- the small-approach warning (issue 41) ----------------------------------------------------------------------
def test_small_approach_warns_with_the_expected_error():
    from tissuemech.fem.spheroid import SmallApproachWarning, small_approach_error

    assert small_approach_error(1e-6, 0) == pytest.approx(0.43)
    assert small_approach_error(1e-6, 1) == pytest.approx(1.6e-2)
    assert small_approach_error(0.05, 1) == 0.0 and small_approach_error(1e-6, 3) == 0.0
    with pytest.warns(SmallApproachWarning, match=r"below the design range of mesh level 1 .* 1.6 % too high"):
        compress(**MAT, displacement=2 * A0 * 1e-6, static=True, mesh="default", n_static=1)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", SmallApproachWarning)
        compress(**MAT, displacement=2 * A0 * 0.01, static=True, mesh="default", n_static=1)


# ---- oscillation: the lumped model's dynamic stiffness ----------------------------------------------------------
def test_dynamic_stiffness_limits_jit_and_inputs():
    """omega -> 0: the relaxed k_eq = dF_eq/ddelta, no loss; omega -> inf: (1 + sum beta) k_eq; one branch: the loss
    peaks at omega tau = 1 with k_eq beta / 2; jit over frequencies."""
    import jax

    from tissuemech.reduced.oscillation import dynamic_stiffness, equilibrium_stiffness
    from tissuemech.reduced.spheroid import equilibrium_force

    d0 = 50e-6
    k = float(equilibrium_stiffness(d0, radius=A0, C=150.0, alpha=0.2))
    h = 1e-9
    fd = (equilibrium_force(d0 + h, **MAT) - equilibrium_force(d0 - h, **MAT)) / (2 * h)
    assert k == pytest.approx(float(fd), rel=1e-6)
    mat = dict(**MAT, branches=[(0.4, 1.0)])
    s0, l0 = dynamic_stiffness(0.0, **mat, approach=d0)
    s_inf, l_inf = dynamic_stiffness(1e9, **mat, approach=d0)
    assert float(s0) == pytest.approx(k) and float(l0) == 0.0
    assert float(s_inf) == pytest.approx(1.4 * k, rel=1e-9) and float(l_inf) < 1e-8 * k
    fs = np.geomspace(0.01, 10.0, 301)
    s, loss = (np.asarray(v) for v in jax.jit(lambda q: dynamic_stiffness(q, **mat, approach=d0))(fs))
    assert np.all(np.diff(s) > 0)
    assert fs[np.argmax(loss)] == pytest.approx(1 / (2 * np.pi), rel=0.03) and loss.max() == pytest.approx(
        0.2 * k, rel=1e-3
    )
    with pytest.raises(ValueError, match="frequency"):
        dynamic_stiffness(-1.0, **mat, approach=d0)


@pytest.mark.slow
def test_dynamic_stiffness_is_the_steady_response_of_the_lumped_law():
    """The closed form against ``reduced.spheroid.force`` driven by a small sinusoid about a relaxed compression
    (amplitude 1e-3 of the approach: linear to ~1e-3), its last period fitted; limits omega -> 0 and infinity."""
    import jax

    from tissuemech.reduced.oscillation import dynamic_stiffness
    from tissuemech.reduced.spheroid import force

    mat = dict(radius=A0, C=150.0, alpha=0.2, branches=[(0.4, 1.0), (0.2, 0.1)])
    d0, eps, f = 50e-6, 50e-9, 0.7
    hold = 20.0
    disp = lambda t: jax.numpy.where(
        t < 0.2, d0 * t / 0.2, d0 + eps * jax.numpy.sin(2 * np.pi * f * (t - hold)) * (t >= hold)
    )
    t = hold + np.linspace(2 / f, 3 / f, 201)
    # the closed form linearises the plain lumped law (coupling=0); the default coupling of the FE table, applied
    # while the approach grows, raises K'' by 1.0-1.1 % and K' by 0.02-0.25 % at 0.05-0.5 Hz (branch (0.4, 1 s))
    F = np.asarray(force(t, **mat, displacement=disp, jump_times=(0.2, hold), method="ode", coupling=0.0))
    w, tt = 2 * np.pi * f, t - hold
    A = np.stack([np.ones_like(tt), np.sin(w * tt), np.cos(w * tt)], axis=1)
    c = np.linalg.lstsq(A, F, rcond=None)[0]
    K1, K2 = (float(v) for v in dynamic_stiffness(f, **mat, approach=d0))
    assert c[1] / eps == pytest.approx(K1, rel=2e-3) and c[2] / eps == pytest.approx(K2, rel=2e-3)
