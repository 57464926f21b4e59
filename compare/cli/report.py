"""``tissuemech report``: the seed's figures, accuracy-vs-speed charts and the stability map in one folder
(:func:`tissuemech.compare.report.build` does the work)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tissuemech.compare.report import build

__all__ = ["add_parser", "run", "run_cli", "main"]


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Register the ``report`` subcommand on an argparse subparsers object."""
    r = sub.add_parser(
        "report",
        help="regenerate the seed's figures, accuracy-vs-speed charts and the stability map into a folder",
        description="Runs the reduced and FE models for both scenes and writes PNG figures, CSV tables and "
        "report.md (with the measured numbers and the comparison with the seed) into --out.",
    )
    r.add_argument("--out", default="tissuemech-report", help="output folder (default: %(default)s)")
    r.add_argument("--quick", action="store_true", help="coarse meshes, fewer levels (under 3 minutes)")
    r.add_argument(
        "--cache-dir",
        default=None,
        help="folder of the FE run cache (default: $TISSUEMECH_CACHE_DIR, else $XDG_CACHE_HOME/tissuemech/runs, "
        "i.e. ~/.cache/tissuemech/runs): FE runs whose inputs and code did not change are reused with their times",
    )
    r.add_argument(
        "--no-cache",
        action="store_true",
        help="run every FE computation anew and compile every JAX program (read and write no cache)",
    )
    r.add_argument("--clear-cache", action="store_true", help="empty the FE run cache first")
    return r


def run(args: argparse.Namespace) -> None:
    """``tissuemech report``: check the folder, build it and print where it went."""
    from tissuemech.compare import runcache
    from tissuemech.compare.cli.common import output_folder

    output_folder("--out", args.out)
    runcache.configure(getattr(args, "cache_dir", None), False if getattr(args, "no_cache", False) else None)
    if not getattr(args, "no_cache", False):
        from tissuemech.compare.cli.blastula import enable_jit_cache

        enable_jit_cache()  # JAX's compiled programs too (a cold report spends ~1/4 of its time compiling)
    if getattr(args, "clear_cache", False):
        print(f"cleared {runcache.clear()} cached FE runs")
    summary = build(args.out, quick=args.quick)
    out = Path(args.out).resolve()
    print(
        f"wrote {len(summary['files'])} files to {out} (report: {out / 'report.md'}) in {summary['total_wall_s']:.0f} s"
    )
    if not summary["spheroid_available"]:
        print("note: spheroid sections not available (fem.spheroid / reduced.spheroid missing)")


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tissuemech.compare.report [--out DIR] [--quick]``."""
    p = argparse.ArgumentParser(prog="python -m tissuemech.compare.report")
    sub = p.add_subparsers(dest="command")
    add_parser(sub)
    args = p.parse_args(["report", *(argv if argv is not None else sys.argv[1:])])
    run(args)
    return 0


run_cli = run  # the earlier name


if __name__ == "__main__":
    raise SystemExit(main())
