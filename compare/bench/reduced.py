"""``python -m tissuemech.compare.bench reduced``: every reduced path's throughput, compile time, accuracy
and its plain-SciPy baseline, in one run and one table.

Rows come from ``compare.bench.reduced_blastula.rows()`` and ``compare.bench.reduced_spheroid.rows()``;
this module adds the ``import reduced`` time (measured in a fresh interpreter) and prints them.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Sequence


def import_time() -> float:
    """Seconds for ``import reduced`` in a fresh interpreter (best of 3)."""
    code = "import time; t = time.perf_counter(); import reduced; print(time.perf_counter() - t)"
    return min(float(subprocess.check_output([sys.executable, "-c", code]).decode().strip()) for _ in range(3))


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def print_rows(rows: list[dict]) -> None:
    keys: list[str] = []
    for r in rows:
        for k in r:
            if k not in keys:
                keys.append(k)
    widths = {k: max(len(k), *(len(_fmt(r.get(k, ""))) for r in rows)) for k in keys}
    print(" | ".join(k.ljust(widths[k]) for k in keys))
    print("-|-".join("-" * widths[k] for k in keys))
    for r in rows:
        print(" | ".join(_fmt(r.get(k, "")).ljust(widths[k]) for k in keys))


def main(argv: Sequence[str] | None = None) -> list[dict]:
    from tissuemech.compare.bench import reduced_blastula, reduced_spheroid

    print(f"import reduced: {import_time():.2f} s (fresh interpreter, best of 3)")
    rows = list(reduced_blastula.rows()) + list(reduced_spheroid.rows())
    print_rows(rows)
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
