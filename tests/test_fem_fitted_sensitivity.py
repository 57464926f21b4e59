"""Exact gradients of time runs on contact-edge-fitted meshes (``fem.fitted_sensitivity``): the replayed Maxwell
history and the contact edge's motion carried through the steps, against central differences of whole runs whose
edge is found to a tight tolerance (the nonlinear solves never differenced)."""

from __future__ import annotations

import numpy as np
import pytest

from tissuemech.fem import spheroid as fs
from tissuemech.fem.contact import FittedEdge

A0 = 100e-6
TIGHT = FittedEdge(tol=1e-10)  # the edge condition N_edge / F = 0 to 1e-10: the whole runs' differences resolve 1e-7
RELAX = dict(radius=A0, displacement=30e-6, ramp_time=0.2, end_time=20.0, mesh="coarse", n_ramp=4, n_hold=6)
BASE = {"C": 150.0, "alpha": 1.4}
TWO = [(0.8, 0.05), (0.3, 20.0)]  # one branch as fast as a quarter of the ramp


def two_branch_run(p: dict, **kw):
    """``fem.spheroid.compress`` of RELAX with C, alpha, [surface_tension,] beta_m and tau_m from ``p``."""
    br = [(p["beta_1"], p["tau_1"]), (p["beta_2"], p["tau_2"])]
    extra = {"surface_tension": p["surface_tension"]} if "surface_tension" in p else {}
    return fs.compress(C=p["C"], alpha=p["alpha"], branches=br, **extra, **RELAX, **kw)


VALUES = {**BASE, "beta_1": 0.8, "tau_1": 0.05, "beta_2": 0.3, "tau_2": 20.0}


@pytest.fixture(scope="module")
def relaxation():
    return fs.compress(branches=TWO, gradient=True, contact=TIGHT, rtol=1e-13, **BASE, **RELAX)


def test_fitted_time_run_has_every_parameter_s_gradient_on_fitted_steps(relaxation):
    r = relaxation
    assert set(r.parameters["contact"]) == {"fitted"}
    assert set(r.gradient) == set(VALUES)
    for name, g in r.gradient.items():
        assert g["force"].shape == r.force.shape and np.all(np.isfinite(g["force"])), name
    # a stiffer material pushes back harder at every step; the elastic part scales with C
    assert np.all(r.gradient["C"]["force"] > 0) and np.all(r.gradient["beta_1"]["force"] > 0)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(VALUES))
def test_fitted_time_run_gradient_equals_central_differences_of_whole_runs(relaxation, name):
    """d force / d theta within 1e-6 of the largest central difference of whole fitted runs (rtol 1e-13, edge to
    1e-10) at every step: the history replayed from every past step's own mesh and each edge's motion carried
    (measured <= 9.9e-8 on the default level with `python -m tissuemech.compare.bench.fem_gradient --only-fitted`).
    Without the edge's motion alpha's gradient is off by 1e-2 (``test_the_contact_edge_carries_...``)."""
    v = VALUES[name]
    h = 1e-4 * v

    def run(x):
        return two_branch_run({**VALUES, name: x}, contact=TIGHT, rtol=1e-13).force

    fd = (run(v + h) - run(v - h)) / (2 * h)
    err = np.max(np.abs(relaxation.gradient[name]["force"] - fd)) / np.max(np.abs(fd))
    assert err <= 1e-6, err


def test_fitted_gradient_at_the_default_edge_tolerance_is_the_tight_one(relaxation):
    """The default run (edge to 1e-6 of the force, rtol 1e-10) gives the gradient of the tight one within 1e-6: the
    sensitivities are those of the exact edge condition, not of the search's last trial."""
    r = fs.compress(branches=TWO, gradient=True, **BASE, **RELAX)
    for name, g in relaxation.gradient.items():
        a, b = r.gradient[name]["force"], g["force"]
        assert np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(b)), name


def test_fitted_time_run_gradient_names_what_it_does_not_carry():
    with pytest.raises(ValueError, match="contact='nodal'") as err:
        fs.compress(branches=TWO, gradient=True, contact=FittedEdge(history="chain"), **BASE, **{**RELAX, "n_hold": 1})
    assert "history='chain'" in str(err.value)


@pytest.mark.slow
def test_fitted_gradient_with_surface_tension_equals_central_differences():
    """With a surface tension (1 mN/m) the edge condition is the slope dz/dr = 0 at the edge node: every parameter's
    d force / d theta, gamma's included, within 1e-6 of the largest central difference of whole fitted runs
    (measured <= 4.1e-8, ``python -m tissuemech.compare.bench.fem_gradient --only-fitted``)."""
    values = {**VALUES, "alpha": 1.2, "surface_tension": 1e-3}

    def run(p, **k):
        return two_branch_run(p, contact=TIGHT, rtol=1e-13, **k)

    g = run(values, gradient=True)
    assert set(g.gradient) == set(values)
    for name, v in values.items():
        h = 1e-4 * v
        fd = (run({**values, name: v + h}).force - run({**values, name: v - h}).force) / (2 * h)
        err = np.max(np.abs(g.gradient[name]["force"] - fd)) / np.max(np.abs(fd))
        assert err <= 1e-6, (name, err)


@pytest.mark.slow
def test_fitted_gradient_through_a_measured_history_with_unloading():
    """A measured approach history (ramp 1 s, hold, a partial unload by 20 %, hold) on fitted meshes: the steps
    that move the plate replay the history, the held ones carry it from the previous mesh (as the run itself does);
    d force / d theta within 1e-6 of the largest central difference of whole runs at every step (measured <= 9.8e-9,
    ``python -m tissuemech.compare.bench.fem_gradient --only-fitted``)."""
    rec = (np.array([0.0, 1.0, 5.0, 6.0, 20.0]), np.array([0.0, 30e-6, 30e-6, 24e-6, 24e-6]))
    kw = dict(radius=A0, displacement=rec, mesh="coarse", n_ramp=6, contact=TIGHT, rtol=1e-13)
    values = {"C": 150.0, "alpha": 1.4, "beta": 0.5, "tau": 2.0}

    def run(p, **k):
        return fs.compress(C=p["C"], alpha=p["alpha"], branches=[(p["beta"], p["tau"])], **kw, **k)

    g = run(values, gradient=True)
    assert set(g.parameters["contact"]) == {"fitted"} and np.ptp(g.approach[-5:]) == 0.0
    for name, v in values.items():
        h = 1e-4 * v
        fd = (run({**values, name: v + h}).force - run({**values, name: v - h}).force) / (2 * h)
        err = np.max(np.abs(g.gradient[name]["force"] - fd)) / np.max(np.abs(fd))
        assert err <= 1e-6, (name, err)
