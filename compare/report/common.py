"""What the report's sections share: the ``Section`` they return and the markdown table formatter."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["Section", "md_table"]


@dataclass
class Section:
    """One section of the report: its markdown lines, figures and tables (by file name), summary entries.

    ``quick`` is the run's mode; ``data`` carries computed results another section reads (e.g. the
    limit-point table the seed comparison quotes). Nothing is written here: ``report.build`` writes
    the figures and tables and joins the markdown in document order.
    """

    key: str
    quick: bool = False
    md: list[str] = field(default_factory=list)
    figures: dict[str, Any] = field(default_factory=dict)
    tables: dict[str, pd.DataFrame] = field(default_factory=dict)
    summary: dict[str, Any] = field(default_factory=dict)
    data: dict[str, Any] = field(default_factory=dict)

    def save(self, fig: Any, name: str) -> str:
        """Keep a matplotlib figure to be written as ``name`` (PNG)."""
        self.figures[name] = fig
        return name

    def table(self, df: pd.DataFrame, name: str) -> str:
        """Keep a table to be written as ``name`` (CSV)."""
        self.tables[name] = df
        return name


def md_table(df: pd.DataFrame, floatfmt: str = ".4g", cols: Sequence[str] | None = None) -> str:
    """A markdown table of ``df`` (NaN as an empty cell; ``|`` in strings replaced by ``/``)."""
    d = df[list(cols)] if cols is not None else df

    def cell(v):
        if isinstance(v, (float, np.floating)):
            return "" if np.isnan(v) else format(float(v), floatfmt)
        return str(v).replace("|", "/")

    lines = ["| " + " | ".join(d.columns) + " |", "|" + "---|" * len(d.columns)]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in d.itertuples(index=False)]
    return "\n".join(lines)
