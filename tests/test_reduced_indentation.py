"""reduced.indentation: two Hertz contacts in series, the half-space limit, the lumped relaxation, gradients."""

import json
import math
from pathlib import Path

import diffrax
import jax
import numpy as np
import pytest
from scipy.integrate import quad

from tissuemech.reduced import indentation as ind
from tissuemech.reduced import spheroid

A0, RP, C = 40e-6, 5e-6, 500.0
TSIT5 = diffrax.Tsit5()  # the explicit solver compiles in half the time of the default Kvaerno5


def test_two_contacts_in_series_closed_form():
    # same force through both Hertz contacts: d_i = (F / k_i)^(2/3), k_i = (4/3) E* sqrt(R_i), E* = 8 C
    d = 1.2e-6
    F = float(ind.equilibrium_force(d, radius=A0, probe_radius=RP, C=C, law="hertz"))
    estar = 8.0 * C  # E = 6 C (mu = 2 C, incompressible), E* = E / (1 - 1/4)
    r1, r2 = RP * A0 / (RP + A0), A0
    k1, k2 = (4 / 3) * estar * math.sqrt(r1), (4 / 3) * estar * math.sqrt(r2)
    d1, d2 = (F / k1) ** (2 / 3), (F / k2) ** (2 / 3)
    assert d1 + d2 == pytest.approx(d, rel=1e-12)
    c1, c2 = ind.contact_depths(d, radius=A0, probe_radius=RP)
    assert float(c1) == pytest.approx(d1, rel=1e-12) and float(c2) == pytest.approx(d2, rel=1e-12)


def test_half_space_limit_and_plates():
    d = 0.3e-6
    half = float(ind.equilibrium_force(d, radius=math.inf, probe_radius=RP, C=C))
    assert half == pytest.approx((4 / 3) * 8 * C * math.sqrt(RP) * d**1.5, rel=1e-13)
    # a0 -> inf: the deficit is the ball-plate contact, 1 - F/F_half ~ (3/2) (R_p / a0)^(1/3) (slow, 1/3 power)
    for a0 in (1e-2, 1e1, 1e4):
        big = float(ind.equilibrium_force(d, radius=a0, probe_radius=RP, C=C, law="hertz"))
        assert 1 - big / half == pytest.approx(1.5 * (RP / a0) ** (1 / 3), rel=3 * (RP / a0) ** (1 / 3))
    # R_1 = R_2 = a0 (a probe as large as... a plate is R_p -> inf): the spheroid's two-plate Hertz law
    plates = float(ind.equilibrium_force(d, radius=A0, probe_radius=1e9, C=C, law="hertz"))
    ref = float(spheroid.equilibrium_force(d, radius=A0, C=C, alpha=0.0, equilibrium="hertz"))
    assert plates == pytest.approx(ref, rel=1e-6)


def test_relaxation_after_ramp_matches_quadrature():
    beta, tau, tr, d = 1.5, 2.0, 1.0, 1e-6
    t = np.array([0.5, 1.0, 3.0, 10.0])
    F = np.asarray(
        ind.force(t, radius=A0, probe_radius=RP, C=C, branches=[(beta, tau)], displacement=d, ramp_time=tr, law="hertz")
    )
    K = (32 / 3) * C * math.sqrt(float(ind.series_radius(A0, RP)))  # F_eq = K delta^1.5

    def ref(tt):
        s_end = min(tt, tr)
        v = d / tr
        q = quad(lambda s: math.exp(-(s_end - s) / tau) * 1.5 * K * v**1.5 * math.sqrt(s), 0, s_end, epsabs=0)[0]
        return K * (v * s_end) ** 1.5 + beta * q * math.exp(-max(tt - tr, 0) / tau)

    assert np.allclose(F, [ref(tt) for tt in t], rtol=1e-8)


