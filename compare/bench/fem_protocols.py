"""Force control and measured histories of the FE spheroid against the reduced model (issue 34).

``python -m tissuemech.compare.bench.fem_protocols [--quick] [--levels 1,2,3]`` (or ``tissuemech bench
fem-protocols``) prints, for the Fig. 10 material (a0 = 500 um, C = 150 Pa, alpha = 0.2, one branch (0.4, 200 s)):

* creep: ``fem.spheroid.compress(force=F)`` (F = 6.8 uN ramped in 0.2 s, held to 1500 s, 160 hold steps: time error
  ~5e-6) against ``reduced.spheroid.approach`` (the lumped law solved for the approach, ``equilibrium="fem"``, the
  geometric coupling ``reduced.spheroid.COUPLING``; a second row: the plain lumped law, ``coupling=0``): the
  approach's relative error per level at t = 0.2, 10, 200, 1500 s and its largest value over every step after the
  ramp; then the reduced creep ODE's timing, coupled (default) and plain side by side;
* a measured history: ``compress(displacement=(times, approaches))`` with noise-free kinks and an unloading (0 ->
  50 um in 0.2 s, held to 20 s, unloaded to 30 um by 20.2 s, held to 100 s, reloaded to 45 um by 100.4 s, held to
  300 s; 3001 samples, the steps at its 6 kinks only) against ``reduced.spheroid.force(displacement=(times,
  approaches))``: the force's relative error, the same way;
* the converged reference: the FE values at those times on the three finest levels, Richardson-extrapolated with
  the observed order (``compare.bench.fem_spheroid.richardson``, h ~ 1/n_core), and each level's error against it.

``--quick``: the default level only against the reduced model (no Richardson), about a minute.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

import numpy as np

from tissuemech.compare.bench.fem_spheroid import richardson
from tissuemech.fem.spheroid import LEVELS, compress

MATERIAL = dict(radius=500e-6, C=150.0, alpha=0.2, branches=[(0.4, 200.0)])
CREEP = dict(force=6.8e-6, ramp_time=0.2, end_time=1500.0)
CREEP_HOLD = (
    160  # hold steps of the FE creep: its time error (2nd order) ~5e-6 of the approach (1.25e-4 at the default 40)
)
CREEP_TIMES = (0.2, 10.0, 200.0, 1500.0)
KINKS = np.array([[0.0, 0.0], [0.2, 50e-6], [20.0, 50e-6], [20.2, 30e-6], [100.0, 30e-6], [100.4, 45e-6]])
HISTORY_END = 300.0
HISTORY_TIMES = (0.2, 20.2, 100.4, 300.0)


def measured_history(n: int = 3001) -> tuple[np.ndarray, np.ndarray]:
    """(times s, approaches m): the kinked history sampled at n uniform times plus its kinks (noise-free)."""
    t = np.union1d(np.linspace(0.0, HISTORY_END, n), KINKS[:, 0])
    return t, np.interp(t, KINKS[:, 0], KINKS[:, 1])


def creep(level: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(step times s, FE approach m, wall s) of the force-controlled creep on ``level``."""
    t0 = time.perf_counter()
    r = compress(**MATERIAL, **CREEP, mesh=level, field_times=list(CREEP_TIMES), n_hold=CREEP_HOLD)
    return r.time, r.approach, time.perf_counter() - t0


