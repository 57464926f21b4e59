"""How well load_control's predictors guess the next blastula state: the monitor-quadratic vs Euler's exact slope.

``python notes/issue14_monitor_predictor.py [--outer 75e-6] [--mesh 8x16]``: a 10-step sweep 100..1000 Pa (A = 50 um,
C = 200 Pa, alpha = 0.2), each state converged; per step from the fourth on, the displacement error of
``continuation._monitor_quadratic`` (through the three states before, monitor = the inner stretch) and of the
Euler guess x + (dx/dlam) dlam with the exact tangent at the state before, relative to the step |x_n - x_(n-1)|
(displacement dofs only). "-" where the quadratic declines (lam(m) turns before the target: load_control then
predicts by Euler).
"""

from __future__ import annotations

import argparse

import numpy as np

from tissuemech.fem import blastula as fb
from tissuemech.fem import continuation as ct
from tissuemech.fem.newton import sparse_solve


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--outer", type=float, default=75e-6, help="outer radius B [m]")
    ap.add_argument("--mesh", default="8x16", help="n_radial x n_circ")
    a = ap.parse_args()
    mesh = tuple(int(v) for v in a.mesh.split("x"))
    prob = fb._setup(50e-6, a.outer, 200.0, 0.2, 2.2e9, mesh)
    disp = prob.free < prob.asm.n_u
    lams = np.linspace(100.0, 1000.0, 10) / 200.0
    xs, x = [], np.zeros(prob.free.size)
    for lam in lams:
        x = prob.solve(lam, x, 1e-10, f"{lam * 200:.0f} Pa").x
        xs.append(x)
    print(f"B = {a.outer * 1e6:.0f} um, mesh {a.mesh}: predictor error / step (displacement dofs)")
    print("pressure   quadratic(inner stretch)   Euler (exact slope)")
    for i in range(3, lams.size):
        hist = [(lams[j], prob.inner_stretch(xs[j]), xs[j]) for j in (i - 3, i - 2, i - 1)]
        quad = ct._monitor_quadratic(hist, lams[i])
        _, K, minus_fp = prob.rk(xs[i - 1], lams[i - 1])
        euler = xs[i - 1] + sparse_solve(K, -minus_fp) * (lams[i] - lams[i - 1])
        step = np.linalg.norm((xs[i] - xs[i - 1])[disp])
        q = "-" if quad is None else f"{np.linalg.norm((quad - xs[i])[disp]) / step:.3f}"
        print(f"{lams[i] * 200:6.0f} Pa  {q:>24s}   {np.linalg.norm((euler - xs[i])[disp]) / step:18.3f}")


if __name__ == "__main__":
    main()
