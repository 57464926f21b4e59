"""Tabulate the exact liquid drop's plate force for the reduced liquid law: ``reduced/data/drop_master.npz``.

``tissuemech calibrate-drop [--knots 361] [--out PATH]`` (``python -m tissuemech.compare.calibrate_drop`` is an alias)
solves ``reduced.drop.compress`` (the
Young-Laplace drop between non-wetting plates, contact angle 180 deg, solved to rtol 1e-12) at ``--knots`` points
uniform in s = sqrt(x), x = delta / (2 a0) in [0, ``X_MAX``], and at the midpoint of every interval; it stores
d(x) = F_drop / (gamma a0) at the knots and, as metadata, the largest relative error of the cubic spline in s
(``reduced.liquid.DropTable``, the reduced liquid's long-time law) at the midpoints from x = 1e-3 on and below it.
The midpoints are the hardest points of a cubic spline, so that error bounds the table's everywhere. Scaled units
(a0 = gamma = 1): d depends on x only.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Sequence

import numpy as np

from tissuemech.reduced import drop, liquid

X_MAX = liquid.X_MAX


def drop_values(x: np.ndarray) -> np.ndarray:
    """d(x) = F_drop / (gamma a0) at each x = delta / (2 a0) (scaled units, exact solve per point)."""
    return np.array([drop.compress(2.0 * float(v), radius=1.0, surface_tension=1.0).force if v > 0 else 0.0 for v in x])


def run(knots: int = 361, out: str | None = None, command: str | None = None) -> dict:
    """Tabulate d(x) at ``knots`` knots (uniform in sqrt(x)), write ``out`` (default the shipped table) and return
    the metadata (``command``: the provenance line stored in it)."""
    t0 = time.perf_counter()
    s = np.linspace(0.0, np.sqrt(X_MAX), knots)
    x = s**2
    d = drop_values(x)
    xm = ((s[:-1] + s[1:]) / 2) ** 2
    dm = drop_values(xm)
    table = liquid.DropTable(x, d)
    err = np.abs(np.asarray(table(xm)) / dm - 1.0)
    big = xm >= 1e-3
    meta = dict(
        definition="d(x) = F_drop / (gamma a0) of the Young-Laplace drop between non-wetting plates (180 deg), "
        "x = delta / (2 a0); cubic spline in sqrt(x)",
        command=command or f"tissuemech calibrate-drop --knots {knots}",
        knots=int(knots),
        spline_error_max=float(err[big].max()),
        spline_error_from_x=1e-3,
        spline_error_below=float(err[~big].max()) if (~big).any() else 0.0,
        wall_seconds=round(time.perf_counter() - t0, 1),
    )
    np.savez(str(liquid.DATA_FILE) if out is None else out, x=x, drop=d, metadata=json.dumps(meta))
    return meta


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tissuemech.compare.calibrate_drop``: an alias of ``tissuemech calibrate-drop``."""
    from tissuemech.compare.cli.calibrate_drop import main as cli_main

    return cli_main(argv)


if __name__ == "__main__":
    sys.exit(main())
