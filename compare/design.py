"""Kept for ``from tissuemech.compare import design`` and ``python -m tissuemech.compare.design``: experiment design
lives in :mod:`tissuemech.compare.fit.design`, the command in :mod:`tissuemech.compare.cli.design`
(``tissuemech design``)."""

from tissuemech.compare.cli.design import main
from tissuemech.compare.fit.design import *  # noqa: F403
from tissuemech.compare.fit.design import __all__ as _design_all

__all__ = [*_design_all, "main"]

if __name__ == "__main__":
    raise SystemExit(main())