def history(level: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(step times s, FE force N, wall s) of the measured history on ``level``."""
    t0 = time.perf_counter()
    r = compress(**MATERIAL, displacement=measured_history(), mesh=level, field_times=list(HISTORY_TIMES))
    return r.time, r.force, time.perf_counter() - t0


def reduced_creep(t: np.ndarray, coupling: float | str = "auto") -> np.ndarray:
    from tissuemech.reduced.spheroid import approach

    kw = dict(force=CREEP["force"], ramp_time=CREEP["ramp_time"], coupling=coupling)
    return np.asarray(approach(t, **MATERIAL, **kw))


def reduced_history(t: np.ndarray, coupling: float | str = "auto") -> np.ndarray:
    from tissuemech.reduced.spheroid import force

    return np.asarray(force(t, **MATERIAL, displacement=measured_history(), coupling=coupling))


OSC_MATERIAL = dict(radius=500e-6, C=150.0, alpha=0.2, branches=[(0.4, 1.0)])
OSC_APPROACH, OSC_AMPLITUDE, OSC_HOLD, OSC_PERIODS = 50e-6, 0.5e-6, 10.0, 3
OSC_FREQUENCIES = (0.05, 0.16, 0.5)  # Hz: omega tau = 0.31, 1.0, 3.1


def oscillation_record(f: float, n_per_period: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """(times s, approaches m): 50 um in 0.2 s, held 10 s (10 tau: relaxed), then 3 periods of 0.5 um at f Hz."""
    T = 1.0 / f
    ts = OSC_HOLD + np.linspace(0.0, OSC_PERIODS * T, OSC_PERIODS * n_per_period + 1)
    t = np.r_[0.0, 0.2, ts]
    d = np.r_[0.0, OSC_APPROACH, OSC_APPROACH + OSC_AMPLITUDE * np.sin(2 * np.pi * f * (ts - OSC_HOLD))]
    return t, d


def fe_dynamic_stiffness(level: int, f: float) -> tuple[float, float, float]:
    """(storage, loss in N/m, wall s): the FE force over the last two periods fitted by F0 + F1 (t - t0) +
    eps (K' sin + K'' cos) (least squares on the step times)."""
    t0 = time.perf_counter()
    r = compress(**OSC_MATERIAL, displacement=oscillation_record(f), mesh=level)
    k = r.time >= OSC_HOLD + (OSC_PERIODS - 2) / f - 1e-12
    tt = r.time[k] - OSC_HOLD
    w = 2 * np.pi * f
    A = np.stack([np.ones_like(tt), tt, np.sin(w * tt), np.cos(w * tt)], axis=1)
    c = np.linalg.lstsq(A, r.force[k], rcond=None)[0]
    return c[2] / OSC_AMPLITUDE, c[3] / OSC_AMPLITUDE, time.perf_counter() - t0


def oscillation(level: int) -> None:
    from tissuemech.reduced.oscillation import dynamic_stiffness

    print(
        f"\n## oscillation (branch (0.4, 1 s), 0.5 um about 50 um): FE (level {level}) / lumped - 1 of the storage and "
        "loss stiffness"
    )
    print("  f [Hz] | K' FE [N/m] |    K' lumped |  K' error | K'' FE [N/m] |  K'' lumped | K'' error | wall [s]")
    for f in OSC_FREQUENCIES:
        s_fe, l_fe, wall = fe_dynamic_stiffness(level, f)
        s_r, l_r = (float(v) for v in dynamic_stiffness(f, **OSC_MATERIAL, approach=OSC_APPROACH))
        print(
            f"{f:8.3g} | {s_fe:11.5g} | {s_r:11.5g} | {s_fe / s_r - 1:+.2e} | {l_fe:11.5g} | {l_r:11.5g} | "
            f"{l_fe / l_r - 1:+.2e} | {wall:6.1f}"
        )


def creep_timing(repeats: int = 20) -> None:
    """The reduced creep ODE (``reduced.spheroid.approach``, 202 output times to 1500 s) with the default coupling and
    with the plain law: the fastest of ``repeats`` calls after a first (compiling) one, side by side (printed only)."""
    print("\n## reduced creep ODE (approach, 202 times to 1500 s): fastest of 20 runs after compiling [s]")
    t = np.union1d(np.linspace(0.0, CREEP["end_time"], 201), [CREEP["ramp_time"]])
    best = {}
    for name, coupling in (("plain (p = 0)", 0.0), ("coupled (default)", "auto")):
        reduced_creep(t, coupling)
        best[name] = np.inf
        for _ in range(repeats):
            t0 = time.perf_counter()
            reduced_creep(t, coupling)
            best[name] = min(best[name], time.perf_counter() - t0)
        print(f"{name:<28} | {best[name]:.4f}")
    plain, coupled = best.values()
    print(f"{'ratio coupled / plain':<28} | {coupled / plain:.2f}")


def at(t: np.ndarray, v: np.ndarray, times: Sequence[float]) -> np.ndarray:
    """The values at the step times closest to ``times`` (they are step times: field_times)."""
    return np.array([v[int(np.argmin(np.abs(t - s)))] for s in times])


def _row(name: str, err: np.ndarray, worst: float, wall: float) -> str:
    return f"{name:<28} | " + " | ".join(f"{e:+.2e}" for e in err) + f" | {worst:.2e} | {wall:6.1f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench.fem_protocols", description=__doc__)
    ap.add_argument("--levels", default="1,2,3", help="FE levels; the three finest give the Richardson reference")
    ap.add_argument("--quick", action="store_true", help="the default level (1) against the reduced model only")
    ap.add_argument("--oscillation", action="store_true", help="with --quick: the oscillation rows too (level 1)")
    a = ap.parse_args(argv)
    levels = [1] if a.quick else [int(v) for v in a.levels.split(",")]
    if not a.quick and len(levels) < 3:
        print("error: --levels needs at least three levels for the Richardson reference", file=sys.stderr)
        return 2
    runs = {}
    for name, run, red, times in (
        ("creep: approach", creep, reduced_creep, CREEP_TIMES),
        ("history: force", history, reduced_history, HISTORY_TIMES),
    ):
        print(
            f"\n## {name}, FE / reduced - 1 at t = {', '.join(f'{v:g}' for v in times)} s | largest after the ramp "
            "| wall [s]"
        )
        vals = {}
        for lev in levels:
            t, v, wall = run(lev)
            r = red(t)
            after = t >= 0.2 - 1e-12
            vals[lev] = at(t, v, times)
            print(
                _row(
                    f"level {lev} ({t.size} steps)",
                    at(t, v / r - 1.0, times),
                    float(np.max(np.abs(v / r - 1)[after])),
                    wall,
                )
            )
            r0 = red(t, 0.0)  # the plain lumped law (no geometric coupling), for comparison
            print(
                _row("  plain lumped (p = 0)", at(t, v / r0 - 1.0, times), float(np.max(np.abs(v / r0 - 1)[after])), 0)
            )
        runs[name] = (vals, red(np.array(times)), times)
    creep_timing()
    if a.oscillation or not a.quick:
        oscillation(1)
    if a.quick:
        return 0
    h = [1.0 / LEVELS[lev][0] for lev in levels[-3:]]
    for name, (vals, r, times) in runs.items():
        est = [richardson([vals[lev][k] for lev in levels[-3:]], h) for k in range(len(times))]
        p = np.array([e[0] for e in est])
        ref = np.array([e[1] for e in est])
        print(f"\n## {name}: converged reference (Richardson over levels {levels[-3:]}); errors value / ref - 1")
        print(f"{'observed order p':<28} | " + " | ".join(f"{v:9.2f}" for v in p))
        for lev in levels:
            print(f"{'level ' + str(lev):<28} | " + " | ".join(f"{e:+.2e}" for e in vals[lev] / ref - 1.0))
        print(f"{'reduced':<28} | " + " | ".join(f"{e:+.2e}" for e in r / ref - 1.0))
    return 0


if __name__ == "__main__":
    sys.exit(main())
