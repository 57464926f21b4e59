"""Physics tests of reduced.viscoshell: the generalized-Maxwell thick shell under p(t)."""

import jax.numpy as jnp
import numpy as np
import pytest

import tissuemech.reduced  # noqa: F401  (x64)
from tissuemech.reduced import blastula as bl
from tissuemech.reduced import viscoshell as vs

A, B, C = 50e-6, 75e-6, 200.0
GEO = dict(inner_radius=A, outer_radius=B)
T_STEP = jnp.array([0.0, 10.0, 100.0, 300.0, 1000.0, 3000.0, 3.0e4, 6.0e4])


@pytest.mark.parametrize("alpha,branches", [(0.2, [(1.2, 200.0)]), (0.1, [(0.5, 3.0), (1.0, 300.0)])])
def test_step_instantaneous_then_relaxed(alpha, branches):
    p = 150.0
    run = vs.inflate(T_STEP, pressure=p, **GEO, C=C, alpha=alpha, branches=branches)
    la = np.asarray(run.inner_stretch)
    c_inst = C * (1 + sum(b for b, _ in branches))
    # t = 0+: glassy response = elastic shell with C_inst = (1 + sum beta) C
    assert la[0] == pytest.approx(float(bl.inner_stretch(p, **GEO, C=c_inst, alpha=alpha)), rel=1e-12)
    # t >> tau: the relaxed elastic curve (C)
    assert la[-1] == pytest.approx(float(bl.inner_stretch(p, **GEO, C=C, alpha=alpha)), rel=1e-9)
    assert np.all(np.diff(la) > -1e-12)  # creep: the cavity only grows under a held pressure
    np.testing.assert_allclose(np.asarray(run.outer_stretch), np.asarray(bl.outer_stretch(la, **GEO)), rtol=1e-14)


def test_small_strain_creep_is_standard_linear_solid():
    """p << C: eps(t) = p/K [1 - beta/(1+beta) exp(-t / (tau (1 + beta)))], K = 8 C (1 - (A/B)^3)."""
    p, beta, tau = 0.01, 1.2, 200.0
    run = vs.inflate(T_STEP, pressure=p, **GEO, C=C, alpha=0.2, branches=[(beta, tau)], rtol=1e-12, atol=1e-14)
    eps = np.asarray(run.inner_stretch) - 1.0
    K = 8 * C * (1 - (A / B) ** 3)
    ref = p / K * (1 - beta / (1 + beta) * np.exp(-np.asarray(T_STEP) / (tau * (1 + beta))))
    np.testing.assert_allclose(eps, ref, rtol=1e-4)  # next term is O(eps) ~ 1e-5


def test_beta_zero_is_elastic_during_ramp_and_hold():
    t = jnp.linspace(0.0, 2.0, T_STEP.size)  # same shapes as the other runs: one compilation
    p0, tr = 180.0, 1.4
    run = vs.inflate(t, pressure=p0, **GEO, C=C, alpha=0.0, branches=[(0.0, 5.0)], ramp_time=tr)
    p_t = p0 * np.minimum(np.asarray(t) / tr, 1.0)
    ref = np.asarray(bl.inner_stretch(p_t, **GEO, C=C, alpha=0.0))
    # the pressure constraint is integrated in rate form: it drifts by ~rtol over the history
    np.testing.assert_allclose(np.asarray(run.inner_stretch), ref, rtol=1e-8)


def test_callable_pressure_elastic_and_fast_ramp_is_glassy():
    t = jnp.linspace(0.0, 5.0, T_STEP.size)
    p_fun = lambda s: 300.0 * (1.0 - jnp.exp(-s))
    run = vs.inflate(t, pressure=p_fun, **GEO, C=C, alpha=0.2, branches=None)
    ref = np.asarray(bl.inner_stretch(np.asarray(p_fun(t)), **GEO, C=C, alpha=0.2))
    np.testing.assert_allclose(np.asarray(run.inner_stretch), ref, rtol=1e-8)
    # a ramp 1000x faster than tau ends close to the instantaneous (glassy) response
    beta, tau, p0 = 1.2, 200.0, 150.0
    t = jnp.linspace(0.0, 0.2, T_STEP.size)
    run = vs.inflate(t, pressure=p0, **GEO, C=C, alpha=0.2, branches=[(beta, tau)], ramp_time=0.2)
    inst = float(bl.inner_stretch(p0, **GEO, C=(1 + beta) * C, alpha=0.2))
    relaxed = float(bl.inner_stretch(p0, **GEO, C=C, alpha=0.2))
    la = float(run.inner_stretch[-1])
    assert inst < la < inst + 2e-3 * (relaxed - inst)


