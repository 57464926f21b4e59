"""Kept for ``python -m tissuemech.compare.coverage``: the study lives in :mod:`tissuemech.compare.studies.coverage`,
the command in :mod:`tissuemech.compare.cli.coverage` (``tissuemech coverage``)."""

from tissuemech.compare.cli.coverage import main
from tissuemech.compare.studies.coverage import *  # noqa: F403
from tissuemech.compare.studies.coverage import __all__ as _study_all

__all__ = [*_study_all, "main"]

if __name__ == "__main__":
    raise SystemExit(main())
