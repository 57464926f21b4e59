r"""The reduced lumped model's error during the ramp (issue 35, item 3), against the FE converged in time.

The lumped model (``reduced.spheroid``) convolves the global equilibrium force F_eq(delta) with each Maxwell
kernel, F = F_eq + sum_m beta_m int e^{-(t-s)/tau_m} dF_eq/ds ds. The FE (``fem.spheroid``) runs the same
branches at every material point on the isochoric stress S_iso; the two agree exactly in the hold's long-time
limit and for tau >> ramp (a glassy, elastic-like response with the factor 1 + sum beta), and for a linear
material in small strain under a growing contact (Lee and Radok's hereditary integral), but not in finite strain
while a fast branch relaxes during the ramp. ``ramp_error`` measures that error: one branch (beta, tau) on a ball
of a0 = 500 um, C = 150 Pa, approached by ``x`` = delta/(2 a0) linearly in ramp_time = 1 s and held; FE on the
contact-edge-fitted ``level`` with ``fem.stepping.Adaptive(tol)`` (time error far below the effect). The table's
own calibration error and the level's spatial error are taken out by an elastic FE run on the same steps:

    e(t) = F_red(t) / F_FE(t) - F_eq,red(delta(t)) / F_FE,elastic(delta(t)),

the lumped model's error beyond that of its equilibrium law, for the default law (``coupling="auto"``: the FE
table's geometric coupling of issue 34, ``reduced.spheroid.COUPLING``; what ``lumped_ramp_error`` tabulates) and,
in the ``plain_*`` columns, the plain lumped law (``coupling=0``). Output times: 0.1, 0.25, 0.5, 0.75, 1 ramp_time
and ramp_time + (0.5, 1, 3) tau; ``max |e|`` over them and the time where it is largest.

``python -m tissuemech.compare.studies.ramp [--level 0] [--ratios 0.05,0.1,...] [--alphas 0,0.8,1.5] [--beta 0.8]
[--x 0.1] [--tol 1e-4] [--csv PATH]`` prints the table (tau / ramp_time in rows, alpha in columns).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

RADIUS, C_PA, RAMP = 500e-6, 150.0, 1.0
RATIOS = (0.05, 0.1, 0.3, 1.0, 3.0, 10.0, 100.0)
ALPHAS = (0.0, 0.8, 1.5)

__all__ = ["ramp_error", "output_times", "RATIOS", "ALPHAS"]


def output_times(ratio: float, ramp_time: float = RAMP) -> np.ndarray:
    """The output times (s) of ``ramp_error`` for tau = ratio ramp_time."""
    tau = ratio * ramp_time
    return np.r_[np.array([0.1, 0.25, 0.5, 0.75, 1.0]) * ramp_time, ramp_time + np.array([0.5, 1.0, 3.0]) * tau]


def _fe(alpha: float, branches, x: float, times: np.ndarray, level: int, tol: float):
    from tissuemech.fem.spheroid import compress
    from tissuemech.fem.stepping import Adaptive

    r = compress(
        radius=RADIUS,
        C=C_PA,
        alpha=alpha,
        branches=branches,
        displacement=2 * RADIUS * x,
        ramp_time=RAMP,
        end_time=float(times[-1]),
        mesh=level,
        field_times=list(times),
        stepping=Adaptive(tol=tol),
    )
    k = [int(np.argmin(np.abs(r.time - t))) for t in times]
    return r.force[k], int((r.parameters or {})["n_steps"])


def ramp_error(
    ratios: Sequence[float] = RATIOS,
    alphas: Sequence[float] = ALPHAS,
    *,
    beta: float = 0.8,
    x: float = 0.1,
    level: int = 0,
    tol: float = 1e-4,
) -> pd.DataFrame:
    """One row per (tau / ramp_time, alpha): ``max_error`` (max |e| over the output times, signed), ``t_max / ramp``
    (where), ``error_ramp_end`` (e at the end of the ramp) of the default (coupled) law, ``plain_max_error`` and
    ``plain_t_max / ramp`` of the plain lumped law (``coupling=0``), FE steps and wall time (module docstring)."""
    from tissuemech.reduced import spheroid as rs

    rows = []
    for alpha in alphas:
        t_all = np.unique(np.concatenate([output_times(q) for q in ratios]))
        t0 = time.perf_counter()
        F_el, _ = _fe(alpha, (), x, t_all, level, tol)
        d_all = 2 * RADIUS * x * np.minimum(t_all / RAMP, 1.0)
        eq = np.asarray(rs.equilibrium_force(d_all, radius=RADIUS, C=C_PA, alpha=alpha))
        bias = dict(zip(np.round(t_all, 12), eq / F_el))
        for q in ratios:
            ts = output_times(q)
            t1 = time.perf_counter()
            F_fe, n = _fe(alpha, [(beta, q * RAMP)], x, ts, level, tol)
            red: dict[str, Any] = dict(
                radius=RADIUS, C=C_PA, alpha=alpha, branches=[(beta, q * RAMP)], displacement=2 * RADIUS * x
            )
            b = np.array([bias[round(t, 12)] for t in ts])
            e = np.asarray(rs.force(ts, **red, ramp_time=RAMP)) / F_fe - b  # the default (coupled) law
            e0 = np.asarray(rs.force(ts, **red, ramp_time=RAMP, coupling=0.0)) / F_fe - b  # the plain lumped law
            k, k0 = int(np.argmax(np.abs(e))), int(np.argmax(np.abs(e0)))
            rows.append(
                {
                    "tau / ramp": q,
                    "alpha": alpha,
                    "max_error": float(e[k]),
                    "t_max / ramp": float(ts[k] / RAMP),
                    "error_ramp_end": float(e[4]),
                    "plain_max_error": float(e0[k0]),
                    "plain_t_max / ramp": float(ts[k0] / RAMP),
                    "fe_steps": n,
                    "wall [s]": time.perf_counter() - t1 + (time.perf_counter() - t0 if q == ratios[0] else 0.0),
                }
            )
    return pd.DataFrame(rows)


if __name__ == "__main__":
    from tissuemech.compare.cli.ramp import main

    sys.exit(main())
