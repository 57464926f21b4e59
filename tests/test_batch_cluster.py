"""compare.batch.cluster: worker thread pinning and the dask-jobqueue recipe."""

import pytest

from tissuemech.compare import batch


def test_worker_env_pins_blas_and_xla():
    env = batch.worker_env(1)
    assert env["OMP_NUM_THREADS"] == env["OPENBLAS_NUM_THREADS"] == env["MKL_NUM_THREADS"] == "1"
    assert "intra_op_parallelism_threads=1" in env["XLA_FLAGS"]
    assert batch.worker_env(4)["MKL_NUM_THREADS"] == "4"
    with pytest.raises(ValueError, match="threads"):
        batch.worker_env(0)


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
