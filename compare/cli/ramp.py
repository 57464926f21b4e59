"""``python -m tissuemech.compare.studies.ramp``: the lumped model's ramp error against the FE (the command line of
:func:`tissuemech.compare.studies.ramp.ramp_error`)."""

from __future__ import annotations

import argparse
import sys

from tissuemech.compare.studies.ramp import ALPHAS, RATIOS, ramp_error
from tissuemech.compare.studies.ramp import __doc__ as STUDY_DOC

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.studies.ramp", description=STUDY_DOC)
    ap.add_argument("--level", type=int, default=0, help="the FE level (default 0)")
    ap.add_argument("--ratios", default=",".join(map(str, RATIOS)), help="tau / ramp_time values")
    ap.add_argument("--alphas", default=",".join(map(str, ALPHAS)), help="Fung alpha values")
    ap.add_argument("--beta", type=float, default=0.8, help="the branch's energy factor (default 0.8)")
    ap.add_argument("--x", type=float, default=0.1, help="the final approach delta / (2 a0) (default 0.1)")
    ap.add_argument("--tol", type=float, default=1e-4, help="Adaptive(tol) of the FE runs (default 1e-4)")
    ap.add_argument("--csv", default=None, help="also write the table to this CSV file")
    a = ap.parse_args(argv)
    df = ramp_error(
        [float(v) for v in a.ratios.split(",")],
        [float(v) for v in a.alphas.split(",")],
        beta=a.beta,
        x=a.x,
        level=a.level,
        tol=a.tol,
    )
    print(
        f"# lumped model's ramp error e = F_red / F_FE - F_eq,red / F_FE,elastic (beta = {a.beta}, x = {a.x}, "
        f"FE level {a.level}, Adaptive(tol={a.tol:g}))"
    )
    wide = df.pivot(index="tau / ramp", columns="alpha", values="max_error")
    print("max error (signed; rows tau / ramp_time, columns alpha)")
    print(wide.to_string(float_format=lambda v: f"{v:+.2e}"))
    print(df.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    if a.csv:
        df.to_csv(a.csv, index=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
