"""Make ``oocyte_cell1_extract.csv.gz`` from the 15 JPK files of afmformats' example data (run once).

pip download --no-deps --no-binary :all: afmformats -d /tmp/afmsrc   # the sdist ships examples/data
python tests/data/afm/make_extract.py /tmp/afmsrc/afmformats-*/examples/data/10.1002_btm2.10294_fig5d-cell1.zip
"""

import sys

from tissuemech.compare.afm import records

curves = records.read_jpk(sys.argv[1])
light = [records.binned(c, {"pause": 8, "approach": 8, "hold": 16, "retract": 64}) for c in curves]
records.write_csv(
    light,
    "tests/data/afm/oocyte_cell1_extract.csv.gz",
    note="Battistella et al., Bioeng. Transl. Med. 7(3), e10294 (2022), doi:10.1002/btm2.10294, Fig. 5d cell 1\n"
    "(an oocyte, 15 stress-relaxation curves), as shipped with afmformats 0.18.7 (MIT, Paul Mueller).\n"
    "Binned means of consecutive samples: pause 8, approach 8, hold 16, retract 64 (tests/data/afm/make_extract.py).",
)
print(f"{len(light)} curves, {sum(c.time.size for c in light)} rows")
