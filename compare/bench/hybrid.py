"""``python -m tissuemech.compare.bench hybrid``: the hybrid layer's speed and accuracy.

Rows:
* fit: a 4-parameter (C, alpha, beta, tau) fit on two synthetic noisy records (compile time, time
  after compile, recovered values vs truth, whether every truth lies in its 95 % interval), and
  the identifiability of a single level (weakest eigenvalue, C-alpha correlation).
* scan: 1e5 spheroid relaxation curves (200 times each) through ``compare.scan.spheroid`` (LHS).
* blastula scan: 1e5 points through ``compare.scan.blastula``.
* batch: overhead per point of ``compare.batch.run`` (2 spawned processes, trivial function).

Model: ``reduced.spheroid.nominal_stress`` with the FE-calibrated equilibrium (alpha-dependent, so two
compression levels separate C and alpha); a stand-in lumped Maxwell model with a Fung-stiffened
equilibrium only if the calibration table is missing (labelled "stand-in" in the table).
Options: ``--n-scan N`` (default 100000), ``--quick`` (n-scan 10000, fewer repeats).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Sequence

import jax.numpy as jnp
import numpy as np

import tissuemech.reduced  # noqa: F401

A0, TR = 500e-6, 0.2
TRUE = dict(C=150.0, alpha=0.2, beta=0.4, tau=200.0)


def standin_nominal_stress(t, *, radius, C, alpha, branches, displacement, ramp_time, equilibrium=None):
    """Stand-in lumped Maxwell nominal stress (Pa): F_eq = C a0^2 (32/3) x^1.5 exp(4 alpha x),
    x = delta/(2 a0), A_mid = pi a0^2 (1 + x); ramp by the exact-for-linear recursion (400 substeps),
    hold by exact exponential decay. Only a benchmark fixture (the real model is reduced.spheroid)."""
    t = jnp.asarray(t, dtype=jnp.float64)
    x_end = displacement / (2 * radius)
    feq = lambda x: C * radius**2 * (32.0 / 3.0) * x**1.5 * jnp.exp(4.0 * alpha * x)
    n = 400
    s = jnp.linspace(0.0, 1.0, n + 1)
    f = feq(x_end * s)
    xt = jnp.clip(t / ramp_time, 0.0, 1.0)
    force = feq(x_end * xt)
    for beta, tau in branches:
        h = ramp_time / n / tau
        a = jnp.exp(-h)
        k = jnp.arange(1, n + 1)
        qn = jnp.concatenate([jnp.zeros(1), jnp.cumsum(jnp.diff(f) * a ** (-k)) * a**k]) * beta * (-jnp.expm1(-h)) / h
        q = jnp.where(
            t <= ramp_time,
            jnp.interp(t, s * ramp_time, qn),
            qn[-1] * jnp.exp(-(jnp.maximum(t, ramp_time) - ramp_time) / tau),
        )
        force = force + q
    return force / (jnp.pi * radius**2 * (1.0 + x_end * xt))


def _reduced_model():
    """(model, label): None lets compare.scan / compare.fit use reduced.spheroid with the FE-calibrated
    equilibrium and their own solver / adjoint choices."""
    try:
        from tissuemech.reduced import spheroid

        spheroid.master_curve()
        return None, "reduced.spheroid (FE-calibrated)"
    except (ImportError, FileNotFoundError):
        return standin_nominal_stress, "stand-in (Fung-Hertz)"


def _records(model, levels, noise, seed, times):
    rng = np.random.default_rng(seed)
    out = []
    if model is None:
        from tissuemech.reduced import spheroid

        model = spheroid.nominal_stress
    for d in levels:
        y = np.asarray(
            model(
                times,
                radius=A0,
                C=TRUE["C"],
                alpha=TRUE["alpha"],
                branches=[(TRUE["beta"], TRUE["tau"])],
                displacement=d,
                ramp_time=TR,
            )
        )
        out.append((times, y + noise * rng.standard_normal(times.shape), d))
    return out


HOLD = np.geomspace(0.3, 1500.0, 120)
CASES = (  # (label, levels, times)
    ("2 levels (50, 200 um), ramp + hold", [50e-6, 200e-6], np.concatenate([np.linspace(0, TR, 21), HOLD])),
    ("1 level (50 um), hold only", [50e-6], np.concatenate([[0.0, TR], HOLD])),
    ("1 level (50 um), ramp resolved", [50e-6], np.concatenate([np.linspace(0, TR, 201), HOLD])),
)


def fit_rows(repeats: int = 9) -> list[dict]:
    from tissuemech.compare import fit

    rows = []
    model, label = _reduced_model()
    for case, levels, times in CASES:
        recs = _records(model, levels, 0.05, 1, times)
        t0 = time.perf_counter()
        res = fit.relaxation(recs, radius=A0, ramp_time=TR, model=model)
        first = time.perf_counter() - t0
        best = np.inf
        hits = [all(res.intervals[k][0] < v < res.intervals[k][1] for k, v in TRUE.items())]
        for seed in range(2, 2 + repeats):  # new noise, same shapes: no recompilation
            recs = _records(model, levels, 0.05, seed, times)
            t0 = time.perf_counter()
            res = fit.relaxation(recs, radius=A0, ramp_time=TR, model=model)
            best = min(best, time.perf_counter() - t0)
            hits.append(all(res.intervals[k][0] < v < res.intervals[k][1] for k, v in TRUE.items()))
        ident = res.identifiability
        rows.append(
            {
                "case": case,
                "model": label,
                "first call [s]": first,
                "after compile [s]": best,
                "C [Pa]": res.params["C"],
                "alpha": res.params["alpha"],
                "beta": res.params["beta"],
                "tau [s]": res.params["tau"],
                "all 4 in 95% CI": f"{sum(hits)}/{len(hits)} noise draws",
                "min eig": float(ident.eigenvalues[0]),
                "corr(C,alpha)": float(ident.correlation()[0, 1]),
                "poorly determined": ",".join(ident.combination(i) for i in ident.poorly) or "-",
            }
        )
    return rows


def scan_rows(n_scan: int) -> list[dict]:
    from tissuemech.compare import scan

    rows = []
    model, label = _reduced_model()
    kw = dict(
        C=(100.0, 300.0),
        alpha=(0.0, 0.3),
        beta=(0.1, 2.0),
        tau=(10.0, 1000.0),
        displacement=(20e-6, 200e-6),
        design_method="lhs",
        model=model,
    )
    t0 = time.perf_counter()
    scan.spheroid(n=1000, batch_size=1000, **kw)
    warm = time.perf_counter() - t0
    t0 = time.perf_counter()
    df = scan.spheroid(n=n_scan, batch_size=8192, **kw)
    wall = time.perf_counter() - t0
    rows.append(
        {
            "case": f"spheroid scan {n_scan} curves x 200 times",
            "model": label,
            "first call [s]": warm,
            "after compile [s]": wall,
            "curves/s": n_scan / wall,
            "finite": bool(np.isfinite(df["sigma_end [Pa]"]).all()),
        }
    )
    t0 = time.perf_counter()
    scan.blastula(alpha=(0.0, 0.3), outer_radius=(52e-6, 75e-6), pressure=(0.0, 150.0), n=1000, design_method="lhs")
    warm = time.perf_counter() - t0
    t0 = time.perf_counter()
    df = scan.blastula(
        alpha=(0.0, 0.3), outer_radius=(52e-6, 75e-6), pressure=(0.0, 150.0), n=n_scan, design_method="lhs"
    )
    wall = time.perf_counter() - t0
    rows.append(
        {
            "case": f"blastula scan {n_scan} points",
            "model": "reduced.blastula",
            "first call [s]": warm,
            "after compile [s]": wall,
            "curves/s": n_scan / wall,
            "finite": f"{int(df['bursts [-]'].sum())} burst",
        }
    )
    return rows


def _noop(*, i: int) -> dict:
    return {"i": i}


def batch_rows(n: int = 40) -> list[dict]:
    from tissuemech.compare import batch

    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        batch.run(_noop, [dict(i=i) for i in range(n)], store=d, progress=False)
        wall = time.perf_counter() - t0
        t0 = time.perf_counter()
        batch.run(_noop, [dict(i=i) for i in range(n)], store=d, progress=False)
        resume = time.perf_counter() - t0
    return [
        {
            "case": f"batch {n} trivial points, 2 spawned processes",
            "model": "-",
            "first call [s]": wall,
            "after compile [s]": resume,
            "curves/s": n / wall,
            "finite": "resume = all stored",
        }
    ]


def main(argv: Sequence[str] | None = None) -> list[dict]:
    from tissuemech.compare.bench.common import print_rows

    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench hybrid")
    ap.add_argument("--n-scan", type=int, default=100_000)
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(list(argv or []))
    n_scan = 10_000 if a.quick else a.n_scan
    rows = fit_rows(3 if a.quick else 9)
    print(
        "Fits (SYNTHETIC records from the reduced model + 0.05 Pa noise; truth C=150 Pa, alpha=0.2, "
        "beta=0.4, tau=200 s; values shown from the last draw):"
    )
    print_rows(rows)
    srows = scan_rows(n_scan) + batch_rows()
    print("\nScans and batches:")
    print_rows(srows)
    return rows + srows


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
