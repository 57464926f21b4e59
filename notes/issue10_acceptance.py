"""Acceptance numbers of issue 10 (run: python notes/issue10_acceptance.py [jitter|table|fit|speed|ramp|push] ...).

jitter: RMS deviation of a 40-point static curve (alpha 0.2, x to 0.3, default mesh) from a smooth fit
        (polynomial of degree 6 in sqrt(x) of F / F_Hertz).
table:  shipped master curves vs the Richardson reference (JSON written by the bench reference, path arg 2).
fit:    noise-free and 0.5 %-noise fits of (C, alpha, beta, tau) to two-level default-mesh FE records.
speed:  default-mesh Fig. 10 run and static curve to 30 % (min of 3 after a warm-up).
ramp:   reduced/FE - 1 per step (ramp and hold) of the fit case's two FE records (mesh: optional arg, default 1).
push:   static compression to x = 0.79 (default mesh): which states used fitted / node-by-node contact.
references A.json B.json: two Richardson references row by row (B / A - 1 and both observed orders), e.g.
        notes/issue10_reference.json (levels 1-3) against notes/issue10_reference_l4.json (levels 1-4, so 2-4).
"""

import json
import sys
import time

import numpy as np

from tissuemech.fem.spheroid import compress, hertz_force

A0 = 500e-6


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


def table(path: str) -> None:
    from tissuemech.reduced import spheroid as sp

    mc = sp.master_curve()
    ref = json.load(open(path))
    worst = 0.0
    for name, v in ref.items():
        if not name.startswith("alpha"):
            continue
        a, x = float(name.split()[1]), float(name.split()[3])
        e = float(mc.f(x, a)) / v["reference"] - 1
        worst = max(worst, abs(e))
        print(f"table vs reference {name}: {e:+.2e}")
    print(f"table: max |f_table / f_ref - 1| = {worst:.2e}; metadata: {mc.metadata}")


def references(path_a: str, path_b: str) -> None:
    a, b = json.load(open(path_a)), json.load(open(path_b))
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


if __name__ == "__main__":
    what = sys.argv[1:] or ["jitter", "speed"]
    for w in what:
        if w == "jitter":
            jitter()
        elif w == "table":
            table(sys.argv[sys.argv.index("table") + 1])
        elif w == "fit":
            fit_case()
        elif w == "speed":
            speed()
        elif w == "ramp":
            i = sys.argv.index("ramp") + 1
            ramp(int(sys.argv[i]) if i < len(sys.argv) and sys.argv[i].isdigit() else 1)
        elif w == "push":
            push()
        elif w == "references":
            i = sys.argv.index("references")
            references(sys.argv[i + 1], sys.argv[i + 2])
