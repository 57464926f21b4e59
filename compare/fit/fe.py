r"""Fits with the FE in the loop: (C, alpha, beta_m, tau_m) from compression-relaxation records where the reduced
model's calibrated table does not reach (alpha beyond 1.5, deep compression) or as a check of a reduced fit.

The model of record j is ``fem.spheroid.compress`` (node-by-node contact on one fixed mesh, or every step on its
contact-edge-fitted mesh: ``contact``) at the record's
approach, its nominal stress sampled at the record's times (piecewise linear between the FE steps: give
records sampled at the FE's own step times, ``step_times``, for none of that interpolation), and the Jacobian
is the FE's exact one (``compress(gradient=True)``: the Maxwell history's sensitivity carried through the
steps), so each Gauss-Newton iteration costs one FE run with gradients per record, never 2P + 1 runs.

Statistics: weighted least squares in log-parameters theta = log p (Levenberg-Marquardt / trust region,
``scipy.optimize.least_squares``): an unweighted pass (residuals relative to each record's largest stress),
the per-record white-noise estimate s_j^2 = RSS_j / (n_j - P n_j / N), a weighted pass; 95 % Wald intervals
exp(theta_i +- t_{0.975, N - P} sd_i) from the Gauss-Newton covariance s^2 (J^T W J)^-1. The robust error
model of :func:`tissuemech.compare.fit.relaxation` (a smooth discrepancy, correlated noise) is not applied
here: the FE is taken as exact and the noise as white; the residual diagnostics say when that is wrong.
"""

from __future__ import annotations

import logging
import time as _time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize as so
import scipy.stats as st

from tissuemech.compare.fit.diagnostics import residual_diagnostics
from tissuemech.compare.fit.intervals import identifiability
from tissuemech.compare.fit.model import parameter_names
from tissuemech.compare.fit.records import Record, as_records
from tissuemech.compare.fit.result import FitResult
from tissuemech.reduced.material import validate_positive

__all__ = ["fe_relaxation", "FEFitResult", "step_times"]

log = logging.getLogger(__name__)

WEIGHTS_TOL = 1e-3  # ftol = xtol of the unweighted pass (it only sets the per-record weights)
FIT_TOL = 1e-6  # ftol = xtol of the weighted pass (relative change of the cost / of the log-parameters)


@dataclass
class FEFitResult(FitResult):
    """Outcome of :func:`fe_relaxation`: a :class:`~tissuemech.compare.fit.FitResult` (``summary()``, ``to_dict()``,
    ``interval_text``; SI: C [Pa], alpha [-], beta(_m) [-], tau(_m) [s]) with the FE's own parts.

    params, intervals (95 % Wald, (lo, hi)), covariance (of the log-parameters, white noise), residual (RMS of the
    residuals, Pa), noise (per record, Pa), diagnostics (per record: lag-1 and runs test), identifiability (the
    Gauss-Newton Fisher matrix in log-parameters), nfev (FE evaluations, each one FE run with gradients per record),
    wall_time (s), mesh (the FE mesh level), contact ("nodal" / "fitted"), scene ("plates": :func:`fe_relaxation`,
    "probe": :func:`fe_indentation`), model (per record: the FE's nominal stress at the record's times, Pa),
    curves (per record: the FE's step times (s) and nominal stress (Pa) at the estimate), success, message."""

    wall_time: float = 0.0
    mesh: str = "default"
    contact: str = "nodal"
    scene: str = "plates"
    model: tuple[np.ndarray, ...] = field(default=())
    curves: tuple[tuple[np.ndarray, np.ndarray], ...] = field(default=())

    def summary(self) -> str:
        """:meth:`FitResult.summary` and a line on the FE model (mesh, FE evaluations, wall time)."""
        return (
            f"model: the FE ({'fem.indentation.indent' if self.scene == 'probe' else 'fem.spheroid.compress'}, "
            f"mesh {self.mesh!r}, "
            f"{'node-by-node contact' if self.contact == 'nodal' else 'contact-edge-fitted meshes'}, exact Jacobians), "
            f"{self.nfev} FE evaluations, {self.wall_time:.1f} s\n" + super().summary()
        )

    def to_dict(self) -> dict[str, Any]:
        """:meth:`FitResult.to_dict` and ``model`` ("fe"), ``mesh``, ``contact``, ``wall_time_s``."""
        return {
            **super().to_dict(),
            "model": "fe",
            "mesh": self.mesh,
            "contact": self.contact,
            "scene": self.scene,
            "wall_time_s": float(self.wall_time),
        }


