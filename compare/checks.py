"""Kept for ``python -m tissuemech.compare.checks``: the study lives in :mod:`tissuemech.compare.studies.checks`."""

from tissuemech.compare.studies.checks import *  # noqa: F403
from tissuemech.compare.studies.checks import main

if __name__ == "__main__":
    raise SystemExit(main())
