"""Exact parameter sensitivities of the FE (``fem.sensitivity``): against central differences of whole runs at
tight Newton tolerance, and for the blastula against the exact shell's JAX gradient under mesh refinement."""

from __future__ import annotations

import jax
import numpy as np
import pytest
import scipy.sparse as sp

from tissuemech.fem import blastula as fb
from tissuemech.fem import sensitivity as sens
from tissuemech.reduced import blastula as rb

A, B, C, ALPHA = 100e-6, 130e-6, 100.0, 0.5
P = np.array([20.0, 60.0, 100.0])


def _exact(name: str) -> np.ndarray:
    out = []
    for p in P:
        kw = {"C": C, "alpha": ALPHA}

        def f(v, p=p, kw=kw):
            return rb.inner_stretch(p, inner_radius=A, outer_radius=B, **{**kw, name: v})

        out.append(float(jax.grad(f)(kw[name])))
    return np.array(out)


def perturbed(base, branches, name, value):
    """(parameters, branches) with ``name`` ("C", "alpha", ..., "beta_m" or "tau_m", m from 1) set to ``value``."""
    p, b = dict(base), [list(x) for x in branches]
    if name in p:
        p[name] = value
    else:
        kind, m = name.split("_")
        b[int(m) - 1][0 if kind == "beta" else 1] = value
    return p, [tuple(x) for x in b]


@pytest.fixture(scope="module")
def gradients():
    return {
        mesh: fb.inflate(inner_radius=A, outer_radius=B, C=C, alpha=ALPHA, pressures=P, mesh=mesh, gradient=True)
        for mesh in ("coarse", "default", "fine")
    }


@pytest.mark.parametrize("name", ["C", "alpha"])
def test_blastula_gradient_equals_central_differences_of_whole_runs(gradients, name):
    """d lambda_a / d theta at every pressure to 1e-6 (measured ~1e-8) of a central difference of two full
    runs at rtol 1e-13 (step 1e-4 theta: truncation ~1e-8)."""
    value = {"C": C, "alpha": ALPHA}[name]
    h = 1e-4 * value

    def run(v):
        kw = {"C": C, "alpha": ALPHA, name: v}
        return fb.inflate(inner_radius=A, outer_radius=B, pressures=P, rtol=1e-13, **kw).inner_stretch

    fd = (run(value + h) - run(value - h)) / (2 * h)
    np.testing.assert_allclose(gradients["default"].gradient[name], fd, rtol=1e-6)


@pytest.mark.parametrize("name", ["C", "alpha"])
def test_blastula_gradient_converges_to_the_exact_shells(gradients, name):
    """Against jax.grad of the exact incompressible shell: the discretisation error falls by >= 8x per
    refinement (measured ~16x: 4th order) and is below 5e-6 on the fine mesh."""
    ex = _exact(name)
    err = [np.max(np.abs(gradients[m].gradient[name] / ex - 1)) for m in ("coarse", "default", "fine")]
    assert err[0] / err[1] > 8 and err[1] / err[2] > 8, err
    assert err[2] < 5e-6


def test_no_gradient_unless_asked():
    r = fb.inflate(inner_radius=A, outer_radius=B, C=C, alpha=ALPHA, pressures=P[:1])
    assert r.gradient is None


def test_refined_solve_reaches_the_exact_tangent_from_a_nearby_factor():
    rng = np.random.default_rng(0)
    n = 40
    K = sp.csr_matrix(np.eye(n) * 4 + rng.normal(scale=0.3, size=(n, n)))
    near = np.linalg.inv(K.toarray() + rng.normal(scale=0.05, size=(n, n)))
    b = rng.normal(size=n)
    x = sens.refined(K, lambda v: near @ v)(b)
    np.testing.assert_allclose(K @ x, b, rtol=0, atol=1e-10)


def test_a_singular_tangent_names_the_state():
    K = sp.csr_matrix(np.diag([1.0, 0.0]))
    with pytest.raises(RuntimeError, match="p = 7 Pa"):
        sens.solve_all(K, {"C": np.ones(2)}, "p = 7 Pa")


# ---- the plates: static compression on contact-edge-fitted meshes and on a fixed mesh ---------------------------
A0, CP, AP, GP = 100e-6, 150.0, 0.8, 1e-3
PLATES = dict(radius=A0, displacement=40e-6, ramp_time=1.0, end_time=1.0, static=True, n_static=4, mesh="coarse")


