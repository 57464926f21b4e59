r"""Fit the tissue surface tension gamma (with C, alpha and the Maxwell branches) to compression-relaxation records.

Model: ``reduced.spheroid.nominal_stress(..., surface_tension=gamma)`` (the elastocapillary law of
``reduced.capillary``: F_eq = C a0^2 R (f_plate + Gamma d), the branches driven by the instantaneous excess over it;
the records' midplane: the ball's calibrated one, or the incompressible a0^2 / (1 - x) of force files). A tension adds
a force nearly linear in the approach (the drop's Laplace pressure on the contact disc, ~ 4 pi gamma a0 x) to the
elastic ~x^1.5 one, and does not relax: records at two or more compression levels separate gamma from C.

Estimation: weighted least squares in the log-parameters ``(C, Gamma, [alpha], beta_m, tau_m)`` with Gamma = gamma /
(C a0) bounded by the calibrated table (``scipy.optimize.least_squares``, exact ``jax.jacfwd`` Jacobian): an
unweighted pass, the per-record noise sd from its residuals, a weighted pass. 95 % Wald intervals in log space
(Student t with N - P degrees of freedom, the Gauss-Newton covariance scaled by the weighted residual variance);
gamma's interval from log gamma = log Gamma + log C + log a0 with their covariance.

Profile measurement (``profile=Profile(R1, R2, R3, sd)``, m): the classic plate-tensiometry formula
gamma_p = F / (pi R3^2 (1/R1 + 1/R2)) (R1 the profile's meridional radius at the equator, R2 the equatorial radius,
R3 the contact radius; exact for a liquid drop at rest, ``reduced.drop``) with F the record's measured force at the
profile's time (nominal stress times the records' midplane area) is one more observation of gamma: the residual
(gamma - gamma_p) / sd_p joins the likelihood, sd_p propagated to first order from the radii's sd and the record's
noise (:func:`formula_tension`). For an aggregate that is still partly elastic the formula over-states gamma (the
elastic stress adds to the Laplace pressure): give the profile at the end of a long hold, and compare the
records-only fit (``TensionFit.profile`` holds gamma_p, its sd and its normal score against the fit).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from scipy import optimize, stats

from tissuemech.compare.fit.diagnostics import residual_diagnostics
from tissuemech.compare.fit.model import initial_guess
from tissuemech.compare.fit.records import as_records

__all__ = ["TensionFit", "Profile", "formula_tension", "tension_relaxation"]


class TensionFit(NamedTuple):
    """Estimates (SI: C Pa, gamma N/m, alpha -, beta -, tau s), 95 % intervals ``(low, high)`` by name, the noise sd
    per record (Pa), the residual norm and whether the solver converged; ``diagnostics``: the residual diagnostics
    per record (``compare.fit.diagnostics.RecordDiagnostics``: lag-1 autocorrelation, runs test); ``profile``: with a
    profile measurement, ``gamma_formula`` (N/m), ``sd`` (N/m), ``z`` = (gamma_formula - gamma) / sd, ``force`` (N)."""

    params: dict[str, float]
    intervals: dict[str, tuple[float, float]]
    noise: list[float]
    cost: float
    success: bool
    diagnostics: tuple = ()
    profile: dict[str, float] | None = None
    midplane: str = "fem"  # the records' midplane ("fem" or "incompressible": tension_relaxation's midplane=)

    def summary(self) -> str:
        """The parameter table with 95 % intervals, the noise and residual diagnostics per record, the profile."""
        units = {"C": "Pa", "gamma": "N/m", "Gamma": "-", "alpha": "-"}
        lines = ["surface-tension fit (reduced elastocapillary model): estimate and 95 % interval"]
        for n, v in self.params.items():
            u = units.get(n, "s" if n.startswith("tau") else "-")
            iv = f"[{self.intervals[n][0]:.5g}, {self.intervals[n][1]:.5g}]" if n in self.intervals else "(fixed)"
            lines.append(f"  {n:<8} {v:12.5g}   {iv} {u}")
        for k, sd in enumerate(self.noise):
            diag = f"; {self.diagnostics[k].text()}" if k < len(self.diagnostics) else ""
            lines.append(f"  record {k + 1}: noise sd {sd:.3g} Pa{diag}")
        if self.profile is not None:
            p = self.profile
            lines.append(
                f"  profile: classic formula gamma = {p['gamma_formula']:.5g} +- {p['sd']:.2g} N/m (1 sd) at F = "
                f"{p['force']:.4g} N; {p['z']:+.2f} sd from the fit (exact for a liquid at rest; over-states gamma "
                "while the aggregate is still elastic)"
            )
        if not self.success:
            lines.append("  WARNING: the least-squares solver did not converge")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: params, intervals, noise, cost, success, diagnostics, profile."""
        return dict(
            params=self.params,
            intervals={k: list(v) for k, v in self.intervals.items()},
            noise=self.noise,
            cost=self.cost,
            success=self.success,
            diagnostics=[{**dataclasses.asdict(d), "correlated": d.correlated} for d in self.diagnostics],
            profile=self.profile,
        )


