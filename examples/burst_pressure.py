"""Inflate a hollow shell and find its burst (limit) pressure: exact solution and finite elements.

A neo-Hookean shell (alpha = 0) has a maximum of the pressure-stretch curve; beyond it the shell
inflates without bound under a prescribed pressure (it "bursts"). The exact thick-shell solution gives
the limit point directly; the FE traces through it by arc length, and load control stops there with a
``LimitPointError``.

    python examples/burst_pressure.py
"""

import os

import numpy as np

from tissuemech.fem import blastula as fe_blastula
from tissuemech.reduced import blastula

FAST = os.environ.get("TISSUEMECH_EXAMPLES_FAST") == "1"  # tests/test_examples.py: small sizes

A, C = 50e-6, 200.0  # inner radius (m), Fung stiffness (Pa)

# 1. exact limit pressure of the seed's three wall thicknesses (neo-Hookean)
for B in (52e-6, 60e-6, 75e-6):
    lp = blastula.limit_point(inner_radius=A, outer_radius=B, C=C, alpha=0.0)
    print(
        f"B = {B * 1e6:.0f} um: bursts above p = {float(lp.pressure):7.2f} Pa (inner stretch {float(lp.inner_stretch):.4f})"
    )

# a Fung shell (alpha = 0.2) stiffens and has no limit point
print("alpha = 0.2, B = 75 um:", blastula.limit_point(inner_radius=A, outer_radius=75e-6, C=C, alpha=0.2))

# 2. the same limit point by finite elements: arc-length continuation through the maximum
B = 75e-6
mesh = (2, 4) if FAST else "default"
run = fe_blastula.inflate(
    inner_radius=A, outer_radius=B, C=C, alpha=0.0, pressures=None, method="arclength", max_inner_stretch=2.0, mesh=mesh
)
k = int(np.argmax(run.pressure))
exact = blastula.limit_point(inner_radius=A, outer_radius=B, C=C, alpha=0.0)
print(
    f"FE arc length ({len(run.pressure)} steps, mesh {mesh}): p_max = {run.pressure[k]:.2f} Pa at "
    f"lambda_a = {run.inner_stretch[k]:.3f}; exact {float(exact.pressure):.2f} Pa "
    f"(rel. difference {run.pressure[k] / float(exact.pressure) - 1:+.1e})"
)

# 3. load control cannot pass the limit point: it says so
try:
    fe_blastula.inflate(inner_radius=A, outer_radius=B, C=C, alpha=0.0, pressures=[100.0, 250.0], mesh=mesh)
except fe_blastula.LimitPointError as err:
    print("load control:", str(err).splitlines()[0])
