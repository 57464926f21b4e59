"""Experiment-design figure: predicted 95 % interval widths of alpha and C against the second compression level
(the tables of :func:`tissuemech.compare.fit.design.scan_second_level`)."""

from __future__ import annotations

from collections.abc import Sequence

import pandas as pd

from tissuemech.compare.plots import pyplot as _plt

__all__ = ["second_level_figure"]


def second_level_figure(scans: Sequence[pd.DataFrame], title: str = ""):
    """Predicted alpha and C interval width against the second level, one curve per first level; returns the
    figure (nothing is shown or saved here)."""
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for df in scans:
        lab = f"first level {df['first um'].iloc[0]:.4g} um"
        axes[0].plot(df["second um"], df["alpha width %"], "o-", ms=3, label=lab)
        axes[1].plot(df["second um"], df["C width %"], "o-", ms=3, label=lab)
    for ax, n in zip(axes, ("alpha", "C")):
        ax.set_yscale("log")
        ax.set_xlabel("second compression level (total approach, um)")
        ax.set_ylabel(f"predicted 95 % width of {n} (% of value)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title or "Experiment design: predicted interval width (Fisher matrix)", fontsize=9)
    fig.tight_layout()
    return fig
