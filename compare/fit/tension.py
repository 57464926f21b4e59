r"""Fit the tissue surface tension gamma (with C, alpha and the Maxwell branches) to compression-relaxation records.

Model: ``reduced.spheroid.nominal_stress(..., surface_tension=gamma)`` (the elastocapillary law of
``reduced.capillary``: F_eq = C a0^2 R (f_plate + Gamma d), the branches driven by the elastic plate part, the
incompressible midplane). A tension adds a force nearly linear in the approach (the drop's Laplace pressure on the
contact disc, ~ 4 pi gamma a0 x) to the elastic ~x^1.5 one, and does not relax: records at two or more compression
levels separate gamma from C.

Estimation: weighted least squares in the log-parameters ``(C, Gamma, [alpha], beta_m, tau_m)`` with Gamma = gamma /
(C a0) bounded by the calibrated table (``scipy.optimize.least_squares``, exact ``jax.jacfwd`` Jacobian): an
unweighted pass, the per-record noise sd from its residuals, a weighted pass. 95 % Wald intervals in log space
(Student t with N - P degrees of freedom, the Gauss-Newton covariance scaled by the weighted residual variance);
gamma's interval from log gamma = log Gamma + log C + log a0 with their covariance.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from scipy import optimize, stats

from tissuemech.compare.fit.model import initial_guess
from tissuemech.compare.fit.records import as_records

__all__ = ["TensionFit", "tension_relaxation"]


class TensionFit(NamedTuple):
    """Estimates (SI: C Pa, gamma N/m, alpha -, beta -, tau s), 95 % intervals ``(low, high)`` by name, the noise sd
    per record (Pa), the residual norm and whether the solver converged."""

    params: dict[str, float]
    intervals: dict[str, tuple[float, float]]
    noise: list[float]
    cost: float
    success: bool


def _names(n_branches: int, fit_alpha: bool) -> list[str]:
    b = ["beta"] if n_branches == 1 else [f"beta_{m}" for m in range(1, n_branches + 1)]
    t = ["tau"] if n_branches == 1 else [f"tau_{m}" for m in range(1, n_branches + 1)]
    return ["C", "Gamma"] + (["alpha"] if fit_alpha else []) + b + t


def tension_relaxation(
    records: Sequence[Any],
    *,
    radius: float,
    ramp_time: float,
    n_branches: int = 1,
    alpha: float | None = None,
    initial: dict[str, float] | None = None,
    max_nfev: int = 200,
) -> TensionFit:
    """Fit ``(C, gamma, alpha, beta_m, tau_m)`` to relaxation records ``(time [s], nominal_stress [Pa],
    displacement [m])`` (one per compression level; the stress divides by the incompressible midplane area).

    ``alpha``: a number fixes it, None fits it (inside the elastocapillary table's alpha range). ``initial``: optional
    starting values by name (C, gamma, alpha, beta.., tau..). Returns a :class:`TensionFit` (``params`` and
    ``intervals`` hold ``gamma`` in N/m and ``Gamma`` = gamma / (C a0)). Raises ValueError for malformed records or
    fewer points than parameters."""
    from tissuemech.reduced import capillary
    from tissuemech.reduced import spheroid as sph

    recs = as_records(records)
    a0, tr = float(radius), float(ramp_time)
    if not (a0 > 0 and tr > 0):
        raise ValueError(f"radius (m) and ramp_time (s) must be > 0; got {radius!r} m and {ramp_time!r} s")
    fit_alpha = alpha is None
    names = _names(n_branches, fit_alpha)
    n_data = sum(r.time.size for r in recs)
    if n_data <= len(names):
        raise ValueError(f"{n_data} data points cannot determine {len(names)} parameters")
    table = capillary.capillary_table()
    g0 = initial_guess(recs, a0, tr, n_branches)  # C, alpha, betas, taus (the plate fit's shape-based start)
    start = {"C": float(g0[0]), "Gamma": 0.1 * table.gamma_max, "alpha": 0.3}
    start.update({n: float(v) for n, v in zip(names[-2 * n_branches :], g0[2:], strict=True)})
    for k, v in (initial or {}).items():
        if k == "gamma":
            start["Gamma"] = float(v) / (float((initial or {}).get("C", start["C"])) * a0)
        elif k in start:
            start[k] = float(v)
    lo = {"C": 1e-6, "Gamma": 1e-4 * table.gamma_max, "alpha": max(1e-6, table.alpha_range[0])}
    hi = {"C": 1e12, "Gamma": table.gamma_max, "alpha": table.alpha_range[1]}
    lb = np.log([lo.get(n, 1e-8 if n.startswith("beta") else 1e-3 * tr) for n in names])
    ub = np.log(
        [hi.get(n, 1e4 if n.startswith("beta") else 1e3 * max(float(r.time.max()) for r in recs)) for n in names]
    )
    x0 = np.clip(np.log([start[n] for n in names]), lb + 1e-9, ub - 1e-9)
    ts = tuple(jnp.asarray(r.time) for r in recs)
    ys = tuple(jnp.asarray(r.nominal_stress) for r in recs)
    ds = tuple(float(r.displacement) for r in recs)
    nb = n_branches

    def predict(theta: Any) -> list[Any]:
        p = dict(zip(names, jnp.exp(theta), strict=True))
        al = p["alpha"] if fit_alpha else float(alpha)  # type: ignore[arg-type]
        br = [(p[names[-2 * nb + m]], p[names[-nb + m]]) for m in range(nb)]
        gam = p["Gamma"] * p["C"] * a0
        return [
            sph.nominal_stress(
                t, radius=a0, C=p["C"], alpha=al, branches=br, displacement=d, ramp_time=tr, surface_tension=gam
            )  # fmt: skip
            for t, d in zip(ts, ds, strict=True)
        ]

    def residual(theta: Any, w: Any) -> Any:
        return jnp.concatenate([(m - y) * wk for m, y, wk in zip(predict(theta), ys, w, strict=True)])

    res_j = jax.jit(residual)
    jac_j = jax.jit(jax.jacfwd(residual))
    scale = float(max(np.max(np.abs(r.nominal_stress)) for r in recs)) or 1.0
    w = tuple(jnp.asarray(1.0 / scale) for _ in recs)
    sol = optimize.least_squares(
        lambda th: np.asarray(res_j(th, w)), x0, jac=lambda th: np.asarray(jac_j(th, w)), bounds=(lb, ub),
        max_nfev=max_nfev, x_scale="jac",
    )  # fmt: skip
    pred = [np.asarray(m) for m in predict(sol.x)]
    noise = [
        max(
            float(np.sqrt(np.sum((m - r.nominal_stress) ** 2) / max(r.time.size - len(names) / len(recs), 1.0))), 1e-300
        )
        for m, r in zip(pred, recs, strict=True)
    ]
    w = tuple(jnp.asarray(1.0 / s) for s in noise)
    sol = optimize.least_squares(
        lambda th: np.asarray(res_j(th, w)), sol.x, jac=lambda th: np.asarray(jac_j(th, w)), bounds=(lb, ub),
        max_nfev=max_nfev, x_scale="jac",
    )  # fmt: skip
    J = np.asarray(jac_j(sol.x, w))
    r = np.asarray(res_j(sol.x, w))
    dof = n_data - len(names)
    s2 = float(r @ r) / dof
    cov = np.linalg.pinv(J.T @ J) * s2
    t = float(stats.t.ppf(0.975, dof))
    est = dict(zip(names, np.exp(sol.x), strict=True))
    iv = {}
    for i, n in enumerate(names):
        sd = math.sqrt(max(cov[i, i], 0.0))
        iv[n] = (float(np.exp(sol.x[i] - t * sd)), float(np.exp(sol.x[i] + t * sd)))
    iC, iG = names.index("C"), names.index("Gamma")
    lg = sol.x[iC] + sol.x[iG] + math.log(a0)
    sd_g = math.sqrt(max(cov[iC, iC] + cov[iG, iG] + 2 * cov[iC, iG], 0.0))
    params = {n: float(v) for n, v in est.items()}
    params["gamma"] = float(math.exp(lg))
    iv["gamma"] = (float(math.exp(lg - t * sd_g)), float(math.exp(lg + t * sd_g)))
    if not fit_alpha:
        params["alpha"] = float(alpha)  # type: ignore[arg-type]
    return TensionFit(params, iv, noise, float(sol.cost), bool(sol.success))
