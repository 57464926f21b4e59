"""``python -m tissuemech.compare.bench fit-dense``: dense records (issue 40, item 1).

1. Binned against full: one synthetic record of ``--samples`` samples (default 1e5: 0.5 kHz-equivalent sampling of
   a 2 s ramp and a 198 s hold; C = 150 Pa, alpha = 0.2, beta = 0.4, tau = 20 s on the FE table, a0 = 500 um,
   approach 200 um; noise sd 1 % of the peak, white or AR(1) with ``--rho``) fitted sample by sample
   (``compress=False``) and in bins (``compress="auto"``): the estimates, the 95 % interval widths and their
   ratios binned / full, and both fits' times (each one fit, its compile included).
2. End to end: ``tissuemech fit`` on a CSV of ``--big`` samples (default 1e6) in a fresh process (read, checks,
   compression, fit, intervals, figure), its wall time and the load average.

``--seeds 1,2,3,4`` runs part 1 on several noise realisations and prints the ratios per seed; ``--misfit M`` gives
the record a smooth misfit (the curve times 1 + M sin(2 pi log(t + ramp) / log(t_end + ramp))). The binned fit's
intervals come from the error model on every sample at its estimate (:mod:`tissuemech.compare.fit.compress`), so
the widths differ from the full fit's by the estimate's shift only.
``--skip-full`` leaves out the full fit of part 1 (it takes about a minute on 1e5 samples), ``--skip-cli`` part 2.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

__all__ = ["make_record", "compare_fits", "main"]

TRUTH = dict(C=150.0, alpha=0.2, beta=0.4, tau=20.0)
RADIUS, RAMP, T_END, APPROACH, NOISE = 500e-6, 2.0, 200.0, 200e-6, 0.01


def make_record(samples: int, rho: float = 0.0, seed: int = 1, misfit: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(time s, nominal stress Pa) of the synthetic record (module doc): uniform sampling of (0, T_END]."""
    from tissuemech.reduced import spheroid

    t = np.arange(1, samples + 1) * (T_END / samples)
    y = np.asarray(
        spheroid.nominal_stress(
            t,
            radius=RADIUS,
            C=TRUTH["C"],
            alpha=TRUTH["alpha"],
            branches=[(TRUTH["beta"], TRUTH["tau"])],
            displacement=APPROACH,
            ramp_time=RAMP,
        )
    )
    if misfit:
        y = y * (1.0 + misfit * np.sin(2.0 * np.pi * np.log(t + RAMP) / np.log(T_END + RAMP)))
    rng = np.random.default_rng(seed)
    e = rng.standard_normal(samples)
    if rho > 0:  # AR(1) of unit marginal variance
        from scipy.signal import lfilter

        e = lfilter([np.sqrt(1 - rho**2)], [1.0, -rho], e)
    return t, y + NOISE * float(np.max(y)) * e


def compare_fits(samples: int, rho: float = 0.0, full: bool = True, seed: int = 1, misfit: float = 0.0) -> list[dict]:
    """Rows per parameter: estimate and 95 % width, binned and full, and their ratios; plus the fits' times
    (``seed``: the noise realisation)."""
    from tissuemech.compare import fit

    t, y = make_record(samples, rho, seed, misfit)
    rec = [(t, y, APPROACH)]
    kw = dict(radius=RADIUS, ramp_time=RAMP)
    runs = {}
    plan: list[tuple[str, bool | int | str]] = [("binned", "auto")]
    plan += [("full", False)] if full else []
    for name, compress in plan:
        c0 = time.perf_counter()
        res = fit.relaxation(rec, compress=compress, **kw)
        runs[name] = (res, time.perf_counter() - c0)
    rows = []
    b = runs["binned"][0]
    for n in b.names:
        row = {"parameter": n, "binned": b.params[n], "binned 95% width": np.subtract(*b.intervals[n][::-1])}
        if full:
            f = runs["full"][0]
            wf = np.subtract(*f.intervals[n][::-1])
            row.update(
                {
                    "full": f.params[n],
                    "full 95% width": wf,
                    "estimate shift / full width": (b.params[n] - f.params[n]) / wf,
                    "width binned / full - 1": row["binned 95% width"] / wf - 1.0,
                }
            )
        rows.append(row)
    for name, (res, wall) in runs.items():
        rows.append({"parameter": f"{name} fit: {sum(res.bins) or samples} points", "fit incl. compile [s]": wall})
    return rows


def cli_time(samples: int) -> dict:
    """``tissuemech fit`` end to end on a fresh CSV of ``samples`` rows, in a fresh process."""
    t, y = make_record(samples)
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "dense.csv"
        with open(path, "w") as f:
            f.write(f"# displacement_um: {APPROACH * 1e6:g}\ntime_s,stress_Pa\n")
            np.savetxt(f, np.column_stack([t, y]), fmt="%.9g", delimiter=",")
        entry = "import sys; from tissuemech.compare.cli import main; sys.exit(main())"
        cmd = [sys.executable, "-c", entry, "fit", str(path), "--radius-um", f"{RADIUS * 1e6:g}"]
        cmd += ["--ramp-time", f"{RAMP:g}", "--out", str(Path(d) / "out")]
        load = os.getloadavg()[0]
        t0 = time.perf_counter()
        out = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if out.returncode:
            raise RuntimeError(out.stderr[-2000:])
        figure = (Path(d) / "out" / "fit.png").exists()
    return {"samples": samples, "end to end [s]": wall, "load average before": load, "figure written": figure}


def main(argv: Sequence[str] | None = None) -> int:
    from tissuemech.compare.bench.common import machine_line, print_rows

    ap = argparse.ArgumentParser(
        prog="python -m tissuemech.compare.bench fit-dense", description=__doc__.split("\n")[0]
    )
    ap.add_argument("--samples", type=float, default=1e5, help="samples of the binned-vs-full record (default 1e5)")
    ap.add_argument("--rho", type=float, default=0.0, help="AR(1) coefficient of the noise (default 0: white)")
    ap.add_argument("--seed", type=int, default=1, help="noise realisation of part 1 (default 1)")
    ap.add_argument("--seeds", default="", help="several noise realisations of part 1, e.g. 1,2,3,4 (over --seed)")
    ap.add_argument("--misfit", type=float, default=0.0, help="relative size of a smooth misfit (default 0)")
    ap.add_argument("--big", type=float, default=1e6, help="samples of the end-to-end record (default 1e6)")
    ap.add_argument("--skip-full", action="store_true", help="no full fit (only the binned one)")
    ap.add_argument("--skip-cli", action="store_true", help="no end-to-end run of tissuemech fit")
    ap.add_argument("--quick", action="store_true", help="accepted for `bench all --quick`: --samples 2e4 --big 2e5")
    a = ap.parse_args(list(argv or []))
    if a.quick:
        a.samples, a.big = min(a.samples, 2e4), min(a.big, 2e5)
    print(machine_line())
    for seed in [int(s) for s in a.seeds.split(",")] if a.seeds else [a.seed]:
        print(f"binned vs full fit, {int(a.samples)} samples, noise rho {a.rho:g}, misfit {a.misfit:g}, seed {seed}")
        print_rows(compare_fits(int(a.samples), a.rho, not a.skip_full, seed, a.misfit))
    if not a.skip_cli:
        print_rows([cli_time(int(a.big))])
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
