"""fem.problem: the scene machinery shared by the blastula and the spheroid (free dofs, admissibility,
round-off floor, element fields, the Maxwell step closure, mesh specs) and the named result rows."""

import numpy as np
import pytest
import scipy.sparse as sp

from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.continuation import ArcStep, LoadStep, arc_length, load_control
from tissuemech.fem.forms import Material
from tissuemech.fem.mesh import ball_section, shell_section
from tissuemech.fem.newton import newton
from tissuemech.fem.problem import (
    BLASTULA_MARGIN,
    SPHEROID_MARGIN,
    SceneProblem,
    check_mesh,
    free_dofs,
    mesh_spec,
    roundoff_floor,
    secant,
)
from tissuemech.fem.timestepping import Step, TimedState, march

A, B = 50e-6, 75e-6
MAT = Material(1.0, 0.2, 2.2e9 / 200.0)


@pytest.fixture(scope="module")
def shell():
    return SceneProblem(shell_section(A, B, 2, 4), MAT)


def _affine(prob, grad):
    """Full unknown vector of the displacement u = (grad - I) X (q = 0)."""
    X = prob.m.X
    u = (np.asarray(grad) - np.eye(2)) @ X
    x = np.zeros(prob.asm.ndof)
    x[: prob.asm.n_u] = u.T.ravel()
    return x


def test_free_dofs_fix_u_r_on_the_axis_and_u_z_on_the_symmetry_plane(shell):
    m, free = shell.m, shell.free
    fixed = np.setdiff1d(np.arange(shell.asm.ndof), free)
    assert np.array_equal(np.sort(fixed), np.union1d(2 * m.nodes["axis"], 2 * m.nodes["symmetry"] + 1))
    assert np.all(np.isin(np.arange(shell.asm.n_u, shell.asm.ndof), free))  # the q-dofs are all free
    assert np.array_equal(free_dofs(m, shell.asm.ndof), free)
    uf = np.arange(free.size, dtype=float) + 1
    x = shell.full(uf)
    assert np.array_equal(x[free], uf) and not np.any(x[fixed])


def test_admissibility_rejects_inverted_and_hoop_negative_states(shell):
    assert shell.admissible(np.zeros(shell.asm.ndof)) is None
    assert shell.admissible(_affine(shell, np.diag([1.2, 0.9]))) is None
    assert "J <= 0" in shell.admissible(_affine(shell, np.diag([1.0, -1.0])))  # z mirrored: F_zz = -1
    # r -> -r: F_rr = F_theta = -1, J = F_rr F_zz F_theta = +1 > 0, but the hoop stretch is negative
    assert shell.admissible(_affine(shell, np.diag([-1.0, 1.0]))) == "hoop stretch <= 0"


def test_roundoff_floor_rule_and_the_scenes_values():
    eps = np.finfo(float).eps
    assert roundoff_floor(1.1e7, 2.5, 1e3) == 1e3 * eps * 1.1e7 * 2.5
    assert roundoff_floor(0.5) == SPHEROID_MARGIN * eps  # kappa/C below 1: the floor of a unit modulus
    from tissuemech.fem.blastula import shell_problem
    from tissuemech.fem.spheroid import BallProblem

    pb = shell_problem(A, B, 200.0, 0.2, 2.2e9, "coarse")
    assert pb.floor == BLASTULA_MARGIN * eps * max(pb.mat.kappa, 1.0) * pb.ref  # the 0.1 rule, bit for bit
    ps = BallProblem(ball_section(500e-6, 4, 3), Material(1.0, 0.2, 2.2e9 / 150.0), [], [], 1e-10)
    assert ps.floor == SPHEROID_MARGIN * eps * max(ps.mat.kappa, 1.0)


def test_element_fields_of_a_uniform_dilation_with_uniform_q(shell):
    lam, q0, C = 1.1, 0.37, 200.0
    x = _affine(shell, lam * np.eye(2))
    x[shell.asm.qdofs[:, 0]] = q0  # q = q0 in every element (psi_0 = 1)
    _, vm, q = shell.point_stresses(x)
    vm_el, ph_el = shell.element_fields(vm, q, C)
    assert np.allclose(q, q0, rtol=0, atol=1e-15)
    assert np.allclose(ph_el, -q0 * C, rtol=1e-14, atol=0)  # hydrostatic pressure = -mean Cauchy stress, Pa
    assert np.max(np.abs(vm_el)) < 1e-11 * C  # a pure dilation has no deviatoric stress
    u = shell.displacement(x)
    assert np.allclose(shell.deformed_nodes(u), lam * shell.m.X.T * A, rtol=1e-14, atol=0)


