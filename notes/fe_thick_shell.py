"""FE blastula inner stretch of thick walls against the exact shell (the FE shell meshes are uniform through the wall).

``python notes/fe_thick_shell.py``: A = 50 um, B/A = 1.5 (the seed's thickest), 3, 10, 100; C = 200 Pa, alpha = 0.2,
at the pressure where the exact inner stretch is ~1.5; prints (lambda_FE - 1) / (lambda_exact - 1) - 1 on the coarse,
default and fine meshes (found by an API audit, 2026-12-02; a known limit in the README).
"""

from __future__ import annotations

from scipy.optimize import brentq

from tissuemech.fem import blastula as fb
from tissuemech.reduced import blastula as rb

A, C, ALPHA = 50e-6, 200.0, 0.2


def main() -> None:
    print(f"{'B/A':>6} {'p [Pa]':>9} {'coarse':>9} {'default':>9} {'fine':>9}   (error of lambda_a - 1)")
    for ratio in (1.5, 3.0, 10.0, 100.0):
        geo = dict(inner_radius=A, outer_radius=ratio * A, C=C, alpha=ALPHA)
        p = brentq(lambda q: float(rb.inner_stretch(q, **geo)) - 1.5, 1.0, 1e4)
        exact = float(rb.inner_stretch(p, **geo))
        errs = []
        for mesh in ("coarse", "default", "fine"):
            r = fb.inflate(**geo, pressures=[p / 4, p / 2, 3 * p / 4, p], mesh=mesh)
            errs.append((float(r.inner_stretch[-1]) - 1) / (exact - 1) - 1)
        print(f"{ratio:6g} {p:9.2f} " + " ".join(f"{e:9.2e}" for e in errs))


if __name__ == "__main__":
    main()
