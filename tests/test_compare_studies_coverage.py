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


def test_noise_kinds_and_misfit_have_the_stated_size():
    """AR(1) noise: lag-1 correlation 0.9 at the stated marginal sd; proportional noise: sd relative to each point;
    the smooth misfit: the stated root-mean-square over the record's log-time span."""
    from tissuemech.compare.fit import diagnostics

    rng = np.random.default_rng(0)
    t = np.linspace(0.75, 1500.0, 20000)
    y = 10.0 + np.exp(-t / 300.0)
    ((_, ar, _),) = coverage.add_noise([(t, y, 1e-4)], 0.01, rng, kind="ar1")
    e = (ar - y) / (0.01 * y.max())
    assert np.std(e) == pytest.approx(1.0, rel=0.1) and diagnostics.lag1(e) == pytest.approx(0.9, abs=0.02)
    ((_, pr, _),) = coverage.add_noise([(t, y, 1e-4)], 0.01, rng, kind="proportional")
    assert np.std((pr - y) / y) == pytest.approx(0.01, rel=0.03)
    with pytest.raises(ValueError, match="noise kind"):
        coverage.add_noise([(t, y, 1e-4)], 0.01, rng, kind="pink")
    tl = np.exp(np.linspace(0.0, np.log(1500.0), 4000)) - 0.2  # uniform in log(t + ramp time)
    rms = [np.sqrt(np.mean((coverage.add_misfit([(tl, y[:4000], 1e-4)], 0.005, rng, 0.2)[0][1] / y[:4000] - 1) ** 2))
           for _ in range(400)]  # fmt: skip
    assert np.sqrt(np.mean(np.square(rms))) == pytest.approx(0.005, rel=0.1)


@pytest.mark.slow
def test_error_model_rows_cover():
    """12 fits each on dense records with AR(1) noise (lag-1 0.9) and with a 0.5 % smooth misfit: the default
    intervals hold the truth >= 9 times per parameter (P(fewer) ~ 0.2 % for a true 95 % interval), where the
    white-noise ones miss it most of the time."""
    df = coverage.scenario_study(["AR(1) 0.9, dense", "misfit 0.5 %, dense"], n=12, seed=5, intervals="wald", log=None)
    table = coverage.summarise_scenarios(df)
    default = table[table["errors"] == "default"]
    assert len(default) == 8 and (default["fits"] == 12).all()
    assert (default["coverage %"] >= 100 * 9 / 12).all(), default
    white = table[table["errors"] == "white"]
    assert white["coverage %"].mean() < 70, white


@pytest.mark.slow
def test_creep_row_covers():
    """10 fits of reduced-made creep records (3 and 25 uN held, 1 % white noise on the approach, fitted by
    compare.fit.protocols.records_fit): the default intervals hold the truth >= 8 times per parameter (P(fewer) ~
    1 % for a true 95 % interval)."""
    df = coverage.scenario_study(["creep"], n=10, seed=7, intervals="wald", log=None)
    table = coverage.summarise_scenarios(df)
    default = table[table["errors"] == "default"]
    assert len(default) == 4 and (default["fits"] == 10).all()
    assert (default["coverage %"] >= 80).all(), default
