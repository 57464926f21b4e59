"""``tissuemech calibrate-capillary``: tabulate the elastocapillary law (``reduced/data/capillary_master.npz``) or
a converged FE reference for it from static FE runs with a surface tension (the work is done by
:mod:`tissuemech.compare.calibrate_capillary`; ``python -m tissuemech.compare.calibrate_capillary`` is an alias)."""

from __future__ import annotations

import argparse
from typing import Any

from tissuemech.compare import calibrate_capillary as lib
from tissuemech.compare.cli.common import Command

__all__ = ["COMMAND", "add_parser", "run", "main"]

DESCRIPTION = (lib.__doc__ or "").strip().split("\n")[0]


def _options(ap: argparse.ArgumentParser) -> argparse.ArgumentParser:
    ap.add_argument("--out", default=str(lib.DEFAULT_OUT), help="table to write (default: the shipped one)")
    ap.add_argument("--store", default=None, help="folder for per-run results (resume)")
    ap.add_argument("--mesh", type=int, default=1, help="FE level of the table (default: %(default)s)")
    ap.add_argument("--error-mesh", type=int, default=2, help="FE level of --check (default: %(default)s)")
    ap.add_argument("--gammas", default=",".join(map(str, lib.DEFAULT_GAMMAS)), help="Gamma = gamma/(C a0) nodes")
    ap.add_argument("--alphas", default=",".join(map(str, lib.DEFAULT_ALPHAS)), help="alpha nodes")
    ap.add_argument("--x-max", type=float, default=0.3, help="largest x = delta/(2 a0) (default: %(default)s)")
    ap.add_argument("--n-x", type=int, default=31, help="x nodes from 0 (default: %(default)s)")
    ap.add_argument("--check", default="0.5:0.1", help="alpha:Gamma columns rerun on --error-mesh (none: skip)")
    ap.add_argument("--executor", default=None, help="'serial' or None (2 processes)")
    ap.add_argument("--reference", default=None, help="write a converged reference (JSON) to this path instead")
    ap.add_argument("--reference-columns", default="0.25:0.15,0.75:0.25", help="alpha:Gamma columns of --reference")
    ap.add_argument("--reference-levels", default="1,2,3", help="mesh levels of --reference (Richardson: 3 finest)")
    ap.add_argument("--against", default=None, help="a --reference JSON: the table's error against it in metadata")
    return ap


def _execute(a: argparse.Namespace, error: Any) -> int:
    return lib.run(a, "tissuemech calibrate-capillary " + " ".join(getattr(a, "words", [])))


COMMAND = Command(
    "calibrate-capillary", "tabulate the elastocapillary law from FE runs", DESCRIPTION, _options, _execute
)
add_parser, run, main = COMMAND.add_parser, COMMAND.run, COMMAND.main

if __name__ == "__main__":
    raise SystemExit(main())