def test_measured_history_linear_equilibrium_closed_form():
    # delta(t) = D (t/tr)^(2/3): F_eq grows linearly in t (a linear equilibrium in time), so the standard
    # linear solid's closed form holds: q(tr) = beta tau F_max / tr (1 - e^{-tr/tau}), then e^{-(t-tr)/tau}
    beta, tau, tr, D = 0.8, 0.7, 1.0, 0.8e-6
    th = np.concatenate([np.linspace(0, tr, 801), [tr + 20.0]])
    dh = D * np.minimum(th / tr, 1.0) ** (2 / 3)
    t = np.array([0.25, 0.5, 1.0, 2.0, 5.0])
    F = np.asarray(
        ind.force(
            t, radius=A0, probe_radius=RP, C=C, branches=[(beta, tau)], displacement=(th, dh), solver=TSIT5, law="hertz"
        )
    )
    Fm = float(ind.equilibrium_force(D, radius=A0, probe_radius=RP, C=C, law="hertz"))
    rate = Fm / tr
    ramp = lambda s: rate * s + beta * tau * rate * (1 - np.exp(-s / tau))
    ref = np.where(t <= tr, ramp(t), Fm + (ramp(tr) - Fm) * np.exp(-(t - tr) / tau))
    assert np.allclose(F, ref, rtol=2e-4)


@pytest.mark.slow
def test_history_agrees_with_ramp_and_hold():
    t = np.linspace(0.0, 20.0, 41)
    kw = dict(radius=A0, probe_radius=RP, C=C, branches=[(2.0, 3.0)], law="hertz")
    F = np.asarray(ind.force(t, **kw, displacement=1e-6, ramp_time=1.0))
    th = np.array([0.0, 1.0, 20.0])
    G = np.asarray(ind.force(t, **kw, displacement=(th, np.array([0.0, 1e-6, 1e-6])), solver=TSIT5))
    assert np.max(np.abs(F - G)) < 1e-7 * np.max(F)


def test_gradients_against_finite_differences():
    t = np.array([0.5, 1.0, 4.0])

    def total(p):
        c, beta, tau, rp = p
        return ind.force(
            t, radius=A0, probe_radius=rp, C=c, branches=[(beta, tau)], displacement=1e-6, ramp_time=1.0, law="hertz"
        ).sum()

    p0 = np.array([C, 1.2, 2.0, RP])
    g = np.asarray(jax.grad(total)(p0))
    for i in range(4):
        h = 1e-6 * p0[i]
        e = np.zeros(4)
        e[i] = h
        fd = (float(total(p0 + e)) - float(total(p0 - e))) / (2 * h)
        assert g[i] == pytest.approx(fd, rel=1e-6)


@pytest.mark.slow
def test_history_jacobian_against_finite_differences():
    # the fit's Jacobian: jacfwd (forward-mode diffrax sensitivities) through a measured history
    th = np.array([0.0, 0.3, 0.7, 1.0, 4.0, 10.0])
    dh = np.array([0.0, 0.2e-6, 0.6e-6, 1.0e-6, 1.05e-6, 1.1e-6])
    t = np.array([0.5, 1.0, 2.0, 8.0])

    def f(p):
        c, beta, tau = p
        return ind.force(
            t,
            radius=A0,
            probe_radius=RP,
            C=c,
            branches=[(beta, tau)],
            displacement=(th, dh),
            adjoint="forward",
            solver=TSIT5,
            law="hertz",
        )

    p0 = np.array([C, 1.2, 2.0])
    J = np.asarray(jax.jacfwd(f)(p0))
    for i in range(3):
        e = np.zeros(3)
        e[i] = 1e-5 * p0[i]
        fd = (np.asarray(f(p0 + e)) - np.asarray(f(p0 - e))) / (2 * e[i])
        assert np.allclose(J[:, i], fd, rtol=1e-5, atol=1e-8 * np.max(np.abs(fd)))


