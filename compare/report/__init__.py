"""``tissuemech report``: the seed's figures, accuracy-vs-speed charts and a stability map in one folder.

One module per section (:mod:`.seed_comparison`, :mod:`.blastula`, :mod:`.accuracy`,
:mod:`.spheroid`, :mod:`.stability`), each returning a :class:`~.common.Section`; :mod:`.build`
runs them and writes the folder. See :func:`build`.
"""

from tissuemech.compare.report.build import (
    FIGURES,
    SPHEROID_FIGURES,
    SPHEROID_TABLES,
    TABLES,
    add_parser,
    build,
    main,
    run_cli,
)

__all__ = ["build", "add_parser", "run_cli", "main", "FIGURES", "TABLES", "SPHEROID_FIGURES", "SPHEROID_TABLES"]
