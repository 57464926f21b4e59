"""Dispatch ``python -m tissuemech.compare.bench NAME [options]``."""

from __future__ import annotations

import importlib
import sys

SUITES = {
    "reduced": "tissuemech.compare.bench.reduced",
    "fem-blastula": "tissuemech.compare.bench.fem_blastula",
    "fem-spheroid": "tissuemech.compare.bench.fem_spheroid",
    "hybrid": "tissuemech.compare.bench.hybrid",
    "fem-perf": "tissuemech.compare.bench.fem_perf",
    "felupe": "tissuemech.compare.bench.felupe_side",
    "fem-time": "tissuemech.compare.bench.fem_time",
    "fem-gradient": "tissuemech.compare.bench.fem_gradient",
    "fem-indentation": "tissuemech.compare.bench.fem_indentation",
    "fem-protocols": "tissuemech.compare.bench.fem_protocols",
    "fem-liquid": "tissuemech.compare.bench.fem_liquid",
    "liquid-relaxation": "tissuemech.compare.bench.liquid_relaxation",
    "tension-relaxation": "tissuemech.compare.bench.tension_relaxation",
    "fit-dense": "tissuemech.compare.bench.fit_dense",
    "scan-kernel": "tissuemech.compare.bench.scan_kernel",
    # checks run one by one (not part of "all")
    "acceptance": "tissuemech.compare.bench.acceptance",
    "stiff-kernel": "tissuemech.compare.bench.stiff_kernel",
}

SEPARATE = (
    "acceptance",
    "stiff-kernel",
    "fem-time",
    "fem-indentation",
    "fem-gradient",
    "fem-protocols",
    "fem-liquid",
    "liquid-relaxation",
    "tension-relaxation",
)  # not part of "all"


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print("usage: python -m tissuemech.compare.bench {" + ",".join(SUITES) + ",all} [options]")
        return 0
    name, rest = argv[0], argv[1:]
    names = [n for n in SUITES if n not in SEPARATE] if name == "all" else [name]
    for n in names:
        if n not in SUITES:
            print(f"error: unknown benchmark {n!r}; choose from {', '.join(SUITES)} or all", file=sys.stderr)
            return 2
    if "-h" in rest or "--help" in rest:  # describe, never start a suite
        for n in names:
            doc = (importlib.import_module(SUITES[n]).__doc__ or "").strip()
            print(f"== {n} (python -m tissuemech.compare.bench {n} [options]) ==\n{doc}\n")
        return 0
    for n in names:
        rc = importlib.import_module(SUITES[n]).main(rest)
        # an int is a suite's exit code (its usage error stops the run); the reduced suites return their rows
        if isinstance(rc, int) and not isinstance(rc, bool) and rc:
            return rc
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
