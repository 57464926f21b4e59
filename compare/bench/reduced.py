"""``python -m tissuemech.compare.bench reduced``: every reduced path's throughput, compile time, accuracy
and its plain-SciPy baseline, in one run and one table.

Rows come from ``compare.bench.reduced_blastula.rows()`` and ``compare.bench.reduced_spheroid.rows()``;
this module adds the ``import tissuemech.reduced`` time (measured in a fresh interpreter) and prints them.
A first table (issue 14) sets the eager public blastula calls against their jitted form, in one run
(``reduced_blastula.api_rows``), times the whole ``tissuemech blastula`` process (``cli_rows``) and the
one-point calls with asynchronous and with inline JAX dispatch (``dispatch_rows``); a third (issue 40) times the
exact ``pressure`` and ``inner_stretch`` on 1e6 random shells against their targets, with the pressure program's
roofline (``workload_rows``).
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Sequence

from tissuemech.compare.bench.common import print_rows

__all__ = ["import_time", "main", "print_rows"]


def import_time() -> float:
    """Seconds for ``import tissuemech.reduced`` in a fresh interpreter (best of 3)."""
    code = "import time; t = time.perf_counter(); import tissuemech.reduced; print(time.perf_counter() - t)"
    return min(float(subprocess.check_output([sys.executable, "-c", code]).decode().strip()) for _ in range(3))


def main(argv: Sequence[str] | None = None) -> list[dict]:
    import argparse

    from tissuemech.compare.bench import reduced_blastula, reduced_spheroid

    ap = argparse.ArgumentParser(prog="python -m tissuemech.compare.bench reduced", description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="accepted for `bench all --quick`: this suite has one size")
    ap.parse_args(list(argv or []))
    print(f"import tissuemech.reduced: {import_time():.2f} s (fresh interpreter, best of 3)")
    print_rows(reduced_blastula.api_rows() + reduced_blastula.cli_rows())
    print_rows(reduced_blastula.dispatch_rows())
    print_rows(reduced_blastula.workload_rows())  # issue 40 item 6: random shells, roofline of the pressure
    rows = list(reduced_blastula.rows()) + list(reduced_spheroid.rows())
    print_rows(rows)
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
