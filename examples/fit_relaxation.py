"""Fit your own compression-relaxation data: C, alpha, beta, tau with 95 % intervals.

Give one CSV per compression level (columns: time in s, nominal stress F / A_mid in Pa; a header line
is optional) and its total plate approach in m:

    python examples/fit_relaxation.py level1.csv:50e-6 level2.csv:150e-6 --radius 500e-6 --ramp-time 0.2

Without files, the example writes two SYNTHETIC records (the reduced model with 1 % noise, true values
C = 150 Pa, alpha = 0.2, beta = 0.4, tau = 200 s) and fits those. With a single compression level the
fit reports that C and alpha cannot be told apart (only the equilibrium force at that level is seen).
"""

import argparse
import os

import numpy as np

from tissuemech.compare import fit
from tissuemech.reduced import spheroid

OUT = os.environ.get("TISSUEMECH_EXAMPLES_OUT", "example-output")  # where the files go
os.makedirs(OUT, exist_ok=True)

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("records", nargs="*", help="CSV:APPROACH_M pairs, e.g. data.csv:50e-6")
ap.add_argument("--radius", type=float, default=500e-6, help="spheroid radius a0 in m")
ap.add_argument("--ramp-time", type=float, default=0.2, help="duration of the loading ramp in s")
a = ap.parse_args()

if not a.records:  # SYNTHETIC data from the reduced model
    rng = np.random.default_rng(1)
    t = np.concatenate([np.linspace(0.01, a.ramp_time, 10), np.geomspace(0.3, 1500.0, 60)])
    for k, d in enumerate((50e-6, 150e-6)):
        s = np.asarray(
            spheroid.nominal_stress(
                t, radius=a.radius, C=150.0, alpha=0.2, branches=[(0.4, 200.0)], displacement=d, ramp_time=a.ramp_time
            )
        )
        path = f"{OUT}/synthetic_level{k}.csv"
        np.savetxt(
            path, np.c_[t, s * (1 + 0.01 * rng.standard_normal(t.size))], delimiter=",", header="time_s,stress_Pa"
        )
        a.records.append(f"{path}:{d}")
        print(f"wrote SYNTHETIC record {path} (approach {d * 1e6:.0f} um)")

records = []
for item in a.records:
    path, _, d = item.rpartition(":")
    records.append(fit.read_csv(path, displacement=float(d)))

res = fit.relaxation(records, radius=a.radius, ramp_time=a.ramp_time)
print(res.summary())
one = fit.relaxation(records[:1], radius=a.radius, ramp_time=a.ramp_time)
print("\nthe first level alone:\n" + one.report)
