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

``--hertz`` prints instead the decomposition of F / F_Hertz - 1 (issue 36), finite strain against the FE's
geometrically linear mode (``indent(..., kinematics="small")``: linear strain, Hooke's law with the shear modulus
2 C, tr(eps) = q / kappa, the Hertz contact gap at the reference radius):

* refinement at x = 0.005, R_p = a0: F / F_Hertz per level for both kinematics, the observed order and the
  Richardson limits;
* x = 0.0005 ... 0.01: the Richardson limits (three levels) of both and their sqrt(x) coefficients, with the least
  squares fits q - 1 = b sqrt(x) + c x of the small-strain FE (the ball's finite size: Hertz assumes two
  half-spaces) and of finite - small strain (the finite strain);
* the half-space check at the same probe-contact depth ratio d_1 / R_1 as R_p = a0, x = 0.005 (R_p = a0 / 20): the
  probe contact's own Hertz law (d_1 = approach - the centre's drop) for both kinematics, and the finite-strain
  effect per a/R carried to the two contacts in series (each weighted by its share of the approach) against the
  finite - small difference measured at R_p = a0;
* the two-plate limit (R_p = 1000 a0) at x = 0.005 for both kinematics, and for both geometries the ball's extra
  compliance k in delta = delta_Hertz(F) - k F / (mu a0) (mu = 2 C) that the small-strain departure implies:
  F / F_Hertz - 1 = 8 k sqrt(2 R_s / a0) sqrt(x) to first order (R_s the series radius).

``--quick``: levels 1..3 for the refinement (node-by-node contact on levels 1, 2 only) and level 1 elsewhere (about
3 minutes on a loaded shared core). ``--hertz --quick``: levels 1..3 throughout (about 9 minutes on a loaded shared
core; without --quick: levels 0..4 for the refinement, 2..4 elsewhere).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from scipy.optimize import brentq

from tissuemech.fem.indentation import LEVELS, hertz_split, indent
from tissuemech.reduced import indentation as ri
from tissuemech.reduced import spheroid

A0 = 100e-6
C = 100.0


