"""Kept for ``python -m tissuemech.compare.readme_tables``: the tables live in
:mod:`tissuemech.compare.report.readme_tables`, the command is ``tissuemech readme-tables``."""

from tissuemech.compare.report.readme_tables import *  # noqa: F403
from tissuemech.compare.report.readme_tables import BLOCKS, DETERMINISTIC, blocks_in, check, render

__all__ = ["BLOCKS", "DETERMINISTIC", "blocks_in", "check", "render"]

if __name__ == "__main__":
    from tissuemech.compare.cli.readme_tables import main

    raise SystemExit(main())
