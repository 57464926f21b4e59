r"""How far the reduced models can be trusted: reduced vs FE, case by case, as tidy tables.

    python -m tissuemech.compare.studies.checks [--spheroid-random 10] [--blastula-random 10] [--mesh default] [--out DIR]

* ``blastula(...)``: exact thick-shell stretch (``reduced.blastula``) against the FE shell
  (``fem.blastula.inflate``, kappa = 2.2 GPa) for the seed sets and random (alpha, B/A, p) points.
* ``spheroid(...)``: the calibrated lumped model (``reduced.spheroid``, ``equilibrium="fem"``) against
  the FE compression-relaxation (``fem.spheroid.compress``) over the whole ramp-and-hold, sigma~(t)
  compared at the FE step times: max relative deviation during the ramp and after it.
* ``blastula_creep(...)``: the viscoelastic shell (``reduced.viscoshell``) against the FE shell with the same
  Maxwell branches (``fem.blastula.creep``) under a pressure ramp-and-hold (issue 5: alpha = 0.2,
  beta = 0.5, tau = 100 s, 300 Pa in 1 s, held 600 s): max |lambda_FE / lambda_reduced - 1| over the history.
* ``hertz_table()``: F_Hertz / F_FE from the calibrated master curve, as compression grows.

Every function returns a pandas DataFrame with units in the column names.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from tissuemech.compare import cases
from tissuemech.compare.cases import spheroid_keywords

__all__ = ["blastula", "blastula_creep", "spheroid", "hertz_table", "fit_demo", "SPHEROID_CASES", "CREEP_CASES"]

UM = cases.UM
A_BLASTULA = cases.BLASTULA_INNER_RADIUS
SPHEROID_CASES = cases.SPHEROID_CHECK_CASES
CREEP_CASES = cases.CREEP_CASES


def blastula(*, n_random: int = 10, seed: int = 0, mesh: str = "default", kappa: float = 2.2e9) -> pd.DataFrame:
    """Inner stretch, exact vs FE, at 200/500/1000 Pa for the seed sets and at random points."""
    from tissuemech.fem import blastula as fe
    from tissuemech.reduced import blastula as red

    rng = np.random.default_rng(seed)
    cases: list[tuple[str, float, float, tuple[float, ...]]] = [
        (f"seed alpha={a:g}", a, 75 * UM, (200.0, 500.0, 1000.0)) for a in (0.1, 0.2, 0.3)
    ]
    cases += [(f"seed B={b:g} um", 0.2, b * UM, (200.0, 500.0, 1000.0)) for b in (52, 60)]
    cases += [("neo-Hookean B=75 um", 1e-5, 75 * UM, (50.0, 100.0, 150.0))]
    for k in range(n_random):
        a, ratio = rng.uniform(0.05, 0.5), rng.uniform(1.05, 1.6)
        B = A_BLASTULA * ratio
        # pressures reachable on the rising branch: below a limit point if there is one
        lp = red.limit_point(inner_radius=A_BLASTULA, outer_radius=B, C=200.0, alpha=a)
        pmax = 0.9 * float(lp.pressure) if lp is not None else 1000.0
        cases.append((f"random {k}", a, B, (float(rng.uniform(0.1, 1.0) * pmax),)))
    rows = []
    for name, a, B, ps in cases:
        geo: dict[str, Any] = dict(inner_radius=A_BLASTULA, outer_radius=B, C=200.0, alpha=a)
        t0 = time.perf_counter()
        r = fe.inflate(**geo, pressures=list(ps), kappa=kappa, mesh=mesh)
        wall = time.perf_counter() - t0
        exact = np.asarray(red.inner_stretch(np.asarray(r.pressure), **geo))
        for p, lf, le in zip(r.pressure, r.inner_stretch, exact):
            rows.append(
                {
                    "case": name,
                    "alpha [-]": a,
                    "B/A [-]": B / A_BLASTULA,
                    "pressure [Pa]": float(p),
                    "exact inner_stretch [-]": float(le),
                    "FE inner_stretch [-]": float(lf),
                    "rel. deviation [-]": abs(float(lf) / float(le) - 1.0),
                    "FE wall [s]": wall,
                }
            )
    return pd.DataFrame(rows)


def blastula_creep(
    *,
    cases: dict | None = None,
    outer_radius: float = 75 * UM,
    C: float = 200.0,
    kappa: float = 2.2e9,
    mesh: str = "default",
    n_ramp: int = 8,
    n_hold: int = 60,
) -> pd.DataFrame:
    """Inner stretch history, reduced viscoelastic shell vs FE shell (same Maxwell branches), per creep case.

    Deviation = |lambda_FE / lambda_reduced - 1| at the FE step times: max over the whole history, during
    the ramp (t <= ramp_time) and the hold; also for the outer stretch. ``cases`` as ``CREEP_CASES``.
    """
    from tissuemech.fem import blastula as fe
    from tissuemech.reduced import viscoshell as red

    rows = []
    for name, c in dict(CREEP_CASES if cases is None else cases).items():
        geo = dict(
            inner_radius=A_BLASTULA, outer_radius=outer_radius, C=C, alpha=c["alpha"], branches=[(c["beta"], c["tau"])]
        )
        tr = c["ramp_time"]
        t0 = time.perf_counter()
        r = fe.creep(
            **geo,
            pressure=c["pressure"],
            ramp_time=tr,
            end_time=tr + c["hold"],
            kappa=kappa,
            mesh=mesh,
            n_ramp=n_ramp,
            n_hold=n_hold,
        )
        wall = time.perf_counter() - t0
        t0 = time.perf_counter()
        ref = red.inflate(r.time, pressure=c["pressure"], ramp_time=tr, **geo)
        wall_red = time.perf_counter() - t0
        dev = np.abs(r.inner_stretch / np.asarray(ref.inner_stretch) - 1.0)
        assert r.outer_stretch is not None  # inflate always reports it
        dev_b = np.abs(r.outer_stretch / np.asarray(ref.outer_stretch) - 1.0)
        ramp = r.time <= tr * (1 + 1e-12)
        rows.append(
            {
                "case": name,
                "alpha [-]": c["alpha"],
                "beta [-]": c["beta"],
                "tau [s]": c["tau"],
                "pressure [Pa]": c["pressure"],
                "ramp [s]": tr,
                "hold [s]": c["hold"],
                "B [m]": outer_radius,
                "max dev. history [-]": float(dev.max()),
                "max dev. during ramp [-]": float(dev[ramp].max()),
                "max dev. during hold [-]": float(dev[~ramp].max()) if (~ramp).any() else float("nan"),
                "max dev. outer [-]": float(dev_b.max()),
                "FE inner_stretch end of ramp [-]": float(r.inner_stretch[ramp][-1]),
                "FE inner_stretch end [-]": float(r.inner_stretch[-1]),
                "FE steps": int(r.inner_stretch.size),
                "FE Newton its": int(r.newton_iterations.sum()),
                "FE wall [s]": wall,
                "reduced wall (incl. compile) [s]": wall_red,
            }
        )
    return pd.DataFrame(rows)


def spheroid(
    *,
    n_random: int = 10,
    seed: int = 0,
    mesh: str = "default",
    radius: float = 500 * UM,
    ramp_time: float = 0.2,
    end_time: float = 1500.0,
    cases: dict | None = None,
) -> pd.DataFrame:
    """sigma~(t), calibrated reduced model vs FE, for the seed cases and random points."""
    from tissuemech.fem import spheroid as fe
    from tissuemech.reduced import spheroid as red

    rng = np.random.default_rng(seed)
    cases = dict(SPHEROID_CASES if cases is None else cases)
    for k in range(n_random):
        cases[f"random {k}"] = dict(
            C=float(rng.uniform(100, 400)),
            alpha=float(rng.uniform(0.0, 0.6)),
            beta=float(rng.uniform(0.1, 1.5)),
            tau=float(10 ** rng.uniform(0.5, 2.7)),
            displacement=float(rng.uniform(0.02, 0.28) * 2 * radius),
        )
    rows = []
    for name, c in cases.items():
        t0 = time.perf_counter()
        kw = spheroid_keywords(c, radius=radius, displacement=c["displacement"], ramp_time=ramp_time)
        r = fe.compress(**kw, end_time=end_time, mesh=mesh)
        wall = time.perf_counter() - t0
        t = np.asarray(r.time)
        s_fe = np.asarray(r.nominal_stress)
        s_red = np.asarray(red.nominal_stress(t, **kw, equilibrium="fem"))
        s_hz = np.asarray(red.nominal_stress(t, **kw, equilibrium="hertz"))
        ramp = (t > 0) & (t <= ramp_time * (1 + 1e-12))
        hold = t > ramp_time * (1 + 1e-12)
        dev = np.abs(s_red / np.where(s_fe != 0, s_fe, np.nan) - 1.0)
        dev_hz = np.abs(s_hz / np.where(s_fe != 0, s_fe, np.nan) - 1.0)
        rows.append(
            {
                "case": name,
                "C [Pa]": c["C"],
                "alpha [-]": c["alpha"],
                "beta [-]": c["beta"],
                "tau [s]": c["tau"],
                "delta/(2 a0) [-]": c["displacement"] / (2 * radius),
                "max dev. after ramp [-]": float(np.nanmax(dev[hold])),
                "max dev. during ramp [-]": float(np.nanmax(dev[ramp])),
                "Hertz: max dev. after ramp [-]": float(np.nanmax(dev_hz[hold])),
                "FE sigma~ peak [Pa]": float(np.max(s_fe)),
                "FE sigma~ end [Pa]": float(s_fe[-1]),
                "FE steps": int(t.size),
                "FE wall [s]": wall,
            }
        )
    return pd.DataFrame(rows)


def fit_demo(
    *,
    levels: Sequence[float] = (50 * UM, 150 * UM),
    noise: float = 0.01,
    seed: int = 0,
    mesh: str | int = "fine",
    radius: float = 500 * UM,
    ramp_time: float = 0.2,
    end_time: float = 1500.0,
    truth: dict | None = None,
    n_ramp: int = 10,
    n_hold: int = 80,
) -> tuple[pd.DataFrame, dict]:
    """Fit the calibrated reduced model to SYNTHETIC records made by the FE (known parameters plus
    Gaussian noise of ``noise`` x the record's peak): once with all ``levels`` and once with the first
    level alone. Returns (table of values and 95 % intervals, {label: FitResult})."""
    from tissuemech.compare import fit
    from tissuemech.fem import spheroid as fe

    truth = dict(C=150.0, alpha=0.2, beta=0.4, tau=200.0) if truth is None else dict(truth)
    rng = np.random.default_rng(seed)
    records = []
    for d in levels:
        kw = spheroid_keywords(truth, radius=radius, displacement=d, ramp_time=ramp_time)
        r = fe.compress(**kw, end_time=end_time, mesh=mesh, n_ramp=n_ramp, n_hold=n_hold)
        s = np.asarray(r.nominal_stress)
        records.append((np.asarray(r.time), s + noise * s.max() * rng.standard_normal(s.shape), d))
    results, rows = {}, []
    for label, recs in ((f"{len(levels)} levels", records), ("1 level", records[:1])):
        t0 = time.perf_counter()
        res = fit.relaxation(recs, radius=radius, ramp_time=ramp_time)
        wall = time.perf_counter() - t0
        results[label] = res
        for k, v in truth.items():
            lo, hi = res.intervals[k]
            rows.append(
                {
                    "records": label,
                    "parameter": k,
                    "truth": v,
                    "fitted": res.params[k],
                    "95% lo": lo,
                    "95% hi": hi,
                    "truth inside": bool(lo <= v <= hi),
                    "fit wall [s]": wall,
                }
            )
    return pd.DataFrame(rows), results


def hertz_table(
    xs: Sequence[float] = (0.005, 0.01, 0.02, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3),
    alphas: Sequence[float] = (0.0, 0.2, 0.5, 1.0),
) -> pd.DataFrame:
    """F_Hertz / F_FE (calibrated master curve) against x = delta/(2 a0), per alpha."""
    from tissuemech.reduced import spheroid as red

    mc = red.master_curve()
    rows = []
    for x in xs:
        row = {"delta/(2 a0) [-]": x}
        for a in alphas:
            row[f"F_Hertz/F_FE alpha={a:g}"] = float(red.hertz_f(x) / mc.f(x, a))
        rows.append(row)
    return pd.DataFrame(rows)


TABLE_NAMES = ("blastula", "creep", "spheroid", "hertz")


if __name__ == "__main__":  # kept: the same as tissuemech checks
    from tissuemech.compare.cli.checks import main

    raise SystemExit(main())
