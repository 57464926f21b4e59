"""Every script in examples/ runs (fast settings: TISSUEMECH_EXAMPLES_FAST=1) and prints what it claims."""

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def run_example(name: str, tmp_path: Path, *args: str) -> str:
    env = dict(os.environ, TISSUEMECH_EXAMPLES_FAST="1", TISSUEMECH_EXAMPLES_OUT=str(tmp_path / "out"))
    env.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    proc = subprocess.run(
        [sys.executable, str(EXAMPLES / name), *args],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, f"{name} failed:\n{proc.stdout}\n{proc.stderr}"
    return proc.stdout


def test_every_example_is_tested():
    tested = {
        "burst_pressure.py",
        "scan_with_fe_check.py",
        "fit_relaxation.py",
        "export_paraview.py",
        "dask_batch.py",
        "afm_relaxation.py",
    }
    assert {p.name for p in EXAMPLES.glob("*.py")} == tested


@pytest.mark.slow
def test_burst_pressure(tmp_path):
    out = run_example("burst_pressure.py", tmp_path)
    # exact neo-Hookean limit pressures of the three walls (physics.md; README table)
    for text in ("B = 52 um: bursts above p =   19.44 Pa", "B = 60 um: bursts above p =   90.06 Pa", "197.41 Pa"):
        assert text in out
    rel = float(re.search(r"rel\. difference ([-+0-9.e]+)\)", out).group(1))
    assert abs(rel) < 1e-3  # FE arc length (coarse mesh) finds the same limit point
    assert "load control: load control reached a limit point" in out


def test_export_paraview(tmp_path):
    import meshio

    from tissuemech.fem.output import read_pvd

    run_example("export_paraview.py", tmp_path)
    b = read_pvd(tmp_path / "out" / "blastula.pvd")
    assert [t for t, _ in b] == [100.0, 400.0, 700.0, 1000.0]
    s = read_pvd(tmp_path / "out" / "spheroid.pvd")
    assert len(s) > 10 and s[-1][0] == 1500.0
    m = meshio.read(s[-1][1])
    assert {"displacement", "contact_pressure_Pa"} <= set(m.point_data)
    assert np.max(m.point_data["contact_pressure_Pa"]) > 0


@pytest.mark.slow
def test_fit_relaxation(tmp_path):
    out = run_example("fit_relaxation.py", tmp_path)
    rows = {
        m.group(1): tuple(map(float, m.groups()[1:]))
        for m in re.finditer(r"^\s*(\w+) \[.*?\]\s+(\S+)\s+(\S+)\s+(\S+)(?:\s|$)", out, re.M)
    }
    for name, true in (("C", 150.0), ("beta", 0.4), ("tau", 200.0)):
        _, lo, hi = rows[name]
        assert lo < true < hi, (name, rows[name])
    # one level alone: alpha flagged as not identifiable
    assert "the data cannot separate the parameters along: alpha" in out.split("the first level alone")[1]


@pytest.mark.slow
def test_scan_with_fe_check(tmp_path):
    run_example("scan_with_fe_check.py", tmp_path)
    df = pd.read_csv(tmp_path / "out" / "scan.csv")
    assert len(df) == 6 and df["deviation [-]"].notna().sum() == 1
    assert df["deviation [-]"].max() < 0.02  # calibrated reduced model vs FE (README: 0.2-0.7 %)
    # stiffer material, higher stress; more Maxwell stiffness, more relaxation
    assert df.groupby("beta [-]")["sigma_peak [Pa]"].apply(lambda s: s.is_monotonic_increasing).all()
    assert (df.groupby("beta [-]")["relaxed_fraction [-]"].mean().diff().dropna() > 0).all()


@pytest.mark.slow
def test_dask_batch(tmp_path):
    pytest.importorskip("dask.distributed")
    out = run_example("dask_batch.py", tmp_path)
    assert len(list((tmp_path / "out" / "dask-store").glob("*.npz"))) == 4
    lam = [float(v) for v in re.findall(r"lambda_a = ([0-9.]+)", out)]
    assert len(lam) == 4 and lam[0] > lam[1]  # alpha = 0.1 inflates more than 0.2 at the same pressure
    # the rerun finds every point in the store (resume)
    out2 = run_example("dask_batch.py", tmp_path)
    assert re.findall(r"lambda_a = ([0-9.]+)", out2) == re.findall(r"lambda_a = ([0-9.]+)", out)


@pytest.mark.slow
def test_afm_relaxation(tmp_path):
    """The real AFM records (3 curves in the fast setting): two Maxwell branches win on AIC, the figure is written."""
    out = run_example("afm_relaxation.py", tmp_path)
    assert "two branches preferred by AIC on 3/3 curves" in out
    assert (tmp_path / "out" / "afm_relaxation.png").stat().st_size > 10_000
