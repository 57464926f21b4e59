"""Verification of the FE indentation (fem.indentation.indent) against its small-strain and limiting laws.

Static states use fitted contact edges unless a line says "nodal".

``python -m tissuemech.compare.bench.fem_indentation [--quick]`` (or ``python -m tissuemech.compare.bench
fem-indentation``) prints, for a probe on a Fung ball resting on a plate (a0 = 100 um, C = 100 Pa, static states):

* refinement at x = approach / (2 a0) = 0.005, R_p = a0, alpha = 0: F / F_Hertz (the two Hertz contacts in series,
  ``reduced.indentation.equilibrium_force``) per mesh level with fitted contact edges (``contact="fitted"``), the
  change between levels, the observed order (h ~ 1 / n_zone) and the Richardson estimate; and with node-by-node
  contact (the default, which time runs use);
* the edge quantisation of the node-by-node contact (F / F_Hertz of the states of one run less a smooth trend);
* the Hertz limit: F / F_Hertz - 1 at x = 0.0005 ... 0.005 and (F / F_Hertz - 1) / sqrt(x): the finite-strain
  deviation grows like sqrt(x) (as the plates' does, ``reduced.spheroid``'s table: 2.25 % at x = 0.005), so the
  FE tends to the series law as x -> 0;
* the two-plate limit (R_p = 1000 a0: the probe is nearly a flat plate): F / F_Hertz against the converged plate
  table's F / F_Hertz (``reduced.spheroid``, FE-calibrated, 1.6e-5) at the same x;
* the half-space limit (R_p = a0 / 20): F / the series law, and F / the probe contact's own Hertz law with the
  probe-ball depth d_1 = approach - the ball centre's drop (the plate contact's share);
* alpha = 1 against alpha = 0 at x = 0.005 (small strain: alpha does not enter Hertz);
* one Maxwell branch (beta = 1, tau = 1 s) ramped in 0.01 s and held to 50 s: F at the end of the ramp / ((1 +
  beta) F_eq) and F(50 s) / F_eq on the same mesh.

``--quick``: levels 1..3 for the refinement (node-by-node contact on levels 1, 2 only) and level 1 elsewhere (about
3 minutes on a loaded shared core).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from scipy.optimize import brentq

from tissuemech.fem.indentation import LEVELS, indent
from tissuemech.reduced import indentation as ri
from tissuemech.reduced import spheroid

A0 = 100e-6
C = 100.0


def static_ratio(
    x: float, probe_radius: float, level: int, alpha: float = 0.0, n_static: int | None = None, contact="fitted"
):
    """(F / F_Hertz of the series law, the result, wall s) of a static indentation to x = approach / (2 a0)
    (fitted contact edges: the state itself; nodal: 3 states to it)."""
    t = time.perf_counter()
    n = n_static or (1 if contact == "fitted" else 3)
    r = indent(
        radius=A0, probe_radius=probe_radius, C=C, alpha=alpha, displacement=2 * A0 * x, static=True, mesh=level,
        n_static=n, contact=contact,
    )  # fmt: skip
    ref = float(ri.equilibrium_force(r.approach[-1], radius=A0, probe_radius=probe_radius, C=C, law="hertz"))
    return r.force[-1] / ref, r, time.perf_counter() - t


def observed_order(values, h) -> float:
    """The order p with (v1 - v2) / (v2 - v3) = (h1^p - h2^p) / (h2^p - h3^p) for the last three levels."""
    v1, v2, v3 = values[-3:]
    h1, h2, h3 = h[-3:]
    q = (v1 - v2) / (v2 - v3)
    if not np.isfinite(q) or q <= 0:
        return float("nan")
    f = lambda p: (h1**p - h2**p) / (h2**p - h3**p) - q
    try:
        return float(brentq(f, 0.05, 8.0))
    except ValueError:
        return float("nan")


def refinement(levels, nodal_max: int = 4) -> None:
    print("\n## Refinement at x = 0.005, R_p = a0, alpha = 0 (F_Hertz: two Hertz contacts in series)")
    print("level | n_zone | nodes | fitted edges: F / F_Hertz | change    | wall [s] | nodal contact: F / F_Hertz")
    vals, hs = [], []
    for lev in levels:
        q, r, w = static_ratio(0.005, A0, lev)
        qn = static_ratio(0.005, A0, lev, contact="nodal")[0] if lev <= nodal_max else float("nan")
        vals.append(q)
        hs.append(1.0 / LEVELS[lev][0])
        ch = f"{q - vals[-2]:+.2e}" if len(vals) > 1 else "         "
        print(
            f"{lev:5d} | {LEVELS[lev][0]:6d} | {r.mesh.n_nodes:5d} | {q:.6f}                  | {ch} | {w:8.0f} | {qn:.6f}"
        )
    if len(vals) >= 3:
        p = observed_order(vals, hs)
        if np.isfinite(p):
            rich = vals[-1] + (vals[-1] - vals[-2]) / ((hs[-2] / hs[-1]) ** p - 1)
            print(f"observed order {p:.2f} (last three levels); Richardson F / F_Hertz = {rich:.6f}")
        else:
            print(f"observed order: not monotone (edge quantisation); spread of the last three {np.ptp(vals[-3:]):.1e}")


def quantisation(level: int, n: int = 16) -> None:
    """The edge quantisation: F / F_Hertz over the states x = 0.0025 ... 0.005 of one static run less its smooth
    trend (a + b sqrt(x) + c x, least squares); node-by-node contact (one mesh, sized for x = 0.005) and fitted
    edges (a mesh per state)."""
    print(f"\n## Edge quantisation, level {level}: F / F_Hertz at the states x = 0.0025 ... 0.005 of one run")
    for contact in ("nodal", "fitted"):
        _, r, _ = static_ratio(0.005, A0, level, n_static=n, contact=contact)
        x = r.approach / (2 * A0)
        q = r.force / np.asarray(ri.equilibrium_force(r.approach, radius=A0, probe_radius=A0, C=C, law="hertz"))
        keep = x >= 0.0025 - 1e-12
        B = np.stack([np.ones(keep.sum()), np.sqrt(x[keep]), x[keep]], 1)
        resid = q[keep] - B @ np.linalg.lstsq(B, q[keep], rcond=None)[0]
        print(f"{contact:6s}: residual about a smooth trend: max {np.abs(resid).max():.1e}, rms "
              f"{np.sqrt(np.mean(resid**2)):.1e} ({keep.sum()} states)")  # fmt: skip


def hertz_limit(level: int) -> None:
    print(f"\n## Hertz limit, R_p = a0, alpha = 0, level {level}: the deviation grows like sqrt(x)")
    print("x       | F / F_Hertz - 1 | (F / F_Hertz - 1) / sqrt(x) | contact radius probe / plate [a0]")
    for x in (0.0005, 0.00125, 0.0025, 0.005):
        q, r, _ = static_ratio(x, A0, level)
        print(
            f"{x:.5f} | {q - 1:+.4e}     | {(q - 1) / np.sqrt(x):.4f}                      | "
            f"{r.contact_radius_probe[-1] / A0:.4f} / {r.contact_radius_plate[-1] / A0:.4f}"
        )


def plate_limit(level: int) -> None:
    x = 0.005
    q, r, _ = static_ratio(x, 1000 * A0, level)
    table = float(spheroid.equilibrium_force(r.approach[-1], radius=A0, C=C, alpha=0.0))
    qt = table / float(spheroid.hertz_force(r.approach[-1], radius=A0, C=C))
    print(f"\n## Two-plate limit (R_p = 1000 a0), x = {x}, level {level}")
    print(f"(F / F_Hertz) / (F_plate_table / F_Hertz,plates) = {q / qt:.6f}   (F / F_Hertz = {q:.6f}, the table's "
          f"{qt:.6f}; F / F_plate_table = {r.force[-1] / table:.6f}, the probe's curvature 1/(1000 a0) makes the "
          "Hertz force 2.5e-4 smaller)")  # fmt: skip


def half_space(level: int) -> None:
    rp = A0 / 20
    print(f"\n## Half-space limit (R_p = a0 / 20), level {level}")
    print("x       | d_1 / R_1 | F / F_series | F / F_probe(d_1 = approach - centre drop)")
    for x in (0.0005, 0.001):
        q, r, _ = static_ratio(x, rp, level)
        d1 = r.approach[-1] - r.centre_drop[-1]
        r1 = rp * A0 / (rp + A0)
        f1 = 32.0 / 3.0 * C * np.sqrt(r1) * d1**1.5
        print(f"{x:.5f} | {d1 / r1:.4f}    | {q:.6f}     | {r.force[-1] / f1:.6f}")


def stiffening(level: int) -> None:
    q0, _, _ = static_ratio(0.005, A0, level)
    q1, _, _ = static_ratio(0.005, A0, level, alpha=1.0)
    print(f"\n## alpha = 1 vs 0 at x = 0.005, level {level}: F(alpha = 1) / F(alpha = 0) = {q1 / q0:.6f}")


def relaxation(level: int) -> None:
    d = 2 * A0 * 0.005
    kw = dict(radius=A0, probe_radius=A0, C=C, alpha=0.0, displacement=d, mesh=level)
    st = indent(**kw, static=True, n_static=3)  # nodal, the same mesh as the time run
    r = indent(**kw, branches=[(1.0, 1.0)], ramp_time=0.01, end_time=50.0, n_ramp=4, n_hold=16)
    k = int(np.argmin(abs(r.time - 0.01)))
    F_eq = st.force[-1]
    print(f"\n## One branch (beta = 1, tau = 1 s), x = 0.005 in 0.01 s, held to 50 s, level {level}")
    print(f"F(0.01 s) / (2 F_eq) = {r.force[k] / (2 * F_eq):.5f}   (a linear law: (1 + beta g) / (1 + beta) = 0.9975)")
    print(f"F(50 s) / F_eq = {r.force[-1] / F_eq:.7f}   (exp(-50) left)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench.fem_indentation", description=__doc__)
    ap.add_argument("--quick", action="store_true", help="levels 1..3 for the refinement, level 1 elsewhere")
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    refinement((1, 2, 3) if a.quick else (1, 2, 3, 4), nodal_max=2 if a.quick else 4)
    lev = 1 if a.quick else 2
    hertz_limit(lev)
    quantisation(lev)
    plate_limit(lev)
    half_space(lev)
    stiffening(lev)
    relaxation(1)
    print(f"\n(total {time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
