"""`tissuemech fit`: the shipped SYNTHETIC example is recovered within its intervals; malformed files
give one line naming the file (and the line); --displacement-um and --out are checked before the fit."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tissuemech.compare.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "data"
TRUTH = dict(C=150.0, alpha=0.2, beta=0.4, tau=200.0)


def _one_line_error(capsys, argv, *needles):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0, err
    assert err.startswith("tissuemech fit: error:")
    for n in needles:
        assert n in err, (n, err)
    return err


@pytest.mark.parametrize(
    "content, needles",
    [
        (b"", ("empty",)),
        (b"# only a comment\n\n", ("empty",)),
        (b"time_s\n0.1\n0.2\n0.3\n", ("one column",)),
        (b"0.1,1.0\n0.2,2.0,3.0\n", ("line 2", "ragged")),
        (b"time_s,stress_Pa\n0.1,1.0\n0.2,abc\n", ("line 3", "column 2", "'abc' is not a number")),
        (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", ("binary",)),
        (b"0.1,nan\n", ("line 1", "not a finite number")),
        (b"-0.1,1.0\n0.2,2.0\n", ("line 1", "negative")),
        (b"time [min];force [uN]\r\n0,2;8,61\r\n0,4;8,59\r\n\r\n", ("line 2", "decimal commas", "decimal=','")),
        (b"8.61,0.2\n8.59,0.4\n8.57,0.6\n", ("line 2", "time runs backwards in column 1", "swapped")),
        (b"0.1,1.0\n0.1,2.0\n0.2,2.5\n", ("lines 1 and 2", "appears twice")),
    ],
)
def test_malformed_files_one_line(tmp_path, capsys, content, needles):
    f = tmp_path / "bad.csv"
    f.write_bytes(content)
    _one_line_error(
        capsys,
        ["fit", str(f), "--radius-um", "500", "--displacement-um", "50", "--ramp-time", "0.2"],
        "bad.csv",
        *needles,
    )


def test_missing_file_and_displacement_count(tmp_path, capsys):
    _one_line_error(
        capsys,
        ["fit", str(tmp_path / "nope.csv"), "--radius-um", "500", "--displacement-um", "50", "--ramp-time", "0.2"],
        "nope.csv",
    )
    a = EXAMPLES / "spheroid_50um.csv"
    b = EXAMPLES / "spheroid_200um.csv"
    _one_line_error(
        capsys,
        ["fit", str(a), str(b), "--radius-um", "500", "--displacement-um", "50", "60", "70", "--ramp-time", "0.2"],
        "one per file",
    )
    g = tmp_path / "nodisp.csv"
    g.write_text("0.1,1\n0.2,2\n0.3,3\n")
    _one_line_error(capsys, ["fit", str(g), "--radius-um", "500", "--ramp-time", "0.2"], "no displacement")


@pytest.mark.slow
def test_example_recovered_within_intervals(tmp_path, capsys):
    out = tmp_path / "res"
    files = [str(EXAMPLES / "spheroid_50um.csv"), str(EXAMPLES / "spheroid_200um.csv")]
    assert main(["fit", *files, "--radius-um", "500", "--ramp-time", "0.2", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Identifiability" in text and "95% statement" in text
    d = json.loads((out / "fit.json").read_text())
    assert d["success"] and np.allclose(d["inputs"]["displacement_m"], [50e-6, 200e-6], rtol=1e-12)
    for k, v in TRUTH.items():
        lo, hi = d["intervals_95"][k]
        assert lo <= v <= hi, (k, lo, v, hi)
        if k != "alpha":  # with the FE table's model-error term two levels may bound alpha from above only
            assert d["interval_kinds"][k] == "two-sided"
    assert (out / "fit.png").stat().st_size > 10_000


def test_repeated_displacement_option_and_out_checked_first(tmp_path, capsys):
    """`--displacement-um 50 --displacement-um 200` gives both values (the last one alone was kept: both files fitted
    at 200 um); an --out that is a file stops before the fit (it printed the fit, then failed to write)."""
    files = [str(EXAMPLES / "spheroid_50um.csv"), str(EXAMPLES / "spheroid_200um.csv")]
    base = ["fit", *files, "--radius-um", "500", "--ramp-time", "0.2", "--no-figure"]
    afile = tmp_path / "afile"
    afile.write_text("x")
    assert main([*base, "--out", str(afile)]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and "--out" in cap.err and "is a file" in cap.err
    out = tmp_path / "res"
    assert main([*base, "--displacement-um", "50", "--displacement-um", "200", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "residuals of record 1: lag-1 autocorrelation" in printed and "residuals of record 2" in printed
    saved = json.loads((out / "fit.json").read_text())
    assert saved["inputs"]["displacement_m"] == pytest.approx([50e-6, 200e-6])
    assert len(saved["residual_diagnostics"]) == 2 and saved["errors"] == "robust"
    # one displacement for the two levels: refused before the fit, saying what to give
    err = _one_line_error(capsys, [*base, "--displacement-um", "50", "--out", str(out)], "given once for 2 files")
    assert "--displacement-um D1 D2" in err


def test_old_fit_cli_module_is_an_alias():
    """``tissuemech.compare.fit_cli`` (the reader and the command before the fit package) still imports."""
    from tissuemech.compare import fit, fit_cli
    from tissuemech.compare.cli import fit as command

    assert fit_cli.read_table is fit.read_table and fit_cli.load_records is fit.load_records
    assert fit_cli.add_parser is command.add_parser and fit_cli.run is command.run


def test_fe_model_says_what_it_does_not_support(tmp_path, capsys):
    """`--model fe` refuses, before any FE run, what its path does not fit yet (each in one line saying what to do):
    force files, creep/history files, the Hertz law, a model-error or misfit term, a malformed --initial."""
    files = [str(EXAMPLES / "spheroid_50um.csv"), str(EXAMPLES / "spheroid_200um.csv")]
    base = ["fit", *files, "--radius-um", "500", "--ramp-time", "0.2", "--model", "fe", "--out", str(tmp_path / "o")]
    _one_line_error(capsys, [*base, "--equilibrium", "hertz"], "--model fe does not support", "--model reduced")
    _one_line_error(capsys, [*base, "--misfit", "0.002"], "--misfit")
    _one_line_error(capsys, [*base, "--initial", "C=150", "alpha=0.2"], "--initial", "missing ['beta', 'tau']")
    _one_line_error(capsys, [*base, "--initial", "C150"], "NAME=VALUE")
    force = tmp_path / "force.csv"
    force.write_text("time [s], force [uN]\n0.1,1.0\n0.2,2.0\n1,1.5\n10,1.2\n100,1.1\n")
    _one_line_error(
        capsys,
        ["fit", str(force), "--radius-um", "500", "--ramp-time", "0.2", "--displacement-um", "50", "--model", "fe"],
        "nominal stress",
        "force.csv",
    )
    creep = tmp_path / "creep.csv"
    creep.write_text("time [s], approach [um], force [uN]\n0.1,1,1\n0.2,2,2\n1,2.1,2\n10,2.2,2\n100,2.3,2\n")
    _one_line_error(capsys, ["fit", str(creep), "--radius-um", "500", "--ramp-time", "0.2", "--model", "fe"], "creep")
    # --initial belongs to the FE path
    _one_line_error(capsys, [*base[:-4], "--initial", "C=1", "alpha=1", "beta=1", "tau=1"], "--initial", "--model fe")


@pytest.mark.slow
def test_fe_model_recovers_fe_made_records_off_the_table(tmp_path, capsys):
    """`tissuemech fit --model fe` on two FE-made CSV records at alpha = 1.8 (off the plate table; coarse mesh, 1 %
    noise, at the FE's step times), started from the reduced fit (alpha at its bound 1.5): every 95 % interval holds
    the truth; fit.json (model "fe", the reduced fit's format), fit.png and one progress line per FE evaluation."""
    from tissuemech.compare.fit import step_times
    from tissuemech.fem import spheroid as fs

    truth = dict(C=150.0, alpha=1.8, beta=0.6, tau=30.0)
    rng = np.random.default_rng(3)
    files = []
    for d in (20.0, 40.0):
        r = fs.compress(radius=100e-6, C=150.0, alpha=1.8, branches=[(0.6, 30.0)], displacement=d * 1e-6,
                        ramp_time=1.0, end_time=300.0, mesh="coarse", contact="nodal", n_ramp=6, n_hold=20)  # fmt: skip
        np.testing.assert_allclose(r.time, step_times(ramp_time=1.0, end_time=300.0))
        y = r.nominal_stress * (1 + 0.01 * rng.standard_normal(r.time.size))
        f = tmp_path / f"fe_{d:g}um.csv"
        f.write_text(
            f"# displacement_um: {d:g}\ntime [s], stress [Pa]\n"
            + "".join(f"{a:.17g},{b:.17g}\n" for a, b in zip(r.time, y))
        )
        files.append(str(f))
    out = tmp_path / "res"
    argv = ["fit", *files, *"--radius-um 100 --ramp-time 1 --model fe --mesh coarse".split(), "--out", str(out)]
    assert main(argv) == 0
    cap = capsys.readouterr()
    assert "starting from the reduced fit's estimate" in cap.out and "Identifiability" in cap.out
    assert "model: the FE" in cap.out and "FE evaluation 1:" in cap.err
    d = json.loads((out / "fit.json").read_text())
    assert d["model"] == "fe" and d["inputs"]["mesh"] == "coarse" and d["success"]
    assert d["inputs"]["contact"] == "nodal" and d["contact"] == "nodal"  # the default: node-by-node contact
    for k, v in truth.items():
        lo, hi = d["intervals_95"][k]
        assert lo <= v <= hi and hi / lo < 1.2, (k, lo, v, hi)
    assert (out / "fit.png").stat().st_size > 10_000
