"""Exact parameter gradients of the FE indentation (``fem.indentation.indent(gradient=True)``): the active nodes
held on their obstacles (the probe's sphere, the plate), the Maxwell history carried through the steps, against
central differences of whole runs at rtol 1e-13."""

from __future__ import annotations

import numpy as np
import pytest

from tissuemech.fem import indentation as fi

KW = dict(radius=100e-6, probe_radius=25e-6, displacement=10e-6, ramp_time=1.0, end_time=20.0, mesh="coarse",
          n_ramp=4, n_hold=6)  # fmt: skip
VALUES = {"C": 150.0, "alpha": 1.4, "beta": 0.5, "tau": 2.0}


def run(p: dict, **kw):
    return fi.indent(C=p["C"], alpha=p["alpha"], branches=[(p["beta"], p["tau"])], **KW, **kw)


@pytest.fixture(scope="module")
def relaxation():
    return run(VALUES, gradient=True)


def test_indentation_gradient_has_each_parameter_and_a_stiffer_ball_pushes_back_harder(relaxation):
    g = relaxation.gradient
    assert set(g) == set(VALUES)
    assert np.all(g["C"]["force"] > 0) and np.all(g["beta"]["force"] > 0)
    np.testing.assert_allclose(g["C"]["force"], relaxation.force / VALUES["C"], rtol=1e-3)  # F ~ C (kappa aside)
    assert run(VALUES).gradient is None


@pytest.mark.slow
@pytest.mark.parametrize("name", list(VALUES))
def test_indentation_gradient_equals_central_differences_of_whole_runs(relaxation, name):
    """d probe force / d theta within 1e-6 of the largest central difference at every step (measured <= 4.3e-9,
    ``python -m tissuemech.compare.bench.fem_gradient --only-indent``), and d centre drop / d theta likewise for the
    parameters that move it (C moves it only through the bulk modulus kappa / C: nothing to compare)."""
    v = VALUES[name]
    h = 1e-4 * v
    a, b = run({**VALUES, name: v + h}, rtol=1e-13), run({**VALUES, name: v - h}, rtol=1e-13)
    for obs in ("force",) + (("centre_drop",) if name != "C" else ()):
        fd = (getattr(a, obs) - getattr(b, obs)) / (2 * h)
        err = np.max(np.abs(relaxation.gradient[name][obs] - fd)) / np.max(np.abs(fd))
        assert err <= 1e-6, (obs, err)


def test_static_indentation_gradient_equals_central_differences():
    """An elastic static run (load fractions of 12 um): d force / d C and d force / d alpha within 1e-6."""
    kw = dict(radius=100e-6, probe_radius=50e-6, displacement=12e-6, mesh="coarse", static=True, n_static=3)
    g = fi.indent(C=150.0, alpha=0.8, gradient=True, **kw).gradient
    assert set(g) == {"C", "alpha"}
    for name, v in {"C": 150.0, "alpha": 0.8}.items():
        h = 1e-4 * v
        p = {"C": 150.0, "alpha": 0.8}
        a = fi.indent(**{**p, name: v + h}, rtol=1e-13, **kw).force
        b = fi.indent(**{**p, name: v - h}, rtol=1e-13, **kw).force
        fd = (a - b) / (2 * h)
        assert np.max(np.abs(g[name]["force"] - fd)) <= 1e-6 * np.max(np.abs(fd)), name


@pytest.mark.parametrize("kw", [{"contact": "fitted", "static": True}, {"kinematics": "small", "static": True}])
def test_indentation_gradient_names_what_it_does_not_carry(kw):
    base = dict(radius=100e-6, probe_radius=25e-6, displacement=5e-6, C=150.0, alpha=1.0, mesh="coarse")
    with pytest.raises(ValueError, match="contact='nodal'"):
        fi.indent(**base, gradient=True, **kw)


@pytest.mark.slow
def test_creep_under_probe_force_control_gradient_equals_central_differences():
    """Force control (a creep at 1.2e-7 N, one mesh for all runs): the approach's and the centre drop's gradients
    within 1e-6 of whole-run differences at every step (on the default level <= 1.3e-8: ``python -m
    tissuemech.compare.bench.fem_gradient --only-indent``), the probe force's gradient 0 (it is prescribed)."""
    kw = dict(KW, force=1.2e-7, sizing_approach=12e-6)
    del kw["displacement"]

    def creep(p: dict, **k):
        return fi.indent(C=p["C"], alpha=p["alpha"], branches=[(p["beta"], p["tau"])], **kw, **k)

    g = creep(VALUES, gradient=True)
    assert set(g.gradient["alpha"]) == {"force", "centre_drop", "approach"}
    for name, v in VALUES.items():
        np.testing.assert_array_equal(g.gradient[name]["force"], 0.0)
        h = 1e-4 * v
        a, b = creep({**VALUES, name: v + h}, rtol=1e-13), creep({**VALUES, name: v - h}, rtol=1e-13)
        np.testing.assert_allclose(a.time, g.time)  # the same steps (a whole-run difference needs them)
        np.testing.assert_allclose(b.time, g.time)
        for obs in ("approach", "centre_drop"):
            fd = (getattr(a, obs) - getattr(b, obs)) / (2 * h)
            err = np.max(np.abs(g.gradient[name][obs] - fd)) / np.max(np.abs(fd))
            assert err <= 1e-6, (name, obs, err)
