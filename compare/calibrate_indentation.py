r"""Tabulate the FE-calibrated equilibrium law of a spherical probe on a ball resting on a plate.

For an incompressible Fung ball of radius a0 under a rigid sphere of radius R_p (both contacts frictionless),
dimensional analysis gives

    F_eq = F_Hertz,series(delta) h(y, alpha, rho),   rho = R_p / a0,   y = d_1 / R_1 = 2 x share(rho) / r_1(rho),

with F_Hertz,series the two-Hertz-contacts law of ``reduced.indentation`` (series radius R_s), x = delta / (2 a0),
R_1 = R_p a0 / (R_p + a0) (r_1 = R_1 / a0) and d_1 = share(rho) delta the probe-ball contact's small-strain share of
the approach (``reduced.material.probe_share``): y is the probe contact's depth in units of its effective radius,
the quantity that bounds what the scene resolves (y <= 1/2 for every rho), so one y grid serves every probe size
(x = y r_1 / (2 share): at y = 0.1, x = 0.045 for R_p = a0 and x = 0.0032 for R_p = a0 / 20). h -> 1 as y -> 0.

One job per (rho, level) (``fem.indentation.fitted_states`` on contact-edge-fitted meshes: every alpha over the
whole y grid, continued in y and in alpha) gives a rho-slice; the grid's end is the largest y every slice reached.
The table is the Richardson extrapolation of a fine and a coarse level (default 2 and 1) with the observed order
``ORDER`` in the zone's element count, h = h_f + (h_f - h_c) / ((n_f / n_c)^p - 1), checked against the same
extrapolation of the check level (default 3) and the fine one at the check slices (``CHECK_RHOS``,
``CHECK_ALPHAS``, ``CHECK_YS``). The file (``reduced/data/indentation_master.npz``): ``y`` (n_y,) from 0, ``alpha``
(n_a,), ``rho`` (n_r,), ``h`` (n_r, n_a, n_y) (h = 1 at y = 0), ``h_fine`` / ``h_coarse`` (the levels' values),
``force`` (N, the fine level at the run's a0 and C) and ``metadata`` (JSON: levels, order, kappa / C, wall time,
``discretisation_error`` = the largest |h_table / h_reference - 1| at the check points, ``fine_vs_check_level``,
the check points, the command). ``reduced.indentation`` interpolates h by natural cubic splines in ln rho, then
in s = sqrt(y) and alpha (the plate table's sqrt rule: h - 1 grows like sqrt(y)).

``tissuemech calibrate-indentation [--out PATH] [--install] [--store DIR] [--mesh L]
[--coarse-mesh L] [--order P] [--check-mesh L] [--check-rhos ..] [--rhos ..] [--alphas ..] [--ys ..] [--serial]``
regenerates it through ``compare.batch`` (resumable with ``--store``; the slices and the checks in one process
pool). The shipped table: 4 min (levels 1 and 3 at rho = 0.05, with level 2 and level 3 at rho = 0.2 already in
the store: 14 min) with 2 processes on a heavily loaded shared 2-core machine.
"""

from __future__ import annotations

import json
import logging
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from tissuemech.reduced.indentation import depth_ratio, x_of_depth_ratio

__all__ = [
    "depth_ratio",  # re-exported from reduced.indentation (the table's coordinate)
    "x_of_depth_ratio",
    "slice_states",
    "tabulate",
    "write",
    "main",
    "RHOS",
    "ALPHAS",
    "YS",
    "CHECK_RHOS",
    "CHECK_ALPHAS",
    "CHECK_YS",
    "ORDER",
    "DEFAULT_OUT",
]

log = logging.getLogger(__name__)

RHOS = (0.05, 0.1, 0.2, 0.4, 1.0)
ALPHAS = (0.0, 0.5, 1.5)
YS = (0.0125, 0.025, 0.05, 0.075, 0.1)
CHECK_RHOS = (0.05, 0.2)
# the observed order of the fitted-edge FE in n_zone (fem.indentation.LEVELS): (h_1 - h_2) / (h_2 - h_3) = 4.09, 4.13,
# 4.10 at rho = 0.05, 0.1, 0.27 (x = 0.0005, 0.0012, 0.0102; alpha 0, 0, 0.75), i.e. p = 2.84 over levels 1-3 (3.79 over
# levels 2-4 at rho = 0.27: the extrapolation from levels 1-2 with 2.84 is on the safe side)
ORDER = 2.84
CHECK_ALPHAS = (0.0, 1.5)
CHECK_YS = (0.025, 0.05, 0.1)
DEFAULT_OUT = Path(__file__).resolve().parent.parent / "reduced" / "data" / "indentation_master.npz"
RADIUS, C_REF, KAPPA = 100e-6, 100.0, 2.2e9  # kappa / C = 2.2e7: nearly incompressible


