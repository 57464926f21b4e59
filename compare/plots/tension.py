"""The tensiometry figure: how far the surface-tension formula is from the true gamma, against the aggregate's
elasticity (static compressions) and against the time since the plates stopped (a relaxing aggregate)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from tissuemech.compare.plots import pyplot

__all__ = ["tensiometry_figure"]


def tensiometry_figure(static: pd.DataFrame, hold: pd.DataFrame, *, tau: float, tol: float = 0.05) -> Any:
    """Two panels of gamma_app / gamma (the formula F / (pi R3^2 (1/R1 + 1/R2)) over the true tension):
    (left) elastic aggregates at rest, against the elastocapillary number gamma / (C a0), with F / F_drop;
    (right) relaxing aggregates under held plates against the time since the compression started, one curve per
    long-time number gamma / (C_inf a0), the branch time ``tau`` (s) marked. The band is 1 +- ``tol``.
    ``static``: :func:`tissuemech.compare.studies.tensiometry.table` of a sweep; ``hold``: concatenated
    :func:`~tissuemech.compare.studies.tensiometry.hold_series` tables."""
    plt = pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(11.0, 4.3), sharey=True)
    for ax in (a, b):
        ax.axhspan(1 - tol, 1 + tol, color="0.9", label=f"within {tol:.0%}")
        ax.axhline(1.0, color="k", lw=0.6)
    n = static["gamma/(C a0)"].to_numpy()
    a.plot(n, static["gamma_app/gamma"], "o-", color="C0", label="formula / true gamma")
    a.plot(n, static["F/F_drop"], "s--", color="C1", ms=4, label="F / F of the exact drop")
    a.set(
        xscale="log",
        xlabel="elastocapillary number gamma / (C a0)",
        ylabel="ratio",
        title="elastic aggregate at rest (10 % compression)",
    )
    a.legend(fontsize=8)
    for k, (num, g) in enumerate(hold.groupby("gamma/(C_inf a0)")):
        t = g["time [s]"].to_numpy()
        b.plot(t, g["gamma_app/gamma"], "o-", color=f"C{k + 2}", ms=4, label=f"gamma / (C_inf a0) = {num:g}")
    b.set(xscale="log", xlabel="time since the compression started (s)", title="relaxing aggregate, plates held")
    b.legend(fontsize=8)
    ymax = max(float(np.nanmax(static[c])) for c in ("gamma_app/gamma", "F/F_drop"))
    ymax = max(ymax, float(np.nanmax(hold["gamma_app/gamma"])))
    a.set_ylim(0.0, ymax * 1.08)
    b.axvline(tau, color="0.4", ls=":", lw=1)
    b.text(tau, ymax, f" tau = {tau:g} s", fontsize=8, va="top", color="0.3")
    fig.tight_layout()
    return fig
