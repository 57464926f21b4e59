"""FE spot-checks of a scan: the FE model at a few points spread over the design, and the deviation there.

:func:`select` picks the points (greedy max-min distance in the unit-scaled design box; a blastula only where
the shell holds at a positive pressure); :func:`spot_check` runs the FE point functions of ``compare.batch``
there (resumable through a store) and adds the ``fe_...`` columns and ``deviation [-]`` (the largest relative
difference between the reduced and FE outputs at that point; NaN where no FE run was made) to the table.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pandas as pd

from tissuemech.compare.scan.table import column, parameters_of, scene_of

__all__ = ["FE_COLUMNS", "spread_indices", "select", "spot_check"]

FE_COLUMNS = {
    "spheroid": ("fe_sigma_peak", "fe_sigma_end", "deviation"),
    "blastula": ("fe_inner_stretch", "deviation"),
}


def spread_indices(points: pd.DataFrame, k: int, seed: int = 0) -> np.ndarray:
    """``k`` row indices spread over the design (greedy max-min distance in the unit-scaled box)."""
    k = min(int(k), len(points))
    if k <= 0:
        return np.zeros(0, dtype=int)
    x = points.to_numpy(dtype=float)
    span = x.max(axis=0) - x.min(axis=0)
    x = (x - x.min(axis=0)) / np.where(span > 0, span, 1.0)
    rng = np.random.default_rng(seed)
    cand = rng.choice(len(x), size=min(len(x), 2000), replace=False)
    chosen = [int(cand[np.argmin(np.abs(x[cand] - 0.5).sum(axis=1))])]  # start near the centre
    d = np.linalg.norm(x[cand] - x[chosen[0]], axis=1)
    for _ in range(k - 1):
        j = int(cand[np.argmax(d)])
        chosen.append(j)
        d = np.minimum(d, np.linalg.norm(x[cand] - x[j], axis=1))
    return np.array(chosen)


def design_points(table: pd.DataFrame) -> pd.DataFrame:
    """The design of a scan table: its parameter columns under their plain names (scene order)."""
    params = parameters_of(table)
    pts = table[[column(k) for k in params]].astype(float)
    pts.columns = list(params)
    return pts.reset_index(drop=True)


def select(table: pd.DataFrame, k: int, seed: int = 0) -> np.ndarray:
    """Row indices of up to ``k`` FE spot-checks spread over the design of a scan table.

    Spheroid: any point. Blastula: only points where the shell holds (finite inner stretch) at a positive
    pressure (fewer than ``k`` if fewer hold)."""
    pts = design_points(table)
    if scene_of(table) == "spheroid":
        return spread_indices(pts, k, seed)
    la = table[column("inner_stretch")].to_numpy(float)
    ok = np.nonzero(~np.isnan(la) & (pts["pressure"].to_numpy() > 0))[0]
    return ok[spread_indices(pts.iloc[ok].reset_index(drop=True), k, seed)]


def spot_check(
    table: pd.DataFrame,
    k: int,
    *,
    times: Any = None,
    seed: int = 0,
    executor: Any = None,
    store: Any = None,
    function: Callable | None = None,
    progress: bool = True,
) -> int:
    """Run the FE model at ``k`` points of a scan table (:func:`select`) and add, in place, the columns
    ``fe_sigma_peak [Pa]``, ``fe_sigma_end [Pa]`` (spheroid: the FE curve at the scan's output ``times``, s;
    default ``table.attrs["time [s]"]``) or ``fe_inner_stretch [-]`` (blastula), and ``deviation [-]``.

    function  the FE point function (default ``compare.batch.fe_spheroid`` / ``fe_blastula``), run through
              ``compare.batch.run`` with ``executor`` and ``store`` (resumable); a point whose FE run fails
              keeps NaN. Returns the number of points with a deviation.
    """
    from tissuemech.compare import batch

    scene = scene_of(table)
    idx = select(table, k, seed)
    pts = design_points(table)
    t = None
    default: Callable[..., Any]
    if scene == "spheroid":
        t = np.asarray(table.attrs.get("time [s]") if times is None else times, dtype=float)
        if t.ndim != 1 or t.size < 2:
            raise ValueError("spheroid FE spot-checks need the scan's output times (times=..., s)")
        fe_points = [dict(pts.iloc[i].to_dict(), end_time=float(np.max(t))) for i in idx]
        default = batch.points.fe_spheroid
    else:
        fe_points = [pts.iloc[i].to_dict() for i in idx]
        default = batch.points.fe_blastula
    results = batch.run(
        function or default, fe_points, executor=executor, store=store, raise_on_error=False, progress=progress
    )
    for name in FE_COLUMNS[scene]:
        table[column(name)] = np.nan
    for i, r in zip(idx, results):
        if r is None:
            continue
        if t is not None:
            s_fe = np.interp(t, r["time"], r["nominal_stress"])
            peak, end = float(np.max(s_fe)), float(s_fe[-1])
            table.loc[i, column("fe_sigma_peak")] = peak
            table.loc[i, column("fe_sigma_end")] = end
            table.loc[i, column("deviation")] = max(
                abs(table[column("sigma_peak")].iloc[i] / peak - 1.0),
                abs(table[column("sigma_end")].iloc[i] / end - 1.0),
            )
        else:
            la_fe = float(r["inner_stretch"])
            table.loc[i, column("fe_inner_stretch")] = la_fe
            table.loc[i, column("deviation")] = abs(table[column("inner_stretch")].iloc[i] / la_fe - 1.0)
    return int(table[column("deviation")].notna().sum())
