"""Figures from already computed data: :mod:`.seed` (the seed's Figs 3-5, 8-10), :mod:`.charts`
(accuracy charts, stability map), :mod:`.scenes` (the ``tissuemech blastula`` / ``spheroid`` plots).

Every function returns a ``matplotlib.figure.Figure``; callers save it. No plotting function chooses a
backend (a notebook keeps its own): the command line (:func:`tissuemech.compare.cli.main`) is the one place
that selects the non-interactive Agg backend.
"""

from __future__ import annotations

from typing import Any


def pyplot() -> Any:
    """``matplotlib.pyplot`` on whatever backend the caller has chosen (headless machines fall back to Agg)."""
    import matplotlib.pyplot as plt

    return plt
