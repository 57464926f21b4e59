"""Former home of ``tissuemech batch``: an alias of ``compare.cli.batch`` (the command) and ``compare.batch``
(job arrays, cluster recipes, FE point functions)."""

import sys

from tissuemech.compare.batch import (
    FUNCTIONS,
    chunk,
    collect,
    fe_blastula,
    fe_spheroid,
    jobqueue_cluster,
    pin_threads,
    read_points,
    resolve_function,
    worker_env,
)
from tissuemech.compare.cli.batch import add_parser, main, run

__all__ = [
    "add_parser",
    "run",
    "main",
    "chunk",
    "read_points",
    "collect",
    "worker_env",
    "pin_threads",
    "jobqueue_cluster",
    "resolve_function",
    "fe_spheroid",
    "fe_blastula",
    "FUNCTIONS",
]

if __name__ == "__main__":
    sys.exit(main())
