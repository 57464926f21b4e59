"""compare.fit.design: Fisher-matrix predictions of interval widths (exact identities, and agreement with
the fit's own covariance)."""

from __future__ import annotations

import numpy as np
import pytest

from tissuemech.compare.fit import design

PC = design.Protocol()  # 50 + 200 um, 0.2 s ramp, 70 samples, 1 % noise


def test_levels_add_and_noise_scales():
    p = design.predict(PC)
    F = design.level_fisher(50e-6, PC) + design.level_fisher(200e-6, PC)
    assert np.allclose(p.fisher, F, rtol=1e-12, atol=0)
    p3 = design.predict(design.Protocol(noise=0.03))
    for n in design.NAMES:  # white noise: sd proportional to the noise level
        assert p3.sd[n] / p.sd[n] == pytest.approx(3.0, rel=1e-9)
        assert p.width[n] == pytest.approx(2 * np.sinh(design.Z95 * p.sd[n]), rel=1e-12)


def test_one_level_cannot_separate_C_and_alpha_two_can():
    one = design.predict(design.Protocol(levels=(200e-6,)))
    two = design.predict(PC)
    assert one.sd["alpha"] > 3 * two.sd["alpha"]
    assert one.sd["C"] > 3 * two.sd["C"]


def test_model_error_adds_in_quadrature_to_C_at_one_level():
    """The model is C x g(alpha, beta, tau; t): a record's model-error factor is indistinguishable from C,
    so with one level var(log C) grows by exactly eps^2 and the other parameters are unchanged."""
    one = design.Protocol(levels=(100e-6,))
    p0 = design.predict(one)
    eps = 0.01
    p1 = design.predict(one, model_error=eps)
    assert p1.sd["C"] ** 2 == pytest.approx(p0.sd["C"] ** 2 + eps**2, rel=1e-6)
    for n in ("alpha", "beta", "tau"):
        assert p1.sd[n] == pytest.approx(p0.sd[n], rel=1e-6)


def test_recommend_and_scan():
    cand = np.array([25e-6, 50e-6, 100e-6, 200e-6, 300e-6])
    lv, pr = design.recommend(PC, n_levels=2, candidates=cand)
    assert len(lv) == 2 and lv[0] < lv[1] and set(lv) <= set(cand)
    scan = design.scan_second_level(50e-6, PC, candidates=cand)
    assert pr.width["alpha"] <= 0.01 * scan["alpha width %"].min() * (1 + 1e-12)
    lv3, pr3 = design.recommend(PC, n_levels=3, candidates=cand)
    assert len(lv3) == 3 and pr3.width["alpha"] <= pr.width["alpha"]


def test_protocol_validation():
    with pytest.raises(ValueError, match="at least one compression level"):
        design.predict(design.Protocol(levels=()))
    with pytest.raises(ValueError, match="beyond the master table"):
        design.predict(design.Protocol(levels=(50e-6, 400e-6)))
    with pytest.raises(ValueError, match="noise"):
        design.predict(design.Protocol(noise=0.0))
    with pytest.raises(ValueError, match="sampling times"):
        design.predict(design.Protocol(times=(0.0, 1.0, 2.0)))


@pytest.mark.slow
def test_prediction_matches_the_fit_covariance():
    """A fit to one noisy record set of the same protocol: its Gauss-Newton sd (with the estimated noise; the
    white-noise error model, which the prediction assumes) agrees with the predicted sd to the sampling error of
    the noise estimate (~10 % for 140 points)."""
    from tissuemech.compare import fit
    from tissuemech.compare.studies import coverage

    truth = design.DEFAULT_TRUTH
    prot = dict(radius=PC.radius, levels=PC.levels, ramp_time=PC.ramp_time, times=PC.times)
    recs = coverage.add_noise(coverage.reduced_records(truth, prot), PC.noise, np.random.default_rng(3))
    res = fit.relaxation(recs, radius=PC.radius, ramp_time=PC.ramp_time, model_error=0.0)
    pred = design.predict(PC, truth)
    sd_fit = np.sqrt(np.diag(res.covariances["white"]))  # the Gauss-Newton covariance the Fisher matrix predicts
    for i, n in enumerate(design.NAMES):
        assert sd_fit[i] == pytest.approx(pred.sd[n], rel=0.3), n


