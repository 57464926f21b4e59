"""Shared fixtures: the seed's cases (``compare.cases``) and one quick report run per session.

Also two guards of the layout: the repository root is the package ``tissuemech`` (pyproject maps it), so
``python -m pytest`` from the root would make ``fem``, ``reduced``, ``compare`` importable a second time as
top-level packages (one file, two module objects): the root is taken off ``sys.path`` here, and the session
fails if any file was nevertheless loaded as two modules. Figures use the non-interactive Agg backend.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from tissuemech.compare import cases as _cases

os.environ.setdefault("MPLBACKEND", "Agg")
# tests run every FE computation (compare.runcache) and leave no cache behind
os.environ.setdefault("TISSUEMECH_NO_CACHE", "1")
_ROOT = Path(__file__).resolve().parents[1]
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != _ROOT]


@pytest.fixture(scope="session")
def seed_cases():
    """The module :mod:`tissuemech.compare.cases` (the seed's cases, defined once)."""
    return _cases


@pytest.fixture(scope="session")
def quick_report(tmp_path_factory):
    """(folder, summary) of one ``report.build(..., quick=True)`` run (about 1.5 min on 2 cores)."""
    from tissuemech.compare import report

    out = tmp_path_factory.mktemp("report")
    summary = report.build(out, quick=True, progress=False)
    return out, summary


def _modules_by_file() -> dict[str, list[str]]:
    seen: dict[str, list[str]] = {}
    for name, mod in list(sys.modules.items()):
        path = getattr(mod, "__file__", None)
        if path and name.split(".")[0] in ("tissuemech", "reduced", "fem", "compare"):
            seen.setdefault(str(Path(path).resolve()), []).append(name)
    return seen


def pytest_sessionfinish(session, exitstatus):
    """Fail the run if one source file of the package was imported as two module objects."""
    twice = {f: names for f, names in _modules_by_file().items() if len(names) > 1}
    if twice:
        lines = "; ".join(f"{f}: {', '.join(n)}" for f, n in sorted(twice.items()))
        print(f"\nconftest: files loaded as two module objects (import them as tissuemech.*): {lines}", file=sys.stderr)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
