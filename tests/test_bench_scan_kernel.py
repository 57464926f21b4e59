"""The scan-kernel benchmark (issue 40, items 2 and 7): its two evaluations of the lumped model's relaxation curves
agree (the JAX quadrature kernel and the NumPy closed form with Dawson's integral), on the CPU path and on the
path a GPU backend takes (chunks, kernel alone, the same kernel on the CPU), which runs here with the backend's
name patched. No timing is asserted."""

from __future__ import annotations

import re

import pytest

from tissuemech.compare.bench import scan_kernel


def _largest(text: str, name: str) -> float:
    m = re.search(rf"largest \|{re.escape(name)} - 1\| = ([0-9.eE+-]+)", text)
    assert m, text
    return float(m.group(1))


def test_scan_kernel_agrees_with_the_closed_form(capsys):
    assert scan_kernel.main(["--curves", "3000", "--reference-curves", "3000"]) == 0
    out = capsys.readouterr().out
    assert "backend cpu" in out and "3000 curves x 200 times" in out
    assert _largest(out, "F_jax / F_numpy") < 1e-9


def test_scan_kernel_gpu_path_runs_on_any_backend(capsys, monkeypatch):
    import jax

    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    assert scan_kernel.main(["--curves", "5000", "--chunk", "4096", "--reference-curves", "3000"]) == 0
    out = capsys.readouterr().out
    assert "chunks of 4096 (gpu)" in out and "forces left on the gpu" in out
    assert _largest(out, "F_jax / F_numpy") < 1e-9
    assert _largest(out, "F_gpu / F_cpu") < 1e-13  # here both are the CPU: the same program's numbers


@pytest.mark.parametrize("curves", [1, 4097])
def test_closed_form_matches_the_public_force(curves):
    """The NumPy closed form itself against ``reduced.spheroid.force`` (Hertz law, one branch) at random
    parameters: the reference of the benchmark is a reference."""
    import numpy as np

    from tissuemech.compare.scan import default_times
    from tissuemech.reduced import spheroid

    rng = np.random.default_rng(curves)
    t = np.asarray(default_times(scan_kernel.TR, scan_kernel.END))
    C, beta = rng.uniform(100, 400, curves), rng.uniform(0.1, 2.0, curves)
    tau, X = np.exp(rng.uniform(0.0, np.log(1000.0), curves)), rng.uniform(0.05, 0.3, curves)
    F_np = scan_kernel.closed_form(t, C, beta, tau, X)
    for i in range(min(curves, 3)):
        F = np.asarray(
            spheroid.force(
                t, radius=scan_kernel.A0, C=C[i], alpha=0.2, branches=[(beta[i], tau[i])],
                displacement=2 * scan_kernel.A0 * X[i], ramp_time=scan_kernel.TR, equilibrium="hertz",
            )
        )  # fmt: skip
        np.testing.assert_allclose(F_np[i, 1:], F[1:], rtol=1e-9)
