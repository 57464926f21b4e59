"""The ``tissuemech`` command line: the seed's scenes from the fast reduced models, the report, the benchmarks.

    tissuemech blastula [--out blastula.png] [--max-pressure 1000] [--step 100] [--fem]
    tissuemech spheroid [--out spheroid.png] [--C 150] [--alpha 0.2] [--beta 0.4] [--tau 200] ...
    tissuemech report [--out DIR] [--quick]     (figures, accuracy-vs-speed charts, stability map)
    tissuemech bench NAME [options]             (benchmark suites)
    tissuemech scan spheroid|blastula [--C 100:400] [--tau 10:1000:log] ... [--out DIR]   (parameter scans)
    tissuemech fit DATA.csv [...] --radius-um R --displacement-um D --ramp-time T   (fit your data)
    tissuemech design [--noise 0.01] [--check N]  (experiment design: predicted interval widths)
    tissuemech coverage [--no-fe] [--n-reduced N] (coverage study of the fit's 95 % intervals)
    tissuemech batch run|collect ...            (FE batches for job arrays)
    tissuemech --version

Tables go to stdout, figures to PNG. Bad arguments get a one-line error (exit code 2).

Each command is a module with ``add_parser(sub)`` (registers the subcommand on an argparse
subparsers object) and ``run(args)``; ``COMMANDS`` lists them in help order. To add a command,
append ``(name, "module path")`` to ``COMMANDS``; the module is imported only when the parser is built.
"""

from __future__ import annotations

import argparse
import gc
import importlib
import logging
import os
import sys
from collections.abc import Sequence

from tissuemech.compare.cli.common import CLIError

__all__ = ["main", "COMMANDS", "CLIError", "build_parser"]

# (subcommand, module with add_parser(sub) and run(args)); extra commands (fit, scan, ...) go here.
COMMANDS: list[tuple[str, str]] = [
    ("blastula", "tissuemech.compare.cli.blastula"),
    ("spheroid", "tissuemech.compare.cli.spheroid"),
    ("report", "tissuemech.compare.cli.report"),
    ("bench", "tissuemech.compare.cli.bench"),
    ("batch", "tissuemech.compare.cli.batch"),
    ("fit", "tissuemech.compare.cli.fit"),
    ("design", "tissuemech.compare.cli.design"),
    ("coverage", "tissuemech.compare.cli.coverage"),
    ("scan", "tissuemech.compare.cli.scan"),
    ("calibrate", "tissuemech.compare.cli.calibrate"),
    ("calibrate-indentation", "tissuemech.compare.cli.calibrate_indentation"),
    ("calibrate-capillary", "tissuemech.compare.cli.calibrate_capillary"),
    ("calibrate-drop", "tissuemech.compare.cli.calibrate_drop"),
    ("checks", "tissuemech.compare.cli.checks"),
    ("readme-tables", "tissuemech.compare.cli.readme_tables"),
    ("afm", "tissuemech.compare.cli.afm"),
]


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The argparse root with every subcommand of ``COMMANDS`` registered (or only the command ``only``:
    registering a command imports its module, and some pull in pandas or the report)."""
    import tissuemech

    p = argparse.ArgumentParser(
        prog="tissuemech",
        description="Mechanics of developing tissue: blastula inflation and spheroid "
        "compression-relaxation (Peters & Iber scenes), fast reduced models with FE checks.",
    )
    p.add_argument("--version", action="version", version=f"tissuemech {tissuemech.__version__}")
    p.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help="log what the solvers do (-v: INFO, -vv: DEBUG: every load/time step and cut-back)",
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    for name, module in COMMANDS:
        if only is None or name == only:
            importlib.import_module(module).add_parser(sub)
    _one_line_errors(p)
    return p


def _one_line_errors(parser: argparse.ArgumentParser) -> None:
    """Bad arguments of ``parser`` and of its subcommands' parsers: one line on stderr, exit code 2 (argparse
    prints its usage block first); a parser with an error method of its own keeps it."""

    def error(message: str, prog: str = parser.prog):
        print(f"{prog}: error: {message} (see {prog} --help)", file=sys.stderr)
        raise SystemExit(2)

    if "error" not in vars(parser):
        parser.error = error  # type: ignore[method-assign]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                _one_line_errors(child)


def _command_in(argv: Sequence[str]) -> str | None:
    """The subcommand named in ``argv`` (the first word that is not an option), if it is one of ``COMMANDS``."""
    for word in argv:
        if not word.startswith("-"):
            return word if word in dict(COMMANDS) else None
    return None


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``tissuemech`` console script; returns the exit code."""
    words = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(_command_in(words))  # a known command: import only its module
    args = parser.parse_args(words)
    if args.command is None:
        parser.print_help()
        return 0
    if args.verbose:
        logging.basicConfig(
            level=logging.DEBUG if args.verbose > 1 else logging.INFO,
            format="%(levelname)s %(name)s: %(message)s",
        )
    module = dict(COMMANDS)[args.command]
    # the command line writes files and never opens a window: the one place a backend is chosen (before
    # matplotlib is imported; an MPLBACKEND the user set wins)
    os.environ.setdefault("MPLBACKEND", "Agg")
    try:
        rc = importlib.import_module(module).run(args)
    except (ValueError, CLIError, OSError) as exc:
        msg = str(exc).replace("Use equilibrium='hertz'", "Use --equilibrium hertz")
        msg = msg.replace("use equilibrium='hertz'", "use --equilibrium hertz").replace(" or a callable,", ",")
        if isinstance(exc, OSError) and exc.filename is not None:  # a raw errno: say which file, in words
            msg = f"{exc.filename!r}: {exc.strerror}"
        print(f"tissuemech {args.command}: error: {msg}", file=sys.stderr)
        return 2
    return rc if isinstance(rc, int) else 0


def console_main() -> int:
    """The ``tissuemech`` console script: :func:`main`, then every object of the process frozen out of Python's
    cyclic garbage collector (``gc.freeze``). The interpreter's exit would otherwise walk the object graphs of
    JAX and matplotlib once more, 0.2-0.3 s of every command on the 2-core machine, to collect cycles in a
    process that is about to end (destructors and ``atexit`` handlers still run). In-process callers use
    :func:`main`, which leaves the collector as it is."""
    try:
        return main()
    finally:
        gc.freeze()


if __name__ == "__main__":
    raise SystemExit(console_main())
