"""Benchmark of the FE spheroid (fem.spheroid.compress): speed, mesh convergence, Hertz limit, relaxation.

``python -m tissuemech.compare.bench fem-spheroid [--quick] [--figure PATH.png]`` prints:
the seed's Fig. 10 run (C = 150 Pa, alpha = 0.2, beta = 0.4, tau = 200 s, 50 um in 0.2 s, held to
1500 s) on the default mesh: wall time (imports and a warm-up run excluded; min of repeats), steps,
Newton iterations per step, force error vs the fine meshes; the fitted relaxation time; F(1500 s) vs
the static F_eq(50 um) corrected for the branch stress left at 1500 s; contact vs reaction force; the
static curve to 30 % (and 40 %) compression; the Hertz ratio at small approach on a pole-refined mesh;
the mesh-convergence table of F at t = 0.2 s and 1500 s; the converged reference (``reference``: static
F_eq at x = delta/(2 a0) in XS for alpha 0, 0.2, 1 and the Fig. 10 force at 0.2 s and 1500 s on levels
1..4, observed order from the three finest, Richardson estimate, each level's error against it); the
Figs 8-9 case. Baselines (FElupe, from the issue): Fig. 10 run 47 s, static curve to 30 % 15 s. The machine
is shared: timings are pessimistic. ``--reference`` prints only the reference table (``--quick``: levels 1..3).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence

import numpy as np
from scipy.optimize import brentq, curve_fit

from tissuemech.fem.mesh import ball_section
from tissuemech.fem.spheroid import LEVELS, compress, hertz_force

A0 = 500e-6
FIG10 = dict(radius=A0, C=150.0, alpha=0.2, branches=[(0.4, 200.0)], displacement=50e-6, ramp_time=0.2, end_time=1500.0)
FIG89 = dict(
    radius=A0, C=200.0, alpha=0.2, branches=[(1.2, 200.0)], displacement=200e-6, ramp_time=0.2, end_time=1500.0
)


def _timed(**kw):
    t = time.perf_counter()
    r = compress(**kw)
    return r, time.perf_counter() - t


def fit_tau(r, ramp_time: float = 0.2):
    """Least-squares fit F(t) = F_inf + A exp(-(t - t_r)/tau) over the hold steps: (tau, F_inf, A)."""
    hold = r.time > ramp_time * (1 + 1e-9)
    t, F = r.time[hold], r.force[hold]
    (Finf, amp, tau), _ = curve_fit(
        lambda t, a, b, c: a + b * np.exp(-(t - ramp_time) / c),
        t,
        F,
        p0=(F[-1], F[0] - F[-1], 0.5 * (t[-1] - t[0]) / 3),
    )
    return tau, Finf, amp


def fig10(quick: bool) -> None:
    print("\n## Fig. 10 case: C = 150 Pa, alpha = 0.2, beta = 0.4, tau = 200 s, delta = 50 um in 0.2 s, held to 1500 s")
    compress(**FIG10)  # warm-up
    times, r = [], None
    for _ in range(2 if quick else 3):
        r, w = _timed(**FIG10)
        times.append(w)
    n = len(r.time)
    print(
        f"default mesh {LEVELS[1]} (n_core, n_radial, grading, n_contact; fitted to the contact edge), "
        f"{r.mesh.mesh.nelements} Q2 elements"
    )
    print(
        f"wall time min {min(times):.3f} s, median {np.median(times):.3f} s ({len(times)} runs; FElupe baseline 47 s)"
    )
    its = r.newton_iterations
    ramp = r.time <= 0.2 + 1e-12
    print(
        f"steps {n} ({ramp.sum()} ramp + {n - ramp.sum()} hold); Newton iterations {its.sum()} in total, "
        f"{its.mean():.2f}/step (ramp {its[ramp].mean():.2f}, hold {its[~ramp].mean():.2f}); "
        f"active-set passes/step max {r.contact_passes.max()}"
    )
    rel = np.abs(r.force - r.reaction_force) / r.force
    print(
        f"max |F_contact - F_reaction| / F = {rel.max():.1e}; min gap {r.min_gap.min():.1e} m; "
        f"min nodal contact force / F {np.min(r.min_contact_force / r.force):.1e} (over all steps)"
    )
    fines = {}
    for lev in [2] if quick else [2, 3]:
        fines[lev], w = _timed(**FIG10, mesh=lev)
        f = fines[lev]
        e = [abs(np.interp(t, r.time, r.force) / np.interp(t, f.time, f.force) - 1) for t in (0.2, 1500.0)]
        print(
            f"force error of the default mesh vs level {lev} ({f.mesh.mesh.nelements} el., {w:.1f} s): "
            f"t = 0.2 s {e[0]:.2e}, t = 1500 s {e[1]:.2e}, max over all steps "
            f"{np.max(np.abs(r.force / np.interp(r.time, f.time, f.force) - 1)):.2e}"
        )
    for name, rr in [("default", r)] + [(f"level {k}", v) for k, v in fines.items()]:
        tau, Finf, amp = fit_tau(rr)
        st = compress(
            radius=A0,
            C=150.0,
            alpha=0.2,
            branches=(),
            displacement=50e-6,
            ramp_time=1,
            end_time=1,
            static=True,
            n_static=5,
            mesh=rr.mesh,
        )
        Feq = st.force[-1]
        k_ramp = 200.0 / 0.2 * (1 - np.exp(-0.2 / 200.0))
        pred = Feq * (1 + 0.4 * k_ramp * np.exp(-(1500.0 - 0.2) / 200.0))
        print(
            f"{name:>8}: fitted tau = {tau:.3f} s (error {tau / 200 - 1:+.2e}); F_inf fit {Finf * 1e6:.5f} uN vs "
            f"static F_eq {Feq * 1e6:.5f} uN ({Finf / Feq - 1:+.1e}); F(1500 s) = {rr.force[-1] * 1e6:.5f} uN vs "
            f"F_eq (1 + beta e^(-1500/200)) = {pred * 1e6:.5f} uN ({rr.force[-1] / pred - 1:+.1e}); "
            f"F(0.2 s) / ((1 + beta) F_eq) - 1 = {rr.force[rr.time == 0.2][0] / (1.4 * Feq) - 1:+.1e}; "
            f"contact radius {rr.contact_radius[-1] * 1e6:.1f} um (sqrt(a0 delta/2) = 111.8 um)"
        )


def static_curve(quick: bool) -> None:
    print("\n## Static elastic compression (C = 200 Pa, alpha = 0.2), default mesh; FElupe baseline to 30 %: 15 s")
    kw = dict(radius=A0, C=200.0, alpha=0.2, branches=(), ramp_time=1.0, end_time=1.0, static=True)
    compress(**kw, displacement=2 * A0 * 0.3)  # warm-up
    for x in (0.3, 0.4):
        r, w = _timed(**kw, displacement=2 * A0 * x)
        print(
            f"to {x:.0%} of the diameter: {w:.3f} s, {len(r.time)} steps, {r.newton_iterations.sum()} Newton its "
            f"({r.newton_iterations.mean():.2f}/step), max active-set passes {r.contact_passes.max()}, "
            f"max |F_c - F_r|/F {np.max(np.abs(r.force - r.reaction_force) / r.force):.1e}"
        )
    f, w = _timed(**kw, displacement=2 * A0 * 0.3, mesh=2)
    r3 = compress(**kw, displacement=2 * A0 * 0.3)
    e = np.abs(r3.force / f.force - 1)
    print(
        f"default vs level 2 ({f.mesh.mesh.nelements} el., {w:.1f} s) on the 30 % curve: max |F/F_fine - 1| = "
        f"{e.max():.2e} (rms {np.sqrt(np.mean(e**2)):.2e}); for delta/2a0 <= 0.05 {e[r3.approach <= 0.1 * A0 * 1.0001].max():.2e}"
    )
    print(
        f"{'delta/2a0':>9} {'delta um':>9} {'F uN':>10} {'F/F_Hertz':>9} {'r_mid um':>9} {'a_c um':>8} {'sigma~ Pa':>9}"
    )
    for k in range(0, len(r.time), 2 if len(r.time) > 12 else 1):
        print(
            f"{r.approach[k] / (2 * A0):9.3f} {r.approach[k] * 1e6:9.2f} {r.force[k] * 1e6:10.4f} "
            f"{r.force[k] / hertz_force(r.approach[k], A0, 200.0):9.4f} {r.midplane_radius[k] * 1e6:9.2f} "
            f"{r.contact_radius[k] * 1e6:8.2f} {r.nominal_stress[k]:9.3f}"
        )


def hertz(quick: bool) -> None:
    print(
        "\n## Hertz limit (neo-Hookean alpha = 0, C = 200 Pa): F / F_Hertz and a_c / sqrt(a0 delta/2) "
        "(a_c = outermost node in contact), pole-refined meshes"
    )
    meshes = [(12, 8, 3.0, 20.0)] if quick else [(12, 8, 3.0, 20.0), (16, 10, 3.0, 30.0), (16, 10, 4.0, 60.0)]
    for spec in meshes:
        m = ball_section(A0, spec[0], spec[1], grading=spec[2], pole_grading=spec[3])
        r, w = _timed(
            radius=A0,
            C=200.0,
            alpha=0.0,
            branches=(),
            displacement=2 * A0 * 0.004,
            ramp_time=1.0,
            end_time=1.0,
            mesh=m,
            static=True,
            n_static=8,
        )
        x = r.approach / (2 * A0)
        print(f"ball_section(n_core, n_radial, grading, pole_grading) = {spec}, {m.mesh.nelements} el., {w:.2f} s")
        print("  delta/2a0 " + " ".join(f"{v:7.4f}" for v in x))
        print("  F/F_H     " + " ".join(f"{v:7.4f}" for v in r.force / hertz_force(r.approach, A0, 200.0)))
        print("  a_c/a_H   " + " ".join(f"{v:7.3f}" for v in r.contact_radius / np.sqrt(A0 * r.approach / 2)))


def convergence(quick: bool) -> None:
    print("\n## Mesh convergence, Fig. 10 case: F (uN) at t = 0.2 s and 1500 s")
    print(
        f"{'level':>5} {'elements':>8} {'F(0.2 s)':>10} {'F(1500 s)':>10} {'rel. to finest':>15} {'wall s':>7} {'its':>5}"
    )
    levels = [0, 1, 2] if quick else [0, 1, 2, 3]
    res = {lev: _timed(**FIG10, mesh=lev) for lev in levels}
    fin = res[levels[-1]][0]
    for lev in levels:
        r, w = res[lev]
        a, b = np.interp(0.2, r.time, r.force), r.force[-1]
        e = max(abs(a / np.interp(0.2, fin.time, fin.force) - 1), abs(b / fin.force[-1] - 1))
        print(
            f"{lev:5d} {r.mesh.mesh.nelements:8d} {a * 1e6:10.5f} {b * 1e6:10.5f} {e:15.2e} {w:7.2f} "
            f"{r.newton_iterations.sum():5d}"
        )


XS = (0.005, 0.01, 0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.35)
REF_ALPHAS = (0.0, 0.2, 1.0)


def static_force(x: float, alpha: float, level, C: float = 200.0) -> float:
    """F_eq / (C a0^2) at x = delta/(2 a0): one static run on a fitted level (steps <= 0.05 in x)."""
    r = compress(
        radius=A0,
        C=C,
        alpha=alpha,
        branches=(),
        displacement=2 * A0 * x,
        ramp_time=1.0,
        end_time=1.0,
        static=True,
        mesh=level,
        n_static=max(2, int(np.ceil(x / 0.05 - 1e-9))),
    )
    return float(r.force[-1] / (C * A0**2))


def richardson(values: Sequence[float], h: Sequence[float]) -> tuple[float, float]:
    """(observed order p, extrapolated value) from the three finest levels (h decreasing, any ratios).

    p solves (v2 - v1) / (v3 - v2) = (h1^p - h2^p) / (h2^p - h3^p); the estimate is
    v3 + (v3 - v2) / ((h2 / h3)^p - 1). A non-monotone triple (no asymptotic range) gives p = nan and
    returns the finest value."""
    v1, v2, v3 = (float(v) for v in values[-3:])
    h1, h2, h3 = (float(v) for v in h[-3:])
    d1, d2 = v2 - v1, v3 - v2
    if d2 == 0:
        return np.inf, v3
    q = d1 / d2
    if not q > 0:
        return np.nan, v3
    g = lambda p: (h1**p - h2**p) / (h2**p - h3**p) - q
    try:
        p = brentq(g, 0.05, 12.0)
    except ValueError:
        return np.nan, v3
    return p, v3 + d2 / ((h2 / h3) ** p - 1.0)


def reference(quick: bool, levels: Sequence[int] | None = None, alphas: Sequence[float] = REF_ALPHAS) -> dict:
    """The converged reference: level sequence, observed order, Richardson estimate, errors per level."""
    levels = list(levels or ((1, 2, 3) if quick else (1, 2, 3, 4)))
    h = [1.0 / LEVELS[lev][0] for lev in levels]
    print(
        f"\n## Converged reference: levels {levels} (h ~ 1/n_core = {', '.join(f'1/{LEVELS[v][0]}' for v in levels)}), "
        "observed order p from the three finest, Richardson estimate F_inf; errors F_level / F_inf - 1"
    )
    head = f"{'case':>22} " + " ".join(f"{'lev ' + str(v):>10}" for v in levels) + f" {'p':>6} {'F_inf':>14}"
    print(head)
    out = {}
    rows = [(f"alpha {a:g} x {x:g}", (lambda lev, a=a, x=x: static_force(x, a, lev))) for a in alphas for x in XS]
    fig = {}

    def fig10_at(lev, k):
        if lev not in fig:
            r = compress(**FIG10, mesh=lev)
            fig[lev] = (np.interp(0.2, r.time, r.force), r.force[-1])
        return fig[lev][k] / (150.0 * A0**2)

    rows += [("Fig. 10 F(0.2 s)", lambda lev: fig10_at(lev, 0)), ("Fig. 10 F(1500 s)", lambda lev: fig10_at(lev, 1))]
    for name, fn in rows:
        v = [fn(lev) for lev in levels]
        p, finf = richardson(v, h)
        out[name] = dict(values=v, order=p, reference=finf)
        print(f"{name:>22} " + " ".join(f"{vi / finf - 1:+10.2e}" for vi in v) + f" {p:6.2f} {finf:14.9f}", flush=True)
    return out


def write_reference(path: str, out: dict, quick: bool) -> None:
    """Write the reference table ``out`` of :func:`reference` as JSON: per row the levels, the values
    (f = F / (C a0^2)), the errors F_level / F_inf - 1, the observed order and the Richardson estimate."""
    import datetime
    import json

    from tissuemech.fem.spheroid import EDGE_TOL

    levels = [1, 2, 3] if quick else [1, 2, 3, 4]
    doc: dict = {
        "_about": (
            f"Richardson-extrapolated f = F/(C a0^2) from fem.spheroid fitted levels {levels} (errors = F_level / F_inf"
            " - 1; static rows: C = 200 Pa, the Fig. 10 rows: C = 150 Pa, a0 = 500 um, time runs on per-step fitted"
            f" meshes), contact-edge tolerance EDGE_TOL = {EDGE_TOL:g}; written by python -m tissuemech.compare.bench"
            f" fem-spheroid --reference{' --quick' if quick else ''} --json {path} on"
            f" {datetime.date.today().isoformat()}"
        )
    }
    for name, row in out.items():
        v, finf = [float(x) for x in row["values"]], float(row["reference"])
        doc[name] = dict(
            levels=levels, errors=[x / finf - 1.0 for x in v], order=float(row["order"]), reference=finf, values=v
        )
    with open(path, "w") as fh:
        json.dump(doc, fh, indent=1)
        fh.write("\n")
    print(f"\nwrote {path}")


def fig89() -> None:
    print(
        "\n## Figs 8-9 case: C = 200 Pa, alpha = 0.2, beta = 1.2, tau = 200 s, delta = 200 um in 0.2 s, held to 1500 s"
    )
    r, w = _timed(**FIG89, field_times=[0.2, 1497.0])
    print(
        f"default mesh: {w:.2f} s, {len(r.time)} steps, {r.newton_iterations.sum()} Newton its "
        f"({r.newton_iterations.mean():.2f}/step); max |F_c - F_r|/F {np.max(np.abs(r.force - r.reaction_force) / r.force):.1e}"
    )
    tau = fit_tau(r)[0]
    for t in (0.2, 1497.0, 1500.0):
        k = int(np.argmin(np.abs(r.time - t)))
        print(
            f"t = {r.time[k]:7.1f} s: F = {r.force[k] * 1e6:9.4f} uN, sigma~ = {r.nominal_stress[k]:8.3f} Pa, "
            f"mean von Mises = {r.mean_von_mises[k]:8.3f} Pa, r_mid = {r.midplane_radius[k] * 1e6:7.2f} um, "
            f"a_c = {r.contact_radius[k] * 1e6:6.1f} um"
        )
    print(f"fitted force relaxation time {tau:.2f} s (tau = 200 s)")
    return r


def figure(path: str, r) -> None:
    """Seed Fig. 8 (von Mises at 0.2 s and 1497 s) and Figs 9-10 curves, Figs 8-9 case; VTU next to it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(11, 9))
    r.plot_von_mises(0.2, ax=ax[0, 0])
    r.plot_von_mises(1497.0, ax=ax[0, 1])
    r.plot_relaxation(axes=ax[1])
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    base = path.rsplit(".", 1)[0]
    r.to_vtu(base + "_t0.2.vtu", time=0.2)
    r.to_vtu(base + "_t1497.vtu", time=1497.0)
    print(f"\nwrote {path} and {base}_t0.2.vtu, {base}_t1497.vtu")


