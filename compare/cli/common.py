"""What every ``tissuemech`` command shares: the one-line error type, argument types, saving a figure."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any


class CLIError(Exception):
    """A user-facing error: printed as one line, exit code 2."""


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
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must not be negative, got {text}")
    return value


def save_figure(fig: Any, path: str, dpi: int = 130) -> None:
    """Save a matplotlib figure to ``path`` and close it."""
    from tissuemech.compare.plots import pyplot

    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)
