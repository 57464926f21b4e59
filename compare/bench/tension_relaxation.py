"""The reduced relaxation of a SOLID ball with a surface tension (``reduced.spheroid.force(..., surface_tension=)``)
against the FE over a ramp and hold (issue 37).

``python -m tissuemech.compare.bench.tension_relaxation [--mesh default] [--ramp 3]`` (or ``tissuemech bench
tension-relaxation``) compresses S180-like Fung balls (a0 = 175 um, C = 100-170 Pa, gamma = 3-6 mN/m: elastocapillary
numbers Gamma = gamma / (C a0) 0.1-0.34; one or two Maxwell branches) with ``fem.spheroid.compress(...,
surface_tension=gamma)``, holds to 10 times the longest tau, and prints the relative error reduced / FE - 1 at the
FE's output times: at the end of the ramp, at 0.3, 1 and 3 tau (the shortest) into the hold, the largest over the hold
(and when), and at the end, with the same case without the tension for the mesh's own error. ``main`` returns the rows.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from tissuemech.fem.spheroid import compress
from tissuemech.reduced import spheroid

RADIUS = 175e-6  # m

#: (C [Pa], alpha, gamma [N/m], x = delta / (2 a0), branches [(beta, tau [s])])
CASES: list[tuple[float, float, float, float, list[tuple[float, float]]]] = [
    (170.0, 0.35, 0.0, 0.13, [(1.5, 30.0)]),
    (170.0, 0.35, 6e-3, 0.13, [(1.5, 30.0)]),
    (170.0, 0.35, 3e-3, 0.13, [(1.5, 30.0)]),
    (170.0, 0.35, 6e-3, 0.13, [(0.3, 30.0)]),
    (170.0, 0.8, 15e-3, 0.22, [(0.7, 60.0)]),
    (100.0, 0.6, 6e-3, 0.18, [(0.8, 10.0), (0.5, 200.0)]),
]


def compare(
    C: float, alpha: float, gamma: float, x: float, branches: list[tuple[float, float]], ramp: float, mesh: Any
) -> dict[str, Any]:
    """Relative errors reduced / FE - 1 of one case (keys ``ramp``, ``t0.3``, ``t1``, ``t3``, ``worst``,
    ``worst_t`` (in units of the shortest tau), ``end``) and the FE wall time ``fe_wall`` (s)."""
    d = 2 * RADIUS * x
    tau = min(b[1] for b in branches)
    kw: dict[str, Any] = dict(radius=RADIUS, C=C, alpha=alpha, branches=branches, displacement=d, ramp_time=ramp)
    t0 = time.perf_counter()
    r = compress(end_time=10 * max(b[1] for b in branches), surface_tension=gamma, mesh=mesh, **kw)
    fe_wall = time.perf_counter() - t0
    t, F = np.asarray(r.time), np.asarray(r.force)
    hold = t >= ramp
    red = np.asarray(spheroid.force(t[hold], surface_tension=gamma, **kw))
    e = red / F[hold] - 1.0
    s = (t[hold] - ramp) / tau
    k = int(np.argmax(np.abs(e)))

    def at(v: float) -> float:
        return float(e[int(np.argmin(np.abs(s - v)))])

    return dict(
        C=C, alpha=alpha, gamma=gamma, Gamma=gamma / (C * RADIUS), x=x, branches=branches, ramp=float(e[0]),
        t0_3=at(0.3), t1=at(1.0), t3=at(3.0), worst=float(e[k]), worst_t=float(s[k]), end=float(e[-1]), fe_wall=fe_wall,
    )  # fmt: skip


def main(argv: Sequence[str] | None = None) -> list[dict[str, Any]]:
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench.tension_relaxation", description=__doc__)
    ap.add_argument("--mesh", default="default", help="FE mesh ('default' or a level)")
    ap.add_argument("--ramp", type=float, default=3.0, help="ramp time (s; the two-branch case 2/3 of it)")
    a = ap.parse_args(argv)
    mesh: Any = int(a.mesh) if a.mesh.isdigit() else a.mesh
    rows = []
    print(f"reduced / FE - 1, solid with surface tension (mesh {a.mesh}, ramp {a.ramp:g} s; t in the shortest tau)")
    print(f"{'C Pa':>5} {'alpha':>5} {'Gamma':>6} {'x':>5} {'branches (beta, tau s)':>24} {'ramp end':>9} "
          f"{'0.3 tau':>9} {'1 tau':>9} {'3 tau':>9} {'worst':>9} {'at':>5} {'end':>9} {'FE s':>5}")  # fmt: skip
    for C, alpha, gamma, x, br in CASES:
        ramp = a.ramp * (2 / 3 if len(br) > 1 else 1)
        w = compare(C, alpha, gamma, x, br, ramp, mesh)
        rows.append(w)
        brs = ", ".join(f"({b:g}, {tau:g})" for b, tau in br)
        print(
            f"{C:>5g} {alpha:>5g} {w['Gamma']:>6.3f} {x:>5g} {brs:>24} {w['ramp']:>+9.2e} {w['t0_3']:>+9.2e} "
            f"{w['t1']:>+9.2e} {w['t3']:>+9.2e} {w['worst']:>+9.2e} {w['worst_t']:>5.2f} {w['end']:>+9.2e} "
            f"{w['fe_wall']:>5.1f}",
            flush=True,
        )
    return rows


if __name__ == "__main__":
    main()
    sys.exit(0)
