"""How far the fitted contact edge's tolerance moves the spheroid force (issue 14 follow-up).

``python notes/issue14_edge.py [LEVELS]`` (default levels 1 2 3): the static curve of the Fig. 10 material
(C = 150 Pa, alpha = 0.2, a0 = 500 um) to 10 % compression in 5 steps, with the contact-edge condition
|N_edge| / F solved to 1e-4 (the tolerance before this change), 1e-6 (``fem.spheroid.EDGE_TOL`` now) and
1e-8 (the yardstick). Prints per level and tolerance the largest |F / F(1e-8) - 1| over the 5 states, the
Newton iterations of the accepted states and the wall time.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from tissuemech.fem import spheroid as fs

KW = dict(radius=500e-6, C=150.0, alpha=0.2, displacement=100e-6, ramp_time=1.0, end_time=1.0, static=True, n_static=5)
TOLS = (1e-4, 1e-6, 1e-8)


def curve(level: int, tol: float) -> tuple[np.ndarray, int, float]:
    """(forces (N), Newton iterations, wall s) of the static curve with the edge solved to ``tol``."""
    solve = fs._EdgeFit.solve
    fs._EdgeFit.solve = lambda self, d, e, x, load, _tol=0.0, visc=None: solve(self, d, e, x, load, tol, visc)  # type: ignore[method-assign]
    try:
        t = time.perf_counter()
        r = fs.compress(**KW, mesh=level)
        return np.asarray(r.force), int(np.sum(r.newton_iterations)), time.perf_counter() - t
    finally:
        fs._EdgeFit.solve = solve  # type: ignore[method-assign]


def main(levels: list[int]) -> None:
    print(f"EDGE_TOL in fem.spheroid: {fs.EDGE_TOL:g}")
    print(f"{'level':>5} {'edge tol':>9} {'max |F/F(1e-8) - 1|':>21} {'iterations':>10} {'wall s':>7}")
    for lev in levels:
        runs = {tol: curve(lev, tol) for tol in TOLS}
        ref = runs[TOLS[-1]][0]
        for tol, (f, its, wall) in runs.items():
            print(f"{lev:5d} {tol:9.0e} {np.max(np.abs(f / ref - 1)):21.2e} {its:10d} {wall:7.2f}")


if __name__ == "__main__":
    main([int(v) for v in sys.argv[1:]] or [1, 2, 3])
