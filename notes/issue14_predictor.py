"""load_control's predictors on the blastula: monitor-quadratic, Euler (the slope from the factorisation the last solve
kept), secant.

``python notes/issue14_predictor.py``: 18 shells (B = 60 / 75 um, alpha 0.1 / 0.2 / 0.3, meshes 2x4 / 4x8 / 8x16)
inflated to 1 kPa in n = 1, 2, 5, 10, 20, 50 equal steps, once with ``fem.blastula``'s Euler predictor and once with
the secant one (``_Problem.load_tangent`` returning None), each without (``continuation._monitor_quadratic`` returning
None) and with the predictor quadratic in the inner stretch through the last three converged states (``+quad``,
the default: the quadratic first, else Euler); per n the summed Newton iterations, the step cuts (``load_control``'s
"cut back" log records), SuperLU factorisations, failures and the wall time. The box is shared: times are indicative.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse.linalg as spla

from tissuemech.fem import blastula as fb
from tissuemech.fem import continuation as ct


class _Cuts(logging.Handler):
    def __init__(self):
        super().__init__()
        self.n = 0

    def emit(self, record):
        if "cut back" in record.getMessage():
            self.n += 1


def main() -> None:
    cuts = _Cuts()
    log = logging.getLogger("tissuemech.fem.continuation")
    log.setLevel(logging.DEBUG)
    log.addHandler(cuts)
    euler = fb._Problem.load_tangent
    quad = ct._monitor_quadratic
    splu = spla.splu
    lu = [0]

    def counted(*a, **k):
        lu[0] += 1
        return splu(*a, **k)

    spla.splu = counted
    print("n steps, predictor: Newton iterations, cuts, SuperLU factorisations, failures, wall (18 shells)")
    for n in (1, 2, 5, 10, 20, 50):
        for name in ("secant", "euler", "secant+quad", "euler+quad"):
            fb._Problem.load_tangent = euler if "euler" in name else (lambda self, lam, uf: None)  # type: ignore[method-assign]
            ct._monitor_quadratic = quad if "quad" in name else (lambda hist, lam: None)  # type: ignore[assignment]
            its = fails = 0
            cuts.n = lu[0] = 0
            t = time.perf_counter()
            for B in (60e-6, 75e-6):
                for alpha in (0.1, 0.2, 0.3):
                    for mesh in ((2, 4), (4, 8), (8, 16)):
                        try:
                            r = fb.inflate(inner_radius=50e-6, outer_radius=B, C=200.0, alpha=alpha,
                                           pressures=np.linspace(1000.0 / n, 1000.0, n), mesh=mesh)  # fmt: skip
                            its += int(np.sum(r.newton_iterations))
                        except Exception:  # a failure is counted, not raised
                            fails += 1
            wall = time.perf_counter() - t
            print(
                f"n {n:2d} {name:11s}: iterations {its:5d}, cuts {cuts.n:3d}, LU {lu[0]:5d}, failures {fails}, wall {wall:.2f} s",
                flush=True,
            )
    fb._Problem.load_tangent = euler  # type: ignore[method-assign]
    ct._monitor_quadratic = quad
    spla.splu = splu


if __name__ == "__main__":
    main()
