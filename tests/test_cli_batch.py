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


def test_chunks_partition_the_points():
    n, N = 23, 5
    seen = sorted(i for k in range(N) for i in batch.chunk(n, k, N))
    assert seen == list(range(n))
    assert batch.chunk(n, 2, N) == [2, 7, 12, 17, 22]
    with pytest.raises(ValueError, match="--index"):
        batch.chunk(n, 5, N)


def test_worker_env_pins_blas_and_xla():
    env = batch.worker_env(1)
    assert env["OMP_NUM_THREADS"] == env["OPENBLAS_NUM_THREADS"] == env["MKL_NUM_THREADS"] == "1"
    assert "intra_op_parallelism_threads=1" in env["XLA_FLAGS"]
    assert batch.worker_env(4)["MKL_NUM_THREADS"] == "4"
    with pytest.raises(ValueError, match="threads"):
        batch.worker_env(0)


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


def test_jobqueue_recipe_pins_every_worker():
    pytest.importorskip("dask_jobqueue")
    with batch.jobqueue_cluster(
        "slurm",
        cores=8,
        memory="16GB",
        walltime="01:00:00",
        queue="normal",
        job_script_prologue=["source ~/venv/bin/activate"],
        scheduler_options={"dashboard_address": None},
    ) as cluster:
        script = cluster.job_script()
    lines = script.splitlines()
    assert "#SBATCH -p normal" in lines and "#SBATCH --cpus-per-task=8" in lines
    assert "export OMP_NUM_THREADS='1'" in lines and "export OPENBLAS_NUM_THREADS='1'" in lines
    assert lines.index("export OMP_NUM_THREADS='1'") < lines.index("source ~/venv/bin/activate")
    assert "--nworkers 8" in script and "--nthreads 1" in script  # 8 single-threaded workers per job
    with pytest.raises(ValueError, match="multiple"):
        batch.jobqueue_cluster("slurm", cores=8, memory="1GB", walltime="1:00:00", threads_per_worker=3)


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
