"""compare.calibrate: tabulation machinery (batch, interpolation, file format) on a fake static FE curve.

The fake is the Hertz law with a Fung factor, F = C a0^2 (32/3) x^1.5 exp(alpha x), r_mid = a0 (1 + x/2),
sampled on an irregular approach grid, so the table must reproduce it to interpolation accuracy.
"""

from __future__ import annotations

import numpy as np
import pytest

from tissuemech.compare import calibrate
from tissuemech.compare.cli import calibrate as calibrate_cli


def fake_curve(*, alpha, x_max, mesh="default"):
    a0, C = 500e-6, 200.0
    x = np.sort(np.r_[np.geomspace(1e-4, x_max, 300), x_max])
    return {
        "approach": 2 * a0 * x,
        "force": C * a0**2 * (32 / 3) * x**1.5 * np.exp(alpha * x),
        "midplane_radius": a0 * (1 + x / 2),
        "radius": a0,
        "C": C,
    }


def test_tabulate_reproduces_curve_and_file_roundtrip(tmp_path):
    curves = calibrate.tabulate(
        alphas=(0.0, 0.5, 1.0), n_x=16, x_max=0.3, executor="serial", store=str(tmp_path / "s"), curve=fake_curve
    )
    x = curves.x
    assert x[0] == 0.0 and x[-1] == pytest.approx(0.3)
    exact = calibrate.hertz_f(x)[None, :] * np.exp(curves.alpha[:, None] * x[None, :])
    assert np.allclose(curves.f, exact, rtol=2e-3, atol=1e-6)
    assert np.allclose(curves.g, 1 + x / 2, rtol=1e-12)
    out = tmp_path / "master.npz"
    calibrate.write(out, curves, {"mesh": "fake"})
    back, meta = calibrate.load(out)
    assert meta == {"mesh": "fake"} and np.array_equal(back.f, curves.f)
    with np.load(out) as z:
        r = z["f_over_hertz"]
    assert np.allclose(r[:, 1:], np.exp(curves.alpha[:, None] * x[None, 1:]), rtol=2e-3)
    assert np.all(r[:, 0] == 1.0)  # Hertz limit at x -> 0
    # the grid: fine steps to x_small, then the main run's states
    assert np.allclose(x[:6], [0, 0.0025, 0.005, 0.0075, 0.01, 0.02])


def test_sqrt_basis_contains_the_small_x_law():
    """h = 1 + c1 sqrt(x) + c2 x is represented exactly by the sqrt(x) basis (an x ln x basis cannot)."""
    x = calibrate.table_grid(19, 0.36)
    h = 1 + 0.3 * np.sqrt(x) + 0.5 * x
    c = calibrate.MasterCurves(x, np.array([0.0]), (calibrate.hertz_f(x) * h)[None], (1 + x / 2)[None])
    sm, change = calibrate.smooth(c, degree=4)
    assert change < 1e-12 and np.allclose(sm.f, c.f, rtol=1e-12, atol=1e-15)


def _short_curve(*, alpha, x_max, mesh="default"):
    d = fake_curve(alpha=alpha, x_max=x_max / 2)
    return d


def test_short_run_and_bad_input_raise():
    with pytest.raises(RuntimeError, match="stopped at"):
        calibrate.tabulate(alphas=(0.2,), executor="serial", curve=_short_curve)
    with pytest.raises(ValueError, match="x_max"):
        calibrate.tabulate(x_max=0.7, executor="serial", curve=fake_curve)


# sha256 of the shipped table's arrays: the level-3 table of 2026-12-02 (static runs with the contact edge solved to
# 1e-6, checked against level 4); regenerate with the command in its metadata and update these
SHIPPED_SHA256 = {
    "x": "9e019baea9874eafae66126ac205eb7de7edfad85f575e7d9bd2840bfae9661f",
    "alpha": "b04a7bb20bf42160ef8ff9fc5ae3a9828e63c7519a69112b8aae22673af1f2ea",
    "f": "d8d45bcec542d6b5370f5f3a61b814fa170b267775ed712263220efdb4623d36",
    "g": "055bb1acaade2386ee48f4d7b28cc5fe9cf2ef89dbc481bbf590165998b22830",
    "f_over_hertz": "e9941988039f0f29092c214cd29d5a1fadab3a03269baaa473013237861904cf",
}


