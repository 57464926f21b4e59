"""Where the default meshes' FE runs spend their wall time, part by part, against the floor of their work.

``python notes/issue14_newton_breakdown.py [--repeats 5]``: the two runs of ``bench fem-perf``'s per-iteration
table (the blastula 4x8 50-step sweep, the spheroid Fig. 10 case on level 1), each timed with wall-clock
accumulators around its residual evaluations (``Assembler.internal`` / ``internal_follower``: kinematics,
constitutive law, follower load, assembly of r), admissibility checks, tangent assemblies, factorisations and
solves; prints the fastest run's parts (ms), the run's floor (``fem_perf._run_floor``: LU x (best bare LU +
tangent element matmuls) + iterations x bare solve + residuals x residual element matmuls, timed on a tangent of
the same mesh) and two ratios to it:

- ``run / floor``: what ``fem-perf``'s ``run`` column shows;
- ``kernels / floor``: the sum of this code's residual, admissibility, tangent, factorisation and solve calls
  alone, as if the Newton loop's own logic (Broyden updates, step and convergence tests, copies) and all work
  outside Newton (predictors, output, fitted meshes) cost nothing. (The admissibility check of a trial state
  forms its F, which the residual then reuses: the two together are one residual pass.) Above 1.5x, no change
  of the loop can reach issue 14's target: the kernels themselves would have to get faster.

The accumulators cost ~1 us a call (a few hundred calls per run).
"""

from __future__ import annotations

import argparse
import time
import types

import numpy as np
from issue14_fig10_breakdown import _accumulate  # (the notes folder is on sys.path when run as a script)

from tissuemech.compare.bench import fem_perf as bp
from tissuemech.fem import blastula as fb
from tissuemech.fem import forms, problem
from tissuemech.fem import newton as nw
from tissuemech.fem import spheroid as fs

PARTS = ("residuals", "tangent assemblies", "factorisations", "solves", "admissibility checks")


def _counted(acc: dict, fn, label: str):
    """fn with its wall time added to acc[label] and its calls counted in acc["n " + label]."""
    holder = types.SimpleNamespace(fn=fn)
    _accumulate(acc, holder, "fn", label)
    timed = holder.fn

    def counting(*a, **k):
        acc["n " + label] = acc.get("n " + label, 0) + 1
        return timed(*a, **k)

    return counting


def _instrument(acc: dict) -> None:
    """Accumulators around the parts (module attributes replaced for this process)."""
    _accumulate(acc, forms.Assembler, "internal", "residuals")
    _accumulate(acc, forms.Assembler, "internal_follower", "residuals")
    _accumulate(acc, problem.SceneProblem, "admissible", "admissibility checks")
    _accumulate(acc, nw, "_tangent", "tangent assemblies")
    _accumulate(acc, nw, "_newton", "inside newton")
    factor = nw.symmetric_factor

    def timed_factor(K, *a, **k):
        t = time.perf_counter()
        s = factor(K, *a, **k)
        acc["factorisations"] = acc.get("factorisations", 0.0) + time.perf_counter() - t
        acc["n LU"] = acc.get("n LU", 0) + 1
        out = _counted(acc, s, "solves")
        for attr in ("unrefined", "inexact"):
            setattr(out, attr, _counted(acc, getattr(s, attr), "solves"))
        return out

    fb.symmetric_factor = fs.symmetric_factor = timed_factor


def main() -> None:
    ap = argparse.ArgumentParser(prog="python notes/issue14_newton_breakdown.py")
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    ps = np.linspace(20.0, 1000.0, 50)
    runs = {
        "blastula 4x8 sweep (50 steps)": (
            lambda: fb.inflate(inner_radius=bp.A, outer_radius=bp.B, C=bp.C, alpha=0.2, pressures=ps),
            lambda: bp._blastula_state((4, 8)),
        ),
        "spheroid Fig. 10 level 1": (lambda: fs.compress(**bp.FIG10), lambda: bp._spheroid_state(1)),
    }
    states = {}
    for name, (_, make) in runs.items():  # the floors' tangents first, before any accumulator is in place
        st = make()
        prob, x, K = st[0], st[1], st[2]
        states[name] = (K, prob.asm, prob.full(x) if name.startswith("blastula") else x, prob.mat)
    acc: dict = {}
    _instrument(acc)
    for name, (run, _) in runs.items():
        run()  # warm-up: patterns, orderings, plans
        best: tuple[float, dict, int] | None = None
        for _ in range(a.repeats):
            acc.clear()
            t = time.perf_counter()
            res = run()
            wall = time.perf_counter() - t
            if best is None or wall < best[0]:
                best = (wall, dict(acc), int(np.sum(res.newton_iterations)))
        assert best is not None
        wall, parts, iters = best
        with bp._count_residuals() as count_r:
            run()
            n_res = count_r.n
        floor, lu_name = bp._run_floor(states[name], parts.get("n LU", 0), iters, n_res)
        kernels = sum(parts.get(k, 0.0) for k in PARTS)
        print(f"\n{name}: fastest of {a.repeats} {1e3 * wall:.1f} ms; {iters} iterations, {parts.get('n LU', 0)} "
              f"factorisations, {n_res} residuals, {parts.get('n solves', 0)} solves")  # fmt: skip
        for k in PARTS:
            print(f"  {k:34s} {1e3 * parts.get(k, 0.0):7.1f} ms")
        loop = parts.get("inside newton", 0.0) - sum(parts.get(k, 0.0) for k in PARTS)
        print(f"  {'the Newton loop itself':34s} {1e3 * loop:7.1f} ms")
        print(f"  {'outside newton':34s} {1e3 * (wall - parts.get('inside newton', 0.0)):7.1f} ms")
        print(f"  floor of this work ({lu_name}) {1e3 * floor:.1f} ms: run / floor {wall / floor:.2f}, "
              f"kernels / floor {kernels / floor:.2f}")  # fmt: skip
        per = 1e6 * (parts.get("residuals", 0.0) + parts.get("admissibility checks", 0.0)) / n_res
        print(f"  one residual pass (residual + admissibility check) {per:.0f} us against its element matmuls "
              f"{1e6 * bp._med(bp._residual_flops(*states[name][1:3]), 20):.0f} us")  # fmt: skip


if __name__ == "__main__":
    main()
