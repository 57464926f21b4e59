"""``tissuemech calibrate-drop``: tabulate the exact liquid drop's plate force for the reduced liquid law
(``reduced/data/drop_master.npz``; the work is done by :mod:`tissuemech.compare.calibrate_drop`; ``python -m
tissuemech.compare.calibrate_drop`` is an alias)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from tissuemech.compare import calibrate_drop as lib
from tissuemech.compare.cli.common import Command
from tissuemech.reduced import liquid

__all__ = ["COMMAND", "add_parser", "run", "main"]

DESCRIPTION = (lib.__doc__ or "").strip().split("\n")[0]


def _options(ap: argparse.ArgumentParser) -> argparse.ArgumentParser:
    ap.add_argument("--knots", type=int, default=361, help="knots uniform in sqrt(x) on [0, X_MAX]")
    ap.add_argument("--out", default=str(liquid.DATA_FILE), help="output .npz (default: the shipped table)")
    return ap


def _execute(a: argparse.Namespace, error: Any) -> int:
    if a.knots < 3:
        error(f"--knots must be at least 3; got {a.knots}")
    command = "tissuemech calibrate-drop " + " ".join(getattr(a, "words", []))
    print(json.dumps(lib.run(a.knots, a.out, command.strip()), indent=1))
    return 0


COMMAND = Command(
    "calibrate-drop", "tabulate the exact liquid drop's force for the reduced liquid", DESCRIPTION, _options, _execute
)
add_parser, run, main = COMMAND.add_parser, COMMAND.run, COMMAND.main

if __name__ == "__main__":
    raise SystemExit(main())