class Profile(NamedTuple):
    """A profile measurement of the compressed aggregate: ``R1`` the meridional radius of curvature at the equator,
    ``R2`` the equatorial radius, ``R3`` the contact radius (m), ``sd`` the 1-sigma uncertainty of each radius (m),
    taken on record ``record`` (index, default the last) at ``time`` (s, default its last sample)."""

    R1: float
    R2: float
    R3: float
    sd: float
    record: int = -1
    time: float | None = None


def formula_tension(
    force: float, R1: float, R2: float, R3: float, *, force_sd: float = 0.0, radius_sd: float = 0.0
) -> tuple[float, float]:
    """The classic plate-tensiometry gamma = F / (pi R3^2 (1/R1 + 1/R2)) (N/m) from the plate force ``force`` (N) and
    the radii (m), and its 1-sigma uncertainty (N/m) to first order from ``force_sd`` (N) and ``radius_sd`` (m, each
    radius, independent). Exact for a liquid drop at rest between non-wetting plates. Raises ValueError naming a bad
    input."""
    for name, v in (("R1 (meridional radius at the equator)", R1), ("R2 (equatorial radius)", R2),
                    ("R3 (contact radius)", R3)):  # fmt: skip
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a positive length in m; got {v!r}")
    if not (math.isfinite(force) and force > 0):
        raise ValueError(f"force (the plate force at the profile's time) must be > 0 N; got {force!r}")
    if not (force_sd >= 0 and radius_sd >= 0):
        raise ValueError(f"force_sd (N) and radius_sd (m) must be >= 0; got {force_sd!r}, {radius_sd!r}")
    k = 1.0 / R1 + 1.0 / R2
    gamma = force / (math.pi * R3**2 * k)
    rel2 = (force_sd / force) ** 2 + (2 * radius_sd / R3) ** 2
    rel2 += (radius_sd / (R1**2 * k)) ** 2 + (radius_sd / (R2**2 * k)) ** 2
    return gamma, gamma * math.sqrt(rel2)


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
    profile: Profile | None = None,
    midplane: str = "fem",
) -> TensionFit:
    """Fit ``(C, gamma, alpha, beta_m, tau_m)`` to relaxation records ``(time [s], nominal_stress [Pa],
    displacement [m])`` (one per compression level). ``midplane``: the area the records' stress divides the force by,
    "fem" (default: the deformed ball's midplane, the tension-free calibrated g(x), as
    ``reduced.spheroid.nominal_stress`` with a tension) or "incompressible" (a0^2 / (1 - x): how ``tissuemech fit``
    turns force files into stress, so that force records are fitted as forces).

    ``alpha``: a number fixes it, None fits it (inside the elastocapillary table's alpha range). ``initial``: optional
    starting values by name (C, gamma, alpha, beta.., tau..). ``profile``: a :class:`Profile` measurement (m) entering
    the likelihood through the classic formula (module docstring). Returns a :class:`TensionFit` (``params`` and
    ``intervals`` hold ``gamma`` in N/m and ``Gamma`` = gamma / (C a0)). Raises ValueError for malformed records or
    fewer points than parameters."""
    from tissuemech.reduced import capillary
    from tissuemech.reduced import spheroid as sph

    recs = as_records(records)
    if midplane not in ("fem", "incompressible"):
        raise ValueError(f"midplane must be 'fem' or 'incompressible'; got {midplane!r}")
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
    prof = None if profile is None else _profile_force(profile, recs, a0, tr, midplane, 0.5 if fit_alpha else alpha)

    def predict(theta: Any) -> list[Any]:
        p = dict(zip(names, jnp.exp(theta), strict=True))
        al = p["alpha"] if fit_alpha else float(alpha)  # type: ignore[arg-type]
        br = [(p[names[-2 * nb + m]], p[names[-nb + m]]) for m in range(nb)]
        gam = p["Gamma"] * p["C"] * a0
        return [
            sph.nominal_stress(
                t,
                radius=a0,
                C=p["C"],
                alpha=al,
                branches=br,
                displacement=d,
                ramp_time=tr,
                surface_tension=gam,
                midplane=midplane,
            )  # fmt: skip
            for t, d in zip(ts, ds, strict=True)
        ]

    def residual(theta: Any, w: Any, psd: Any = 1.0) -> Any:
        r = [(m - y) * wk for m, y, wk in zip(predict(theta), ys, w, strict=True)]
        if prof is not None:  # the classic formula's gamma as one more observation
            gam = jnp.exp(theta[names.index("Gamma")] + theta[names.index("C")]) * a0
            r.append(jnp.atleast_1d((gam - prof[1]) / psd))
        return jnp.concatenate(r)

    res_j = jax.jit(residual)
    jac_j = jax.jit(jax.jacfwd(residual))
    scale = float(max(np.max(np.abs(r.nominal_stress)) for r in recs)) or 1.0
    w = tuple(jnp.asarray(1.0 / scale) for _ in recs)
    psd = 1.0
    if prof is not None:  # the radii's share of the formula's sd (the record's noise is not known yet)
        psd = formula_tension(prof[0], profile.R1, profile.R2, profile.R3, radius_sd=profile.sd)[1]  # type: ignore[union-attr]
        psd = max(psd, 1e-12 * prof[1])
    sol = optimize.least_squares(
        lambda th: np.asarray(res_j(th, w, psd)), x0, jac=lambda th: np.asarray(jac_j(th, w, psd)), bounds=(lb, ub),
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
    prof_out = None
    if prof is not None:  # the formula's sd with the record's force noise
        F_sd = noise[prof[2]] * prof[3]
        psd = formula_tension(prof[0], profile.R1, profile.R2, profile.R3, force_sd=F_sd, radius_sd=profile.sd)[1]  # type: ignore[union-attr]
        psd = max(psd, 1e-12 * prof[1])
    sol = optimize.least_squares(
        lambda th: np.asarray(res_j(th, w, psd)), sol.x, jac=lambda th: np.asarray(jac_j(th, w, psd)), bounds=(lb, ub),
        max_nfev=max_nfev, x_scale="jac",
    )  # fmt: skip
    J = np.asarray(jac_j(sol.x, w, psd))
    r = np.asarray(res_j(sol.x, w, psd))
    dof = n_data + (prof is not None) - len(names)
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
    pred = [np.asarray(m) for m in predict(sol.x)]
    diags = tuple(residual_diagnostics(r.nominal_stress - m) for m, r in zip(pred, recs, strict=True))
    if prof is not None:
        prof_out = dict(gamma_formula=prof[1], sd=float(psd), z=float((prof[1] - params["gamma"]) / psd), force=prof[0])
    return TensionFit(params, iv, noise, float(sol.cost), bool(sol.success), diags, prof_out, midplane)


def _profile_force(
    profile: Profile, recs: Sequence[Any], a0: float, tr: float, midplane: str = "fem", alpha: Any = 0.5
) -> tuple[float, float, int, float]:
    """(F [N], the formula's gamma [N/m], record index, midplane area [m^2]) at the profile's time and record; the
    area is the records' ``midplane`` at ``alpha`` (0.5 when alpha is fitted: the calibrated g(x) moves by 1e-4 at
    x = 0.1 and 1.4e-3 at x = 0.3 over alpha 0 .. 1)."""
    if not isinstance(profile, Profile):
        raise ValueError(f"profile must be a Profile(R1, R2, R3, sd) in m; got {profile!r}")
    if not (math.isfinite(profile.sd) and profile.sd > 0):
        raise ValueError(f"the profile's sd (1-sigma uncertainty of each radius) must be > 0 m; got {profile.sd!r}")
    k = int(profile.record)
    if not -len(recs) <= k < len(recs):
        raise ValueError(f"profile.record {k} does not name one of the {len(recs)} records")
    k %= len(recs)
    r = recs[k]
    tp = float(r.time[-1]) if profile.time is None else float(profile.time)
    i = int(np.argmin(np.abs(r.time - tp)))
    x = float(r.displacement) / (2 * a0) * min(float(r.time[i]) / tr, 1.0)
    from tissuemech.reduced import spheroid as sph

    r_mid = float(sph.midplane_radius(2 * a0 * x, radius=a0, alpha=float(alpha), midplane=midplane))
    area = math.pi * r_mid**2  # the records' midplane
    F = float(r.nominal_stress[i]) * area
    return F, formula_tension(F, profile.R1, profile.R2, profile.R3)[0], k, area