def step_times(*, ramp_time: float, end_time: float, n_ramp: int = 6, n_hold: int = 20) -> np.ndarray:
    """The FE's step times (s) of a ramp-hold run (``fem.timestepping.ramp_hold_schedule``): records sampled there
    are compared with the FE without interpolation."""
    from tissuemech.fem.timestepping import ramp_hold_schedule

    return np.asarray(ramp_hold_schedule(float(ramp_time), float(end_time), n_ramp=n_ramp, n_hold=n_hold), float)


def fe_relaxation(
    records: Sequence[Any],
    *,
    radius: float,
    ramp_time: float,
    initial: dict[str, float],
    n_branches: int = 1,
    mesh: Any = "default",
    contact: str = "nodal",
    n_ramp: int = 6,
    n_hold: int = 20,
    max_nfev: int = 40,
    progress: bool = False,
) -> FEFitResult:
    """Fit (C, alpha, beta_m, tau_m) with the FE as the model (module doc: the statistics).

    records   ``(time [s], nominal_stress [Pa], displacement [m])`` per compression level (ramp over
              ``ramp_time`` to the displacement, then held); radius a0 (m).
    initial   starting values by name (:func:`tissuemech.compare.fit.parameter_names`), e.g. from a reduced fit
              or a coarse guess: every name needed (C, alpha > 0, beta, tau in SI).
    mesh      the FE mesh level ("coarse", "default", ...).
    contact   "nodal" (node-by-node contact on that mesh: the default, ~2x faster per evaluation) or "fitted" (every
              step on its contact-edge-fitted mesh, as ``fem.spheroid.compress`` runs by default: no edge
              quantisation in the force; its exact gradients carry the edge's motion, ``fem.fitted_sensitivity``).
    n_ramp, n_hold  the FE's steps (:func:`step_times`).
    progress  log one line per FE evaluation (``logging``, logger ``tissuemech.compare.fit.fe``, level INFO).

    Raises ValueError for a missing or non-positive initial value or malformed records."""
    from tissuemech.fem import spheroid as fem_spheroid

    t_start = _time.perf_counter()
    recs: list[Record] = as_records(records)
    if contact not in ("nodal", "fitted"):
        raise ValueError(f"contact must be 'nodal' or 'fitted', got {contact!r}")
    validate_positive("radius (of the spheroid)", radius, "m")
    validate_positive("ramp_time (duration of the loading ramp)", ramp_time, "s")
    names = _checked_initial(initial, n_branches)
    betas = [n for n in names if n.startswith("beta")]
    taus = [n for n in names if n.startswith("tau")]

    def run_record(p: dict[str, float], r: Record) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        res = fem_spheroid.compress(radius=radius, C=p["C"], alpha=p["alpha"],
                                    branches=[(p[b], p[t]) for b, t in zip(betas, taus)],
                                    displacement=r.displacement, ramp_time=ramp_time,
                                    end_time=float(np.max(r.time)), mesh=mesh, contact=contact,
                                    n_ramp=n_ramp, n_hold=n_hold, gradient=True)  # fmt: skip
        grad = res.gradient or {}
        return res.time, res.nominal_stress, {n: grad[n]["nominal_stress"] for n in names}

    data = [(r.time, r.nominal_stress) for r in recs]
    return _fit_fe(data, names, initial, run_record, recs, max_nfev=max_nfev, progress=progress, t_start=t_start,
                   mesh=str(mesh), contact=str(contact), scene="plates")  # fmt: skip


