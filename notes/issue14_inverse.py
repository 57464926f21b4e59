"""inner_stretch rates for three kinds of input, this tree against a base commit, side by side.

    python notes/issue14_inverse.py [--base fa94acf] [--n 200000]

Runs the same script on ``git archive BASE`` (unpacked to a temporary folder, imported first on
PYTHONPATH) and on this checkout, in turn, and prints points/s for each case and the largest relative
difference of the answers. Cases: shells that vary per point (B in 52-100 um, alpha in 0.15-0.3, inner
stretch 1-3), one shell alpha 0 below its limit point, one shell alpha 0.2 (stretch 0.5-4); A = 50 um.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile

CHILD = r"""
import json, sys, time
import numpy as np
from tissuemech.reduced import blastula as bl
n = int(sys.argv[1]); out = sys.argv[2]
rng = np.random.default_rng(1)
A = 50e-6
B = rng.uniform(52e-6, 100e-6, n); al = rng.uniform(0.15, 0.3, n); la = rng.uniform(1.0, 3.0, n)
lim = float(bl.limit_point(inner_radius=A, outer_radius=75e-6, C=200.0, alpha=0.0).inner_stretch)
cases = {
    "per-point shells": (la, dict(inner_radius=A, outer_radius=B, C=200.0, alpha=al)),
    "one shell, alpha 0, below the limit": (rng.uniform(0.5, lim - 1e-3, n),
                                            dict(inner_radius=A, outer_radius=75e-6, C=200.0, alpha=0.0)),
    "one shell, alpha 0.2": (rng.uniform(0.5, 4.0, n), dict(inner_radius=A, outer_radius=75e-6, C=200.0, alpha=0.2)),
}
res = {}
for name, (x, kw) in cases.items():
    p = np.asarray(bl.pressure(x, **kw))
    bl.inner_stretch(p, **kw)
    ts = []
    for _ in range(3):
        t = time.perf_counter(); y = np.asarray(bl.inner_stretch(p, **kw)); ts.append(time.perf_counter() - t)
    res[name] = dict(rate=n / min(ts), y=y.tolist())
json.dump(dict(file=bl.__file__, cases=res), open(out, "w"))
"""


def _run(pythonpath: str | None, n: int, tmp: str, tag: str) -> dict:
    out = os.path.join(tmp, f"{tag}.json")
    env = dict(os.environ, OMP_NUM_THREADS="1")
    if pythonpath:
        env["PYTHONPATH"] = pythonpath
    subprocess.run([sys.executable, "-c", CHILD, str(n), out], check=True, env=env)
    return json.load(open(out))


def main() -> None:
    import numpy as np

    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--base", default="fa94acf")
    ap.add_argument("--n", type=int, default=200_000)
    a = ap.parse_args()
    root = subprocess.run(["git", "rev-parse", "--show-toplevel"], capture_output=True, text=True, check=True)
    with tempfile.TemporaryDirectory() as tmp:
        pkg = os.path.join(tmp, "pkg")
        tree = os.path.join(pkg, "tissuemech")
        os.makedirs(tree)
        arch = subprocess.run(["git", "archive", a.base], capture_output=True, check=True, cwd=root.stdout.strip())
        subprocess.run(["tar", "-x", "-C", tree], input=arch.stdout, check=True)
        old = _run(pkg, a.n, tmp, "old")
        new = _run(None, a.n, tmp, "new")
    print(f"inner_stretch, {a.n} points, one thread; base {a.base} ({old['file']}) vs this tree ({new['file']})")
    for name in new["cases"]:
        o, w = old["cases"][name], new["cases"][name]
        yo, yn = np.asarray(o["y"]), np.asarray(w["y"])
        ok = np.isfinite(yo) & np.isfinite(yn)
        diff = float(np.max(np.abs(yn[ok] / yo[ok] - 1.0)))
        print(
            f"{name:38s} base {o['rate']:.3g} points/s  now {w['rate']:.3g} points/s  "
            f"x{w['rate'] / o['rate']:.2f}  max rel diff {diff:.2g}"
        )


if __name__ == "__main__":
    main()
