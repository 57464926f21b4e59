"""Acceptance checks of the plate scene and the limits of the methods (scripts, not API).

    python -m tissuemech.compare.bench acceptance CHECK [CHECK ...]     (or: tissuemech bench acceptance ...)

jitter          RMS deviation of a 40-point static curve (alpha 0.2, x to 0.3, default mesh) from a smooth fit
                (polynomial of degree 6 in sqrt(x) of F / F_Hertz): the fitted contact edge leaves no jitter.
table           the shipped master curves against the Richardson reference of levels 1-4
                (tests/data/plate_reference_levels1-4.json, written by ``bench fem-spheroid reference --json``).
references      the two shipped Richardson references row by row (levels 1-3 against levels 1-4: B / A - 1
                and both observed orders).
fit             noise-free and 0.5 %-noise fits of (C, alpha, beta, tau) to two-level default-mesh FE records.
speed           default-mesh Fig. 10 run and static curve to 30 % (min of 3 after a warm-up).
ramp            reduced / FE - 1 per step (ramp and hold) of the fit case's two FE records (level 1).
push            static compression to x = 0.79 (default mesh): which states used fitted / node-by-node contact.
small-approach  FE force at delta = 1e-9 .. 1e-6 m (x = 1e-6 .. 1e-3) against the table (which tends to Hertz):
                the elements below the contact patch are not refined with it, so the force is too stiff far
                below the meshes' design range.
thick-shell     FE blastula inner stretch of thick walls (B/A = 1.5, 3, 10, 100) against the exact shell
                (the FE shell meshes are uniform through the wall).
fit-noise-free  one Fig. 10 level made by the FE on levels 1-3, fitted without noise and with 0.5 % noise:
                alpha's estimate and 95 % interval, which intervals contain the truth.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from tissuemech.compare import fit as fit_module
from tissuemech.fem import blastula as fb
from tissuemech.fem import spheroid as fs
from tissuemech.fem.spheroid import compress, hertz_force
from tissuemech.reduced import blastula as rb
from tissuemech.reduced import spheroid as rs

DATA = Path(__file__).resolve().parents[2] / "tests" / "data"
REFERENCE_3 = DATA / "plate_reference_levels1-3.json"
REFERENCE_4 = DATA / "plate_reference_levels1-4.json"

A0 = 500e-6

A, C_SHELL, ALPHA = 50e-6, 200.0, 0.2
TRUTH = dict(C=150.0, alpha=0.2, beta=0.4, tau=200.0)
KW = dict(radius=500e-6, C=150.0, alpha=0.2, branches=[(0.4, 200.0)], displacement=50e-6, ramp_time=0.2)


def jitter() -> None:
    r = compress(
        radius=A0,
        C=200.0,
        alpha=0.2,
        branches=(),
        displacement=2 * A0 * 0.3,
        ramp_time=1,
        end_time=1,
        static=True,
        n_static=40,
    )
    x = r.approach / (2 * A0)
    h = r.force / hertz_force(r.approach, A0, 200.0)
    V = np.stack([np.sqrt(x) ** k for k in range(7)], axis=1)
    fit = V @ np.linalg.lstsq(V, h, rcond=None)[0]
    print(
        f"jitter: 40 states x = {x[0]:.4f}..{x[-1]:.3f}: RMS |F/F_fit - 1| = {np.sqrt(np.mean((h / fit - 1) ** 2)):.2e}"
    )


def table(path: str | Path = REFERENCE_4) -> None:
    from tissuemech.reduced import spheroid as sp

    mc = sp.master_curve()
    ref = json.loads(Path(path).read_text())
    worst = 0.0
    for name, v in ref.items():
        if not name.startswith("alpha"):
            continue
        a, x = float(name.split()[1]), float(name.split()[3])
        e = float(mc.f(x, a)) / v["reference"] - 1
        worst = max(worst, abs(e))
        print(f"table vs reference {name}: {e:+.2e}")
    print(f"table: max |f_table / f_ref - 1| = {worst:.2e}; metadata: {mc.metadata}")


def references(path_a: str | Path = REFERENCE_3, path_b: str | Path = REFERENCE_4) -> None:
    a, b = json.loads(Path(path_a).read_text()), json.loads(Path(path_b).read_text())
    rows = [k for k in a if not k.startswith("_") and k in b]
    worst: dict[str, float] = {}
    for k in rows:
        d = b[k]["reference"] / a[k]["reference"] - 1
        print(f"{k:20s} B/A - 1 {d:+.2e}   order A {a[k]['order']:5.2f}   order B {b[k]['order']:5.2f}")
        band = (
            "x <= 0.01"
            if "x 0.0" in k and float(k.split()[-1]) <= 0.01
            else ("x = 0.02" if k.endswith("x 0.02") else "rest")
        )
        worst[band] = max(worst.get(band, 0.0), abs(d))
    print("largest |B/A - 1|: " + ", ".join(f"{band} {v:.2e}" for band, v in worst.items()))


def fit_case() -> None:
    from tissuemech.compare.fit import relaxation

    a0, C, alpha, beta, tau = 400e-6, 260.0, 0.3, 0.7, 120.0
    recs = []
    for d in (40e-6, 120e-6):
        r = compress(radius=a0, C=C, alpha=alpha, branches=[(beta, tau)], displacement=d, ramp_time=1.0, end_time=900.0)
        k = r.time > 0
        recs.append((r.time[k], r.nominal_stress[k], d))
    truth = dict(C=C, alpha=alpha, beta=beta, tau=tau)
    rng = np.random.default_rng(1)
    for noise in (0.0, 0.005):
        rr = [(t, s * (1 + noise * rng.standard_normal(s.size)), d) for t, s, d in recs]
        f = relaxation(rr, radius=a0, ramp_time=1.0)
        print(f"fit, noise {noise:.1%}:")
        for n in ("C", "alpha", "beta", "tau"):
            lo, hi = f.intervals[n]
            print(
                f"  {n:>5} {f.params[n]:10.5g} (true {truth[n]:g}, {f.params[n] / truth[n] - 1:+.2%}) "
                f"95% [{lo:.5g}, {hi:.5g}] {'contains' if lo <= truth[n] <= hi else 'EXCLUDES'} the truth"
            )


def speed() -> None:
    fig10 = dict(
        radius=A0, C=150.0, alpha=0.2, branches=[(0.4, 200.0)], displacement=50e-6, ramp_time=0.2, end_time=1500.0
    )
    st = dict(
        radius=A0, C=200.0, alpha=0.2, branches=(), ramp_time=1.0, end_time=1.0, static=True, displacement=2 * A0 * 0.3
    )
    compress(**fig10)
    a, b = [], []
    for _ in range(3):
        t = time.perf_counter()
        compress(**fig10)
        a.append(time.perf_counter() - t)
        t = time.perf_counter()
        compress(**st)
        b.append(time.perf_counter() - t)
    print(f"speed: Fig. 10 default mesh {min(a):.2f} s, static curve to 30 % {min(b):.2f} s (min of 3)")


def ramp(mesh: int = 1) -> None:
    from tissuemech.reduced import spheroid as sp

    a0, C, alpha, br = 400e-6, 260.0, 0.3, [(0.7, 120.0)]
    for d in (40e-6, 120e-6):
        r = compress(radius=a0, C=C, alpha=alpha, branches=br, displacement=d, ramp_time=1.0, end_time=900.0, mesh=mesh)
        k = r.time > 0
        red = np.asarray(
            sp.nominal_stress(r.time[k], radius=a0, C=C, alpha=alpha, branches=br, displacement=d, ramp_time=1.0)
        )
        rat = red / r.nominal_stress[k] - 1
        ramp_k = r.time[k] <= 1.0 + 1e-9
        print(f"ramp: mesh {mesh}, delta {d * 1e6:g} um, reduced/FE - 1 per step")
        print("  ramp:", " ".join(f"{v:+.2e}" for v in rat[ramp_k]))
        print("  hold:", " ".join(f"{v:+.2e}" for v in rat[~ramp_k]))
        print(f"  F(1 s) = {np.interp(1.0, r.time, r.force):.9e} N, F(900 s) = {r.force[-1]:.9e} N")


def push() -> None:
    r = compress(
        radius=A0, C=200.0, alpha=0.2, branches=(), displacement=2 * A0 * 0.79, ramp_time=1, end_time=1, static=True
    )
    x, mode = r.approach / (2 * A0), np.array(r.parameters["contact"])
    fit = x[mode == "fitted"]
    print(
        f"push: reached x = {x[-1]:.3f}; fitted contact for x <= {fit.max():.3f} ({fit.size} states), node-by-node "
        f"for x = {x[mode == 'nodal'].min():.3f}..{x[-1]:.3f}; force monotone: {bool(np.all(np.diff(r.force) > 0))}"
    )


def small_approach() -> None:
    print(f"{'delta [m]':>10} {'x':>8} {'coarse':>8} {'default':>8}   (F_FE / F_table)")
    for d in (1e-9, 1e-8, 1e-7, 1e-6):
        ref = float(rs.equilibrium_force(d, radius=A0, C=150.0, alpha=0.2))
        ratios = []
        for mesh in ("coarse", "default"):
            r = fs.compress(radius=A0, C=150.0, alpha=0.2, displacement=d, static=True, mesh=mesh, ramp_time=1.0,
                            end_time=1.0)  # fmt: skip
            ratios.append(float(r.force[-1]) / ref)
        print(f"{d:10.0e} {d / (2 * A0):8.0e} {ratios[0]:8.4f} {ratios[1]:8.4f}")


def thick_shell() -> None:
    print(f"{'B/A':>6} {'p [Pa]':>9} {'coarse':>9} {'default':>9} {'fine':>9}   (error of lambda_a - 1)")
    for ratio in (1.5, 3.0, 10.0, 100.0):
        geo = dict(inner_radius=A, outer_radius=ratio * A, C=C_SHELL, alpha=ALPHA)
        p = brentq(lambda q: float(rb.inner_stretch(q, **geo)) - 1.5, 1.0, 1e4)
        exact = float(rb.inner_stretch(p, **geo))
        errs = []
        for mesh in ("coarse", "default", "fine"):
            r = fb.inflate(**geo, pressures=[p / 4, p / 2, 3 * p / 4, p], mesh=mesh)
            errs.append((float(r.inner_stretch[-1]) - 1) / (exact - 1) - 1)
        print(f"{ratio:6g} {p:9.2f} " + " ".join(f"{e:9.2e}" for e in errs))


def fit_noise_free() -> None:
    print(
        f"{'FE level':>8} {'noise':>6} {'alpha':>9} {'95 % interval':>20} {'covers':>6} {'noise sd [Pa]':>13} {'success':>7}  covered"
    )
    for level in (1, 2, 3):
        run = fs.compress(**KW, end_time=1500.0, mesh=level)
        for noise in (0.0, 0.005):
            y = run.nominal_stress * (1 + noise * np.random.default_rng(1).standard_normal(run.time.size))
            res = fit_module.relaxation([(run.time, y, 50e-6)], radius=500e-6, ramp_time=0.2)
            lo, hi = res.intervals["alpha"]
            cov = [n for n, v in TRUTH.items() if res.intervals[n][0] <= v <= res.intervals[n][1]]
            print(
                f"{level:8d} {100 * noise:5.1f}% {res.params['alpha']:9.5f} {f'[{lo:.5g}, {hi:.5g}]':>20} "
                f"{str(lo <= 0.2 <= hi):>6} {res.noise[0]:13.3g} {str(res.success):>7}  {', '.join(cov) or 'none'}"
            )


CHECKS = {
    "jitter": jitter,
    "table": table,
    "references": references,
    "fit": fit_case,
    "speed": speed,
    "ramp": ramp,
    "push": push,
    "small-approach": small_approach,
    "thick-shell": thick_shell,
    "fit-noise-free": fit_noise_free,
}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="tissuemech bench acceptance", description=__doc__.split("\n")[0])
    ap.add_argument("checks", nargs="*", default=["jitter", "speed"], choices=list(CHECKS), metavar="CHECK")
    args = ap.parse_args(argv)
    for name in args.checks:
        print(f"== {name} ==")
        CHECKS[name]()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