def fe_indentation(
    records: Sequence[Any],
    *,
    radius: float,
    probe_radius: float,
    ramp_time: float,
    initial: dict[str, float],
    n_branches: int = 1,
    mesh: Any = "default",
    n_ramp: int = 6,
    n_hold: int = 20,
    max_nfev: int = 40,
    progress: bool = False,
) -> FEFitResult:
    """Fit (C, alpha, beta_m, tau_m) to AFM-style indentation relaxation records with the FE indentation as the model
    (``fem.indentation.indent``: a rigid sphere of radius ``probe_radius`` (m) on the ball of radius ``radius`` (m)
    resting on a plate, node-by-node contact, its exact Jacobian ``indent(gradient=True)``), the statistics of the
    module doc: for probe geometries, depths or alphas the reduced indentation table does not cover.

    records   ``(time [s], probe force [N], approach [m])`` per indentation depth (the probe travels to the approach
              over ``ramp_time``, then holds); sampled at the FE's steps (:func:`step_times`) for no interpolation.
    initial, n_branches, mesh, n_ramp, n_hold, max_nfev, progress: as :func:`fe_relaxation`.

    Raises ValueError for malformed records or a missing or non-positive initial value."""
    from tissuemech.fem import indentation as fem_indentation

    t_start = _time.perf_counter()
    validate_positive("radius (of the spheroid)", radius, "m")
    validate_positive("probe_radius (of the spherical probe)", probe_radius, "m")
    validate_positive("ramp_time (duration of the loading ramp)", ramp_time, "s")
    recs = as_records(records, quantity=("probe force", "N"), approach="approach (the probe's travel)")
    names = _checked_initial(initial, n_branches)
    betas = [n for n in names if n.startswith("beta")]
    taus = [n for n in names if n.startswith("tau")]

    def run_record(p: dict[str, float], r: Record) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        res = fem_indentation.indent(radius=radius, probe_radius=probe_radius, C=p["C"], alpha=p["alpha"],
                                     branches=[(p[b], p[t]) for b, t in zip(betas, taus)], displacement=r.displacement,
                                     ramp_time=ramp_time, end_time=float(np.max(r.time)), mesh=mesh, n_ramp=n_ramp,
                                     n_hold=n_hold, gradient=True)  # fmt: skip
        grad = res.gradient or {}
        return res.time, res.force, {n: grad[n]["force"] for n in names}

    return _fit_fe([(r.time, r.nominal_stress) for r in recs], names, initial, run_record, recs, max_nfev=max_nfev,
                   progress=progress, t_start=t_start, mesh=str(mesh), contact="nodal", scene="probe")  # fmt: skip


def _checked_initial(initial: dict[str, float], n_branches: int) -> list[str]:
    """The parameter names of ``n_branches`` branches, with ``initial`` checked to give each, finite and > 0."""
    names = list(parameter_names(n_branches))
    missing = [n for n in names if n not in initial]
    if missing or set(initial) - set(names):
        raise ValueError(f"initial must give exactly {', '.join(names)}; missing {missing}, unknown "
                         f"{sorted(set(initial) - set(names))}")  # fmt: skip
    for n in names:
        if not (np.isfinite(initial[n]) and initial[n] > 0):
            raise ValueError(f"initial[{n!r}] must be finite and > 0; got {initial[n]!r}")
    return names