def main(argv: list[str] | None = None) -> int:
    """Options: --quick (fewer meshes/repeats), --figure PATH.png (seed Figs 8-9 + VTU), --reference (only
    the reference table) with --json PATH (also write it, the format of tests/data/plate_reference_levels1-4.json)."""
    argv = list(argv or [])
    quick = "--quick" in argv
    json_path = None
    if "--json" in argv:
        i = argv.index("--json") + 1
        if "--reference" not in argv or i >= len(argv) or argv[i].startswith("--"):
            print("fem-spheroid: --json PATH (a file name) goes with --reference", file=sys.stderr)
            return 2
        json_path = argv[i]
    if "--reference" in argv:
        out = reference(quick)
        if json_path is not None:
            write_reference(json_path, out, quick)
        return 0
    print(
        "# FE spheroid benchmark (fem.spheroid.compress; a0 = 500 um, kappa = 2.2 GPa, quarter section, "
        "exact active-set contact)"
    )
    fig10(quick)
    static_curve(quick)
    hertz(quick)
    convergence(quick)
    reference(quick)
    r = fig89()
    if "--figure" in argv:
        figure(argv[argv.index("--figure") + 1], r)
    return 0


if __name__ == "__main__":
    import sys

    if "-h" in sys.argv or "--help" in sys.argv:  # describe, never start the benchmark
        print(__doc__)
        raise SystemExit(0)
    raise SystemExit(main(sys.argv[1:]))
