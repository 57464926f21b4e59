"""compare.studies.coverage: the study's bookkeeping, and a small reduced-made run with honest coverage."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from tissuemech.compare.studies import coverage


def test_wilson_interval():
    lo, hi = coverage.wilson(19, 20)
    # closed form: (p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)
    z, n, p = 1.959963984540054, 20, 0.95
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    assert (lo, hi) == pytest.approx((c - h, c + h), rel=1e-14)
    assert coverage.wilson(0, 10)[0] == pytest.approx(0.0, abs=1e-15)


def test_summarise_counts():
    df = pd.DataFrame(
        dict(
            source="x",
            noise=0.01,
            job=[0, 1, 2, 3],
            parameter="C",
            truth=100.0,
            estimate=[101.0, 99.0, 100.0, 102.0],
            lo=[99.0, 98.0, 99.0, 101.0],
            hi=[103.0, 100.0, 101.0, 103.0],
            kind=["two-sided", "two-sided", "upper", "two-sided"],
            inside=[True, True, True, False],
            success=True,
            error="",
        )
    )
    s = coverage.summarise(df).iloc[0]
    assert s["coverage %"] == 75.0 and s["fits"] == 4 and s["one-sided"] == 1
    assert s["median bias %"] == pytest.approx(0.5)


def test_truths_in_the_box():
    tr = coverage.sample_truths(50, np.random.default_rng(0))
    for k, (a, b) in coverage.BOX.items():
        v = np.array([t[k] for t in tr])
        assert np.all((v >= a) & (v <= b))


@pytest.mark.slow
def test_small_reduced_made_study_covers():
    """16 reduced-made records at 1 % noise: every parameter's interval holds the truth >= 13 times
    (P(fewer) ~ 0.7 % for a true 95 % interval)."""
    df, table = coverage.run(n_reduced=16, n_fe=0, noises=(0.01,), seed=11, fe=False, log=None)
    assert len(df) == 16 * 4 and set(table["parameter"]) == set(coverage.NAMES)
    assert (table["coverage %"] >= 100 * 13 / 16).all(), table
    assert (table["failed"] == 0).all()


def test_coverage_command_and_its_old_module_path(capsys):
    """``tissuemech coverage`` is registered (``python -m tissuemech.compare.coverage`` is its thin alias); bad counts
    are one-line errors."""
    from tissuemech.compare import coverage as old
    from tissuemech.compare.cli import main

    assert old.summarise is coverage.summarise
    assert main(["coverage", "--n-reduced", "-1", "--no-fe"]) == 2
    assert "--n-reduced" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:  # argparse's own errors: one line, exit code 2
        old.main(["--noise", "0"])
    assert exc.value.code == 2
    assert "must be positive" in capsys.readouterr().err