def test_vmap_and_jit():
    t = np.linspace(0, 5, 11)
    f = jax.jit(
        jax.vmap(
            lambda c: ind.force(
                t, radius=A0, probe_radius=RP, C=c, branches=[(1.0, 1.0)], displacement=1e-6, ramp_time=1.0, law="hertz"
            )
        )
    )
    out = np.asarray(f(np.array([100.0, 200.0])))
    assert out.shape == (2, 11) and np.allclose(out[1], 2 * out[0], rtol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        (dict(probe_radius=-1e-6), "probe_radius"),
        (dict(radius=0.0), "radius (of the indented ball"),
        (dict(C=-1.0), "C (the Fung stiffness"),
        (dict(displacement=1e-3), "effective radius"),
        (dict(displacement=(np.array([0.0, 1.0]), np.array([1e-7, 1e-6]))), "first contact"),
        (dict(displacement=(np.array([0.0, 1.0]), np.array([0.0, -1e-6]))), "must not be negative"),
        (dict(ramp_time=None), "ramp_time"),
    ],
)
def test_bad_inputs_name_quantity_and_unit(kwargs, words):
    kw = dict(radius=A0, probe_radius=RP, C=C, displacement=1e-6, ramp_time=1.0)
    kw.update(kwargs)
    with pytest.raises(ValueError, match=words.replace("(", r"\(")):
        ind.force(np.array([0.5]), **kw)


# ---------------------------------------------------------------- the FE-calibrated table


def _synthetic_table():
    y = np.array([0.0, 0.0125, 0.025, 0.05, 0.075, 0.1])
    alpha, rho = np.array([0.0, 0.5, 1.5]), np.array([0.05, 0.2, 1.0])
    c = lambda r, a: 0.05 + 0.02 * np.log(r) + 0.01 * a  # a smooth h - 1 = c sqrt(y)
    h = np.array([[1.0 + c(r, a) * np.sqrt(y) for a in alpha] for r in rho])
    return ind.MasterTable(y, alpha, rho, h, metadata={"discretisation_error": 1e-5}), c


def test_master_table_reproduces_its_nodes_and_raises_outside():
    tab, c = _synthetic_table()
    for r in tab.rho:
        x = ind.x_of_depth_ratio(tab.y[1:], r)
        assert np.allclose(ind.depth_ratio(x, r), tab.y[1:], rtol=1e-14)
        for a in tab.alpha:
            assert np.allclose(tab(x, a, r), 1.0 + c(r, a) * np.sqrt(tab.y[1:]), rtol=1e-12)
    # between the nodes the splines (ln rho, sqrt y, alpha) follow the smooth h
    r, a = 0.45, 0.8
    x = ind.x_of_depth_ratio(np.array([0.04, 0.09]), r)
    assert np.allclose(tab(x, a, r), 1.0 + c(r, a) * np.sqrt([0.04, 0.09]), rtol=2e-4)
    with pytest.raises(ValueError, match=r"probe_radius / radius = 2 is outside .* law='hertz'"):
        tab.check(0.001, 0.0, 2.0)
    with pytest.raises(ValueError, match=r"delta / \(2 a0\) = .* beyond the calibrated indentation table"):
        tab.check(float(tab.x_max(0.2)) * 1.01, 0.0, 0.2)
    with pytest.raises(ValueError, match=r"alpha \(Fung exponent, -\) = 2 is outside"):
        tab.check(0.001, 2.0, 0.2)


def test_table_law_is_the_equilibrium_of_the_lumped_force():
    tab = ind.master_table()
    assert tab.metadata["discretisation_error"] < 2e-5 and tab.y[0] == 0.0
    rho, a = float(tab.rho[2]), float(tab.alpha[1])
    a0 = 50e-6
    d = 2 * a0 * float(ind.x_of_depth_ratio(tab.y[3], rho))  # a node
    kw = dict(radius=a0, probe_radius=rho * a0, C=C, alpha=a)
    F = float(ind.equilibrium_force(d, **kw, law="table"))
    hz = float(ind.equilibrium_force(d, **kw, law="hertz"))
    assert F / hz == pytest.approx(tab.h[2, 1, 3], rel=1e-12) and F > hz
    assert float(ind.equilibrium_force(d, **kw)) == F  # auto: the table inside its range
    # elastic ball: the lumped force is the equilibrium law at every time, branches relax to it
    t = np.array([0.5, 1.0, 50.0])
    Fe = np.asarray(ind.force(t, **kw, displacement=d, ramp_time=1.0))
    assert np.allclose(Fe[1:], F, rtol=1e-10) and Fe[0] < F
    Fb = np.asarray(ind.force(t, **kw, branches=[(1.0, 0.5)], displacement=d, ramp_time=1.0))
    assert Fb[1] > F and Fb[2] == pytest.approx(F, rel=1e-10)


