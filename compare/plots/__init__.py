"""Figures from already computed data: :mod:`.seed` (the seed's Figs 3-5, 8-10), :mod:`.charts`
(accuracy charts, stability map), :mod:`.scenes` (the ``tissuemech blastula`` / ``spheroid`` plots).

Every function returns a ``matplotlib.figure.Figure`` drawn with the Agg backend; callers save it.
"""

from __future__ import annotations

from typing import Any


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the non-interactive Agg backend (nothing opens a window)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt
