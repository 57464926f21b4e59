"""Kept for ``python -m tissuemech.compare.checks``: the study lives in :mod:`tissuemech.compare.studies.checks`,
the command is ``tissuemech checks``."""

from tissuemech.compare.studies.checks import *  # noqa: F403

if __name__ == "__main__":
    from tissuemech.compare.cli.checks import main

    raise SystemExit(main())
