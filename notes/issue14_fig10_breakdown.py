"""Where a Fig. 10 run's wall time goes: inside Newton and outside it (fitted meshes, Maxwell history transfers).

``python notes/issue14_fig10_breakdown.py [--repeats 3]``: the spheroid Fig. 10 case (default mesh, to 1500 s)
run with wall-clock accumulators wrapped around ``fem.spheroid``'s calls of ``newton`` (the fitted-mesh solves),
``fitted_mesh``, ``_gauss_transfer``, ``_Problem.__init__`` and ``_Problem.observe``; prints the fastest run's
wall time and each share (ms). The accumulators cost ~1 us a call; what is not listed is the rest of the step
(the converged state's residual, gaps, the march and the output fields).
"""

from __future__ import annotations

import argparse
import functools
import time

from tissuemech.fem import spheroid as fs

FIG10 = dict(
    radius=500e-6, C=150.0, alpha=0.2, branches=[(0.4, 200.0)], displacement=50e-6, ramp_time=0.2, end_time=1500.0
)


def _accumulate(acc: dict, owner, name: str, label: str) -> None:
    f = getattr(owner, name)

    @functools.wraps(f)
    def timed(*a, **k):
        t = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            acc[label] = acc.get(label, 0.0) + time.perf_counter() - t

    setattr(owner, name, timed)


def main() -> None:
    ap = argparse.ArgumentParser(prog="python notes/issue14_fig10_breakdown.py")
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    acc: dict = {}
    _accumulate(acc, fs, "newton", "Newton solves (fitted meshes)")
    _accumulate(acc, fs, "_gauss_transfer", "Maxwell history transfers")
    _accumulate(acc, fs, "fitted_mesh", "fitted meshes")
    _accumulate(acc, fs._Problem, "__init__", "problems (assemblers, planes)")
    _accumulate(acc, fs._Problem, "observe", "observables")
    fs.compress(**FIG10)  # warm-up: sparsity patterns, orderings, topologies
    best: tuple[float, dict] | None = None
    for _ in range(a.repeats):
        acc.clear()
        t = time.perf_counter()
        fs.compress(**FIG10)
        wall = time.perf_counter() - t
        if best is None or wall < best[0]:
            best = (wall, dict(acc))
    assert best is not None
    wall, parts = best
    print(f"Fig. 10 (default mesh, to 1500 s), fastest of {a.repeats}: {1e3 * wall:.1f} ms")
    for k, v in sorted(parts.items(), key=lambda kv: -kv[1]):
        print(f"  {k:32s} {1e3 * v:7.1f} ms  ({100 * v / wall:4.1f} %)")
    print(f"  {'the rest':32s} {1e3 * (wall - sum(parts.values())):7.1f} ms")


if __name__ == "__main__":
    main()