def _plate_fd(name: str, contact: str, **kw):
    from tissuemech.fem import spheroid as fs

    base = {"C": CP, "alpha": AP, "surface_tension": GP}
    h = 1e-4 * base[name]

    def run(v):
        return fs.compress(rtol=1e-13, contact=contact, **{**base, name: v}, **PLATES, **kw)

    rp, rm = run(base[name] + h), run(base[name] - h)
    return {o: (getattr(rp, o) - getattr(rm, o)) / (2 * h) for o in ("force", "midplane_radius", "nominal_stress")}


@pytest.fixture(scope="module")
def plate_gradients():
    from tissuemech.fem import spheroid as fs

    return {
        c: fs.compress(C=CP, alpha=AP, surface_tension=GP, contact=c, gradient=True, **PLATES)
        for c in ("fitted", "nodal")
    }


@pytest.mark.slow
@pytest.mark.parametrize("contact", ["fitted", "nodal"])
@pytest.mark.parametrize("name", ["C", "alpha", "surface_tension"])
def test_plate_gradient_equals_central_differences_of_whole_runs(plate_gradients, contact, name):
    """dF/dtheta, d r_mid/dtheta, d sigma~/dtheta of static compressions (4 states to 0.2 of the diameter, with
    surface tension) against central differences of whole runs at rtol 1e-13: within 1e-5 at every state
    (measured 1e-10 - 3e-6; the fitted edge found to EDGE_TOL = 1e-6 limits the differences, not the gradient).
    On fitted meshes the edge's motion matters: the force is not stationary in it (without that term alpha's
    sensitivity was 5 % off)."""
    fd = _plate_fd(name, contact)
    g = plate_gradients[contact].gradient[name]
    for obs in ("force", "nominal_stress"):
        np.testing.assert_allclose(g[obs], fd[obs], rtol=1e-5, err_msg=obs)
    scale = np.max(np.abs(fd["midplane_radius"]))
    np.testing.assert_allclose(g["midplane_radius"], fd["midplane_radius"], rtol=1e-5, atol=1e-5 * scale)


def test_plate_gradient_of_the_scaling_in_C():
    """Without surface tension and with kappa -> its share only, F = C a0^2 f(alpha, kappa / C): dF/dC = F / C up to
    the compressibility term, which is ~1e-9 of it at kappa / C = 1.5e7."""
    from tissuemech.fem import spheroid as fs

    r = fs.compress(C=CP, alpha=AP, gradient=True, **{**PLATES, "n_static": 2})
    np.testing.assert_allclose(r.gradient["C"]["force"], r.force / CP, rtol=1e-6)
    assert np.all(r.gradient["surface_tension"]["force"] > 0)  # a tension adds to the plate force


@pytest.mark.slow
def test_time_run_gradient_equals_central_differences_of_whole_runs():
    """A relaxation with two branches (one as fast as the ramp) and surface tension on one fixed mesh with
    node-by-node contact: d force / d theta for C, alpha, gamma and each branch's beta and tau through the time
    steps (the Maxwell history's sensitivity carried) within 1e-6 of the largest central difference of whole
    runs at rtol 1e-13 at every step (measured <= 1.1e-7)."""
    from tissuemech.fem import spheroid as fs

    base = {"C": 150.0, "alpha": 1.2, "surface_tension": 1e-3}
    br = [(0.8, 0.05), (0.3, 20.0)]
    kw = dict(
        radius=A0, displacement=30e-6, ramp_time=0.2, end_time=20.0, mesh="coarse", contact="nodal", n_ramp=4, n_hold=6
    )
    g = fs.compress(branches=br, gradient=True, **base, **kw).gradient
    values = {**base, "beta_1": 0.8, "tau_1": 0.05, "beta_2": 0.3, "tau_2": 20.0}

    def run(name, v):
        p, b = perturbed(base, br, name, v)
        return fs.compress(branches=b, rtol=1e-13, **p, **kw).force

    for name, v in values.items():
        h = 1e-4 * v
        fd = (run(name, v + h) - run(name, v - h)) / (2 * h)
        assert np.max(np.abs(g[name]["force"] - fd)) <= 1e-6 * np.max(np.abs(fd)), name


def test_time_run_gradient_names_one_branch_as_the_fit_does():
    from tissuemech.fem import spheroid as fs

    kw = dict(radius=A0, C=CP, alpha=AP, displacement=20e-6, ramp_time=1.0, end_time=5.0, mesh="coarse")
    r = fs.compress(branches=[(0.5, 2.0)], contact="nodal", gradient=True, n_ramp=2, n_hold=3, **kw)
    assert set(r.gradient) == {"C", "alpha", "beta", "tau"}
    assert np.all(r.gradient["beta"]["force"] > 0)  # a stiffer branch pushes back harder at every step