def slice_states(
    *, rho: float, alphas: Sequence[float], ys: Sequence[float], mesh: Any = 2, radius: float = RADIUS,
    C: float = C_REF, kappa: float = KAPPA,
) -> dict:  # fmt: skip
    """One rho-slice (module level, picklable for ``compare.batch``): ``fem.indentation.fitted_states`` at the
    approaches of the depth ratios ``ys``; ``h`` (n_a, n_y) = F / F_Hertz,series (NaN where not reached)."""
    from tissuemech.fem.indentation import fitted_states
    from tissuemech.reduced.indentation import HERTZ_PREFACTOR, series_radius

    d = 2 * radius * x_of_depth_ratio(np.asarray(ys, float), rho)
    r = fitted_states(
        radius=radius, probe_radius=rho * radius, C=C, alphas=alphas, approaches=d, kappa=kappa, mesh=mesh
    )
    hertz = HERTZ_PREFACTOR * C * np.sqrt(float(series_radius(radius, rho * radius))) * d**1.5
    return dict(r, h=r["force"] / hertz, y=np.asarray(ys, float), rho=float(rho))


def tabulate(
    *,
    rhos: Sequence[float] = RHOS,
    alphas: Sequence[float] = ALPHAS,
    ys: Sequence[float] = YS,
    mesh: Any = 2,
    coarse_mesh: Any = 1,
    order: float = ORDER,
    check_mesh: Any = 3,
    check_rhos: Sequence[float] = CHECK_RHOS,
    check_alphas: Sequence[float] = CHECK_ALPHAS,
    check_ys: Sequence[float] = CHECK_YS,
    executor: Any = None,
    store: str | None = None,
) -> tuple[dict, dict]:
    """(table, metadata): the rho-slices on ``mesh`` (and ``coarse_mesh``, None: none) and the checks on
    ``check_mesh`` (None: none) through ``compare.batch`` in one pool, cut at the largest y every slice reached.

    With ``coarse_mesh`` the table is the Richardson extrapolation h = h_f + (h_f - h_c) / ((n_f / n_c)^p - 1) of
    the two levels (n: elements across the contact zone, ``fem.indentation.LEVELS``; p = ``order``), and a check
    point's reference is the same extrapolation of the check level and ``mesh``; without it, the table is ``mesh``
    and the reference the check level itself."""
    from tissuemech.compare import batch
    from tissuemech.fem.indentation import LEVELS

    ygrid = np.asarray(sorted(ys), float)
    al = [float(a) for a in alphas]
    jobs = [dict(rho=float(r), alphas=al, ys=ygrid.tolist(), mesh=mesh) for r in rhos]
    coarse = [] if coarse_mesh is None else [dict(j, mesh=coarse_mesh) for j in jobs]
    checks = []
    if check_mesh is not None:
        ca, cy = [float(a) for a in check_alphas], [float(v) for v in check_ys]
        checks = [dict(rho=float(r), alphas=ca, ys=cy, mesh=check_mesh) for r in check_rhos]
    t0 = time.perf_counter()
    runs = batch.run(slice_states, checks + jobs + coarse, executor=executor, store=store)  # the long checks first
    wall = time.perf_counter() - t0
    if any(r is None for r in runs):
        raise RuntimeError("calibration: an FE slice failed; rerun with the same --store to retry")
    done: list[Any] = [dict(r) for r in runs]  # type: ignore[arg-type]
    check_runs, fine, crs = (
        done[: len(checks)],
        done[len(checks) : len(checks) + len(jobs)],
        done[len(checks) + len(jobs) :],
    )
    h_f = np.stack([np.asarray(s["h"]) for s in fine])  # (n_r, n_a, n_y)
    h_c = np.stack([np.asarray(s["h"]) for s in crs]) if crs else None
    both = h_f if h_c is None else h_f + h_c
    reached = np.all(np.isfinite(both), axis=(0, 1))
    n_ok = int(np.argmin(reached)) if not reached.all() else ygrid.size
    if n_ok < 3:
        raise RuntimeError(f"calibration: the FE reached only y = {ygrid[:n_ok]} in every slice; the table needs >= 3")
    n_of = lambda m: LEVELS[int(m)][0]
    gain = lambda fine_m, coarse_m: 1.0 / ((n_of(fine_m) / n_of(coarse_m)) ** order - 1.0)
    h_ext = h_f if h_c is None else h_f + (h_f - h_c) * gain(mesh, coarse_mesh)
    y = np.r_[0.0, ygrid[:n_ok]]
    h_tab = np.concatenate([np.ones(h_f.shape[:2] + (1,)), h_ext[:, :, :n_ok]], axis=2)
    force = np.stack([np.asarray(s["force"])[:, :n_ok] for s in fine])
    err, raw, at = 0.0, 0.0, ""
    points = []
    for c in check_runs:
        if c["rho"] not in list(rhos):
            continue
        k = list(rhos).index(c["rho"])
        for i, a in enumerate(c["alpha"]):
            if float(a) not in al:
                continue
            ia = al.index(float(a))
            for j, yc in enumerate(c["y"]):
                if not np.isfinite(c["h"][i, j]) or yc > y[-1] * (1 + 1e-12) or not np.any(np.isclose(y, yc)):
                    continue
                jy = int(np.argmin(np.abs(y - yc)))
                h3, h2 = float(c["h"][i, j]), float(h_f[k, ia, jy - 1])
                ref = h3 if h_c is None else h3 + (h3 - h2) * gain(check_mesh, mesh)
                e = float(h_tab[k, ia, jy] / ref - 1.0)
                points.append(dict(rho=float(c["rho"]), alpha=float(a), y=float(yc), table=float(h_tab[k, ia, jy]),
                                   level_fine=h2, level_check=h3, reference=ref, rel=e))  # fmt: skip
                raw = max(raw, abs(h2 / h3 - 1.0))
                if abs(e) > abs(err):
                    err, at = e, f"rho {c['rho']:g} alpha {a:g} y {yc:g}"
    stopped = {
        f"rho {s['rho']:g} alpha {a:g} level {s.get('mesh', '')}": float(ygrid[int(np.argmin(np.isfinite(s["h"][i])))])
        for s in fine + crs
        for i, a in enumerate(s["alpha"])
        if not np.all(np.isfinite(s["h"][i]))
    }
    meta = dict(
        quantity="h = F_eq / F_Hertz,series (reduced.indentation), y = d_1 / R_1 = 2 x share(rho) / r_1(rho)",
        scene="rigid frictionless sphere R_p = rho a0 on a Fung ball a0 resting on a rigid frictionless plate",
        mesh=mesh,
        coarse_mesh=coarse_mesh,
        richardson_order=None if h_c is None else order,
        check_mesh=check_mesh,
        contact="fitted",
        kappa_over_C=KAPPA / C_REF,
        radius=RADIUS,
        C=C_REF,
        y_max=float(y[-1]),
        x_max_per_rho={f"{r:g}": float(x_of_depth_ratio(y[-1], r)) for r in rhos},
        stopped=stopped,
        discretisation_error=abs(err),
        discretisation_error_at=at,
        fine_vs_check_level=raw,
        check_points=points,
        interpolation="natural cubic splines in s = sqrt(y), alpha and ln(rho)",
        wall_seconds=wall,
        command="python -m tissuemech.compare.calibrate_indentation " + " ".join(sys.argv[1:]),
    )
    table = dict(y=y, alpha=np.asarray(al), rho=np.asarray(rhos, float), h=h_tab, force=force, h_fine=h_f[:, :, :n_ok])
    if h_c is not None:
        table["h_coarse"] = h_c[:, :, :n_ok]
    return table, meta


def write(path: str | Path, table: dict, metadata: dict) -> None:
    """Write the table (``y``, ``alpha``, ``rho``, ``h``, ``force``) with JSON ``metadata`` to an npz file."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    arrays = {k: np.asarray(v) for k, v in table.items()}
    np.savez(path, **arrays, metadata=np.asarray(json.dumps(metadata)))  # type: ignore[arg-type]


def main(argv: Sequence[str] | None = None) -> int:
    """The command line: ``tissuemech calibrate-indentation`` (:mod:`tissuemech.compare.cli.calibrate_indentation`)."""
    from tissuemech.compare.cli.calibrate_indentation import main as cli_main

    return cli_main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