def test_creep_past_the_limit_point_bursts():
    # neo-Hookean: relaxed limit ~197 Pa, instantaneous ~434 Pa; 250 Pa holds at first, then bursts
    with pytest.raises(RuntimeError, match="bursts"):
        vs.inflate(T_STEP, pressure=250.0, **GEO, C=C, alpha=0.0, branches=[(1.2, 200.0)])


@pytest.mark.parametrize(
    "kw,match",
    [
        (dict(t=[-1.0, 1.0]), "t"),
        (dict(t=[2.0, 1.0]), "ascending"),
        (dict(ramp_time=0.0), "ramp_time"),
        (dict(ramp_time=-1.0), "ramp_time"),
        (dict(branches=[(1.0, 0.0)]), "tau"),
        (dict(branches=[(-1.0, 10.0)]), "beta"),
        (dict(branches=[(1.0,)]), "pair"),
        (dict(pressure=float("nan")), "pressure"),
        (dict(C=0.0), "C"),
        (dict(alpha=-0.2), "alpha"),
        (dict(inner_radius=80e-6), "inner_radius"),
        (dict(pressure=1000.0), "instantaneous"),
    ],
)
def test_bad_inputs_raise(kw, match):
    args = dict(t=[0.0, 1.0], pressure=100.0, **GEO, C=C, alpha=0.0, branches=[(1.0, 10.0)])
    args.update(kw)
    t = args.pop("t")
    with pytest.raises(ValueError, match=match):
        vs.inflate(t, **args)


def _recursion_reference(p_of_t, t_end, dt, alpha, beta, tau, n_nodes=16):
    """Independent check: the physics.md S-based recursion (exact for S_iso linear over a step),
    Q^{n+1} = e^{-dt/tau} Q^n + beta (1 - e^{-dt/tau})/(dt/tau) (S^{n+1} - S^n), at Gauss points in
    log R, with the pressure balance solved for lambda_a at every step (brentq). Plain NumPy."""
    from scipy.optimize import brentq

    x, w = np.polynomial.legendre.leggauss(n_nodes)
    uA, uB = np.log(A), np.log(B)
    R = np.exp(0.5 * (uA + uB) + 0.5 * (uB - uA) * x)
    wu = 0.5 * (uB - uA) * w

    def fields(la):
        l = (1 + (la**3 - 1) * (A / R) ** 3) ** (1 / 3)
        I1 = 2 * l**2 + l**-4
        w1 = np.exp(alpha * (I1 - 3))  # W'(I1)/C
        S = np.array([2 * w1 * (1 - I1 * l**4 / 3), 2 * w1 * (1 - I1 * l**-2 / 3)])  # (S_rr, S_tt)/C
        return l, w1, S

    def P(la, Q):
        l, w1, _ = fields(la)
        dsig = 2 * w1 * (l**2 - l**-4) + l**2 * Q[1] - l**-4 * Q[0]
        return np.sum(wu * 2 * dsig / l**3)

    la, Q, S_old = 1.0, np.zeros((2, n_nodes)), fields(1.0)[2]
    a = np.exp(-dt / tau)
    g = beta * (1 - a) / (dt / tau)
    out = {}
    for n in range(1, int(round(t_end / dt)) + 1):
        t = n * dt
        Q_of = lambda la_: a * Q + g * (fields(la_)[2] - S_old)
        la = brentq(lambda la_: P(la_, Q_of(la_)) - p_of_t(t) / C, 0.9, 4.0, xtol=1e-14)
        Q, S_old = Q_of(la), fields(la)[2]
        out[round(t, 9)] = la
    return out


def test_matches_the_s_based_recursion_of_the_fe():
    """The DAE (diffrax) and the FE-style S-based recursion (dt = 0.05 s) agree to O(dt^2) on ramp + hold."""
    beta, tau, alpha, p0, tr = 1.2, 20.0, 0.2, 150.0, 2.0
    t_out = np.array([1.0, 2.0, 5.0, 10.0, 20.0, 40.0])
    ref = _recursion_reference(lambda s: p0 * min(s / tr, 1.0), t_out[-1], 0.05, alpha, beta, tau)
    t = jnp.asarray(np.concatenate([[0.0], t_out, [41.0]]))  # 8 outputs: shares the compiled ramp solve
    run = vs.inflate(t, pressure=p0, **GEO, C=C, alpha=alpha, branches=[(beta, tau)], ramp_time=tr)
    la = np.asarray(run.inner_stretch)[1:-1]
    # observed 1.2e-7 at dt = 0.05 s and 4.9e-7 at dt = 0.1 s (second order in dt)
    np.testing.assert_allclose(la, [ref[round(s, 9)] for s in t_out], rtol=5e-7)
