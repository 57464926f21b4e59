"""A parameter scan of the reduced spheroid with FE spot-checks.

``compare.scan.spheroid`` evaluates the fast reduced model (FE-calibrated lumped Maxwell) on a grid of
(C, beta) and runs the finite-element model at a few spread points to show how far the reduced model is
off there (column ``deviation [-]``).

    python examples/scan_with_fe_check.py
"""

import os

import pandas as pd

from tissuemech.compare import scan

FAST = os.environ.get("TISSUEMECH_EXAMPLES_FAST") == "1"  # tests/test_examples.py: small sizes
OUT = os.environ.get("TISSUEMECH_EXAMPLES_OUT", "example-output")  # where the files go
os.makedirs(OUT, exist_ok=True)

table = scan.spheroid(
    C=[100.0, 150.0, 200.0] if FAST else list(range(100, 301, 25)),
    beta=[0.2, 0.8] if FAST else [0.1, 0.2, 0.4, 0.8, 1.2],
    alpha=0.2,
    tau=200.0,
    displacement=50e-6,
    ramp_time=0.2,
    end_time=300.0 if FAST else 1500.0,
    fe_checks=1 if FAST else 3,
    fe_executor="serial",  # FE runs in this process; None: 2 local processes; or a dask Client
)
pd.set_option("display.width", 160)
print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
checked = table.dropna(subset=["deviation [-]"])
print(
    f"\n{len(table)} reduced curves; FE spot-checks at {len(checked)} points, max deviation {checked['deviation [-]'].max():.2%}"
)
path = f"{OUT}/scan.csv"
table.to_csv(path, index=False)
print("wrote", path)
