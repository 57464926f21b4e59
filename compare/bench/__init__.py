"""Benchmarks: ``python -m tissuemech.compare.bench {reduced,fem-blastula,fem-spheroid,all}``.

Each sub-module has a ``main(argv)`` that prints its table (throughput or wall time after
compile, accuracy, and a plain SciPy/other baseline with the ratio). Timings live here, never
in tests.
"""
