"""A resumable FE batch on a dask cluster (here a LocalCluster; the same code runs on SLURM/PBS).

Each point is one FE inflation of the blastula; results go to a store folder the moment they finish,
so a rerun with the same store skips the finished points. Workers run one thread each, with BLAS and
XLA pinned to one thread (``compare.batch.worker_env``) so they do not oversubscribe the cores.
For a cluster, replace the LocalCluster by a ``dask_jobqueue.SLURMCluster`` (docs: "Clusters").

    python examples/dask_batch.py
"""

import os

import numpy as np

from tissuemech.compare import batch

FAST = os.environ.get("TISSUEMECH_EXAMPLES_FAST") == "1"  # tests/test_examples.py: small sizes
OUT = os.environ.get("TISSUEMECH_EXAMPLES_OUT", "example-output")  # where the files go
os.makedirs(OUT, exist_ok=True)


def inner_stretch(*, outer_radius: float, alpha: float, pressure: float) -> dict:
    """FE inner stretch of a shell (A = 50 um, C = 200 Pa) at one pressure (Pa)."""
    from tissuemech.fem import blastula as fe_blastula

    r = fe_blastula.inflate(
        inner_radius=50e-6, outer_radius=outer_radius, C=200.0, alpha=alpha, pressures=[pressure], mesh=(2, 4)
    )
    return {"inner_stretch": r.inner_stretch[-1], "newton_iterations": r.newton_iterations.sum()}


if __name__ == "__main__":
    from dask.distributed import Client, LocalCluster

    points = [
        dict(outer_radius=b, alpha=al, pressure=p)
        for b in (60e-6, 75e-6)
        for al in (0.1, 0.2)
        for p in ((500.0,) if FAST else (200.0, 500.0, 1000.0))
    ]
    store = f"{OUT}/dask-store"
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, env=batch.worker_env(1), dashboard_address=None) as cluster,
        Client(cluster) as client,
    ):
        results = batch.run(inner_stretch, points, executor=client, store=store, progress=False)
    for p, r in zip(points, results):
        b_um, lam = p["outer_radius"] * 1e6, float(r.inner_stretch)
        print(f"B = {b_um:.0f} um, alpha = {p['alpha']}, p = {p['pressure']:g} Pa: lambda_a = {lam:.5f}")
    lam = np.array([float(r.inner_stretch) for r in results])
    print(f"{len(points)} FE runs stored in {store}; stretch range {lam.min():.4f} .. {lam.max():.4f}")
