"""Interleaved A/B of the FE runs between a base commit and the working tree (issue 14's speed claims).

``python notes/ab_commits.py BASE [--cases b4x8,fig10,...] [--rounds 4] [--repeats 3]``

Exports BASE (a commit of this repository) with ``git archive`` into a temporary folder, then runs each
case alternately in fresh subprocesses of this interpreter with the package imported from BASE and from the
working tree (``rounds`` times each, ``repeats`` timed runs after one warm-up per subprocess, min taken).
The box is shared and noisy: only the interleaved ratio means much. Prints per case the wall times of
both sides (min, median and max over the rounds), the ratio base / new of the medians, the Newton
iterations and the SuperLU factorisations of one run, and the largest relative difference of the
answers (inner stretches or plate forces).

Cases: ``b4x8`` / ``b16x32`` (blastula, alpha 0.2, B = 75 um, 50 pressures 20..1000 Pa on the 4x8 / 16x32
mesh), ``fe8x16`` (``compare/bench/felupe_side.py``'s fine pairing: B = 60 um, kappa = 2.2 GPa, the
50 pressures 20..1000 Pa on 8x16), ``s8x16`` / ``s24x48`` (``fem-perf``'s scaling sweep: B = 75 um, 10 pressures
100..1000 Pa on 8x16 / 24x48), ``fig10`` (the spheroid Fig. 10 case to 1500 s, default mesh), ``static1`` / ``static2`` /
``static3`` (the spheroid static curve of the Fig. 10 material to 10 % in 5 steps on that level),
``static30`` (the static curve to 30 % in 6 steps on the default mesh, ``compare/bench/felupe_side.py``'s
case).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
CASES = ("b4x8", "b16x32", "fe8x16", "s8x16", "s24x48", "fig10", "static1", "static2", "static3", "static30")

CHILD = r"""
import json, sys, time
src, case, repeats = sys.argv[1], sys.argv[2], int(sys.argv[3])
if src != "-":  # import tissuemech from the exported base, not the installed (editable) tree
    sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in type(f).__name__.lower()]
    sys.path.insert(0, src)
import numpy as np
import scipy.sparse.linalg as spla
import tissuemech
from tissuemech.fem import blastula as fb, spheroid as fs
assert (src != "-") == tissuemech.__file__.startswith(src), tissuemech.__file__
count = [0]
splu = spla.splu
def counted(*a, **k):
    count[0] += 1
    return splu(*a, **k)
spla.splu = counted
FIG10 = dict(radius=500e-6, C=150.0, alpha=0.2, branches=[(0.4, 200.0)], displacement=50e-6, ramp_time=0.2,
             end_time=1500.0)
ps = np.linspace(20.0, 1000.0, 50)
def run():
    if case in ("b4x8", "b16x32"):
        mesh = (4, 8) if case == "b4x8" else (16, 32)
        r = fb.inflate(inner_radius=50e-6, outer_radius=75e-6, C=200.0, alpha=0.2, pressures=ps, mesh=mesh)
        return np.asarray(r.inner_stretch), r
    if case in ("s8x16", "s24x48"):  # fem-perf's scaling sweep: B = 75 um, 10 pressures 100..1000 Pa
        mesh = (8, 16) if case == "s8x16" else (24, 48)
        r = fb.inflate(inner_radius=50e-6, outer_radius=75e-6, C=200.0, alpha=0.2, pressures=np.linspace(100.0, 1000.0, 10),
                       mesh=mesh)
        return np.asarray(r.inner_stretch), r
    if case == "fe8x16":  # compare/bench/felupe_side.py's fine pairing: B = 60 um, kappa 2.2 GPa, 8x16
        r = fb.inflate(inner_radius=50e-6, outer_radius=60e-6, C=200.0, alpha=0.2, kappa=2.2e9, pressures=ps,
                       mesh=(8, 16))
        return np.asarray(r.inner_stretch), r
    if case == "fig10":
        r = fs.compress(**FIG10)
        return np.asarray(r.force), r
    if case == "static30":
        r = fs.compress(radius=500e-6, C=200.0, alpha=0.2, branches=(), displacement=300e-6,
                        ramp_time=1.0, end_time=1.0, static=True, n_static=6)
        return np.asarray(r.force), r
    level = int(case[len("static"):])
    r = fs.compress(**{**FIG10, "mesh": level, "static": True, "displacement": 100e-6, "n_static": 5})
    return np.asarray(r.force), r
run()
ts = []
for _ in range(repeats):
    count[0] = 0
    t = time.perf_counter()
    out, r = run()
    ts.append(time.perf_counter() - t)
print(json.dumps(dict(wall=min(ts), iterations=int(np.sum(r.newton_iterations)), lu=count[0],
                      answer=[float(v) for v in out])))
"""


def _child(src: str, case: str, repeats: int) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", CHILD, src, case, str(repeats)], capture_output=True, text=True, check=True
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python notes/ab_commits.py")
    ap.add_argument("base", help="the base commit (any git revision of this repository)")
    ap.add_argument("--cases", default="b4x8,fig10", help=f"comma-separated, of {', '.join(CASES)}")
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args(argv)
    cases = [c for c in a.cases.split(",") if c]
    bad = [c for c in cases if c not in CASES]
    if bad:
        ap.error(f"unknown case(s) {bad}; choose from {CASES}")
    rev = subprocess.run(["git", "rev-parse", "--short", a.base], cwd=ROOT, capture_output=True, text=True, check=True)
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout
    dirty = subprocess.run(
        ["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT, capture_output=True, text=True
    )
    with tempfile.TemporaryDirectory() as tmp:
        pkg = Path(tmp) / "tissuemech"
        pkg.mkdir()
        arch = subprocess.run(["git", "archive", rev.stdout.strip()], cwd=ROOT, capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(pkg)], input=arch.stdout, check=True)
        print(
            f"base {rev.stdout.strip()} vs working tree (HEAD {head.strip()}{', modified' if dirty.stdout else ''}); "
            f"{a.rounds} interleaved rounds, min of {a.repeats} runs per subprocess"
        )
        for case in cases:
            runs: dict[str, list[dict]] = {"base": [], "new": []}
            for _ in range(a.rounds):
                runs["base"].append(_child(tmp, case, a.repeats))
                runs["new"].append(_child("-", case, a.repeats))
            w = {k: np.array([r["wall"] for r in v]) for k, v in runs.items()}
            ans = {k: np.array(v[-1]["answer"]) for k, v in runs.items()}
            diff = float(np.max(np.abs(ans["new"] / ans["base"] - 1.0)))
            print(
                f"{case:9s} base {np.min(w['base']):7.3f} / {np.median(w['base']):7.3f} / {np.max(w['base']):7.3f} s "
                f"(min / median / max), {runs['base'][-1]['iterations']} iterations, {runs['base'][-1]['lu']} LU; "
                f"new {np.min(w['new']):7.3f} / {np.median(w['new']):7.3f} / {np.max(w['new']):7.3f} s, "
                f"{runs['new'][-1]['iterations']} iterations, {runs['new'][-1]['lu']} LU; "
                f"base / new {np.median(w['base']) / np.median(w['new']):.2f}x; answers within {diff:.1e}"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
