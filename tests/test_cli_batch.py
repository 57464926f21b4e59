"""Job-array batches without a scheduler: ``batch run`` (one chunk into a shared store) and ``batch collect``."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tissuemech.compare import batch
from tissuemech.compare.cli import batch as batch_cli

HERE = Path(__file__).resolve().parent


def probe_threads(*, x: float) -> dict:
    """What a worker sees: its thread pinning and its process id."""
    return dict(x2=2.0 * x, omp=int(os.environ["OMP_NUM_THREADS"]), openblas=int(os.environ["OPENBLAS_NUM_THREADS"]),
                xla_single="--xla_cpu_multi_thread_eigen=false" in os.environ.get("XLA_FLAGS", ""), pid=os.getpid())  # fmt: skip


def _cli(*args, env=None, module="tissuemech.compare.cli.batch"):
    e = dict(os.environ, PYTHONPATH=str(HERE) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    for k in ("SLURM_ARRAY_TASK_ID", "PBS_ARRAY_INDEX", "PBS_ARRAYID", "SGE_TASK_ID", "LSB_JOBINDEX"):
        e.pop(k, None)
    e.update(env or {})
    return subprocess.Popen(
        [sys.executable, "-m", module, *args], env=e, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )  # fmt: skip


def test_two_array_tasks_fill_one_store_then_collect(tmp_path):
    pts = pd.DataFrame(dict(x=np.arange(7.0)))
    pts.to_csv(tmp_path / "points.csv", index=False)
    store = tmp_path / "store"
    common = [
        "run",
        str(tmp_path / "points.csv"),
        "--store",
        str(store),
        "--function",
        "test_cli_batch:probe_threads",
    ]
    # task 0 takes its index from SLURM, task 1 from PBS, on its own spawned worker; both at once
    a = _cli(*common, "--chunks", "2", env=dict(SLURM_ARRAY_TASK_ID="0"))
    b = _cli(*common, "--chunks", "2", "--workers", "1", env=dict(PBS_ARRAY_INDEX="1"))
    outs = []
    for p in (a, b):
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err
        outs.append(out)
    assert "chunk 0/2: 4 of 4 points stored" in outs[0] and "chunk 1/2: 3 of 3 points stored" in outs[1]
    assert len(list(store.glob("*.npz"))) == 7

    table = batch.collect(batch.read_points(tmp_path / "points.csv"), store, probe_threads)
    assert table["stored"].all()
    assert np.allclose(table["x2"], 2 * table["x"])
    assert (table["omp"] == 1).all() and (table["openblas"] == 1).all() and table["xla_single"].all()
    assert table.loc[table["x"] % 2 == 0, "pid"].nunique() == 1  # chunk 0: one process (in-process)

    # resume: a rerun of a chunk recomputes nothing
    before = {f: f.stat().st_mtime_ns for f in store.glob("*.npz")}
    c = _cli(*common, "--chunks", "2", "--index", "0")
    c.communicate(timeout=300)
    assert c.returncode == 0
    assert {f: f.stat().st_mtime_ns for f in store.glob("*.npz")} == before

    # the command-line collect writes the same table
    out = tmp_path / "table.csv"
    d = _cli(
        "collect",
        str(tmp_path / "points.csv"),
        "--store",
        str(store),
        "--function",
        "test_cli_batch:probe_threads",
        "--out",
        str(out),
        module="tissuemech.compare.batch_cli",
    )  # the old path
    so, se = d.communicate(timeout=300)
    assert d.returncode == 0, se
    assert "7 of 7 points stored" in so
    assert np.allclose(pd.read_csv(out)["x2"], 2 * np.arange(7.0))


def test_fe_blastula_chunk_matches_the_exact_shell(tmp_path):
    from tissuemech.reduced import blastula

    pts = pd.DataFrame(
        {"outer_radius [m]": [60e-6, 75e-6], "C [Pa]": 200.0, "alpha": 0.2, "pressure [Pa]": 300.0, "mesh": "coarse"}
    )
    pts.to_csv(tmp_path / "p.csv", index=False)
    args = ["run", str(tmp_path / "p.csv"), "--store", str(tmp_path / "s"), "--function", "fe-blastula", "--index", "0"]
    assert batch_cli.main(args) == 0
    table = batch.collect(batch.read_points(tmp_path / "p.csv"), tmp_path / "s", batch.fe_blastula)
    exact = blastula.inner_stretch(
        300.0, inner_radius=50e-6, outer_radius=table["outer_radius"].to_numpy(), C=200.0, alpha=0.2
    )
    assert np.allclose(table["inner_stretch"], np.asarray(exact), rtol=1e-3)  # coarse 2 x 4 mesh


def test_bad_arguments_exit_2_with_one_line(tmp_path, capsys):
    pd.DataFrame(dict(x=[1.0])).to_csv(tmp_path / "p.csv", index=False)
    base = ["run", str(tmp_path / "p.csv"), "--store", str(tmp_path / "s")]
    assert batch_cli.main([*base, "--index", "3", "--chunks", "2"]) == 2
    assert "--index must be in 0..1" in capsys.readouterr().err
    assert batch_cli.main([*base, "--index", "0", "--function", "nowhere"]) == 2
    assert "--function" in capsys.readouterr().err


def test_units_in_the_header_are_checked_and_failures_say_why(tmp_path):
    """A '[kPa]' column was read as SI (C = 0.2 Pa for 0.2 kPa) and failed points were listed without a reason."""
    bad = tmp_path / "kpa.csv"
    bad.write_text("C [kPa],x [m]\n0.2,1\n")
    with pytest.raises(ValueError, match=r"column 'C \[kPa\]': the points are passed as they are, in SI units"):
        batch.read_points(bad)
    ok = tmp_path / "ok.csv"
    ok.write_text("x [m],y [-]\n1,2\n")
    assert batch.read_points(ok) == [dict(x=1, y=2)]
    pts = tmp_path / "p.csv"
    pts.write_text("y\n1.0\n")  # probe_threads needs x
    p = _cli(
        "run",
        str(pts),
        "--store",
        str(tmp_path / "s"),
        "--function",
        "test_cli_batch:probe_threads",
        "--index",
        "0",
    )
    out, err = p.communicate(timeout=120)
    assert p.returncode == 1 and "row 0: TypeError" in err and "'y'" in err, err


@pytest.mark.parametrize(
    "extra, env, want",
    [
        (["--index", "0", "--function", "os:system"], {}, "--function 'os:system': os is part of Python's standard"),
        (["--index", "0", "--function", "..x:f"], {}, "--function '..x:f': expected one of"),
        (["--function", "fe-blastula"], {"SGE_TASK_ID": "0"}, "SGE_TASK_ID=0 is not a valid array index"),
        (
            ["--function", "fe-blastula", "--chunks", "2"],
            {"SLURM_ARRAY_TASK_ID": "2"},
            "SLURM_ARRAY_TASK_ID=2 is chunk 2",
        ),
    ],
)
def test_refusals_are_one_line(tmp_path, monkeypatch, capsys, extra, env, want):
    for k in ("SLURM_ARRAY_TASK_ID", "PBS_ARRAY_INDEX", "PBS_ARRAYID", "SGE_TASK_ID", "LSB_JOBINDEX"):
        monkeypatch.delenv(k, raising=False)
    for k, v in env.items():
        monkeypatch.setenv(k, v)
    (tmp_path / "p.csv").write_text("command\necho hacked > " + str(tmp_path / "hacked") + "\n")
    assert batch_cli.main(["run", str(tmp_path / "p.csv"), "--store", str(tmp_path / "s"), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and want in err[0] and "Traceback" not in err[0], err
    assert not (tmp_path / "hacked").exists() and not (tmp_path / "s").exists()


def test_semicolon_table_and_wrong_function_say_what_is_there(tmp_path, capsys):
    (tmp_path / "semi.csv").write_text("outer_radius;C;alpha;pressure\n6e-05;200;0.2;300\n")
    assert batch_cli.main(["collect", str(tmp_path / "semi.csv"), "--store", str(tmp_path / "s")]) == 2
    assert "separated by ';'" in capsys.readouterr().err
    pts = tmp_path / "p.csv"
    pts.write_text("outer_radius,C,alpha,pressure,mesh\n6e-05,200,0.2,300,coarse\n")
    args = ["--store", str(tmp_path / "s"), "--function", "fe-blastula"]
    assert batch_cli.main(["run", str(pts), *args, "--index", "0"]) == 0
    capsys.readouterr()
    assert batch_cli.main(["collect", str(pts), "--store", str(tmp_path / "s")]) == 2  # default: fe-spheroid
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "holds 1 result of tissuemech.compare.batch.points.fe_blastula" in err[0]
    assert batch_cli.main(["collect", str(pts), *args, "--out", str(tmp_path / "t.csv")]) == 0
    assert pd.read_csv(tmp_path / "t.csv")["stored"].all() and not list(tmp_path.glob(".t.csv*"))


def test_collect_says_when_the_store_is_missing_or_a_file_is_damaged(tmp_path, capsys):
    """A mistyped --store read like a batch not started; a garbage .npz ended in "holds 1 result of (unreadable), but
    none of fe_spheroid": now one warning line each names the store (and the file), exit 0, nothing stored."""
    pts = tmp_path / "p.csv"
    pts.write_text("C,alpha,beta,tau,displacement\n150,0.2,0.4,200,5e-05\n")
    assert batch_cli.main(["collect", str(pts), "--store", str(tmp_path / "nowhere")]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"tissuemech batch: warning: store {tmp_path / 'nowhere'} does not exist: no point is stored"]
    store = tmp_path / "s"
    store.mkdir()
    key = batch.point_key(batch.fe_spheroid, batch.read_points(pts)[0])
    (store / f"{key}.npz").write_bytes(b"garbage" * 100)
    assert batch_cli.main(["collect", str(pts), "--store", str(store)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"store {store}: result file {key}.npz is unreadable" in err[0], err
