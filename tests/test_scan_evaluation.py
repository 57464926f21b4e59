"""compare.scan: designs, vmapped reduced evaluation against direct calls, FE spot-check columns."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from fakes import fake_nominal_stress

from tissuemech.compare import scan


def test_design_grid_random_lhs():
    g = scan.design({"C": (100.0, 300.0), "alpha": [0.0, 0.2], "tau": 5.0}, n=3, method="grid")
    assert len(g) == 6 and set(g["C"]) == {100.0, 200.0, 300.0} and set(g["tau"]) == {5.0}
    lh = scan.design({"C": (100.0, 300.0), "tau": (1.0, 1000.0)}, n=50, method="lhs", log=("tau",))
    # Latin hypercube: exactly one point per stratum in each coordinate
    assert sorted(np.floor((lh["C"] - 100) / 200 * 50).astype(int)) == list(range(50))
    assert sorted(np.floor(np.log10(lh["tau"]) / 3 * 50).astype(int)) == list(range(50))
    r = scan.design({"C": (100.0, 300.0)}, n=100, method="random", seed=1)
    assert r["C"].between(100, 300).all() and r["C"].std() > 30
    with pytest.raises(ValueError, match="low <= high"):
        scan.design({"C": (3.0, 1.0)}, n=2)
    with pytest.raises(ValueError, match="grid"):
        scan.design({"C": [1.0, 2.0]}, n=2, method="lhs")
    with pytest.raises(ValueError, match="log scale"):
        scan.design({"tau": (0.0, 1.0)}, n=2, log=("tau",))


def test_spheroid_scan_matches_direct_model():
    df = scan.spheroid(
        C=(100.0, 300.0),
        alpha=(0.0, 0.3),
        beta=(0.1, 1.0),
        tau=(10.0, 500.0),
        n=3,
        model=fake_nominal_stress,
        equilibrium="fake",
        batch_size=16,
        curves=True,
    )
    assert len(df) == 81
    assert {"C [Pa]", "sigma_peak [Pa]", "sigma_end [Pa]", "relaxed_fraction [-]", "t_half [s]"} <= set(df.columns)
    t = df.attrs["time [s]"]
    for i in (0, 40, 80):  # last batch is padded: check rows in every batch
        row = df.iloc[i]
        s = np.asarray(
            fake_nominal_stress(
                t,
                radius=row["radius [m]"],
                C=row["C [Pa]"],
                alpha=row["alpha [-]"],
                branches=[(row["beta [-]"], row["tau [s]"])],
                displacement=row["displacement [m]"],
                ramp_time=row["ramp_time [s]"],
            )
        )
        assert np.allclose(row["sigma [Pa]"], s, rtol=1e-13)
        assert row["sigma_peak [Pa]"] == pytest.approx(s.max(), rel=1e-13)
        assert row["sigma_end [Pa]"] == pytest.approx(s[-1], rel=1e-13)
        # half-relaxation time of a single branch after a fast ramp ~ tau ln 2 (if the hold is long enough)
        if row["tau [s]"] < 200:
            assert row["t_half [s]"] - 0.2 == pytest.approx(row["tau [s]"] * np.log(2), rel=0.05)
    # elastic-limit physics: peak/end = 1 + beta (fast ramp, long hold relative to tau)
    fast = df[df["tau [s]"] == 10.0]
    assert np.allclose(fast["sigma_peak [Pa]"] / fast["sigma_end [Pa]"], 1 + fast["beta [-]"], rtol=2e-2)


def test_spheroid_curves_run_in_blocks_with_each_rows_values():
    # 1225 curves in one call run as blocks of scan.BLOCK (512) and a remainder (201): each row its own curve
    assert scan.BLOCK == 512
    df = scan.spheroid(
        C=(100.0, 300.0), tau=(10.0, 500.0), n=35, model=fake_nominal_stress, equilibrium="fake", batch_size=1225,
        curves=True,
    )  # fmt: skip
    assert len(df) == 1225
    t = df.attrs["time [s]"]
    for i in (0, 511, 512, 1023, 1024, 1224):
        row = df.iloc[i]
        s = fake_nominal_stress(
            t, radius=row["radius [m]"], C=row["C [Pa]"], alpha=row["alpha [-]"],
            branches=[(row["beta [-]"], row["tau [s]"])], displacement=row["displacement [m]"],
            ramp_time=row["ramp_time [s]"],
        )  # fmt: skip
        assert np.allclose(row["sigma [Pa]"], np.asarray(s), rtol=1e-13)


def test_blastula_scan_exact_and_bursts():
    from tissuemech.reduced import blastula as red

    df = scan.blastula(alpha=[1e-5, 0.2], outer_radius=[60e-6, 75e-6], pressure=(0.0, 150.0), n=16)
    assert len(df) == 64
    ok = ~df["bursts [-]"]
    # round trip: p(lambda_a) reproduces the scanned pressure where the shell holds
    p = red.pressure(
        df.loc[ok, "inner_stretch [-]"].to_numpy(),
        inner_radius=df.loc[ok, "inner_radius [m]"].to_numpy(),
        outer_radius=df.loc[ok, "outer_radius [m]"].to_numpy(),
        C=df.loc[ok, "C [Pa]"].to_numpy(),
        alpha=df.loc[ok, "alpha [-]"].to_numpy(),
    )
    assert np.allclose(np.asarray(p), df.loc[ok, "pressure [Pa]"], rtol=1e-9, atol=1e-9)
    # bursting exactly where the pressure exceeds the limit pressure
    lim = df["p_limit [Pa]"].to_numpy()
    assert np.array_equal(df["bursts [-]"].to_numpy(), np.nan_to_num(lim, nan=np.inf) < df["pressure [Pa]"].to_numpy())
    assert df["bursts [-]"].any() and (~df["bursts [-]"]).any()
    assert (df.loc[ok, "outer_stretch [-]"] <= df.loc[ok, "inner_stretch [-]"] + 1e-15).all()


def test_validation():
    with pytest.raises(ValueError, match="inner_radius must be smaller"):
        scan.blastula(inner_radius=80e-6, outer_radius=75e-6, pressure=10.0, n=1)
    with pytest.raises(ValueError, match="alpha"):
        scan.spheroid(alpha=(-0.1, 0.2), n=2, model=fake_nominal_stress)


def test_spheroid_scan_with_reduced_model():
    from tissuemech.reduced import spheroid as red

    df = scan.spheroid(C=(100.0, 300.0), beta=(0.1, 1.0), n=3, curves=True, batch_size=4, rtol=1e-10)
    fast = scan.spheroid(C=(100.0, 300.0), beta=(0.1, 1.0), n=3, curves=True, batch_size=4)  # default rtol 1e-6
    for a, b in zip(df["sigma [Pa]"], fast["sigma [Pa]"]):
        assert np.max(np.abs(a - b)) < 1e-5 * np.max(a)
    t = df.attrs["time [s]"]
    for i in (0, 8):
        row = df.iloc[i]
        s = np.asarray(
            red.nominal_stress(
                t,
                radius=row["radius [m]"],
                C=row["C [Pa]"],
                alpha=row["alpha [-]"],
                branches=[(row["beta [-]"], row["tau [s]"])],
                displacement=row["displacement [m]"],
                ramp_time=row["ramp_time [s]"],
            )
        )
        assert np.allclose(row["sigma [Pa]"], s, rtol=1e-8)  # jit (Kvaerno5) vs eager (Tsit5), both at rtol 1e-10


def test_user_design_points():
    pts = {"C [Pa]": [100.0, 250.0], "alpha": [0.0, 0.3]}
    df = scan.spheroid(points=pts, model=fake_nominal_stress, tau=20.0)
    ref = scan.spheroid(C=[100.0, 250.0], alpha=[0.0, 0.3], tau=20.0, model=fake_nominal_stress)
    ref = ref[
        ((ref["C [Pa]"] == 100.0) & (ref["alpha [-]"] == 0.0)) | ((ref["C [Pa]"] == 250.0) & (ref["alpha [-]"] == 0.3))
    ]
    assert np.allclose(df["sigma_end [Pa]"].to_numpy(), ref["sigma_end [Pa]"].to_numpy(), rtol=1e-13)
    with pytest.raises(ValueError, match="unknown columns"):
        scan.blastula(points={"E": [1.0]})
    with pytest.raises(ValueError, match="single number"):
        scan.spheroid(points={"C": [1.0]}, alpha=(0.0, 0.1), model=fake_nominal_stress)


def test_scan_flags_bursts_above_the_limit_pressure():
    from tissuemech.compare import scan

    pts = pd.DataFrame(dict(inner_radius=50e-6, outer_radius=52.84e-6, C=200.0, alpha=0.0357, pressure=[10.0, 962.8]))
    t = scan.blastula(points=pts)
    p_lim = t["p_limit [Pa]"].to_numpy()
    assert list(t["bursts [-]"]) == [False, True] and np.all(p_lim > 10.0) and np.all(p_lim < 962.8)


def test_blastula_scan_bursts_only_past_the_limit_pressure():
    """Where the compiled inverse leaves NaN below the limit pressure (its one-panel rule untrusted: thick shells at
    high pressure), the scan solves eagerly; only a pressure at or above the limit pressure is a burst (these thick
    shells were reported as bursting although they have no limit point)."""
    from tissuemech.reduced import blastula as red

    pts = dict(
        inner_radius=[50e-6] * 4,
        outer_radius=[500e-6, 500e-6, 75e-6, 196.4e-6],
        C=[200.0] * 4,
        alpha=[0.2, 0.2, 1e-5, 0.0428],
        pressure=[1e4, 2e4, 300.0, 3e4],
    )
    df = scan.blastula(points=pts)
    la = df["inner_stretch [-]"].to_numpy()
    eager = red.inner_stretch([1e4, 2e4], inner_radius=50e-6, outer_radius=500e-6, C=200.0, alpha=0.2)
    assert np.allclose(la[:2], eager, rtol=1e-12) and np.isnan(df["p_limit [Pa]"].to_numpy()[:2]).all()
    assert np.allclose(
        df["outer_stretch [-]"].to_numpy()[:2], red.outer_stretch(eager, inner_radius=50e-6, outer_radius=500e-6)
    )
    # neo-Hookean 75 um shell at 300 Pa: past its limit pressure (197.4 Pa): bursts
    assert np.isnan(la[2]) and df["bursts [-]"].to_numpy()[2] and df["p_limit [Pa]"].to_numpy()[2] < 300.0
    # no limit point, but the state lies beyond the largest stretch searched (10): NaN, and it does not burst
    assert np.isnan(la[3]) and not df["bursts [-]"].to_numpy()[3]
    assert list(df["bursts [-]"]) == [False, False, True, False]


@pytest.mark.parametrize(
    "scene, kw, match",
    [
        ("spheroid", dict(C=(1e-320, 1e-319)), r"^C \(Pa\) is 1e-320 at point 0: below the smallest normal float64"),
        ("spheroid", dict(displacement=1e-310, radius=1e-309), r"^radius \(m\) is 1e-309"),
        ("blastula", dict(pressure=(0.0, 1e-310)), r"^pressure \(Pa\) is .* below the smallest normal float64"),
    ],
)
def test_denormal_parameters_are_refused(scene, kw, match):
    """C = 1e-320 Pa gave zero stresses and NaN summaries without a word."""
    fn = scan.spheroid if scene == "spheroid" else scan.blastula
    with pytest.raises(ValueError, match=match):
        fn(n=2, **kw)
    assert scan.check_normal(pd.DataFrame({"C": [0.0, 200.0, scan.TINY]})) is None  # zero and TINY are fine


def test_underflowing_stresses_are_refused():
    """Normal numbers whose products underflow (a 1e-160 m ball: area 1e-320 m^2) give no stress: an error, not NaN."""
    with pytest.raises(
        ValueError, match=r"peak nominal stress of nan Pa at 1 of 1 points, e.g. point 0 \(radius=1e-160 m"
    ):
        scan.spheroid(radius=1e-160, displacement=1e-161, equilibrium="hertz", n=1)
