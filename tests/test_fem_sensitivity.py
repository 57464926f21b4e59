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
