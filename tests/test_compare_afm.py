"""compare.afm: readers on the shipped real records, the contact point on synthetic curves, the HAC fit."""

import math
from pathlib import Path

import numpy as np
import pytest

from tissuemech.compare.afm import contact, records
from tissuemech.compare.afm import fit as afm_fit
from tissuemech.reduced import indentation as probe_model

DATA = Path(__file__).resolve().parent / "data" / "afm"
EXTRACT = DATA / "oocyte_cell1_extract.csv.gz"


@pytest.fixture(scope="module")
def curves():
    return records.read_csv(EXTRACT)


def test_csv_extract_reads_the_real_records(curves):
    assert len(curves) == 15
    c = curves[0]
    assert c.spring_constant == pytest.approx(1.0677) and c.sensitivity == pytest.approx(1.1028e-7)
    assert c.segment_names == ("pause", "approach", "hold", "retract")
    # the protocol: 1 s approach at 20 um/s (height measured), 30 s hold at constant height
    appr, hold = c.part("approach"), c.part("hold")
    assert np.ptp(c.height[appr]) == pytest.approx(20e-6, rel=0.01)
    assert c.time[hold][-1] - c.time[hold][0] == pytest.approx(30.0, abs=0.1)
    assert np.ptp(c.height[hold]) < 50e-9
    peak = np.max(c.force[appr]) - np.mean(c.force[c.part("pause")])
    assert 250e-9 < peak < 350e-9  # ~300 nN


def test_jpk_reader_matches_the_extract(curves):
    pytest.importorskip("afmformats")
    (jpk,) = records.read_jpk(DATA / "cell1-0001.jpk-force")
    assert jpk.spring_constant == curves[0].spring_constant
    light = records.binned(jpk, {"pause": 8, "approach": 8, "hold": 16, "retract": 64})
    assert np.allclose(light.force, curves[0].force, rtol=1e-5, atol=1e-14)
    assert np.allclose(light.height, curves[0].height, rtol=1e-8)


def test_csv_units_and_deflection(tmp_path):
    t = np.linspace(0, 1, 20)
    h = 10.0 - 2.0 * t  # um
    defl_v = np.linspace(0, 0.5, 20)  # V
    p = tmp_path / "lab.csv"
    p.write_text(
        "# spring constant: 0.5 N/m\n# sensitivity: 100 nm/V\ntime (ms), height (um), deflection (V)\n"
        + "\n".join(f"{a * 1e3},{b},{c}" for a, b, c in zip(t, h, defl_v))
    )
    (c,) = records.read_csv(p)
    assert np.allclose(c.time, t) and np.allclose(c.height, h * 1e-6)
    assert np.allclose(c.force, defl_v * 100e-9 * 0.5)
    with pytest.raises(ValueError, match="spring constant"):
        q = tmp_path / "nok.csv"
        q.write_text("time (s), height (m), deflection (m)\n0,1,0\n1,0.5,0\n2,0.2,0\n3,0.1,0\n")
        records.read_csv(q)
    with pytest.raises(ValueError, match="unit"):
        q = tmp_path / "unit.csv"
        q.write_text("time (s), height (furlong), force (N)\n0,1,0\n1,0.5,0\n2,0.2,0\n3,0.1,0\n")
        records.read_csv(q, spring_constant=1.0)


def test_write_then_read_round_trip(curves, tmp_path):
    records.write_csv(curves[:2], tmp_path / "two.csv")
    back = records.read_csv(tmp_path / "two.csv")
    assert len(back) == 2 and np.allclose(back[1].force, curves[1].force, rtol=1e-5)


def synthetic(hc: float, noise: float, seed: int = 0, n_exp: float = 1.5) -> records.Curve:
    """Pause at 10 um, approach 10 -> 4 um, F = F0 + K (hc - h)^n after contact, white noise."""
    rng = np.random.default_rng(seed)
    tp = np.linspace(0.0, 0.5, 64, endpoint=False)
    ta = np.linspace(0.5, 1.5, 512)
    hp = np.full(tp.size, 10e-6)
    ha = 10e-6 - 6e-6 * (ta - 0.5)
    K = 50e-9 / (1e-6) ** n_exp  # 50 nN at 1 um
    f0 = -20e-9
    fa = f0 + K * np.maximum(hc - ha, 0.0) ** n_exp
    f = np.concatenate([np.full(tp.size, f0), fa]) + noise * rng.standard_normal(tp.size + ta.size)
    seg = np.r_[np.zeros(tp.size, int), np.ones(ta.size, int)]
    return records.Curve(np.r_[tp, ta], np.r_[hp, ha], f, seg, 1.0, None, ("pause", "approach"), name="synthetic")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_contact_point_on_synthetic_curves(seed):
    hc = 7.3e-6
    c = synthetic(hc, noise=0.5e-9, seed=seed)
    cp = contact.find_contact(c, window=0.3)
    assert not cp.at_start
    assert 0 < cp.height_sd < 100e-9
    assert abs(cp.height - hc) < 4 * cp.height_sd + 5e-9
    assert cp.exponent == pytest.approx(1.5, abs=0.15)
    assert cp.baseline == pytest.approx(-20e-9, abs=0.3e-9)


