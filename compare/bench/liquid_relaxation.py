"""The reduced viscoelastic liquid (``reduced.liquid.force``) against the FE liquid over a ramp and hold (issue 37).

``python -m tissuemech.compare.bench.liquid_relaxation [--level 1] [--approaches 0.2]`` (or ``tissuemech bench
liquid-relaxation``) compresses the S180 aggregate of ``compare.bench.fem_liquid`` (a0 = 175 um, gamma = 6 mN/m,
C_m = E0 / 6 = 167 Pa, tau = 1500 s from the flow viscosity 5e5 Pa s, alpha = 0.2) as an FE Maxwell liquid
(``fem.spheroid.compress(C=0, branches=[Branch(C_m, tau)], surface_tension=gamma)``) by delta (fraction of a0) in
1 s, holds to 1000 tau, and prints the relative error of the reduced liquid at the FE's output times: at the end of
the ramp, the largest over the hold before 10 tau (the flow the lumped branches leave out), and at the long-time
plateau (both against the exact drop too). ``main`` returns the rows (dicts) when called from Python.

``--modes 0.05,0.2,0.8`` characterises instead the FE liquid's slow mode, the shape's flow toward the drop that the
lumped branches leave out, at these elastocapillary numbers Gamma = gamma / (C_m a0) (C_m = gamma / (Gamma a0), the
same gamma and tau) and the ``--approaches``: the FE's and the reduced excess over the drop, F / F_drop - 1, at 3.6,
10 and 20 tau into the hold and the FE excess's local e-folding time -dt / d ln(excess) there (in tau; 120 hold
steps): the measurements a second lumped mode would be calibrated on.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

import numpy as np

from tissuemech.compare.bench.fem_liquid import LIQUID, N_HOLD, RADIUS, TAU
from tissuemech.fem.spheroid import compress
from tissuemech.reduced import drop, liquid

RAMP = 1.0  # s


def compare(approach: float, level: int = 1) -> dict[str, float]:
    """Relative errors reduced / FE - 1 at the end of the ramp (``ramp``), the largest |error| over the hold up to
    10 tau (``hold``, at ``hold_t`` s), the plateau (``plateau``), the FE's and the reduced plateau against the drop
    (``fe_drop``, ``reduced_drop``), the FE wall time (s) and the reduced one after compilation (s)."""
    t0 = time.perf_counter()
    r = compress(
        **LIQUID, displacement=approach * RADIUS, ramp_time=RAMP, end_time=1000 * TAU, mesh=level, n_hold=N_HOLD
    )
    fe_wall = time.perf_counter() - t0
    t, F = np.asarray(r.time), np.asarray(r.force)
    kw = dict(
        radius=RADIUS, alpha=LIQUID["alpha"], branches=LIQUID["branches"], surface_tension=LIQUID["surface_tension"]
    )
    red = np.asarray(liquid.force(t, displacement=approach * RADIUS, ramp_time=RAMP, **kw))  # type: ignore[arg-type]
    t0 = time.perf_counter()
    np.asarray(liquid.force(t, displacement=approach * RADIUS, ramp_time=RAMP, **kw))  # type: ignore[arg-type]
    red_wall = time.perf_counter() - t0
    err = red / F - 1.0
    iend = int(np.argmin(np.abs(t - RAMP)))
    hold = (t > RAMP) & (t <= 10 * TAU)
    k = int(np.argmax(np.where(hold, np.abs(err), -1.0)))
    Fd = drop.compress(approach * RADIUS, radius=RADIUS, surface_tension=float(LIQUID["surface_tension"])).force  # type: ignore[arg-type]
    return dict(
        approach=approach,
        ramp=float(err[iend]),
        hold=float(err[k]),
        hold_t=float(t[k]),
        plateau=float(err[-1]),
        fe_drop=float(F[-1] / Fd - 1),
        reduced_drop=float(red[-1] / Fd - 1),
        fe_wall=fe_wall,
        reduced_wall=red_wall,
    )


MODE_TIMES = (3.6, 10.0, 20.0)  # t / tau into the hold where --modes reports


def slow_mode(gamma_number: float, approach: float, level: int = 1) -> dict[str, float]:
    """The FE liquid's excess over the drop and its e-folding time at ``MODE_TIMES`` (see the module) for
    Gamma = gamma / (C_m a0) = ``gamma_number`` at total approach ``approach`` (fraction of a0)."""
    from tissuemech.fem.viscoelastic import Branch

    gamma = float(LIQUID["surface_tension"])  # type: ignore[arg-type]
    Cm = gamma / (gamma_number * RADIUS)
    kw = dict(radius=RADIUS, alpha=LIQUID["alpha"], surface_tension=gamma)
    t0 = time.perf_counter()
    r = compress(C=0.0, branches=[Branch(Cm, TAU)], displacement=approach * RADIUS, ramp_time=RAMP,
                 end_time=1000 * TAU, mesh=level, n_hold=120, **kw)  # type: ignore[arg-type]  # fmt: skip
    wall = time.perf_counter() - t0
    t, F = np.asarray(r.time), np.asarray(r.force)
    red = np.asarray(liquid.force(t, displacement=approach * RADIUS, ramp_time=RAMP, branches=[(Cm, TAU)], **kw))  # type: ignore[arg-type]
    Fd = drop.compress(approach * RADIUS, radius=RADIUS, surface_tension=gamma).force
    hold = t > RAMP
    th, ex, er = t[hold] / TAU, F[hold] / Fd - 1.0, red[hold] / Fd - 1.0
    efold = -np.gradient(th, np.log(np.maximum(np.abs(ex), 1e-300)))
    row: dict[str, float] = dict(Gamma=gamma_number, approach=approach, fe_wall=wall)
    for s in MODE_TIMES:
        i = int(np.argmin(np.abs(th - s)))
        row[f"fe_{s:g}"], row[f"red_{s:g}"], row[f"efold_{s:g}"] = float(ex[i]), float(er[i]), float(efold[i])
    return row


def main(argv: Sequence[str] | None = None) -> list[dict[str, float]]:
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench.liquid_relaxation", description=__doc__)
    ap.add_argument("--level", type=int, default=1, help="FE mesh level")
    ap.add_argument("--approaches", default="0.2", help="total approaches delta / a0 (<= 0.6)")
    ap.add_argument("--modes", default="", help="Gamma = gamma / (C_m a0) values: characterise the slow mode instead")
    a = ap.parse_args(argv)
    if a.modes:
        rows = [slow_mode(float(g), float(v), a.level) for g in a.modes.split(",") for v in a.approaches.split(",")]
        print(f"FE liquid's slow mode (level {a.level}, tau = {TAU:g} s): excess F / F_drop - 1 of the FE and of the "
              "reduced liquid, and the FE excess's e-folding time (tau), at t / tau into the hold")  # fmt: skip
        head = " ".join(f"{'FE ' + format(s, 'g'):>9} {'red ' + format(s, 'g'):>9} {'efold':>6}" for s in MODE_TIMES)
        print(f"{'Gamma':>6} {'delta/a0':>8} {head} {'FE s':>6}")
        for w in rows:
            cells = " ".join(
                f"{w[f'fe_{s:g}']:>9.2e} {w[f'red_{s:g}']:>9.2e} {w[f'efold_{s:g}']:>6.2f}" for s in MODE_TIMES
            )
            print(f"{w['Gamma']:>6g} {w['approach']:>8g} {cells} {w['fe_wall']:>6.1f}")
        return rows
    rows = [compare(float(v), a.level) for v in a.approaches.split(",")]
    print(f"reduced liquid / FE liquid - 1 (level {a.level}, ramp {RAMP:g} s, tau = {TAU:g} s)")
    print(f"{'delta/a0':>8} {'ramp end':>10} {'hold max':>10} {'at t/tau':>8} {'plateau':>10} {'FE-drop':>10} "
          f"{'red-drop':>10} {'FE s':>6} {'red s':>8}")  # fmt: skip
    for w in rows:
        print(
            f"{w['approach']:>8g} {w['ramp']:>+10.2e} {w['hold']:>+10.2e} {w['hold_t'] / TAU:>8.3g} {w['plateau']:>+10.2e} "
            f"{w['fe_drop']:>+10.2e} {w['reduced_drop']:>+10.2e} {w['fe_wall']:>6.1f} {w['reduced_wall']:>8.1e}"
        )
    return rows


if __name__ == "__main__":
    main()
    sys.exit(0)
