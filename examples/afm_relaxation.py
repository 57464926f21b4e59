"""Fit real AFM stress-relaxation records: a spherical probe on an oocyte resting on a dish.

The data: 15 force curves on one oocyte (Battistella et al., Bioeng. Transl. Med. 7(3), e10294 (2022),
doi:10.1002/btm2.10294, Fig. 5d cell 1; shipped with afmformats, MIT), as the binned CSV extract in
tests/data/afm (or your own JPK/CSV files). For each curve: the contact point on the approach, the measured
indentation history (piezo travel minus cantilever deflection), and the lumped Maxwell model of
``tissuemech.reduced.indentation`` fitted to the 30 s hold with one and with two branches:

    python examples/afm_relaxation.py                                  # all 15 curves (~2 min)
    python examples/afm_relaxation.py my_curves.zip --probe-radius-um 10 --radius-um 40

The probe and ball radii are NOT in the files: the defaults (R_p = 25 um, a0 = 40 um) are assumptions. beta and
tau do not depend on them; C scales as R_s^(-1/2) (see docs/afm.md).
"""

import argparse
import os
import time
from pathlib import Path

from tissuemech.compare.afm import study
from tissuemech.compare.cli.afm import load_curves
from tissuemech.compare.plots import pyplot
from tissuemech.compare.plots.afm import relaxation_figure

OUT = os.environ.get("TISSUEMECH_EXAMPLES_OUT", "example-output")
FAST = os.environ.get("TISSUEMECH_EXAMPLES_FAST") == "1"  # the test suite: 3 curves
os.makedirs(OUT, exist_ok=True)
EXTRACT = Path(__file__).resolve().parents[1] / "tests" / "data" / "afm" / "oocyte_cell1_extract.csv.gz"

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("data", nargs="*", default=[str(EXTRACT)], help="JPK file/folder/.zip or CSV files")
ap.add_argument("--probe-radius-um", type=float, default=25.0, help="probe radius R_p in um (assumed)")
ap.add_argument("--radius-um", type=float, default=40.0, help="ball (oocyte) radius a0 in um (assumed)")
a = ap.parse_args()

curves = load_curves(a.data)
if FAST:
    curves = curves[:3]
print(f"{len(curves)} curves; spring constant {curves[0].spring_constant:.4g} N/m")
t0 = time.perf_counter()
st = study.run(curves, probe_radius=a.probe_radius_um * 1e-6, radius=a.radius_um * 1e-6)
print(st.report())
print(f"wall time {time.perf_counter() - t0:.1f} s")
fig = relaxation_figure(st.one, st.two, title="AFM stress relaxation of an oocyte (Battistella et al. 2022)")
fig.savefig(f"{OUT}/afm_relaxation.png", dpi=110)
pyplot().close(fig)
print(f"wrote {OUT}/afm_relaxation.png")
