"""`tissuemech scan`: value/range/list syntax, one-line errors before any computing, every promised file."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from fakes import fake_nominal_stress

from tissuemech.compare import batch, cli, scan
from tissuemech.compare.cli import scan as sc

C_OPT = [o for o in sc.SPHEROID_OPTIONS if o.name == "C"][0]
R_OPT = [o for o in sc.SPHEROID_OPTIONS if o.name == "radius"][0]
TAU_OPT = [o for o in sc.SPHEROID_OPTIONS if o.name == "tau"][0]


def test_parse_value_syntax():
    assert sc.parse_value("200", C_OPT).value == 200.0
    assert sc.parse_value("100:400", C_OPT) == (((100.0, 400.0)), False, "100:400")
    p = sc.parse_value("10:1000:log", TAU_OPT)
    assert p.value == (10.0, 1000.0) and p.log
    assert sc.parse_value("0,0.1,0.2", C_OPT).value == [0.0, 0.1, 0.2]
    lo, hi = sc.parse_value("400:600", R_OPT).value  # um on the command line, m in the scan
    assert lo == pytest.approx(400e-6, rel=1e-15) and hi == pytest.approx(600e-6, rel=1e-15)
    for bad, match in [
        ("400:100", "low end 400 must be below the high end 100"),
        ("abc", "not a number"),
        ("1:2:3", "LOW:HIGH"),
        ("1:inf", "finite"),
    ]:
        with pytest.raises(sc.ScanInputError, match=match):
            sc.parse_value(bad, C_OPT)
    with pytest.raises(sc.ScanInputError, match="positive low end"):
        sc.parse_value("0:10:log", TAU_OPT)


@pytest.mark.parametrize(
    "argv, match",
    [
        (["scan", "spheroid", "--C", "400:100"], "--C 400:100: the low end 400 must be below the high end 100 (Pa)"),
        (["scan", "spheroid", "--tau", "0:10:log"], "--tau 0:10:log: a log-scaled range needs a positive low end"),
        (["scan", "blastula", "--pressure", "1000:0"], "--pressure 1000:0"),
        (["scan", "spheroid", "--alpha", "0,0.1", "--design", "lhs"], "needs --design grid"),
        (["scan", "spheroid", "--n", "0"], "--n 0: must be at least 1"),
        (["scan", "blastula", "--map", "C,alpha"], "is not varied"),
        (["scan", "spheroid", "--alpha=-0.1:0.2", "--n", "3"], "alpha"),
        (["scan", "blastula", "--alpha", "0:0.3", "--n", "4", "--color-by", "bogus"], "--color-by bogus: choose from"),
        (["scan", "spheroid", "--C", "1e-320:1e-319"], "--C 1e-320:1e-319: 1e-320 is too small to compute with"),
        (["scan", "spheroid", "--radius-um", "1e-303"], "--radius-um 1e-303: 1e-303 is too small"),
        (["scan", "blastula", "--pressure=-1000:0"], "--pressure -1000:0: the largest pressure must be positive (Pa)"),
        (["scan", "blastula", "--pressure", "0"], "--pressure 0: the largest pressure must be positive (Pa)"),
    ],
)
def test_bad_input_one_line_exit_2(tmp_path, capsys, argv, match):
    out = tmp_path / "o"
    assert cli.main(argv + ["--out", str(out), "--no-progress"]) == 2
    assert not out.exists() or not any(out.iterdir())  # refused before anything is written
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and match in err[0] and "Traceback" not in err[0], err
    assert err[0].startswith("tissuemech scan ")


def test_bad_out_is_refused_before_computing(tmp_path, capsys):
    f = tmp_path / "a_file"
    f.write_text("keep me")
    assert cli.main(["scan", "blastula", "--out", str(f), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "exists and is not a folder" in err[0]
    assert f.read_text() == "keep me"
    assert cli.main(["scan", "blastula", "--out", str(f / "sub"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot write there" in err[0]


def test_argparse_errors_are_one_line_too(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["scan", "spheroid", "--design", "sobol"])
    assert e.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--design" in err[0]


def test_help_names_units(capsys):
    with pytest.raises(SystemExit):
        cli.main(["scan", "spheroid", "--help"])
    text = capsys.readouterr().out
    for s in ("Fung stiffness C (shear modulus 2C), Pa", "ball radius a0, um", "relaxation time", "LOW:HIGH:log"):
        assert s in " ".join(text.split()), s


def _fake_fe_blastula(*, inner_radius, outer_radius, C, alpha, pressure):
    """'FE' = the exact shell with a 2 % softer wall (in process: --fe-workers 0)."""
    from tissuemech.reduced import blastula as red

    la = red.inner_stretch(pressure, inner_radius=inner_radius, outer_radius=outer_radius, C=C, alpha=alpha)
    return {"inner_stretch": float(la) * 1.02}


PROMISED = ("table.csv", "scan.nc", "map.png", "curves.png", "sensitivity.png", "parity.png", "summary.md")


def test_blastula_command_writes_every_promised_file(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(batch.points, "fe_blastula", _fake_fe_blastula)
    out = tmp_path / "b"
    argv = ["scan", "blastula", "--alpha", "0.05:0.3", "--outer-radius-um", "55,75", "--pressure", "0:400"]
    argv += ["--design", "grid", "--n", "4", "--fe-checks", "3", "--fe-workers", "0", "--sens-points", "16"]
    assert cli.main(argv + ["--out", str(out), "--no-progress"]) == 0
    for f in PROMISED:
        assert (out / f).is_file() and (out / f).stat().st_size > 500, f
    df = pd.read_csv(out / "table.csv")
    assert len(df) == 4 * 2 * 4
    # the checked points are design points with the deviation of a 2 % offset
    chk = df[df["deviation [-]"].notna()]
    assert len(chk) == 3
    assert np.allclose(chk["deviation [-]"], 1 - 1 / 1.02, rtol=1e-9)
    assert (chk["pressure [Pa]"] > 0).all() and chk["inner_stretch [-]"].notna().all()
    with xr.open_dataset(out / "scan.nc") as ds:
        assert ds["inner_stretch"].dims == ("outer_radius", "alpha", "pressure")
        assert int(ds["deviation"].notnull().sum()) == 3
    md = (out / "summary.md").read_text()
    assert "FE spot-checks" in md and "Largest deviation" in md and "2.04 %" not in md
    assert f"{100 * (1 - 1 / 1.02):.3g} %" in md
    assert len(list((out / "fe_store").glob("*.npz"))) == 3  # resumable batch store
    assert "wrote" in capsys.readouterr().out


def _fake_fe_spheroid(*, radius, C, alpha, beta, tau, displacement, ramp_time, end_time):
    """'FE' = the reduced Hertz model of a 1 % stiffer ball (stress proportional to C)."""
    from tissuemech.reduced import spheroid as red

    t = scan.default_times(ramp_time, end_time)
    s = red.nominal_stress(
        t,
        radius=radius,
        C=1.01 * C,
        alpha=alpha,
        branches=[(beta, tau)],
        displacement=displacement,
        ramp_time=ramp_time,
        equilibrium="hertz",
    )
    return {"time": t, "nominal_stress": np.asarray(s)}


@pytest.mark.slow
def test_spheroid_command_writes_every_promised_file(tmp_path, monkeypatch):
    monkeypatch.setattr(batch.points, "fe_spheroid", _fake_fe_spheroid)
    out = tmp_path / "s"
    argv = ["scan", "spheroid", "--C", "100:300", "--tau", "20:500:log", "--displacement-um", "50"]
    argv += ["--equilibrium", "hertz", "--n", "40", "--fe-checks", "2", "--fe-workers", "0", "--sens-points", "8"]
    assert cli.main(argv + ["--out", str(out), "--no-progress", "--save-curves"]) == 0
    for f in PROMISED:
        assert (out / f).is_file() and (out / f).stat().st_size > 500, f
    df = pd.read_csv(out / "table.csv")
    assert len(df) == 40 and "sigma [Pa]" not in df.columns
    assert df["tau [s]"].between(20, 500).all() and np.allclose(df["displacement [m]"], 50e-6, rtol=1e-15)
    assert np.allclose(df["deviation [-]"].dropna(), 1 - 1 / 1.01, rtol=1e-6)
    with xr.open_dataset(out / "scan.nc") as ds:
        assert ds["sigma"].dims == ("point", "time")  # --save-curves
        assert np.allclose(ds["sigma"].max("time").values, df["sigma_peak [Pa]"].to_numpy(), rtol=1e-12)


def test_chunked_evaluation_equals_one_call():
    """Large designs go through the reduced model in equal chunks (plus the design's extreme rows, so
    every chunk compiles to the same evaluator): the table is the one of a single call."""
    pts = scan.design({"alpha": (0.05, 0.3), "C": (100.0, 300.0), "pressure": (0.0, 300.0)}, n=45, method="lhs")
    pts = pts.assign(inner_radius=50e-6, outer_radius=75e-6)[list(scan.BLASTULA_PARAMS)]
    direct = scan.blastula(points=pts)
    got = scan.evaluate_in_chunks(scan.blastula, pts, ["C", "alpha", "pressure"], {}, progress=False, chunk=16)
    pd.testing.assert_frame_equal(got, direct)
    df = scan.spheroid(C=(100.0, 300.0), tau=(10.0, 100.0), n=5, model=fake_nominal_stress, equilibrium="fake")
    sp_pts = df[[scan.column(k) for k in scan.SPHEROID_PARAMS]]
    sp_pts.columns = list(scan.SPHEROID_PARAMS)
    kw = dict(model=fake_nominal_stress, equilibrium="fake", curves=True)
    got = scan.evaluate_in_chunks(scan.spheroid, sp_pts, ["C", "tau"], kw, progress=False, stiff_row=0, chunk=16)
    want = scan.spheroid(points=sp_pts, **kw)
    pd.testing.assert_frame_equal(got.drop(columns="sigma [Pa]"), want.drop(columns="sigma [Pa]"))
    assert np.array_equal(got.attrs["time [s]"], want.attrs["time [s]"])


@pytest.mark.slow
def test_scan_fe_sensitivities_beyond_the_table(tmp_path):
    """``--fe-sensitivities N``: alpha 1.6-2.0 (beyond the plate table; the scan on the Hertz law) gets the FE's
    sensitivity chart next to the reduced one."""
    from tissuemech.compare.cli import main as cli_main

    out = tmp_path / "s"
    argv = "scan spheroid --alpha 1.6:2.0 --beta 0.4:1.0 --n 2 --design grid --equilibrium hertz --no-progress"
    assert cli_main([*argv.split(), "--fe-sensitivities", "2", "--out", str(out)]) == 0
    assert (out / "sensitivity_fe.png").stat().st_size > 10_000 and (out / "sensitivity.png").exists()