@pytest.mark.parametrize("alpha", [0.2, 1.4])
def test_closed_form_stress_derivative_equals_the_stress_differences(alpha):
    """The isochoric second Piola stress and its directional derivative in closed form (what the time runs' sensitivities
    use) equal the constitutive module's stress and its central differences (step 1e-6: truncation ~1e-12)."""
    from tissuemech.fem import constitutive as cm

    rng = np.random.default_rng(3)
    f = np.array([1.0, 0.0, 0.0, 1.0, 1.0]) + 0.2 * rng.standard_normal((40, 5))
    lin = sens.IsoLinearisation(f, 1.0, alpha)
    np.testing.assert_allclose(lin.S, cm.iso_second_piola(f, 1.0, alpha), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(lin.P, cm.iso_stress(f, 1.0, alpha)[0], rtol=1e-12, atol=1e-12)
    df = rng.standard_normal((3, 40, 5))
    h = 1e-6
    fd = np.stack([(cm.iso_second_piola(f + h * d, 1.0, alpha) - cm.iso_second_piola(f - h * d, 1.0, alpha)) / (2 * h)
                   for d in df])  # fmt: skip
    assert np.max(np.abs(lin.dS(df) - fd)) <= 1e-8 * np.max(np.abs(fd))
    fa = (cm.iso_second_piola(f, 1.0, alpha + h) - cm.iso_second_piola(f, 1.0, alpha - h)) / (2 * h)
    assert np.max(np.abs(lin.d_alpha[..., None] * lin.S - fa)) <= 1e-8 * np.max(np.abs(fa))


def test_block_solve_refines_from_a_nearby_factor_and_names_a_singular_state():
    from tissuemech.fem.linalg import symmetric_factor

    rng = np.random.default_rng(0)
    n = 60
    M = sp.random(n, n, density=0.1, random_state=1)
    K = sp.csr_matrix(M @ M.T + 10 * sp.eye(n))
    near = symmetric_factor(sp.csr_matrix(K + 0.05 * sp.eye(n)))
    b = rng.standard_normal((n, 3))
    X, _, its = sens.solve_block(K, near, b, "t = 1 s", tol=1e-12, max_iter=10)
    assert its > 0  # refined, not factored again
    np.testing.assert_allclose(K @ X, b, atol=1e-10 * np.max(np.abs(b)))
    with pytest.raises(RuntimeError, match="t = 2 s"):
        sens.solve_block(sp.csr_matrix((n, n)), None, b, "t = 2 s")


CREEP = dict(radius=A0, force=3e-6, ramp_time=1.0, end_time=30.0, mesh="coarse", contact="nodal", n_ramp=4, n_hold=8)


def test_force_control_gradient_moves_the_approach_not_the_force():
    """Under force control the force is prescribed: its gradient is 0; a stiffer material (C, beta) gives a smaller
    approach at every step, and the nominal stress F / (pi r_mid^2) falls as the midplane widens."""
    from tissuemech.fem import spheroid as fs

    r = fs.compress(C=150.0, alpha=1.4, branches=[(0.5, 2.0)], gradient=True, **{**CREEP, "n_hold": 3})
    g = r.gradient
    assert set(g) == {"C", "alpha", "beta", "tau"}
    for name in g:
        assert np.all(g[name]["force"] == 0.0)
        rm, F = r.midplane_radius, r.force
        np.testing.assert_allclose(
            g[name]["nominal_stress"], -2 * F / (np.pi * rm**3) * g[name]["midplane_radius"], rtol=1e-12
        )
    assert np.all(g["C"]["approach"] < 0) and np.all(g["beta"]["approach"] < 0)


@pytest.mark.slow
def test_force_control_gradient_equals_central_differences_of_whole_runs():
    """A creep under force control (3 uN, alpha = 1.4, two branches, coarse, node by node): d approach / d theta,
    d r_mid / d theta and d sigma~ / d theta for C, alpha and each branch's beta and tau within 1e-6 of the largest
    central difference of whole runs at rtol 1e-13 (force control then to 1e-10) at every step (measured <= 4e-7:
    the nominal stress's differences carry the force tolerance)."""
    from tissuemech.fem import spheroid as fs

    base = {"C": 150.0, "alpha": 1.4}
    br = [(0.8, 0.5), (0.3, 20.0)]
    g = fs.compress(branches=br, gradient=True, **base, **CREEP).gradient
    values = {**base, "beta_1": 0.8, "tau_1": 0.5, "beta_2": 0.3, "tau_2": 20.0}

    def run(name, v):
        p, b = perturbed(base, br, name, v)
        return fs.compress(branches=b, rtol=1e-13, **p, **CREEP)

    for name, v in values.items():
        h = 1e-4 * v
        rp, rm = run(name, v + h), run(name, v - h)
        for obs in ("approach", "midplane_radius", "nominal_stress"):
            fd = (getattr(rp, obs) - getattr(rm, obs)) / (2 * h)
            assert np.max(np.abs(g[name][obs] - fd)) <= 1e-6 * np.max(np.abs(fd)), (name, obs)


@pytest.mark.slow
def test_force_removed_gradient_follows_the_free_top():
    """A force history that removes the force (3 uN held 4 s, then 0: the plates leave the recovering ball, whose
    approach is the plate touching its top): d approach / d theta within 1e-6 of the largest central difference of
    whole runs at every step, the free steps included (measured <= 1.1e-7)."""
    from tissuemech.fem import spheroid as fs

    F = (np.array([0.0, 1.0, 5.0, 5.5, 12.0]), np.array([0.0, 3e-6, 3e-6, 0.0, 0.0]))
    kw = dict(radius=A0, force=F, mesh="coarse", contact="nodal", n_ramp=4, alpha=1.0)
    r = fs.compress(C=150.0, branches=[(0.8, 2.0)], gradient=True, **kw)
    assert not r.in_contact[-1]
    for name, v in {"C": 150.0, "beta": 0.8, "tau": 2.0}.items():
        h = 1e-4 * v

        def run(x, name=name):
            p = {"C": 150.0, "branches": [(0.8, 2.0)]}
            if name == "C":
                p["C"] = x
            else:
                p["branches"] = [(x, 2.0)] if name == "beta" else [(0.8, x)]
            return fs.compress(rtol=1e-13, **p, **kw).approach

        fd = (run(v + h) - run(v - h)) / (2 * h)
        assert np.max(np.abs(r.gradient[name]["approach"] - fd)) <= 1e-6 * np.max(np.abs(fd)), name


@pytest.mark.slow
def test_the_contact_edge_carries_alpha_s_sensitivity_on_fitted_meshes():
    """Why a time run's gradient on fitted meshes carries the edge's motion (``fem.fitted_sensitivity``): with every
    step's contact edge (its mesh and the history's transfer) frozen at the unperturbed run's, d force / d alpha
    changes at the percent level (the edge is no stationary point of the force), while C (a scale of the scaled
    problem) moves no edge; nor is the node-by-node run's gradient a stand-in for the fitted run's."""
    from tissuemech.compare.bench.fem_gradient import edge_share

    fixed = dict(radius=A0, displacement=30e-6, ramp_time=0.2, end_time=20.0, mesh="coarse", n_ramp=4, n_hold=6)
    share = edge_share(fixed, {"C": CP, "alpha": AP}, [(0.5, 2.0)])
    assert share["C"][0] < 1e-6
    assert share["alpha"][0] > 1e-3
    assert share["alpha"][1] > 1e-3  # nor is the node-by-node gradient a stand-in for the fitted run's


def test_time_run_refactors_after_slow_refinements_with_the_same_gradients(monkeypatch):
    """Fig. 10 on level 0: a step whose block solve took >= REFACTOR_AFTER refinement iterations has the next step's
    tangent factored afresh (-1 in the solve log), which then refines in fewer iterations; the gradients equal those
    of the run that never refactors to the solves' tolerance (1e-7 relative)."""
    from tissuemech.compare.bench.fem_gradient import refinement_log
    from tissuemech.compare.cases import FIG10, FIG10_END_TIME
    from tissuemech.fem import spheroid as fs

    kw = dict(FIG10, end_time=FIG10_END_TIME, mesh=0, contact="nodal")
    rule = fs.REFACTOR_AFTER
    got: dict = {}
    with_rule = refinement_log(lambda: got.update(rule=fs.compress(**kw, gradient=True).gradient))
    monkeypatch.setattr(fs, "REFACTOR_AFTER", 10**9)
    without = refinement_log(lambda: got.update(none=fs.compress(**kw, gradient=True).gradient))
    slow = [i for i, its in enumerate(with_rule[:-1]) if its >= rule]
    assert slow and all(with_rule[i + 1] == -1 for i in slow)
    solves = lambda log: sum(i + 1 if i >= 0 else 1 for i in log)
    assert solves(with_rule) < solves(without)
    for name in ("C", "alpha", "beta", "tau"):
        a, b = got["rule"][name]["force"], got["none"][name]["force"]
        assert np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(b)), name
