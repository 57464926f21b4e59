"""One BLAS thread per batch worker vs the BLAS default (issue 14: "set BLAS threads deliberately").

``python notes/batch_blas_threads.py [--rounds 2]``

Runs a batch of 6 Fig. 10 spheroid runs (C = 140..190 Pa, default mesh, to 1500 s) through
``compare.batch.run`` with the default executor (2 spawned worker processes), alternately with the
workers limited to one BLAS thread (``batch.worker_init``, what the default pool does) and with the
BLAS libraries' own default (the initializer replaced by a no-op: OpenBLAS starts one thread per core),
each into a fresh store; prints the wall times (imports and process start included) and the machine's
core count.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

from tissuemech.compare import batch
from tissuemech.fem import spheroid as fs


def fig10(*, C: float) -> dict:
    """Plate force (N) of the Fig. 10 case with shear parameter C (Pa)."""
    r = fs.compress(
        radius=500e-6, C=C, alpha=0.2, branches=[(0.4, 200.0)], displacement=50e-6, ramp_time=0.2, end_time=1500.0
    )
    return dict(force=np.asarray(r.force))


def _no_limit() -> None:
    """A worker initializer that leaves the BLAS thread count at the libraries' default."""


def main() -> None:
    ap = argparse.ArgumentParser(prog="python notes/batch_blas_threads.py")
    ap.add_argument("--rounds", type=int, default=2)
    a = ap.parse_args()
    points = [dict(C=c) for c in (140.0, 150.0, 160.0, 170.0, 180.0, 190.0)]
    limit = batch.worker_init
    walls: dict[str, list[float]] = {"one BLAS thread per worker": [], "BLAS default": []}
    print(f"{os.cpu_count()} CPUs; 6 Fig. 10 runs, 2 worker processes; {a.rounds} interleaved rounds")
    for _ in range(a.rounds):
        for name, init in (("one BLAS thread per worker", limit), ("BLAS default", _no_limit)):
            batch.worker_init = init
            try:
                with tempfile.TemporaryDirectory() as d:
                    t = time.perf_counter()
                    batch.run(fig10, points, store=d, progress=False)
                    walls[name].append(time.perf_counter() - t)
            finally:
                batch.worker_init = limit
    for name, w in walls.items():
        print(f"{name:28s} wall " + ", ".join(f"{v:.2f}" for v in w) + " s")


if __name__ == "__main__":
    main()
