"""Shared fixtures: the seed's cases (``compare.cases``) and one quick report run per session."""

from __future__ import annotations

import pytest

from tissuemech.compare import cases as _cases


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
