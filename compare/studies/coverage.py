r"""Coverage study of :func:`tissuemech.compare.fit.relaxation`: do its 95 % intervals hold the truth 95 % of the time?

    tissuemech coverage [--n-reduced 200] [--n-fe 30] [--noise 0.005 0.01 0.03]
                        [--no-fe] [--seed 0] [--csv coverage.csv]
    (or python -m tissuemech.compare.coverage ...)

Synthetic records, two compression levels (50 and 200 um total approach of a 500 um ball, 0.2 s ramp,
held to 1500 s; 10 samples on the ramp, 60 log-spaced over the hold), white Gaussian noise of standard
deviation ``noise`` x the record's peak stress:

* reduced-made: ``reduced.spheroid.nominal_stress`` with the shipped FE master table, one fresh truth per
  record drawn from C in [100, 250] Pa, alpha in [0.1, 0.5], beta in [0.2, 1.0], tau in [50, 400] s
  (log-uniform); fitted with ``model_error=0`` (the model made the data: this tests the noise part);
* FE-made: ``fem.spheroid.compress`` (default mesh) at a few truths from the same box, several noise
  draws each; fitted with ``model_error="auto"`` (the table's own error estimate), which is what a
  user fitting real data gets.

Printed per noise level and parameter: empirical coverage of the 95 % interval (with its binomial
95 % range), median bias of the estimate (%), median relative interval width (%), how many intervals
were one-sided, and fit failures (counted as misses). Target: 90-99 % on reduced-made, >= 90 % on
FE-made records. Rerun after regenerating the master table: the numbers follow the table.

The error-model rows (:data:`SCENARIOS`, :func:`scenario_study`; ``tissuemech coverage --scenarios
[--n-scenario 200]``): reduced-made records with 1 % noise that is white, AR(1) with lag-1 correlation 0.9, or
proportional to the signal, or white plus a 0.5 % smooth misfit (:func:`add_misfit`), on sparse records (the
protocol above) and dense ones (:data:`DENSE`: 2000 samples every 0.75 s), and creep records (:data:`CREEP`: 3 and
25 uN held, 1 % white noise on the approach, fitted by :func:`tissuemech.compare.fit.protocols.records_fit`); each
fit's own intervals and the Wald intervals of every error model of :mod:`tissuemech.compare.fit.diagnostics` are
scored. Target: 90-99 % for every parameter on every row. Measured (200 fits per row, 2026-12-03): docs/fitting.md.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Sequence

import numpy as np
import pandas as pd

from tissuemech.compare import cases
from tissuemech.compare.fit import Z95, parameter_names, relaxation
from tissuemech.compare.fit.diagnostics import discrepancy_basis
from tissuemech.compare.fit.protocols import CreepRecord, records_fit

__all__ = [
    "PROTOCOL",
    "BOX",
    "NAMES",
    "sample_truths",
    "reduced_records",
    "creep_records",
    "CREEP",
    "fe_records",
    "add_noise",
    "add_misfit",
    "DENSE",
    "SCENARIOS",
    "scenario_study",
    "summarise_scenarios",
    "fit_many",
    "wilson",
    "summarise",
    "run",
]

A0 = 500e-6
PROTOCOL = dict(
    radius=A0,
    levels=(50e-6, 200e-6),
    ramp_time=0.2,
    end_time=1500.0,
    times=tuple(np.concatenate([np.linspace(0.0, 0.2, 11)[1:], np.geomspace(0.3, 1500.0, 60)])),
)
# creep records: a plate force ramped over 0.2 s to 3 and 25 uN and held to 1500 s (approaches of about 20-200 um of
# the 500 um ball over the box), sampled as PROTOCOL; the model reduced.spheroid.approach, fitted to the approach
CREEP = dict(PROTOCOL, levels=(), forces=(3e-6, 25e-6))
BOX = dict(C=(100.0, 250.0), alpha=(0.1, 0.5), beta=(0.2, 1.0), tau=(50.0, 400.0))
NAMES = parameter_names(1)


def sample_truths(n: int, rng: np.random.Generator, box: dict = BOX) -> list[dict[str, float]]:
    """``n`` parameter sets: C, alpha, beta uniform in ``box``, tau log-uniform (Pa, -, -, s)."""
    out = []
    for _ in range(n):
        out.append(
            dict(
                C=float(rng.uniform(*box["C"])),
                alpha=float(rng.uniform(*box["alpha"])),
                beta=float(rng.uniform(*box["beta"])),
                tau=float(math.exp(rng.uniform(math.log(box["tau"][0]), math.log(box["tau"][1])))),
            )
        )
    return out


def _case(truth: dict, protocol: dict, displacement: float) -> dict:
    """The keywords one record shares between the reduced model and the FE (SI units)."""
    return cases.spheroid_keywords(
        truth, radius=protocol["radius"], displacement=displacement, ramp_time=protocol["ramp_time"]
    )


def reduced_records(truth: dict, protocol: dict = PROTOCOL, equilibrium="fem") -> list[tuple]:
    """Noise-free records (time s, nominal stress Pa, displacement m) from the reduced model."""
    from tissuemech.reduced import spheroid

    t = np.asarray(protocol["times"], dtype=float)
    out = []
    for d in protocol["levels"]:
        y = spheroid.nominal_stress(t, **_case(truth, protocol, d), equilibrium=equilibrium)
        out.append((t, np.asarray(y), d))
    return out


def creep_records(truth: dict, protocol: dict = CREEP, equilibrium="fem") -> list[tuple]:
    """Noise-free creep records (time s, approach m, held force N) from ``reduced.spheroid.approach``, one per force
    of ``protocol["forces"]`` (N, reached linearly at ``protocol["ramp_time"]``)."""
    from tissuemech.reduced import spheroid

    t = np.asarray(protocol["times"], dtype=float)
    br = [(truth["beta"], truth["tau"])]
    out = []
    for f in protocol["forces"]:
        d = spheroid.approach(
            t,
            radius=protocol["radius"],
            C=truth["C"],
            alpha=truth["alpha"],
            branches=br,
            force=f,
            ramp_time=protocol["ramp_time"],
            equilibrium=equilibrium,
        )
        out.append((t, np.asarray(d), f))
    return out


def fe_records(truth: dict, protocol: dict = PROTOCOL, mesh="default", n_ramp: int = 10, n_hold: int = 60) -> list:
    """Noise-free records from the FE (``fem.spheroid.compress``); t = 0 dropped."""
    from tissuemech.fem import spheroid as fe

    out = []
    for d in protocol["levels"]:
        r = fe.compress(
            **_case(truth, protocol, d), end_time=protocol["end_time"], mesh=mesh, n_ramp=n_ramp, n_hold=n_hold
        )
        keep = np.asarray(r.time) > 0
        out.append((np.asarray(r.time)[keep], np.asarray(r.nominal_stress)[keep], d))
    return out


def add_noise(
    records: Sequence[tuple], noise: float, rng: np.random.Generator, kind: str = "white", rho: float = 0.9
) -> list[tuple]:
    """Gaussian noise on each record: ``kind`` "white" (sd ``noise`` x the record's peak stress), "ar1" (stationary
    AR(1) in sample order with lag-1 correlation ``rho`` and the same marginal sd) or "proportional" (sd ``noise``
    x the stress at each point)."""
    out = []
    for t, y, d in records:
        e = rng.standard_normal(y.shape)
        if kind == "white":
            dy = noise * np.max(np.abs(y)) * e
        elif kind == "ar1":
            x = np.empty_like(e)
            x[0] = e[0]
            c = math.sqrt(1.0 - rho * rho)
            for k in range(1, e.size):
                x[k] = rho * x[k - 1] + c * e[k]
            dy = noise * np.max(np.abs(y)) * x
        elif kind == "proportional":
            dy = noise * np.abs(y) * e
        else:
            raise ValueError(f"noise kind must be 'white', 'ar1' or 'proportional'; got {kind!r}")
        out.append((t, y + dy, d))
    return out


def add_misfit(records: Sequence[tuple], amplitude: float, rng: np.random.Generator, ramp_time: float) -> list[tuple]:
    """A smooth relative model misfit on each record: y (1 + delta(t)), delta a random smooth function of log time
    of root-mean-square ``amplitude`` over the record's log-time span: the sum of the record's
    :func:`~tissuemech.compare.fit.diagnostics.discrepancy_basis` shapes (Legendre polynomials of degree 0..5 in
    log(t + ramp_time)) with independent normal weights (a fresh draw per record).
    This is the misfit the "robust" error model assumes; a misfit concentrated in the shapes the parameters
    absorb cannot be told from the parameters by any residual analysis."""
    out = []
    for t, y, d in records:
        B = discrepancy_basis(np.asarray(t), ramp_time)
        a = rng.standard_normal(B.shape[1]) * amplitude / math.sqrt(B.shape[1])
        out.append((t, y * (1.0 + B @ a), d))
    return out


# lab-style dense records: 2000 samples every 0.75 s over the 1500 s hold (the 0.2 s ramp is not resolved)
DENSE = dict(PROTOCOL, times=tuple(np.linspace(0.75, 1500.0, 2000)))
# the rows of the error-model study: records (protocol), 1 % noise of a kind, a smooth misfit (relative amplitude)
SCENARIOS: dict[str, dict] = {
    "white": dict(protocol=PROTOCOL, kind="white", misfit=0.0),
    "white, dense": dict(protocol=DENSE, kind="white", misfit=0.0),
    "AR(1) 0.9, dense": dict(protocol=DENSE, kind="ar1", misfit=0.0),
    "proportional": dict(protocol=PROTOCOL, kind="proportional", misfit=0.0),
    "proportional, dense": dict(protocol=DENSE, kind="proportional", misfit=0.0),
    "misfit 0.5 %": dict(protocol=PROTOCOL, kind="white", misfit=0.005),
    "misfit 0.5 %, dense": dict(protocol=DENSE, kind="white", misfit=0.005),
    "creep": dict(protocol=CREEP, kind="white", misfit=0.0),
}


def scenario_study(
    names: Sequence[str] = tuple(SCENARIOS),
    n: int = 200,
    *,
    noise: float = 0.01,
    seed: int = 0,
    intervals: str = "profile",
    log=sys.stderr,
) -> pd.DataFrame:
    """``n`` reduced-made fits per scenario of :data:`SCENARIOS` (fresh truth and noise each, ``model_error=0``):
    one row per fit, parameter and error model ("default": the fit's own intervals, ``intervals`` method, error
    model "robust"; the others: Wald intervals of :attr:`FitResult.wald_by_error_model`)."""
    rng = np.random.default_rng(seed)
    rows = []
    for name in names:
        sc = SCENARIOS[name]
        prot = sc["protocol"]
        t0 = time.perf_counter()
        for k, truth in enumerate(sample_truths(n, rng)):
            creep = bool(prot.get("forces"))
            clean = creep_records(truth, prot) if creep else reduced_records(truth, prot)
            recs = add_noise(clean, noise, rng, kind=sc["kind"])
            if sc["misfit"]:
                recs = add_misfit(recs, sc["misfit"], rng, prot["ramp_time"])
            fit = records_fit if creep else relaxation
            if creep:
                recs = [CreepRecord(*r) for r in recs]
            try:
                res = fit(
                    recs, radius=prot["radius"], ramp_time=prot["ramp_time"], model_error=0.0, intervals=intervals
                )
            except (ValueError, RuntimeError):
                res = None
            for p in NAMES:
                base = dict(scenario=name, job=k, parameter=p, truth=truth[p])
                if res is None:
                    rows.append(dict(base, errors="default", estimate=math.nan, lo=math.nan, hi=math.nan, inside=False))
                    continue
                lo, hi = res.intervals[p]
                rows.append(
                    dict(base, errors="default", estimate=res.params[p], lo=lo, hi=hi, inside=lo <= truth[p] <= hi)
                )
                for m, iv in res.wald_by_error_model.items():
                    lo, hi = iv[p]
                    rows.append(dict(base, errors=m, estimate=res.params[p], lo=lo, hi=hi, inside=lo <= truth[p] <= hi))
            if log is not None and (k + 1) % 50 == 0:
                print(f"  {name}: {k + 1}/{n} fits, {time.perf_counter() - t0:.0f} s", file=log)
        if log is not None:
            print(f"{name}: {n} fits in {time.perf_counter() - t0:.0f} s", file=log)
    return pd.DataFrame(rows)


def summarise_scenarios(df: pd.DataFrame) -> pd.DataFrame:
    """Coverage (%) per scenario, error model and parameter, with its Wilson 95 % range and the median relative
    width (%)."""
    out = []
    for (sc, m, p), g in df.groupby(["scenario", "errors", "parameter"], sort=False):
        k, n = int(g["inside"].sum()), len(g)
        a, b = wilson(k, n)
        width = ((g["hi"] - g["lo"]) / g["truth"] * 100).replace([np.inf], np.nan)
        out.append(
            {
                "scenario": sc,
                "errors": m,
                "parameter": p,
                "fits": n,
                "coverage %": 100 * k / n,
                "Wilson 95 %": f"{100 * a:.0f}-{100 * b:.0f}",
                "median width %": float(np.nanmedian(width)) if width.notna().any() else math.nan,
            }
        )
    return pd.DataFrame(out)


def fit_many(
    jobs: Sequence[tuple[dict, list]],
    *,
    protocol: dict = PROTOCOL,
    model_error=0.0,
    source: str = "",
    noise: float = math.nan,
    log=None,
) -> pd.DataFrame:
    """Fit each (truth, records) job; one row per job and parameter (truth, estimate, interval, inside)."""
    rows = []
    t0 = time.perf_counter()
    for k, (truth, recs) in enumerate(jobs):
        try:
            res = relaxation(recs, radius=protocol["radius"], ramp_time=protocol["ramp_time"], model_error=model_error)
            err = ""
        except (ValueError, RuntimeError) as exc:
            res, err = None, str(exc)
        for n in NAMES:
            if res is None:
                est, lo, hi, kind, ok = math.nan, math.nan, math.nan, "failed", False
            else:
                est, (lo, hi), kind, ok = res.params[n], res.intervals[n], res.kinds[n], res.success
            rows.append(
                dict(
                    source=source,
                    noise=noise,
                    job=k,
                    parameter=n,
                    truth=truth[n],
                    estimate=est,
                    lo=lo,
                    hi=hi,
                    kind=kind,
                    inside=bool(lo <= truth[n] <= hi),
                    success=ok,
                    error=err,
                )
            )
        if log is not None and (k + 1) % 50 == 0:
            print(f"  {source} noise {noise:g}: {k + 1}/{len(jobs)} fits, {time.perf_counter() - t0:.0f} s", file=log)
    return pd.DataFrame(rows)


def wilson(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval (lo, hi) of a binomial proportion: ``k`` successes in ``n`` trials, ``z`` the normal
    quantile (1.96: 95 %); (nan, nan) for n = 0."""
    if n == 0:
        return math.nan, math.nan
    p = k / n
    den = 1 + z * z / n
    c = (p + z * z / (2 * n)) / den
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return c - h, c + h


