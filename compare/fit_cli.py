"""Kept for old imports: the reader lives in :mod:`tissuemech.compare.fit.records`, the command ``tissuemech fit``
in :mod:`tissuemech.compare.cli.fit`."""

from tissuemech.compare.cli.fit import add_parser, run
from tissuemech.compare.fit.records import Table, load_records, read_table

__all__ = ["Table", "read_table", "add_parser", "run", "load_records"]