def test_shipped_table_arrays_and_its_model_error():
    """The shipped table is the one its metadata's command makes (level 3, checked against level 4); the fits
    read its own error estimate: half its largest error against the converged reference in the notes."""
    import hashlib
    import json
    from pathlib import Path

    from tissuemech.compare.fit import model_error_of

    with np.load(calibrate.DEFAULT_OUT, allow_pickle=False) as z:
        assert sorted(k for k in z.files if k != "metadata") == sorted(SHIPPED_SHA256)
        for k, digest in SHIPPED_SHA256.items():
            assert hashlib.sha256(np.ascontiguousarray(z[k]).tobytes()).hexdigest() == digest, k
        meta = json.loads(str(z["metadata"]))
    assert meta["mesh"] == 3 and meta["error_mesh"] == 4 and "--mesh 3 --error-mesh 4" in meta["command"]
    assert meta["discretisation_error_f"] < 2e-5  # level 3 against level 4
    assert meta["model_error_rel"] == pytest.approx(1.486e-5, rel=1e-3)
    assert model_error_of("fem") == meta["model_error_rel"]
    ref = Path(__file__).resolve().parent / "data" / "plate_reference_levels1-3.json"
    err, at = calibrate.reference_error(calibrate.DEFAULT_OUT, json.loads(ref.read_text()))
    assert err / 2 == pytest.approx(meta["model_error_rel"], rel=0.02) and at == "alpha 0 x 0.35"


@pytest.mark.slow
def test_shipped_table_is_the_level_3_static_force():
    """At a table node (x = 0.1, alpha = 0.2) the shipped f equals a fresh static run on level 3 (the contact edge
    solved to 1e-6 either way: only the solver tolerances differ), not the level-2 value 1.2e-5 below it."""
    from tissuemech.fem.spheroid import compress
    from tissuemech.reduced.spheroid import master_curve

    a0, C = 500e-6, 200.0
    run = compress(radius=a0, C=C, alpha=0.2, branches=(), displacement=2 * a0 * 0.1, ramp_time=1.0, end_time=1.0,
                   static=True, mesh=3, n_static=2)  # fmt: skip
    table = float(master_curve().f(0.1, 0.2))
    assert table / float(run.force[-1] / (C * a0**2)) - 1 == pytest.approx(0.0, abs=2e-8)


def test_reference_error_of_a_written_table(tmp_path):
    curves = calibrate.tabulate(alphas=(0.0, 0.5, 1.0), n_x=16, x_max=0.3, executor="serial", curve=fake_curve)
    out = tmp_path / "master.npz"
    calibrate.write(out, curves, {"mesh": "fake"})
    exact = lambda x, a: float(calibrate.hertz_f(np.array(x)) * np.exp(a * x))
    ref = {"_about": "ignored", "alpha 0.5 x 0.1": {"reference": exact(0.1, 0.5) * (1 - 1e-3)}}
    ref["alpha 0 x 0.2"] = {"reference": exact(0.2, 0.0)}
    ref["alpha 2 x 0.2"] = {"reference": 1.0}  # outside the alpha range: skipped
    err, at = calibrate.reference_error(out, ref)
    assert at == "alpha 0.5 x 0.1" and err == pytest.approx(1e-3, rel=0.05)
    with pytest.raises(ValueError, match="no point"):
        calibrate.reference_error(out, {"alpha 3 x 0.1": {"reference": 1.0}})


