"""load_control's predictor on the blastula: Euler (the slope from the factorisation the last solve kept) vs secant.

``python notes/issue14_predictor.py``: 18 shells (B = 60 / 75 um, alpha 0.1 / 0.2 / 0.3, meshes 2x4 / 4x8 / 8x16)
inflated to 1 kPa in n = 1, 2, 5, 10, 20, 50 equal steps, once with ``fem.blastula``'s Euler predictor and once with
the secant one (``_Problem.load_tangent`` returning None); per n the summed Newton iterations, the step cuts
(``load_control``'s "cut back" log records), failures and the wall time. The box is shared: times are indicative.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from tissuemech.fem import blastula as fb


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
    print("n steps, predictor: Newton iterations, cuts, failures, wall (18 shells)")
    for n in (1, 2, 5, 10, 20, 50):
        for name in ("secant", "euler"):
            fb._Problem.load_tangent = euler if name == "euler" else (lambda self, lam, uf: None)  # type: ignore[method-assign]
            its = fails = 0
            cuts.n = 0
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
                f"n {n:2d} {name:6s}: iterations {its:5d}, cuts {cuts.n:3d}, failures {fails}, wall {wall:.2f} s",
                flush=True,
            )
    fb._Problem.load_tangent = euler  # type: ignore[method-assign]


if __name__ == "__main__":
    main()
