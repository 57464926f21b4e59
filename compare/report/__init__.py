"""``tissuemech report``: the seed's figures, accuracy-vs-speed charts and a stability map in one folder.

One module per section (:mod:`.seed_comparison`, :mod:`.blastula`, :mod:`.accuracy`,
:mod:`.spheroid`, :mod:`.stability`), each returning a :class:`~.common.Section`; :mod:`.build`
runs them and writes the folder. See :func:`build`.
"""

from typing import Any

from tissuemech.compare.report.build import FIGURES, SPHEROID_FIGURES, SPHEROID_TABLES, TABLES, build

__all__ = ["build", "FIGURES", "TABLES", "SPHEROID_FIGURES", "SPHEROID_TABLES"]


def __getattr__(name: str) -> Any:
    """The command-line entry points moved to :mod:`tissuemech.compare.cli.report`; the old names still work."""
    if name in ("add_parser", "run_cli", "main"):
        from tissuemech.compare.cli import report as cli_report

        return getattr(cli_report, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