def test_contact_at_start_is_flagged(curves):
    cp = contact.find_contact(curves[0])
    assert cp.at_start  # the real records start in contact: the probe touches when the approach begins
    assert cp.height_sd < 200e-9


def test_indentation_history(curves):
    c = curves[0]
    cp = contact.find_contact(c)
    ind = contact.indentation(c, cp)
    assert ind.time[0] == 0.0 and ind.approach[0] == 0.0 and ind.force[0] == 0.0
    # piezo travel minus deflection: ~20 um minus ~0.3 um at the peak
    assert np.max(ind.approach) == pytest.approx(20e-6 - np.max(ind.force) / c.spring_constant, rel=0.01)
    # the cantilever relaxes at constant height: the tip creeps in by the deflection it loses (~0.2 um)
    drop = (ind.force[ind.hold][0] - ind.force[ind.hold][-1]) / c.spring_constant
    assert ind.creep == pytest.approx(drop, rel=0.05)
    assert ind.ramp_time == pytest.approx(1.0, abs=0.05)


def test_runs_test_and_hac():
    rng = np.random.default_rng(3)
    z, p = afm_fit.runs_test(rng.standard_normal(2000))
    assert abs(z) < 3.5 and p > 1e-3
    z, p = afm_fit.runs_test(np.sin(np.linspace(0, 6, 2000)))
    assert z < -20
    # AR(1) errors on a mean: the HAC variance of the mean approaches the long-run variance
    rho, n = 0.8, 4000
    e = np.zeros(n)
    for i in range(1, n):
        e[i] = rho * e[i - 1] + rng.standard_normal()
    J = np.ones((n, 1))
    cov, L = afm_fit.hac_covariance(J, e - e.mean())
    long_run = 1.0 / (1 - rho) ** 2 / n
    assert cov[0, 0] == pytest.approx(long_run, rel=0.35) and L > 5


@pytest.mark.slow
def test_fit_recovers_synthetic_parameters():
    """The model itself, through the whole chain (history -> fit), with white noise: truth inside the intervals."""
    C, beta, tau = 70.0, 1.5, 3.0
    t_ramp = np.linspace(0, 1.0, 200)
    t_hold = np.linspace(1.0 + 1 / 16, 31.0, 480)
    t = np.r_[t_ramp, t_hold]
    d = np.minimum(t, 1.0) * 10e-6 + 0.1e-6 * np.maximum(t - 1.0, 0) / 30
    f = np.asarray(
        probe_model.force(t, radius=40e-6, probe_radius=25e-6, C=C, branches=[(beta, tau)], displacement=(t, d))
    )
    rng = np.random.default_rng(0)
    f = f + 0.5e-9 * rng.standard_normal(t.size)
    ind = contact.Indentation(t, d, f, np.where(t > 1.0, "hold", "approach"), 1.0, 0.1e-6, "synthetic")
    r = afm_fit.fit_curve(ind, probe_radius=25e-6, radius=40e-6, n_branches=1)
    for k, v in dict(C=C, beta=beta, tau=tau).items():
        lo, hi = r.intervals[k]
        assert lo < v < hi, (k, v, lo, hi)
        assert r.params[k] == pytest.approx(v, rel=0.02)
    assert abs(r.lag1) < 0.3 and r.success


@pytest.mark.slow
def test_real_curve_two_branches_beat_one(curves):
    ind = contact.indentation(curves[0])
    one = afm_fit.fit_curve(ind, probe_radius=25e-6, radius=40e-6, n_branches=1)
    two = afm_fit.fit_curve(ind, probe_radius=25e-6, radius=40e-6, n_branches=2)
    assert two.aic < one.aic - 100 and two.bic < one.bic - 100
    assert two.rms < 0.5 * one.rms
    assert one.lag1 > 0.5  # one branch leaves structure (reported, not hidden)
    # beta and tau do not depend on the geometry; C scales as R_s^(-1/2)
    half = afm_fit.fit_curve(ind, probe_radius=25e-6, radius=math.inf, n_branches=1)
    rs = float(probe_model.series_radius(40e-6, 25e-6))
    # (to the optimizer's stopping tolerance, a small fraction of the intervals' widths)
    assert half.params["tau"] == pytest.approx(one.params["tau"], rel=5e-3)
    assert half.params["C"] == pytest.approx(one.params["C"] * math.sqrt(rs / 25e-6), rel=5e-3)
    assert abs(math.log(half.params["tau"] / one.params["tau"])) < 0.1 * one.sd_log["tau"]


def test_recalibration_rescales_the_force(curves):
    c = curves[0]
    d = records.recalibrated(c, spring_constant=2 * c.spring_constant, sensitivity=0.5 * c.sensitivity)
    assert np.allclose(d.force, c.force) and d.spring_constant == 2 * c.spring_constant
    e = records.recalibrated(c, spring_constant=3 * c.spring_constant)
    assert np.allclose(e.force, 3 * c.force) and np.allclose(e.deflection, c.deflection)
    with pytest.raises(ValueError, match="spring_constant"):
        records.recalibrated(c, spring_constant=-1.0)


def test_cli_one_line_errors(capsys):
    from tissuemech.compare.cli import main

    assert main(["afm", "no_such_file.csv", "--probe-radius-um", "25", "--radius-um", "40"]) == 2
    assert "no such file" in capsys.readouterr().err