def test_design_command_and_its_old_module_path(tmp_path, capsys):
    """``tissuemech design`` (and ``python -m tissuemech.compare.design``, a thin alias): the predicted widths, the
    best levels, the scan table and the figure; a bad --out stops before any computation."""
    from tissuemech.compare import design as old
    from tissuemech.compare.cli import main

    assert old.predict is design.predict and old.Protocol is design.Protocol
    out = tmp_path / "d.png"
    assert main(["design", "--first-um", "50", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "predicted 95 % width" in text and "best 2 level(s) for alpha" in text and "alpha width %" in text
    assert out.stat().st_size > 10_000
    assert old.main(["--out", str(tmp_path / "no" / "d.png")]) == 2
    assert "does not exist" in capsys.readouterr().err


@pytest.mark.slow
def test_fe_design_agrees_with_the_reduced_one_and_reaches_beyond_the_table():
    """``predict(model="fe")`` (the FE's exact sensitivities, coarse mesh, at the protocol's times) gives the
    reduced model's predicted sd where both exist (measured on the default protocol: C, beta, tau within 0.22 %,
    alpha within 1.4 %: the coarse mesh's alpha-dependence), and a prediction at alpha = 1.8 with a level at x = 0.45,
    which the reduced model refuses."""
    from tissuemech.compare.fit.design import Protocol, predict, scan_second_level

    pc = Protocol()
    red, fe = predict(pc), predict(pc, model="fe", mesh="coarse")
    for n, tol in dict(C=5e-3, alpha=3e-2, beta=5e-3, tau=5e-3).items():
        assert fe.sd[n] == pytest.approx(red.sd[n], rel=tol), (n, fe.sd[n], red.sd[n])
    stiff = dict(C=150.0, alpha=1.8, beta=0.4, tau=200.0)
    deep = Protocol(levels=(50e-6, 450e-6))
    with pytest.raises(ValueError, match="alpha"):
        predict(deep, stiff)
    pr = predict(deep, stiff, model="fe", mesh="coarse")
    assert all(0 < w < 0.5 for w in pr.width.values()), pr.width
    df = scan_second_level(50e-6, Protocol(), stiff, candidates=[250e-6, 450e-6], model="fe", mesh="coarse")
    assert list(df["second um"]) == pytest.approx([250.0, 450.0])
    assert df["alpha width %"].iloc[1] < df["alpha width %"].iloc[0]  # a deeper second level pins alpha better


def test_design_model_is_checked():
    from tissuemech.compare.fit.design import Protocol, predict, scan_second_level

    with pytest.raises(ValueError, match="model must be 'reduced'"):
        predict(Protocol(), model="exact")
    with pytest.raises(ValueError, match="model must be 'reduced'"):
        scan_second_level(50e-6, model="FE")


def test_design_command_truth_and_fe_options_are_checked(tmp_path, capsys):
    """``tissuemech design --truth``/``--model fe``: a malformed guess or --check with the FE stops in one line."""
    from tissuemech.compare.cli import main

    out = str(tmp_path / "d.png")
    assert main(["design", "--truth", "C=150", "alpha=x", "beta=0.4", "tau=200", "--out", out]) == 2
    assert "--truth 'alpha=x'" in capsys.readouterr().err
    assert main(["design", "--truth", "C=150", "alpha=0.2", "beta=0.4", "C=200", "--out", out]) == 2
    assert "each of C, alpha, beta, tau once" in capsys.readouterr().err
    assert main(["design", "--model", "fe", "--check", "3", "--out", out]) == 2
    assert "--check" in capsys.readouterr().err
