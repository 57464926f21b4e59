"""`tissuemech fit --fit-surface-tension` / `--profile`: gamma from reduced-made relaxation records (1 % noise) with
an interval that covers the truth, a profile measurement in the likelihood, and the classic formula alone."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tissuemech.compare.cli import main
from tissuemech.compare.fit.tension import Profile, formula_tension, tension_relaxation
from tissuemech.reduced import drop
from tissuemech.reduced import spheroid as sph

A0, C, ALPHA = 175e-6, 170.0, 0.5  # S180 radius (m), C (Pa)
GAMMA = 6e-3  # N/m (elastocapillary number 0.2)
BRANCH = (2.0, 30.0)
TR = 1.0
LEVELS = (0.1, 0.2, 0.3)


def _records(seed: int = 3, noise: float = 0.01):
    t = np.r_[np.linspace(0.05, TR, 10), np.geomspace(1.2, 300.0, 40)]
    rng = np.random.default_rng(seed)
    out = []
    for x in LEVELS:
        d = 2 * A0 * x
        s = np.asarray(sph.nominal_stress(t, radius=A0, C=C, alpha=ALPHA, branches=[BRANCH], displacement=d,
                                          ramp_time=TR, surface_tension=GAMMA))  # fmt: skip
        out.append((t, s + noise * s.max() * rng.standard_normal(t.size), d))
    return out


def _write(tmp_path, recs):
    paths = []
    for k, (t, s, d) in enumerate(recs):
        p = tmp_path / f"level{k}.csv"
        rows = "\n".join(f"{a:.9g},{b:.9g}" for a, b in zip(t, s))
        p.write_text(f"# displacement_um: {d * 1e6:.9g}\ntime [s],stress [Pa]\n{rows}\n")
        paths.append(str(p))
    return paths


def _consistent_profile(recs):
    """Radii whose classic formula gives the true gamma at the last record's last sample (the drop's R1, R2, and R3
    set by the formula: a partly elastic aggregate's measured radii are not the drop's)."""
    t, s, d = recs[-1]
    r_mid = float(sph.midplane_radius(d, radius=A0, alpha=ALPHA, midplane="fem"))  # the records' midplane
    F = float(s[-1]) * np.pi * r_mid**2
    st = drop.compress(d, radius=A0, surface_tension=GAMMA)
    R1, R2 = st.meridional_radius, st.equatorial_radius
    R3 = np.sqrt(F / (np.pi * GAMMA * (1 / R1 + 1 / R2)))
    return R1, R2, R3


def test_formula_tension_is_exact_for_the_drop():
    st = drop.compress(0.3 * A0, radius=A0, surface_tension=GAMMA)
    g, sd = formula_tension(st.force, st.meridional_radius, st.equatorial_radius, st.contact_radius)
    assert abs(g / GAMMA - 1) < 1e-8 and sd == 0
    g, sd = formula_tension(st.force, st.meridional_radius, st.equatorial_radius, st.contact_radius, radius_sd=1e-6)
    # R3 enters squared (2 sd / R3); R1 and R2 add less (their weights in 1/R1 + 1/R2 sum to 1 / min(R1, R2))
    lead = 2e-6 / st.contact_radius
    assert lead < sd / g < 1.2 * lead
    with pytest.raises(ValueError, match="R3"):
        formula_tension(1e-6, 1e-4, 1e-4, -1.0)


@pytest.mark.slow
def test_profile_enters_the_likelihood():
    recs = _records()
    R1, R2, R3 = _consistent_profile(recs)
    base = tension_relaxation(recs, radius=A0, ramp_time=TR, alpha=ALPHA)
    fit = tension_relaxation(recs, radius=A0, ramp_time=TR, alpha=ALPHA, profile=Profile(R1, R2, R3, 0.5e-6))
    lo, hi = fit.intervals["gamma"]
    assert lo < GAMMA < hi
    assert hi / lo < base.intervals["gamma"][1] / base.intervals["gamma"][0]  # the profile adds information
    assert fit.profile is not None and abs(fit.profile["gamma_formula"] / GAMMA - 1) < 1e-9
    assert len(fit.diagnostics) == len(LEVELS)


@pytest.mark.slow
def test_cli_fits_gamma_with_interval_and_profile(tmp_path, capsys):
    recs = _records()
    paths = _write(tmp_path, recs)
    out = tmp_path / "out"
    argv = ["fit", *paths, "--radius-um", "175", "--ramp-time", "1", "--surface-tension", "0.004", "--alpha", "0.5",
            "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "gamma" in text and "lag-1 autocorrelation" in text
    d = json.loads((out / "fit.json").read_text())
    lo, hi = d["intervals"]["gamma"]
    assert lo < GAMMA < hi and hi / lo < 2.0
    assert (out / "fit.png").stat().st_size > 0
    R1, R2, R3 = (v * 1e6 for v in _consistent_profile(recs))
    assert main([*argv, "--profile", f"{R1},{R2},{R3}", "--profile-sd", "0.5", "--no-figure"]) == 0
    d2 = json.loads((out / "fit.json").read_text())
    lo2, hi2 = d2["intervals"]["gamma"]
    assert lo2 < GAMMA < hi2 and hi2 / lo2 < hi / lo
    assert d2["profile"]["z"] == pytest.approx(0.0, abs=3.0)


def test_cli_profile_alone_gives_the_formula_and_its_error(tmp_path, capsys):
    st = drop.compress(0.3 * A0, radius=A0, surface_tension=GAMMA)
    prof = tmp_path / "profile.csv"
    R = np.array([st.meridional_radius, st.equatorial_radius, st.contact_radius]) * 1e6
    prof.write_text("R1 [um],R2 [um],R3 [um]\n" + "\n".join(",".join(f"{v + e:.9g}" for v in R) for e in (-1, 0, 1)))
    out = tmp_path / "o"
    argv = ["fit", "--radius-um", "175", "--ramp-time", "1", "--profile", str(prof), "--profile-force-un",
            f"{st.force * 1e6:.12g}", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "classic formula" in text and "over-state" in text
    d = json.loads((out / "fit.json").read_text())
    g = d["params"]["gamma"]
    assert abs(g / GAMMA - 1) < 1e-3  # the rows' mean is the drop's radii
    lo, hi = d["intervals"]["gamma"]
    assert lo < GAMMA < hi
    assert d["sd"]["gamma"] > 0  # sd of the mean of the three rows (1 um apart)


def test_cli_profile_without_sd_or_force_is_one_line(tmp_path, capsys):
    assert main(["fit", "--radius-um", "175", "--ramp-time", "1", "--profile", "150,190,80"]) == 2
    assert "DATA.csv" in capsys.readouterr().err
    argv = ["fit", "--radius-um", "175", "--ramp-time", "1", "--profile", "150,190,80", "--profile-force-un", "0.3"]
    assert main(argv) == 2
    assert "--profile-sd" in capsys.readouterr().err
