"""The FE viscoelastic liquid's long-time state against the exact Young-Laplace drop (issue 37).

``python -m tissuemech.compare.bench.fem_liquid [--levels 0,1,2] [--approaches 0.1,0.2,0.4]`` (or ``tissuemech bench
fem-liquid``) compresses an S180 aggregate as a Maxwell liquid (``fem.spheroid.compress(C=0, branches=[Branch(C_m,
tau)])``: a0 = 175 um, gamma = 6 mN/m, instantaneous E0 = 6 C_m = 1 kPa, tau = 3 eta / E0 = 1500 s for the flow
viscosity eta = 5e5 Pa s, alpha = 0.2) by delta = 0.1, 0.2, 0.4 a0 in 1 s, holds the plates to 1000 tau (its stress
relaxed: the last two steps agree to ~1e-8), and prints the plate force F, the contact radius R3 and the midplane
radius R2 against ``reduced.drop.compress`` (the exact drop, 180 deg plates) per level of the contact-edge-fitted
meshes, with the observed order and the Richardson estimate (h ~ 1/n_core; ``compare.bench.fem_spheroid.richardson``)
of the three finest levels. Why the long-time state of a time run and not a static run with a vanishing C: a liquid
has no elastic state (its static tangent is singular: the surface nodes slide freely), while every hold step
regularises the shear by the branch's algorithmic modulus sum_m beta_m g_m ~ tau / dt; the fixed point of the Maxwell
recursion under held plates (Q_m -> 0) is the drop on the mesh, whatever the step sizes.

Measured (levels 0, 1, 2; docs/tension.md): F within 1e-4 of the drop from level 1 on at 10 / 20 / 40 %; the contact
radius R3 (the fitted edge node) converges more slowly (observed order 0.91 / 0.82 / 2.7), its Richardson estimates
+3.6e-5 / -9.5e-6 / -2.7e-5 off the drop, level 2 itself -1.4e-4 / -9.7e-5 / -3.1e-5.

``--quick``: level 1 at delta = 0.2 a0 only (a few seconds on an idle machine).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

import numpy as np

from tissuemech.compare.bench.fem_spheroid import richardson
from tissuemech.fem.spheroid import LEVELS, Branch, compress
from tissuemech.reduced import drop

RADIUS = 175e-6  # m, S180 aggregate
GAMMA = 6e-3  # N/m
E0 = 1e3  # Pa, instantaneous Young's modulus (E = 6 C)
VISCOSITY = 5e5  # Pa s
TAU = 3 * VISCOSITY / E0  # s (eta = E tau / 3)
LIQUID = dict(radius=RADIUS, C=0.0, alpha=0.2, branches=[Branch(E0 / 6, TAU)], surface_tension=GAMMA)
HOLD = 1000.0  # hold to this many tau
N_HOLD = 40
QUANTITIES = ("force", "contact_radius", "midplane_radius")


def liquid(level: int, approach: float, contact_angle: float = np.pi) -> tuple[dict[str, float], float, float]:
    """({F [N], R3 [m], R2 [m]} at the end of the hold, |F_end / F_before - 1|, wall [s]) on ``level`` for the total
    approach ``approach`` (as a fraction of a0), plates of ``contact_angle`` (rad)."""
    t0 = time.perf_counter()
    r = compress(
        **LIQUID,
        displacement=approach * RADIUS,
        ramp_time=1.0,
        end_time=HOLD * TAU,
        mesh=level,
        n_hold=N_HOLD,
        contact_angle=contact_angle,
    )
    out = {q: float(getattr(r, q)[-1]) for q in QUANTITIES}
    return out, abs(r.force[-1] / r.force[-2] - 1.0), time.perf_counter() - t0


def exact(approach: float, contact_angle: float = np.pi) -> dict[str, float]:
    """The drop's {F [N], R3 [m], R2 [m]} at the approach (fraction of a0), plates of ``contact_angle`` (rad)."""
    s = drop.compress(approach * RADIUS, radius=RADIUS, surface_tension=GAMMA, contact_angle=contact_angle)
    return {"force": s.force, "contact_radius": s.contact_radius, "midplane_radius": s.equatorial_radius}


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench.fem_liquid", description=__doc__)
    ap.add_argument("--levels", default="0,1,2", help="FE levels; the three finest give the Richardson estimate")
    ap.add_argument("--approaches", default="0.1,0.2,0.4", help="total approaches delta / a0")
    ap.add_argument("--quick", action="store_true", help="level 1 at delta = 0.2 a0 only")
    ap.add_argument("--contact-angle", type=float, default=180.0, help="the plates' contact angle (deg, 90 < . <= 180)")
    a = ap.parse_args(argv)
    theta = np.radians(a.contact_angle) if a.contact_angle != 180.0 else np.pi
    levels = [1] if a.quick else [int(v) for v in a.levels.split(",")]
    approaches = [0.2] if a.quick else [float(v) for v in a.approaches.split(",")]
    print(
        f"Maxwell liquid (C = 0, C_m = {E0 / 6:.4g} Pa, tau = {TAU:g} s, alpha = 0.2), a0 = {RADIUS * 1e6:g} um, gamma = "
        f"{GAMMA * 1e3:g} mN/m (gamma / (C_m a0) = {GAMMA / (E0 / 6 * RADIUS):.3f}), held to {HOLD:g} tau; "
        f"plates at {a.contact_angle:g} deg; relative errors against reduced.drop"
    )
    for x in approaches:
        ref = exact(x, theta)
        print(
            f"\n## delta = {x:g} a0: drop F = {ref['force'] * 1e6:.7g} uN, R3 = {ref['contact_radius'] / RADIUS:.7f} a0, "
            f"R2 = {ref['midplane_radius'] / RADIUS:.7f} a0"
        )
        print(f"{'level':>6} {'F err':>10} {'R3 err':>10} {'R2 err':>10} {'last step':>10} {'wall s':>8}")
        vals: dict[int, dict[str, float]] = {}
        for lev in levels:
            v, settle, wall = liquid(lev, x, theta)
            vals[lev] = v
            err = [v[q] / ref[q] - 1 for q in QUANTITIES]
            print(f"{lev:>6} " + " ".join(f"{e:>10.2e}" for e in err) + f" {settle:>10.1e} {wall:>8.1f}")
        if len(levels) >= 3:
            h = [1.0 / LEVELS[lev][0] for lev in levels[-3:]]
            row = []
            for q in QUANTITIES:
                p, est = richardson([vals[lev][q] for lev in levels[-3:]], h)
                row.append(f"{q}: p = {p:.2f}, Richardson {est / ref[q] - 1:+.2e}")
            print("  " + "; ".join(row))
    return 0


if __name__ == "__main__":
    sys.exit(main())
