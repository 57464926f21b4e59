"""What every ``tissuemech`` command shares: the one-line error type, argument types, saving a figure."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any


class CLIError(Exception):
    """A user-facing error: printed as one line, exit code 2."""


def refuse(message: str) -> None:
    """Report a bad combination of options found after parsing (``tissuemech``'s main prints it as one line)."""
    raise CLIError(message)


@dataclass(frozen=True)
class Command:
    """A subcommand written once: its name, help line, ``options(parser)`` (adds the arguments, returns the
    parser) and ``execute(args, error)`` (does the work; ``error(message)`` reports a bad option, and
    ``args.words`` holds the command's own words for a provenance line). It gives the module's
    ``add_parser(sub)``, ``run(args)`` and a stand-alone ``main(argv)`` (``python -m ...``)."""

    name: str
    help: str
    description: str
    options: Callable[[argparse.ArgumentParser], argparse.ArgumentParser]
    execute: Callable[[argparse.Namespace, Callable[[str], None]], int]

    def add_parser(self, sub: Any) -> argparse.ArgumentParser:
        """Register the subcommand on an argparse subparsers object."""
        return self.options(sub.add_parser(self.name, help=self.help, description=self.description))

    def run(self, args: argparse.Namespace) -> int:
        """Run it from ``tissuemech NAME ...``."""
        args.words = sys.argv[sys.argv.index(self.name) + 1 :] if self.name in sys.argv else []
        return self.execute(args, refuse)

    def main(self, argv: Sequence[str] | None = None) -> int:
        """Run it stand-alone (``python -m``, or from Python with a list of words)."""
        words = list(sys.argv[1:] if argv is None else argv)
        ap = self.options(argparse.ArgumentParser(prog=f"tissuemech {self.name}", description=self.description))
        args = ap.parse_args(words)
        args.words = words
        return self.execute(args, ap.error)


def positive(kind: type = float) -> Callable[[str], Any]:
    """argparse type: a number > 0 of type ``kind``."""

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not value > 0:
            raise argparse.ArgumentTypeError(f"must be positive, got {text}")
        return value

    return parse


def nonnegative(text: str) -> float:
    """argparse type: a number >= 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text}")
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must not be negative, got {text}")
    return value


def save_figure(fig: Any, path: str, dpi: int = 130) -> None:
    """Save a matplotlib figure to ``path`` and close it."""
    from tissuemech.compare.plots import pyplot

    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)


def figure_path(option: str, text: str) -> str:
    """Check a figure output path before any computation; returns the path that will be written.

    A name without an extension gets ``.png`` (what matplotlib would write anyway, now said aloud);
    an existing folder, an unknown image format, a missing or read-only parent folder are CLIError
    with a one-line message naming ``option``.
    """
    from pathlib import Path

    p = Path(text)
    if p.is_dir():
        raise CLIError(f"{option} {text!r} is a folder; give a file name such as {str(p / 'figure.png')!r}")
    if not p.suffix:
        p = p.with_name(p.name + ".png")
    formats = {"png", "pdf", "svg", "jpg", "jpeg", "eps", "ps", "tif", "tiff", "webp"}
    if p.suffix.lower().lstrip(".") not in formats:
        raise CLIError(f"{option} {text!r}: unknown image format {p.suffix!r}; use .png, .pdf or .svg")
    _writable_parent(option, p)
    return str(p)


def output_folder(option: str, text: str) -> str:
    """Check an output folder before any computation (it may exist or will be created)."""
    from pathlib import Path

    p = Path(text)
    if p.exists() and not p.is_dir():
        raise CLIError(f"{option} {text!r} exists and is a file, not a folder; give a folder name")
    if not p.exists():
        _writable_parent(option, p)
    elif not _can_write(p):
        raise CLIError(f"{option} {text!r}: the folder is not writable")
    return str(p)


def _can_write(folder: Any) -> bool:
    import os

    return os.access(folder, os.W_OK | os.X_OK)


def _writable_parent(option: str, p: Any) -> None:
    parent = p.parent if str(p.parent) else type(p)(".")
    if not parent.exists():
        raise CLIError(f"{option} {str(p)!r}: the folder {str(parent)!r} does not exist")
    if not parent.is_dir():
        raise CLIError(f"{option} {str(p)!r}: {str(parent)!r} is not a folder")
    if not _can_write(parent):
        raise CLIError(f"{option} {str(p)!r}: the folder {str(parent)!r} is not writable")