def summarise(df: pd.DataFrame) -> pd.DataFrame:
    """Coverage (%), its binomial 95 % range, median bias (%), median relative width (%), one-sided count."""
    out = []
    for (src, noise, n), g in df.groupby(["source", "noise", "parameter"], sort=False):
        k, m = int(g["inside"].sum()), len(g)
        a, b = wilson(k, m)
        rel = (g["estimate"] / g["truth"] - 1.0) * 100
        width = (g["hi"] - g["lo"]) / g["truth"] * 100
        out.append(
            {
                "records": src,
                "noise %": 100 * noise,
                "parameter": n,
                "fits": m,
                "coverage %": 100 * k / m,
                "coverage 95% range": f"{100 * a:.0f}-{100 * b:.0f}",
                "median bias %": float(np.nanmedian(rel)),
                "mean bias %": float(np.nanmean(rel)),
                "median width %": float(np.nanmedian(width.replace([np.inf], np.nan))),
                "one-sided": int(np.sum(g["kind"].isin(["upper", "lower"]))),
                "failed": int(np.sum(g["kind"] == "failed")),
            }
        )
    return pd.DataFrame(out)


def run(
    n_reduced: int = 200,
    n_fe: int = 30,
    noises: Sequence[float] = (0.005, 0.01, 0.03),
    seed: int = 0,
    fe_truths: int = 6,
    fe: bool = True,
    log=sys.stderr,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The whole study: (per-fit rows, summary table)."""
    rng = np.random.default_rng(seed)
    frames = []
    truths = sample_truths(n_reduced, rng)
    clean = [reduced_records(tr) for tr in truths]
    for noise in noises:
        jobs = [(tr, add_noise(c, noise, rng)) for tr, c in zip(truths, clean)]
        t0 = time.perf_counter()
        frames.append(fit_many(jobs, model_error=0.0, source="reduced-made", noise=noise, log=log))
        print(f"reduced-made, noise {100 * noise:g} %: {len(jobs)} fits in {time.perf_counter() - t0:.0f} s", file=log)
    if fe and n_fe > 0:
        ftruths = sample_truths(fe_truths, rng)
        t0 = time.perf_counter()
        fclean = [fe_records(tr) for tr in ftruths]
        print(f"FE records: {2 * fe_truths} runs in {time.perf_counter() - t0:.0f} s", file=log)
        for noise in noises:
            jobs = [(ftruths[k % fe_truths], add_noise(fclean[k % fe_truths], noise, rng)) for k in range(n_fe)]
            t0 = time.perf_counter()
            frames.append(fit_many(jobs, model_error="auto", source="FE-made", noise=noise, log=log))
            print(f"FE-made, noise {100 * noise:g} %: {len(jobs)} fits in {time.perf_counter() - t0:.0f} s", file=log)
    df = pd.concat(frames, ignore_index=True)
    return df, summarise(df)
