"""Issue 35: the Maxwell history on contact-edge-fitted meshes rebuilt by replay (fem.contact.replayed_history),
and the time convergence of the fast two-branch case it gives."""

import numpy as np
import pytest

from tissuemech.fem import viscoelastic as ve
from tissuemech.fem.contact import FittedEdge, replayed_history
from tissuemech.fem.forms import Assembler, Material
from tissuemech.fem.mesh import fitted_mesh
from tissuemech.fem.spheroid import compress

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