def test_maxwell_step_closure_is_the_total_stress_and_decays_exactly_in_a_hold():
    beta, tau = [0.4, 0.7], [2.0, 30.0]
    prob = SceneProblem(shell_section(A, B, 2, 4), MAT, beta=beta, tau=tau)
    s0 = prob.maxwell_initial()
    assert s0.Q.shape == (2,) + prob.asm.w.shape + (5,) and not s0.Q.any()
    x1 = _affine(prob, np.array([[1.15, 0.05], [0.0, 0.9]]))
    dt = 0.5
    iso, extra = prob.maxwell_factors(s0, dt)
    s1 = prob.maxwell_update(s0, dt, x1)
    # the algorithmic stress of the step is the stress after it: iso_scale S_iso + extra_S = S_iso + sum Q
    S1 = prob.asm.iso_S(x1, MAT)
    assert np.allclose(iso * S1 + extra, S1 + ve.branch_stress(s1), rtol=0, atol=1e-14)
    # a hold at fixed strain: every branch decays by e^{-dt/tau_m}
    s2 = prob.maxwell_update(s1, 3.0, x1)
    assert np.allclose(s2.Q, np.exp(-3.0 / np.array(tau))[:, None, None, None] * s1.Q, rtol=1e-14, atol=0)
    assert prob.maxwell_factors(s1, None) == (1.0, None)  # static: elastic
    st = prob.maxwell_update(s1, None, x1)
    assert st.Q is s1.Q and np.array_equal(st.S_iso, S1)
    elastic = SceneProblem(prob.m, MAT)
    assert elastic.maxwell_factors(elastic.maxwell_initial(), dt) == (1.0, None)


def test_secant_predictor_is_exact_on_a_line():
    x0, x1 = np.array([1.0, 2.0]), np.array([1.5, 1.0])
    assert np.allclose(secant(x1, x0, 0.25, 0.5), x1 + 0.5 * (x1 - x0))


def test_mesh_specs_and_mesh_objects():
    names = {"coarse": (2, 4), "fine": (8, 16)}
    assert mesh_spec("fine", names, "a tuple") == (8, 16)
    assert mesh_spec((3, 5), names, "a tuple") == (3, 5)
    with pytest.raises(ValueError, match=r"mesh must be 'coarse', 'fine', a tuple, got 'huge'"):
        mesh_spec("huge", names, "a tuple")
    m = shell_section(A, B, 1, 2)
    assert check_mesh(m, A, "wrong") is m
    with pytest.raises(ValueError, match="wrong scale"):
        check_mesh(m, 2 * A, "wrong scale")
    with pytest.raises(ValueError, match="no surface"):
        check_mesh(m, A, "no surface", tags=("no-such-tag",))


def test_spheroid_observation_is_named_and_balanced():
    from tissuemech.fem.contact import PlateState
    from tissuemech.fem.spheroid import BallProblem, Observation

    a0 = 500e-6
    prob = BallProblem(ball_section(a0, 4, 3), Material(1.0, 0.2, 2.2e9 / 150.0), [0.4], [2.0], 1e-10)
    n = prob.asm.ndof
    act = np.zeros(prob.plane.nodes.size, bool)
    act[0] = True  # the pole
    s0 = PlateState(np.zeros(n), act, prob.maxwell_initial(), 0.0, np.zeros(n), 1.0, None, 0)
    s1, its = prob.step(s0, 0.02, 0.1, None, "test")
    ob = prob.observe(s1)
    assert isinstance(ob, Observation) and its > 0
    assert ob.plate_force > 0 and abs(ob.plate_force - ob.reaction_force) < 1e-6 * ob.plate_force
    assert np.isclose(ob.normal_force.sum(), ob.plate_force, rtol=1e-14)
    assert ob.min_gap > -1e-10 and ob.min_normal_force >= 0
    assert 0 < ob.contact_radius_node <= ob.contact_radius < 1.0 < ob.midplane_radius
    assert ob.von_mises.shape == ob.pressure.shape == prob.asm.w.shape
    assert ob.von_mises.min() >= 0 and ob.mean_von_mises > 0


def test_named_steps_of_march_load_control_and_arc_length():
    def step(t0, s, t1, prev):
        assert prev is None or isinstance(prev, TimedState) and prev.time < t0
        return s + (t1 - t0), 1

    out = march(step, 0.0, [0.5, 1.0])
    assert all(isinstance(st, Step) for st in out)
    assert [st.time for st in out] == [0.5, 1.0] and [st.newton_iterations for st in out] == [1, 1]
    last = out[-1]  # the old attribute names are aliases of the new ones
    assert last.t == last.time and last.iterations == 1
    seconds_alias = (last.wall_s, last.wall_time)
    assert seconds_alias[0] == seconds_alias[1]

    def fun(x, lam):  # x^3 / 3 + x = lam
        return np.array([x[0] ** 3 / 3 + x[0] - lam]), sp.csr_matrix([[x[0] ** 2 + 1]]), np.array([-1.0])

    solve = lambda lam, g: newton(lambda x: fun(x, lam)[:2], g, rtol=1e-13, xtol=1e-13)
    steps = load_control(solve, [0.5, 1.0], np.array([0.0]))
    assert all(isinstance(s, LoadStep) for s in steps) and [s.load for s in steps] == [0.5, 1.0]
    assert abs(steps[-1].solution.x[0] ** 3 / 3 + steps[-1].solution.x[0] - 1.0) < 1e-12
    path = arc_length(fun, np.array([0.0]), 0.0, 0.3, stop=lambda x, lam: lam >= 1.0, rtol=1e-12)
    assert all(isinstance(p, ArcStep) for p in path) and path[-1].load >= 1.0
    assert all(abs(p.x[0] ** 3 / 3 + p.x[0] - p.load) < 1e-10 for p in path) and path[0].newton_iterations > 1