def test_auto_law_outside_the_table_and_under_jit():
    tab = ind.master_table()
    d = 0.2e-6
    half = float(ind.equilibrium_force(d, radius=math.inf, probe_radius=RP, C=C))  # half-space: Hertz
    assert half == pytest.approx((4 / 3) * 8 * C * math.sqrt(RP) * d**1.5, rel=1e-13)
    big = 2 * tab.rho_range[1]  # a probe larger than the table's
    kw = dict(radius=A0, probe_radius=big * A0, C=C)
    assert float(ind.equilibrium_force(d, **kw)) == float(ind.equilibrium_force(d, **kw, law="hertz"))
    with pytest.raises(ValueError, match="outside the calibrated indentation table"):
        ind.equilibrium_force(d, **kw, law="table")
    deep = dict(radius=A0, probe_radius=RP, C=C, displacement=1e-6, ramp_time=1.0)  # y = 0.15: beyond the table
    with pytest.raises(ValueError, match=r"delta / \(2 a0\) = .* beyond the calibrated indentation table"):
        ind.force(np.array([1.0]), **deep, law="table")
    with pytest.warns(UserWarning, match="Hertz law here: displacement"):
        auto = float(ind.force(np.array([1.0]), **deep)[0])
    assert auto == float(ind.force(np.array([1.0]), **deep, law="hertz")[0])
    with pytest.raises(ValueError, match="alpha .* outside the calibrated indentation table"):
        ind.equilibrium_force(d, radius=A0, probe_radius=RP, C=C, alpha=2.0, law="table")
    with pytest.raises(ValueError, match="law must be one of"):
        ind.equilibrium_force(d, radius=A0, probe_radius=RP, C=C, law="fem")
    # a traced geometry: auto is the Hertz law, 'table' refuses
    f = jax.jit(lambda rp: ind.equilibrium_force(d, radius=A0, probe_radius=rp, C=C))
    assert float(f(RP)) == pytest.approx(float(ind.equilibrium_force(d, radius=A0, probe_radius=RP, C=C, law="hertz")))
    with pytest.raises(ValueError, match="law='table' needs concrete radius and probe_radius"):
        jax.jit(lambda rp: ind.equilibrium_force(d, radius=A0, probe_radius=rp, C=C, law="table"))(RP)
    # traced C and alpha with a concrete geometry: the table, gradients through it
    g = jax.grad(lambda c, a: ind.equilibrium_force(d, radius=A0, probe_radius=RP, C=c, alpha=a), argnums=(0, 1))
    dc, da = g(C, 0.5)
    F = float(ind.equilibrium_force(d, radius=A0, probe_radius=RP, C=C, alpha=0.5))
    assert float(dc) == pytest.approx(F / C, rel=1e-12) and float(da) > 0  # alpha stiffens


REFERENCE = Path(__file__).parent / "data" / "indentation_reference.json"


@pytest.mark.slow
def test_table_against_converged_fe_off_the_nodes():
    """Reduced (table) vs the FE's Richardson limit over levels at a point between the table's nodes in x, alpha
    and rho (tests/data/indentation_reference.json); the level-2 FE state is recomputed here."""
    from tissuemech.fem.indentation import fitted_states

    ref = json.loads(REFERENCE.read_text())
    tab = ind.master_table()
    rho, a, y = ref["rho"], ref["alpha"], ref["y"]
    assert not np.any(np.isclose(tab.rho, rho)) and not np.any(np.isclose(tab.alpha, a))
    assert not np.any(np.isclose(tab.y, y))
    a0, c = ref["radius"], ref["C"]
    d = ref["approach"]
    F = float(ind.equilibrium_force(d, radius=a0, probe_radius=rho * a0, C=c, alpha=a, law="table"))
    assert abs(F / ref["richardson_force"] - 1) < 5e-4  # measured: 5.1e-6
    lv = ref["levels"]["2"]
    r = fitted_states(radius=a0, probe_radius=rho * a0, C=c, alphas=[0.0, a], approaches=lv["approaches"], mesh=2)
    assert float(r["force"][1, -1]) == pytest.approx(lv["force"], rel=1e-7)