def static_ratio(
    x: float, probe_radius: float, level: int, alpha: float = 0.0, n_static: int | None = None, contact="fitted",
    kinematics: str = "finite",
):  # fmt: skip
    """(F / F_Hertz of the series law, the result, wall s) of a static indentation to x = approach / (2 a0)
    (fitted contact edges: the state itself; nodal: 3 states to it)."""
    t = time.perf_counter()
    n = n_static or (1 if contact == "fitted" else 3)
    r = indent(
        radius=A0, probe_radius=probe_radius, C=C, alpha=alpha, displacement=2 * A0 * x, static=True, mesh=level,
        n_static=n, contact=contact, kinematics=kinematics,
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


def richardson(values, levels) -> tuple[float, float]:
    """(Richardson limit, observed order) of the values on the mesh levels (h ~ 1 / n_zone, the last three);
    (the finest value, nan) when the changes are not monotone."""
    hs = [1.0 / LEVELS[lev][0] for lev in levels]
    p = observed_order(values, hs)
    if not np.isfinite(p):
        return float(values[-1]), float("nan")
    return float(values[-1] + (values[-1] - values[-2]) / ((hs[-2] / hs[-1]) ** p - 1)), p


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


def hertz_refinement(levels) -> dict[str, float]:
    """F / F_Hertz at x = 0.005, R_p = a0 per level, finite and small strain; returns their Richardson limits."""
    print("\n## Refinement at x = 0.005, R_p = a0, alpha = 0: finite strain and the geometrically linear FE")
    print("level | n_zone | finite strain: F / F_Hertz | small strain: F / F_Hertz | finite - small | wall [s]")
    vals: dict[str, list[float]] = {"finite": [], "small": []}
    for lev in levels:
        w = 0.0
        for kin in vals:
            q, _, wk = static_ratio(0.005, A0, lev, kinematics=kin)
            vals[kin].append(q)
            w += wk
        qf, qs = vals["finite"][-1], vals["small"][-1]
        print(f"{lev:5d} | {LEVELS[lev][0]:6d} | {qf:.6f}                   | {qs:.6f}                  | "
              f"{qf - qs:+.6f}      | {w:5.0f}")  # fmt: skip
    out = {}
    for kin, v in vals.items():
        lim, p = richardson(v, levels)
        out[kin] = lim
        print(f"{kin:6s} strain: observed order {p:.2f}, Richardson F / F_Hertz = {lim:.6f} "
              f"((F / F_Hertz - 1) / sqrt(x) = {(lim - 1) / np.sqrt(0.005):.4f})")  # fmt: skip
    return out


def hertz_sweep(levels, xs=(0.0005, 0.001, 0.002, 0.005, 0.01)) -> None:
    """Richardson limits of F / F_Hertz over x for both kinematics, and the sqrt(x) fits."""
    print(f"\n## F / F_Hertz over x = approach / (2 a0), R_p = a0, alpha = 0: Richardson limits of levels {levels}")
    print("x       | finite: q_f  | order | small: q_s   | order | (q_s - 1)/sqrt(x) | (q_f - q_s)/sqrt(x) | "
          "(q_f - 1)/sqrt(x)")  # fmt: skip
    rows = []
    for x in xs:
        lim = {}
        for kin in ("finite", "small"):
            v = [static_ratio(x, A0, lev, kinematics=kin)[0] for lev in levels]
            lim[kin] = richardson(v, levels)
        (qf, pf), (qs, ps) = lim["finite"], lim["small"]
        rx = np.sqrt(x)
        rows.append((x, qf, qs))
        print(f"{x:.5f} | {qf:.6f}     | {pf:5.2f} | {qs:.6f}     | {ps:5.2f} | {(qs - 1) / rx:.4f}            | "
              f"{(qf - qs) / rx:+.4f}             | {(qf - 1) / rx:.4f}")  # fmt: skip
    x, qf, qs = (np.array(c) for c in zip(*rows))
    B = np.stack([np.sqrt(x), x], 1)
    for name, y in (("small strain (finite size): q_s - 1", qs - 1), ("finite strain: q_f - q_s", qf - qs),
                    ("both: q_f - 1", qf - 1)):  # fmt: skip
        (b, c), *_ = np.linalg.lstsq(B, y, rcond=None)
        resid = np.abs(y - B @ np.array([b, c])).max()
        print(f"{name:40s} = {b:+.4f} sqrt(x) {c:+.4f} x   (max residual {resid:.1e})")


def hertz_half_space(levels, q_a0: dict[str, float] | None = None) -> None:
    """R_p = a0 / 20 at the probe-contact depth ratio d_1 / R_1 of R_p = a0, x = 0.005 (the same a/R at the probe)."""
    rp = 1.0 / 20
    d1a, d2a, a1a, a2a = hertz_split(0.01, 1.0)  # R_p = a0, x = 0.005 (lengths / a0)
    ratio = d1a / 0.5  # d_1 / R_1, R_1 = a0 / 2
    r1 = rp / (1 + rp)
    x = 0.5 * ratio * r1 / hertz_split(1.0, rp)[0]  # the approach whose d_1 / R_1 is ratio
    print(f"\n## Half-space check: R_p = a0 / 20 at x = {x:.3e}, the probe contact's d_1 / R_1 = {ratio:.5f} (as R_p = "
          f"a0 at x = 0.005; a_1 / R_1 = {np.sqrt(ratio):.4f}); levels {levels}")  # fmt: skip
    print("kinematics | F / F_probe(d_1 = approach - centre drop) per level | Richardson | order | F / F_series")
    lim = {}
    for kin in ("finite", "small"):
        v, qs = [], 0.0
        for lev in levels:
            qs, r, _ = static_ratio(x, rp * A0, lev, kinematics=kin)
            d1 = r.approach[-1] - r.centre_drop[-1]
            v.append(r.force[-1] / (32.0 / 3.0 * C * np.sqrt(r1 * A0) * d1**1.5))
        lim[kin], p = richardson(v, levels)
        print(f"{kin:10s} | {' '.join(f'{q:.6f}' for q in v):50s} | {lim[kin]:.6f}   | {p:5.2f} | {qs:.6f}")
    k = (lim["finite"] / lim["small"] - 1) / np.sqrt(ratio)
    w1, w2 = d1a / 0.01, d2a / 0.01
    pred = k * (w1 * a1a / 0.5 + w2 * a2a / 1.0)
    print(f"finite-strain effect of one contact: (q_finite / q_small - 1) = {k:+.4f} a/R; carried to R_p = a0, x = "
          f"0.005 (d_1 / delta = {w1:.3f} at a_1 / R_1 = {a1a / 0.5:.4f}, d_2 / delta = {w2:.3f} at a_2 / R_2 = "
          f"{a2a:.4f}): {pred:+.5f}")  # fmt: skip
    if q_a0 is not None:
        print(f"measured there: q_finite / q_small - 1 = {q_a0['finite'] / q_a0['small'] - 1:+.5f}")


def series_radius(rho: float) -> float:
    """R_s / a0 of the two Hertz contacts in series for R_p / a0 = rho (``fem.indentation.IndentProblem``)."""
    return ((rho / (1.0 + rho)) ** (-1.0 / 3.0) + 1.0) ** -3.0


def hertz_plates(levels, q_a0: dict[str, float], x: float = 0.005) -> None:
    """The two-plate limit for both kinematics and the ball's extra compliance k of both geometries."""
    rho = 1000.0
    print(f"\n## Two-plate limit (R_p = 1000 a0), x = {x}: Richardson limits of levels {levels}, and the ball's extra "
          "compliance k (delta = delta_Hertz(F) - k F / (mu a0), mu = 2 C) from the small-strain departure")  # fmt: skip
    lim = {}
    for kin in ("finite", "small"):
        v = [static_ratio(x, rho * A0, lev, kinematics=kin)[0] for lev in levels]
        lim[kin], p = richardson(v, levels)
        print(f"{kin:6s} strain: F / F_Hertz = {lim[kin]:.6f} (order {p:.2f}; (F / F_Hertz - 1) / sqrt(x) = "
              f"{(lim[kin] - 1) / np.sqrt(x):.4f})")  # fmt: skip
    for name, r, q in (("R_p = a0", 1.0, q_a0["small"]), ("R_p = 1000 a0", rho, lim["small"])):
        k = (q - 1) / (8 * np.sqrt(2 * series_radius(r)) * np.sqrt(x))
        print(f"{name:14s}: k = {k:.4f}")


def hertz(quick: bool) -> None:
    """The decomposition of F / F_Hertz - 1 (``--hertz``)."""
    levels = (1, 2, 3) if quick else (0, 1, 2, 3, 4)
    q = hertz_refinement(levels)
    hertz_sweep((1, 2, 3) if quick else (2, 3, 4))
    hertz_half_space((1, 2, 3) if quick else (2, 3, 4), q)
    hertz_plates((1, 2, 3) if quick else (2, 3, 4), q)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench.fem_indentation", description=__doc__)
    ap.add_argument("--quick", action="store_true", help="levels 1..3 for the refinement, level 1 elsewhere")
    ap.add_argument("--hertz", action="store_true", help="the decomposition of F / F_Hertz - 1: finite strain, size")
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    if a.hertz:
        hertz(a.quick)
        print(f"\n(total {time.perf_counter() - t0:.0f} s)")
        return 0
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
