"""``tissuemech bench NAME [options]``: run one benchmark suite (or ``all``), as
``python -m tissuemech.compare.bench`` does."""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Register ``bench`` on an argparse subparsers object."""
    from tissuemech.compare.bench.__main__ import SUITES

    b = sub.add_parser(
        "bench",
        help="run a benchmark suite (timings and accuracy tables quoted in the README)",
        description="Run one of the benchmark suites and print its tables. Options after NAME go to the "
        "suite (e.g. --quick); 'tissuemech bench NAME --help' describes the suite without running it.",
    )
    b.add_argument("name", choices=[*SUITES, "all"], help="suite: %(choices)s")
    b.add_argument("options", nargs=argparse.REMAINDER, help="options passed to the suite")
    return b


def run(args: argparse.Namespace) -> None:
    """Dispatch to ``tissuemech.compare.bench.__main__.main``."""
    from tissuemech.compare.bench.__main__ import main

    rc = main([args.name, *args.options])
    if rc:
        raise SystemExit(rc)
