"""Export whole FE runs to ParaView as time series (PVD + one VTU per step).

Open ``blastula.pvd`` or ``spheroid.pvd`` in ParaView, apply *Warp By Vector* (vector:
``displacement``) and colour by ``von_mises_Pa``, ``hydrostatic_pressure_Pa`` or, for the spheroid,
``contact_pressure_Pa``; the time slider steps through the run (the pressure in Pa for the blastula
sweep, the time in s for the spheroid). *Reflect* (plane Z, then X) gives the full section.

    python examples/export_paraview.py
"""

import os

import numpy as np

from tissuemech.fem import blastula as fe_blastula
from tissuemech.fem import spheroid as fe_spheroid
from tissuemech.fem.output import read_pvd

FAST = os.environ.get("TISSUEMECH_EXAMPLES_FAST") == "1"  # tests/test_examples.py: small sizes
OUT = os.environ.get("TISSUEMECH_EXAMPLES_OUT", "example-output")  # where the files go
os.makedirs(OUT, exist_ok=True)


shell = fe_blastula.inflate(
    inner_radius=50e-6,
    outer_radius=75e-6,
    C=200.0,
    alpha=0.2,
    pressures=np.linspace(100.0, 1000.0, 4 if FAST else 10),
    mesh=(2, 4) if FAST else "default",
    store_fields=True,  # keep the fields of every step, not only the last
)
files = shell.to_pvd(f"{OUT}/blastula.pvd")
print(f"blastula: {files[0]} with {len(files) - 1} states at p = {[t for t, _ in read_pvd(files[0])]} Pa")

ball = fe_spheroid.compress(
    radius=500e-6,
    C=150.0,
    alpha=0.2,
    branches=[(0.4, 200.0)],
    displacement=50e-6,
    ramp_time=0.2,
    end_time=1500.0,
    mesh="coarse" if FAST else "default",
    field_times="all",  # every converged step (default: the requested field_times and the last)
)
files = ball.to_pvd(f"{OUT}/spheroid.pvd")
times = [t for t, _ in read_pvd(files[0])]
print(f"spheroid: {files[0]} with {len(files) - 1} states, t = {times[0]:.3g} .. {times[-1]:.4g} s")
