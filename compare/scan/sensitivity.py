"""Which parameter drives which summary of a scan: exact JAX derivatives of the reduced models, or of the FE.

:func:`sensitivities` differentiates the reduced model's summaries (``jax.jacfwd``) at points of a scan's
design with respect to each varied parameter scaled to its scan range; :func:`fe_sensitivities` does the same
with the FE's exact parameter sensitivities at a few spot-check points, where the reduced model does not reach
(alpha > 1.5, x > 0.36); ``compare.plots.scan.sensitivity_chart`` draws either.
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from tissuemech.compare.scan.evaluation import default_times, summaries
from tissuemech.compare.scan.table import UNITS, column, is_log_sampled, parameters_of, scene_of, varied_parameters

logger = logging.getLogger(__name__)

__all__ = [
    "sensitivities",
    "fe_sensitivities",
    "fe_summary_jacobian",
    "SPHEROID_SUMMARIES",
    "BLASTULA_SUMMARIES",
    "FE_MATERIAL",
    "FE_FD_STEP",
]

SPHEROID_SUMMARIES = ("sigma_peak", "sigma_end", "relaxed_fraction", "t_half")
BLASTULA_SUMMARIES = ("inner_stretch", "p_limit", "bursts")


def _spheroid_jacobian(p: np.ndarray, varied: list[str], fixed: dict, times: np.ndarray, equilibrium: Any):
    import jax.numpy as jnp

    key = (tuple(varied), tuple(sorted(fixed.items())), times.shape, times.tobytes())
    try:
        f = _spheroid_jacobian_fn(key, equilibrium)
    except TypeError:  # an unhashable equilibrium (arrays): compile for this call only
        f = _spheroid_jacobian_fn.__wrapped__(key, equilibrium)
    y, J = f(jnp.asarray(p))
    return np.asarray(y), np.asarray(J)


@functools.lru_cache(maxsize=8)
def _spheroid_jacobian_fn(key: tuple, equilibrium: Any):
    """jit(vmap(v -> (summaries, d summaries / d v))) for one (varied, fixed, times, law); reused."""
    import jax
    import jax.numpy as jnp

    from tissuemech.reduced import spheroid as red

    varied, fixed_items, shape, tbytes = key
    fixed = dict(fixed_items)
    t = jnp.asarray(np.frombuffer(tbytes, dtype=float).reshape(shape))

    def outputs(v):
        q = {**fixed, **{k: v[j] for j, k in enumerate(varied)}}
        s = red.nominal_stress(
            t,
            radius=q["radius"],
            C=q["C"],
            alpha=q["alpha"],
            branches=[(q["beta"], q["tau"])],
            displacement=q["displacement"],
            ramp_time=q["ramp_time"],
            equilibrium=equilibrium,
            method="quadrature",
        )
        out = summaries(t, s)
        return jnp.stack([out[k] for k in SPHEROID_SUMMARIES])

    return jax.jit(jax.vmap(lambda v: (outputs(v), jax.jacfwd(outputs)(v))))


def _blastula_jacobian(p: np.ndarray, varied: list[str], fixed: dict):
    import jax.numpy as jnp

    y, J = _blastula_jacobian_fn(tuple(varied), tuple(sorted(fixed.items())))(jnp.asarray(p))
    return np.asarray(y), np.asarray(J)


@functools.lru_cache(maxsize=8)
def _blastula_jacobian_fn(varied: tuple, fixed_items: tuple):
    import jax
    import jax.numpy as jnp

    from tissuemech.reduced import blastula as red

    fixed = dict(fixed_items)

    def outputs(v):
        q = {**fixed, **{k: v[j] for j, k in enumerate(varied)}}
        geo = dict(inner_radius=q["inner_radius"], outer_radius=q["outer_radius"], C=q["C"], alpha=q["alpha"])
        la, _ = red.inner_stretch_solve(q["pressure"], **geo)
        lim = red.limit_point(**geo)
        return jnp.stack([la, lim.pressure])

    return jax.jit(jax.vmap(lambda v: (outputs(v), jax.jacfwd(outputs)(v))))


def sensitivities(
    table: pd.DataFrame,
    *,
    n_points: int = 256,
    seed: int = 0,
    log: Sequence[str] | None = None,
    equilibrium: Any = "fem",
    times: np.ndarray | None = None,
) -> pd.DataFrame:
    """Which varied parameter drives which summary: normalised exact derivatives over the design.

    At ``n_points`` rows of the table (picked at random; all if fewer) the reduced model's summaries
    y_i and their exact derivatives (``jax.jacfwd``: through the exact-kernel quadrature of
    ``reduced.spheroid.nominal_stress``, through the implicit-function derivatives of
    ``reduced.blastula``) are taken with respect to each varied parameter x_j scaled to its scan
    range, u_j in [0, 1] (log-scaled for parameters in ``log``, default as for the map axes):
    dy/du_j = dy/dx_j (hi - lo), or dy/dx_j x_j ln(hi/lo). Per summary:

    * ``mean_abs_dy_du``: mean |dy/du_j| over the points (units of y: the linearised change of y
      across the parameter's whole range),
    * ``share [-]``: that divided by its sum over the parameters (which parameter drives y),
    * ``direction``: the sign of the mean dy/du_j (+1: y grows with x_j).

    Points where y is undefined (burst shell, no limit point, no half-relaxation) are left out.
    Spheroid: ``equilibrium`` as in the scan; ``times`` (s) default ``table.attrs["time [s]"]``, else
    ``default_times(ramp_time, 1500)``. Returns a long DataFrame (quantity, parameter, share [-],
    mean_abs_dy_du, unit, direction, points). Raises ValueError if no parameter is varied.
    """
    scene = scene_of(table)
    params = parameters_of(table)
    varied = varied_parameters(table)
    if not varied:
        raise ValueError("no parameter varies in this table: nothing to differentiate")
    if n_points < 1:
        raise ValueError(f"n_points (points of the design to differentiate at) must be at least 1; got {n_points}")
    rng = np.random.default_rng(seed)
    rows = np.sort(rng.choice(len(table), size=min(int(n_points), len(table)), replace=False))
    vals = {k: table[column(k)].to_numpy(float) for k in params}
    fixed = {k: float(vals[k][0]) for k in params if k not in varied}
    p = np.stack([vals[k][rows] for k in varied], axis=1)
    n_rows = len(rows)
    pad = -n_rows % 64  # point counts rounded up to 64: the compiled derivative is reused across calls
    p = np.concatenate([p, np.repeat(p[:1], pad, axis=0)])
    quantities: tuple[str, ...]
    if scene == "spheroid":
        if times is None:
            times = table.attrs.get("time [s]")
        if times is None:
            if "ramp_time" in varied:
                raise ValueError("give times= (s): the table has no output times and ramp_time varies")
            times = default_times(fixed["ramp_time"], 1500.0)
        y, J = _spheroid_jacobian(p, varied, fixed, np.asarray(times, dtype=float), equilibrium)
        quantities = SPHEROID_SUMMARIES
    else:
        y, J = _blastula_jacobian(p, varied, fixed)
        quantities = ("inner_stretch", "p_limit")
    y, J, p = y[:n_rows], J[:n_rows], p[:n_rows]
    return _shares(y, J, p, varied, vals, log, quantities)


def _shares(
    y: np.ndarray,
    J: np.ndarray,
    p: np.ndarray,
    varied: Sequence[str],
    vals: dict[str, np.ndarray],
    log: Sequence[str] | None,
    quantities: Sequence[str],
) -> pd.DataFrame:
    """The long table of :func:`sensitivities` from summaries ``y`` (points, quantities), their derivatives ``J``
    (points, quantities, varied) at the points ``p`` (points, varied), each parameter scaled to its scan range."""
    scale = []
    for j, k in enumerate(varied):
        lo, hi = float(vals[k].min()), float(vals[k].max())
        if is_log_sampled(vals[k], k, log) and lo > 0:
            scale.append(p[:, j] * np.log(hi / lo))
        else:
            scale.append(np.full(len(p), hi - lo))
    dydu = J * np.stack(scale, axis=1)[:, None, :]  # (points, quantities, params)
    out = []
    for i, q in enumerate(quantities):
        good = np.isfinite(y[:, i]) & np.all(np.isfinite(dydu[:, i, :]), axis=1)
        m_abs = np.abs(dydu[good, i, :]).mean(axis=0) if good.any() else np.full(len(varied), np.nan)
        m = dydu[good, i, :].mean(axis=0) if good.any() else np.full(len(varied), np.nan)
        tot = np.nansum(m_abs)
        for j, k in enumerate(varied):
            out.append(
                dict(
                    quantity=q,
                    parameter=k,
                    **{"share [-]": m_abs[j] / tot if tot > 0 else np.nan},
                    mean_abs_dy_du=m_abs[j],
                    unit=UNITS.get(q, "-"),
                    direction=float(np.sign(m[j])),
                    points=int(good.sum()),
                )
            )
    return pd.DataFrame(out)


FE_MATERIAL = ("C", "alpha", "beta", "tau")  # the FE's exact sensitivities (compress(gradient=True))
FE_FD_STEP = 1e-4  # relative step of the FE's central differences in the other parameters (radius, approach, ramp)


def fe_summary_jacobian(
    point: dict[str, float], varied: Sequence[str], times: np.ndarray, *, mesh: Any = "coarse"
) -> tuple[np.ndarray, np.ndarray]:
    """The spheroid summaries (:data:`SPHEROID_SUMMARIES`, at ``times`` s) of the FE at one point (SI: radius m, C
    Pa, alpha, beta, tau s, displacement m, ramp_time s) and their derivatives with respect to ``varied``: exact
    for C, alpha, beta, tau (``fem.spheroid.compress(gradient=True)``, node-by-node contact on ``mesh``), central
    differences (relative step :data:`FE_FD_STEP`, two FE runs each) for the others. Returns (y (Q,), J (Q, V));
    the FE curve is linear between its steps at ``times``. Where the reduced model does not reach (alpha > 1.5,
    x > 0.36) this is what the scan's sensitivities rest on."""
    import jax
    import jax.numpy as jnp

    from tissuemech.fem import spheroid as fem_spheroid

    t = np.asarray(times, dtype=float)

    def curve(q: dict[str, float], gradient: bool):
        r = fem_spheroid.compress(radius=q["radius"], C=q["C"], alpha=q["alpha"], branches=[(q["beta"], q["tau"])],
                                  displacement=q["displacement"], ramp_time=q["ramp_time"], end_time=float(t.max()),
                                  mesh=mesh, contact="nodal", gradient=gradient)  # fmt: skip
        tt = np.concatenate([[0.0], r.time])
        s = np.interp(t, tt, np.concatenate([[0.0], r.nominal_stress]))
        g = {n: np.interp(t, tt, np.concatenate([[0.0], d["nominal_stress"]])) for n, d in (r.gradient or {}).items()}
        return s, g

    def summ(s):
        out = summaries(jnp.asarray(t), s)
        return jnp.stack([out[k] for k in SPHEROID_SUMMARIES])

    q = {k: float(v) for k, v in point.items()}
    s, g = curve(q, gradient=any(k in FE_MATERIAL for k in varied))
    y = np.asarray(summ(jnp.asarray(s)))
    dsum = np.asarray(jax.jacfwd(summ)(jnp.asarray(s)))  # (Q, T): the summaries' derivative in the curve
    cols = []
    for k in varied:
        if k in FE_MATERIAL:
            ds = g[k]
        else:
            h = FE_FD_STEP * q[k]
            ds = (curve({**q, k: q[k] + h}, False)[0] - curve({**q, k: q[k] - h}, False)[0]) / (2 * h)
        cols.append(dsum @ ds)
    return y, np.stack(cols, axis=1)


def fe_sensitivities(
    table: pd.DataFrame,
    k: int = 8,
    *,
    mesh: Any = "coarse",
    seed: int = 0,
    log: Sequence[str] | None = None,
    times: np.ndarray | None = None,
    progress: bool = False,
) -> pd.DataFrame:
    """:func:`sensitivities` computed by the FE at ``k`` spot-check points of a spheroid scan
    (``compare.scan.fe_checks.select``: spread over the design) with :func:`fe_summary_jacobian`: the same table
    (and ``compare.plots.scan.sensitivity_chart`` draws it), for scans beyond the reduced model's table (alpha >
    1.5, x > 0.36), where the reduced derivatives do not exist. ``times`` (s) as in :func:`sensitivities`. About
    one FE run with gradients per point on ``mesh`` (seconds on "coarse"), two more per varied radius, approach or
    ramp time. ValueError for a blastula scan or no varied parameter."""
    from tissuemech.compare.scan.fe_checks import select

    if scene_of(table) != "spheroid":
        raise ValueError("FE sensitivities are made for spheroid scans (the blastula's shell model is exact)")
    params = parameters_of(table)
    varied = varied_parameters(table)
    if not varied:
        raise ValueError("no parameter varies in this table: nothing to differentiate")
    vals = {n: table[column(n)].to_numpy(float) for n in params}
    if times is None:
        times = table.attrs.get("time [s]")
    if times is None:
        times = default_times(float(vals["ramp_time"][0]), 1500.0)
    rows = select(table, k, seed)
    ys, Js = [], []
    for i, r in enumerate(rows):
        point = {n: float(vals[n][r]) for n in params}
        y, J = fe_summary_jacobian(point, varied, np.asarray(times, dtype=float), mesh=mesh)
        ys.append(y)
        Js.append(J)
        if progress:
            logger.info("FE sensitivities: point %d/%d", i + 1, len(rows))
    p = np.stack([vals[n][rows] for n in varied], axis=1)
    return _shares(np.stack(ys), np.stack(Js), p, varied, vals, log, SPHEROID_SUMMARIES)
