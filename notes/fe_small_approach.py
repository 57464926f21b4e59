"""FE spheroid force at very small approaches against the calibrated table (which tends to Hertz as x -> 0).

``python notes/fe_small_approach.py``: static FE states at delta = 1e-9, 1e-8, 1e-7, 1e-6 m (x = delta / (2 a0) =
1e-6 .. 1e-3, a0 = 500 um, C = 150 Pa, alpha = 0.2) on the coarse and the default mesh; prints F_FE / F_table. The
contact edge is a node of each step's fitted mesh at any approach, but the elements below the contact patch are
not refined with it: at approaches far below the meshes' design range the force is too stiff (found by an API
audit, 2026-12-02; a known limit in the README).
"""

from __future__ import annotations

from tissuemech.fem import spheroid as fs
from tissuemech.reduced import spheroid as rs

A0 = 500e-6


def main() -> None:
    print(f"{'delta [m]':>10} {'x':>8} {'coarse':>8} {'default':>8}   (F_FE / F_table)")
    for d in (1e-9, 1e-8, 1e-7, 1e-6):
        ref = float(rs.equilibrium_force(d, radius=A0, C=150.0, alpha=0.2))
        ratios = []
        for mesh in ("coarse", "default"):
            r = fs.compress(radius=A0, C=150.0, alpha=0.2, displacement=d, static=True, mesh=mesh, ramp_time=1.0,
                            end_time=1.0)  # fmt: skip
            ratios.append(float(r.force[-1]) / ref)
        print(f"{d:10.0e} {d / (2 * A0):8.0e} {ratios[0]:8.4f} {ratios[1]:8.4f}")


if __name__ == "__main__":
    main()
