"""The reduced relaxation of a SOLID ball with a surface tension (``reduced.spheroid.force(..., surface_tension=)``)
against the FE over a ramp and hold (issue 37).

``python -m tissuemech.compare.bench.tension_relaxation [--mesh default] [--ramp 3]`` (or ``tissuemech bench
tension-relaxation``) compresses S180-like Fung balls (a0 = 175 um, C = 100-170 Pa, gamma = 3-6 mN/m: elastocapillary
numbers Gamma = gamma / (C a0) 0.1-0.34; one or two Maxwell branches) with ``fem.spheroid.compress(...,
surface_tension=gamma)``, holds to 10 times the longest tau, and prints the relative error reduced / FE - 1 at the
FE's output times: at the end of the ramp, at 0.3, 1 and 3 tau (the shortest) into the hold, the largest over the hold
(and when), and at the end, with the same case without the tension for the mesh's own error. ``main`` returns the rows.

``--fits``: instead, the gamma fit (``compare.fit.tension.tension_relaxation``) of FE-made records (C = 170 Pa,
alpha = 0.5, gamma = 6 mN/m, one branch beta = 2, tau = 30 s; delta = 35, 70, 105 um in 1 s, held 300 s; FE level 1,
its 29 output times) given as the FE's nominal stress (its own deformed midplane: ``midplane="fem"``) and as force
files turned into stress by a0^2 / (1 - x) (``midplane="incompressible"``, what ``tissuemech fit`` does with force
files), noise-free and with 1 % noise (seeds 1, 2), alpha fixed and fitted: the estimate, its 95 % interval, the bias.
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


def fe_made_fits(level: int = 1, seeds: Sequence[int] = (1, 2)) -> list[dict[str, Any]]:
    """The ``--fits`` rows (module docstring): dicts with ``records``, ``noise``, ``seed``, ``alpha`` ("fixed" or
    "fitted"), ``gamma`` and ``low``, ``high`` (N/m), ``bias`` (gamma / truth - 1) and ``seconds``."""
    from tissuemech.compare.fit.tension import tension_relaxation

    C, alpha, gamma, branch, ramp = 170.0, 0.5, 6e-3, (2.0, 30.0), 1.0
    recs = []
    for x in (0.1, 0.2, 0.3):
        d = 2 * RADIUS * x
        r = compress(radius=RADIUS, C=C, alpha=alpha, branches=[branch], displacement=d, ramp_time=ramp,
                     end_time=300.0, surface_tension=gamma, mesh=level)  # fmt: skip
        t = np.asarray(r.time)
        k = t > 0
        xs = x * np.minimum(t[k] / ramp, 1.0)
        as_force = np.asarray(r.force)[k] / (np.pi * RADIUS**2 / (1 - xs))
        recs.append((t[k], np.asarray(r.nominal_stress)[k], d, as_force))
    rows = []
    for noise, seed in [(0.0, 0)] + [(0.01, int(s)) for s in seeds]:
        rng = np.random.default_rng(seed)
        z = [rng.standard_normal(rec[0].size) for rec in recs]
        for kind, col, mid in (("stress", 1, "fem"), ("force", 3, "incompressible")):
            data = [(rec[0], rec[col] + noise * rec[col].max() * zk, rec[2]) for rec, zk in zip(recs, z, strict=True)]
            for fixed in (True, False):
                t0 = time.perf_counter()
                fit = tension_relaxation(data, radius=RADIUS, ramp_time=ramp, alpha=alpha if fixed else None,
                                         midplane=mid)  # fmt: skip
                g = fit.params["gamma"]
                lo, hi = fit.intervals["gamma"]
                rows.append(dict(records=kind, noise=noise, seed=seed if noise else None,
                                 alpha="fixed" if fixed else "fitted", gamma=g, low=lo, high=hi, bias=g / gamma - 1,
                                 seconds=time.perf_counter() - t0))  # fmt: skip
    return rows


def main(argv: Sequence[str] | None = None) -> list[dict[str, Any]]:
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench.tension_relaxation", description=__doc__)
    ap.add_argument("--mesh", default="default", help="FE mesh ('default' or a level)")
    ap.add_argument("--ramp", type=float, default=3.0, help="ramp time (s; the two-branch case 2/3 of it)")
    ap.add_argument("--fits", action="store_true", help="the gamma fits of FE-made records instead")
    a = ap.parse_args(argv)
    if a.fits:
        fits = fe_made_fits(int(a.mesh) if a.mesh.isdigit() else 1)
        print("gamma fits of FE-made records (truth 6 mN/m; FE level 1), mN/m")
        for w in fits:
            print(f"{w['records']:>6} records, noise {100 * w['noise']:g} % (seed {w['seed']}), alpha {w['alpha']:>6}: "
                  f"{1e3 * w['gamma']:.4f} [{1e3 * w['low']:.3f}, {1e3 * w['high']:.3f}] ({w['bias']:+.2%}), "
                  f"{w['seconds']:.1f} s", flush=True)  # fmt: skip
        return fits
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
