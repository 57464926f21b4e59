"""The blastula shell's Gauss rule: 3 x 3 points (degree 4) against 4 x 4 (degree 6), accuracy and time.

``python notes/issue14_shell_gauss.py``: for the seed's six sets (alpha 1e-5 / 0.1 / 0.2 / 0.3 at B = 75 um,
B = 52 / 60 um at alpha 0.2; 10 pressures to 1 kPa or 97 % of the limit pressure) the largest |lambda_a - ref|
on the 4x8 and 8x16 meshes with either rule, ref = the 24x48 mesh with the 4 x 4 rule, and the wall time of
each sweep (min of 2); then ``bench felupe``'s fine case (B = 60 um, kappa 2.2 GPa, 50 pressures) on 8x16
against its Richardson limit ``LAMBDA_RICHARDSON`` (made with the 4 x 4 rule). The box is shared: the
times are indicative, the errors exact.
"""

from __future__ import annotations

import time

import numpy as np

from tissuemech.compare.bench.felupe_side import LAMBDA_RICHARDSON, PRESSURES
from tissuemech.fem import blastula as fb
from tissuemech.fem.mesh import shell_section
from tissuemech.reduced import blastula as rb

A, C = 50e-6, 200.0
SETS = [(1e-5, 75e-6), (0.1, 75e-6), (0.2, 75e-6), (0.3, 75e-6), (0.2, 52e-6), (0.2, 60e-6)]


def sweep(alpha, B, ps, divisions, degree, kappa=2.2e9, repeats=2):
    m = shell_section(A, B, *divisions, intorder=degree)
    walls = []
    for _ in range(repeats):
        t = time.perf_counter()
        r = fb.inflate(inner_radius=A, outer_radius=B, C=C, alpha=alpha, kappa=kappa, pressures=ps, mesh=m)
        walls.append(time.perf_counter() - t)
    return np.asarray(r.inner_stretch), min(walls)


def main() -> None:
    print("max |lambda_a - ref| (wall s) per mesh / Gauss degree (6: 4 x 4 points, 4: 3 x 3); ref = 24x48, degree 6")
    for alpha, B in SETS:
        lim = rb.limit_point(inner_radius=A, outer_radius=B, C=C, alpha=alpha)
        pmax = min(1000.0, 0.97 * lim.pressure) if lim is not None else 1000.0
        ps = np.linspace(pmax / 10, pmax, 10)
        ref, _ = sweep(alpha, B, ps, (24, 48), 6, repeats=1)
        cells = []
        for div in ((4, 8), (8, 16)):
            for degree in (6, 4):
                lam, wall = sweep(alpha, B, ps, div, degree)
                cells.append(f"{div[0]}x{div[1]}/{degree} {np.max(np.abs(lam - ref)):.2e} ({wall:.2f})")
        print(f"alpha {alpha:g}, B {B * 1e6:g} um, to {pmax:.0f} Pa: " + "  ".join(cells), flush=True)
    print("bench felupe fine case (B 60 um, 50 pressures), 8x16 against LAMBDA_RICHARDSON:")
    for degree in (6, 4):
        lam, wall = sweep(0.2, 60e-6, PRESSURES, (8, 16), degree, repeats=3)
        print(f"  degree {degree}: error {np.max(np.abs(lam - LAMBDA_RICHARDSON)):.3e}, wall {wall:.3f} s")


if __name__ == "__main__":
    main()