def _fit_fe(
    data_records: list[tuple[np.ndarray, np.ndarray]],
    names: list[str],
    initial: dict[str, float],
    run_record: Callable,
    recs: Sequence[Any],
    *,
    max_nfev: int,
    progress: bool,
    t_start: float,
    mesh: str,
    contact: str,
    scene: str,
) -> FEFitResult:
    """The weighted least squares of the module doc on ``data_records`` ((time [s], observed values) per record),
    the FE's values and gradients at the records' own settings from ``run_record(parameters, record)`` ->
    (step times, values, {name: d values / d parameter}) (``recs[k]`` is handed back as the record)."""
    P = len(names)
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}
    curves: dict[bytes, list[tuple[np.ndarray, np.ndarray]]] = {}  # per point: the FE's (step times, values)
    calls = [0]

    def model(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Stacked model and its Jacobian in log-parameters over all records."""
        key = np.asarray(z).tobytes()
        if key in cache:  # least_squares asks for the Jacobian after the residual, and the passes share points
            return cache[key]
        p = dict(zip(names, np.exp(z)))
        ys, Js = [], []
        curves[key] = []
        for (t_obs, _), r in zip(data_records, recs):
            t_fe, y_fe, g_fe = run_record(p, r)
            tt = np.concatenate([[0.0], t_fe])
            curves[key].append((tt, np.concatenate([[0.0], y_fe])))
            ys.append(np.interp(t_obs, tt, np.concatenate([[0.0], y_fe])))
            cols = [np.interp(t_obs, tt, np.concatenate([[0.0], g_fe[n]])) * p[n] for n in names]  # d/d log p
            Js.append(np.stack(cols, axis=1))
        calls[0] += 1
        out = (np.concatenate(ys), np.concatenate(Js))
        cache[key] = out
        if progress:
            log.info("FE evaluation %d: %s", calls[0], ", ".join(f"{n} = {v:.5g}" for n, v in p.items()))
        return out

    data = np.concatenate([y for _, y in data_records])
    sizes = [t.size for t, _ in data_records]
    split = np.cumsum(sizes)[:-1]
    scale = np.concatenate([np.full(n, np.max(np.abs(y))) for n, (_, y) in zip(sizes, data_records)])

    def fit(z0: np.ndarray, w: np.ndarray, tol: float) -> so.OptimizeResult:
        return so.least_squares(
            lambda z: (model(z)[0] - data) * w,
            z0,
            jac=lambda z: model(z)[1] * w[:, None],
            method="trf",
            x_scale="jac",
            ftol=tol,
            xtol=tol,
            max_nfev=max_nfev,
        )

    z0 = np.log([float(initial[n]) for n in names])
    # the unweighted pass only sets the records' weights: a loose tolerance (it stopped 1e-5 from its optimum after
    # twice the FE runs); the weighted pass to FIT_TOL (the last runs moved C by 1e-5 of itself, 1/500 of its sd)
    first = fit(z0, 1.0 / scale, WEIGHTS_TOL)
    r1 = model(first.x)[0] - data
    N = data.size
    noise = [float(np.sqrt(np.sum(part**2) / max(n - P * n / N, 1.0))) for part, n in zip(np.split(r1, split), sizes)]
    w = np.concatenate([np.full(n, 1.0 / max(s, 1e-300)) for n, s in zip(sizes, noise)])
    second = fit(first.x, w, FIT_TOL)
    y, J = model(second.x)
    rw = (y - data) * w
    s2 = float(np.sum(rw**2) / max(N - P, 1))
    Jw = J * w[:, None]
    cov = s2 * np.linalg.pinv(Jw.T @ Jw)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    tq = float(st.t.ppf(0.975, max(N - P, 1)))
    est = np.exp(second.x)
    intervals = {n: (float(np.exp(second.x[i] - tq * sd[i])), float(np.exp(second.x[i] + tq * sd[i])))
                 for i, n in enumerate(names)}  # fmt: skip
    resid = y - data
    diags = [residual_diagnostics(part) for part in np.split(resid, split)]
    ok = bool(second.success) and bool(np.all(np.isfinite(sd)))
    fisher = Jw.T @ Jw / max(s2, 1e-300)  # in units of the noise, as the reduced fit's
    return FEFitResult(
        params={n: float(v) for n, v in zip(names, est)},
        intervals=intervals,
        residual=float(np.sqrt(np.mean(resid**2))),
        identifiability=identifiability(fisher, tuple(names)),
        covariance=cov,
        success=ok,
        message=str(second.message),
        nfev=calls[0],
        names=tuple(names),
        kinds={n: "two-sided" for n in names},
        methods={n: "wald" for n in names},
        noise=tuple(noise),
        dof=int(N - P),
        diagnostics=tuple(diags),
        errors="white",
        wall_time=_time.perf_counter() - t_start,
        mesh=mesh,
        contact=contact,
        scene=scene,
        model=tuple(np.split(y, split)),
        curves=tuple(curves[second.x.tobytes()]),
    )
