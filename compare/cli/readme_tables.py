"""``tissuemech readme-tables``: print the README's result tables from the commands that make them, or check a
README against them (the work is done by :mod:`tissuemech.compare.report.readme_tables`)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import tissuemech.compare.report.readme_tables as lib
from tissuemech.compare.cli.common import Command

__all__ = ["COMMAND", "add_parser", "run", "main"]

DESCRIPTION = (lib.__doc__ or "").strip().split("\n")[0]


def _options(ap: argparse.ArgumentParser) -> argparse.ArgumentParser:
    ap.add_argument("--only", default=",".join(lib.BLOCKS), help="comma list of: " + ",".join(lib.BLOCKS))
    ap.add_argument(
        "--check", metavar="README.md", help="compare the deterministic blocks of this file; exit 1 if any differs"
    )
    return ap


def _execute(a: argparse.Namespace, error: Any) -> int:
    names = [n for n in a.only.split(",") if n]
    bad = [n for n in names if n not in lib.BLOCKS]
    if bad:
        error(f"unknown table(s) {', '.join(bad)}; choose from {', '.join(lib.BLOCKS)}")
    if a.check:
        if not Path(a.check).is_file():
            error(f"--check {a.check!r}: no such file")
        present = lib.blocks_in(Path(a.check).read_text())
        diffs = lib.check(a.check, names)
        for d in diffs:
            print(d)
        checked = [n for n in names if n in present and n in lib.DETERMINISTIC]
        print(f"checked {', '.join(checked) or 'no blocks'}: {'all match' if not diffs else f'{len(diffs)} differ'}")
        return 1 if diffs else 0
    for n in names:
        print(lib.render(n) + "\n")
    return 0


COMMAND = Command(
    "readme-tables", "print the README's result tables (or check a page against them)", DESCRIPTION, _options, _execute
)
add_parser, run, main = COMMAND.add_parser, COMMAND.run, COMMAND.main

if __name__ == "__main__":
    raise SystemExit(main())
