"""``tissuemech report``: the argparse wiring lives with the report (:mod:`tissuemech.compare.report`)."""

from __future__ import annotations

from tissuemech.compare.report import add_parser, run_cli

run = run_cli

__all__ = ["add_parser", "run"]