def test_main_writes_model_error_rel_from_a_reference(tmp_path, monkeypatch):
    import json

    fake = calibrate.tabulate(alphas=(0.0, 0.5, 1.0), n_x=16, x_max=0.3, executor="serial", curve=fake_curve)
    monkeypatch.setattr(calibrate, "build", lambda tables, **kw: [fake] * len(tables))
    x, a = 0.1, 0.5
    ref = tmp_path / "ref.json"
    ref.write_text(
        json.dumps(
            {f"alpha {a} x {x}": {"reference": float(calibrate.hertz_f(np.array(x)) * np.exp(a * x)) * (1 + 4e-4)}}
        )
    )
    out = tmp_path / "m.npz"
    args = ["--out", str(out), "--alphas", "0.0,0.5,1.0", "--check-alphas", "0.0", "--error-mesh", "", "--degree", "0"]
    assert calibrate_cli.main(args) == 0
    assert "model_error_rel" not in calibrate.load(out)[1]  # a finer-level check alone does not set it
    assert calibrate_cli.main([*args, "--reference", str(ref)]) == 0
    meta = calibrate.load(out)[1]
    assert meta["model_error_rel"] == pytest.approx(2e-4, rel=0.05) and "2-sigma" in meta["model_error_basis"]


def test_a_table_built_in_parallel_equals_the_serial_one(tmp_path):
    """Two worker processes, largest runs first, give the table of one in-process pass bit for bit (each run is
    independent); the finer-level check shares the pool and comes back as its own table."""
    spec = calibrate.plate_table(alphas=(0.0, 0.3, 0.7, 1.2), n_x=11, x_max=0.3, mesh=1, curve=fake_curve)
    check = calibrate.plate_table(alphas=(0.0, 1.2), n_x=11, x_max=0.3, mesh=2, curve=fake_curve, name="check")
    serial = calibrate.build([spec, check], executor="serial", progress=False)
    parallel = calibrate.build([spec, check], workers=2, store=str(tmp_path / "s"), progress=False)
    for a, b in zip(serial, parallel, strict=True):
        for k in ("x", "alpha", "f", "g"):
            assert np.array_equal(getattr(a, k), getattr(b, k)), k
    assert serial[1].f.shape == (2, len(serial[0].x)) and np.array_equal(serial[1].f, serial[0].f[[0, 3]])
    # the store holds every run once (the check's alphas on another mesh are other runs): a rerun computes nothing
    again = calibrate.build([spec], executor=_Refuse(), store=str(tmp_path / "s"), progress=False)[0]
    assert np.array_equal(again.f, serial[0].f)


class _Refuse:
    """An executor that fails the test if anything is submitted."""

    def submit(self, *a, **k):
        raise AssertionError("a stored run was computed again")

    def shutdown(self, wait=True, cancel_futures=False):
        pass


CALLS: list[float] = []


def _recording_run(*, size):
    CALLS.append(size)
    return {"y": np.array([size])}


def test_build_runs_the_most_expensive_first_and_assembles_in_column_order():
    CALLS.clear()
    spec = calibrate.Table(
        "toy",
        _recording_run,
        columns=(({"size": 1.0}, {"size": 5.0}), ({"size": 3.0},)),
        assemble=lambda res: [[float(r["y"][0]) for r in col] for col in res],
        cost=lambda kw: kw["size"],
    )
    assert calibrate.build([spec], executor="serial", progress=False) == [[[1.0, 5.0], [3.0]]]
    assert CALLS == [5.0, 3.0, 1.0]
    assert spec.runs() == [{"size": 1.0}, {"size": 5.0}, {"size": 3.0}]


def test_table_and_build_reject_bad_input():
    with pytest.raises(ValueError, match="at least one run"):
        calibrate.Table("empty", _recording_run, columns=((),), assemble=list)
    with pytest.raises(ValueError, match="callables"):
        calibrate.Table("bad", _recording_run, columns=(({"size": 1.0},),), assemble=None)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="Table"):
        calibrate.build(["not a table"])  # type: ignore[list-item]
    spec = calibrate.Table("toy", _recording_run, columns=(({"size": 1.0},),), assemble=list)
    with pytest.raises(ValueError, match="workers"):
        calibrate.build([spec], workers=0)


def test_plate_cost_orders_levels_and_steps():
    assert calibrate.plate_cost({"mesh": 4, "n": 18}) > calibrate.plate_cost({"mesh": 3, "n": 18})
    assert calibrate.plate_cost({"mesh": 3, "n": 18}) > calibrate.plate_cost({"mesh": 3, "n": 4})
    assert calibrate.plate_cost({"mesh": "coarse", "n": 4}) == calibrate.plate_cost({"mesh": 1, "n": 4})
