"""The `tissuemech` command: tables with the right physics, PNGs written, one-line errors."""

import re

import numpy as np
import pytest

from tissuemech.compare import cli
from tissuemech.compare.cli import blastula as cli_blastula


@pytest.fixture(autouse=True)
def _no_jit_cache_in_home(monkeypatch):
    """The commands would keep compiled programs in ~/.cache/tissuemech/jax: not from the tests."""
    monkeypatch.setenv(cli_blastula.JIT_CACHE_OPT_OUT, "1")


def test_jit_cache_is_opt_out_and_respects_a_user_choice(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert cli_blastula.enable_jit_cache() is None  # opted out (fixture)
    assert not (tmp_path / "tissuemech").exists()
    monkeypatch.setenv(cli_blastula.JIT_CACHE_OPT_OUT, "0")
    monkeypatch.setenv("JAX_COMPILATION_CACHE_DIR", str(tmp_path / "mine"))
    assert cli_blastula.enable_jit_cache() is None  # the user's own cache setting wins
    assert not (tmp_path / "tissuemech").exists()


def test_only_the_named_command_is_imported():
    assert cli._command_in(["-v", "blastula", "--step", "50"]) == "blastula"
    assert cli._command_in(["--version"]) is None and cli._command_in(["nosuch"]) is None
    sub = next(a for a in cli.build_parser("blastula")._actions if a.dest == "command")
    assert list(sub.choices) == ["blastula"]


def test_blastula_table_and_plot(tmp_path, capsys):
    out = tmp_path / "b.png"
    assert cli.main(["blastula", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert out.stat().st_size > 10_000
    # neo-Hookean limit for A = 50 um, B = 75 um, C = 200 Pa (exact shell): 197.41 Pa at lambda_a ~ 1.603
    assert re.search(r"a=1e-05, B=75 um: p_max = 197\.41 Pa at lambda_a = 1\.603", text)
    # alpha = 0.2, B = 75 um at 1 kPa: inner stretch 3.01223 (exact), outer 2.06471
    row = [ln for ln in text.splitlines() if ln.strip().startswith("1000.0")][0]
    assert "3.01223 / 2.06471" in row
    assert "burst" in [ln for ln in text.splitlines() if ln.strip().startswith("300.0")][0]
    # a step that does not divide the range: no row above --max-pressure (600 gave a 1200 Pa row)
    assert cli.main(["blastula", "--out", str(out), "--step", "600"]) == 0
    rows = [ln.split()[0] for ln in capsys.readouterr().out.splitlines() if ln[:9].strip().replace(".", "").isdigit()]
    assert "1200.0" not in rows and "600.0" in rows


def test_blastula_curves_solve_every_set_with_one_shape(monkeypatch):
    """Every Fig. 4/5 set goes through the inverse with the same array shape (one compiled program for
    the command, not one per set length: ``tissuemech blastula --step 50`` compiled the inverse twice); tables of up
    to ``ONE_POINT_ROWS`` rows take one-point calls (the program other commands compile too) and agree with the array
    path; the entries past a set's limit point are NaN, not a solution of the 0 Pa stand-in."""
    from tissuemech.reduced import blastula

    shapes = []
    real = blastula.inner_stretch

    def recording(p, **kw):
        shapes.append(np.shape(p))
        return real(p, **kw)

    monkeypatch.setattr(blastula, "inner_stretch", recording)
    curves = cli_blastula.blastula_curves(200.0, 50e-6, 1000.0, 10.0)  # 101 rows: one array call per set
    assert len(shapes) == len(curves) == 7 and set(shapes) == {(101,)}
    shapes.clear()
    few = cli_blastula.blastula_curves(200.0, 50e-6, 1000.0, 50.0)  # 21 rows: one-point calls
    assert 21 <= cli_blastula.ONE_POINT_ROWS < 101 and set(shapes) == {()}
    for c, f in zip(curves, few):
        np.testing.assert_allclose(f["inner_stretch"], c["inner_stretch"][::5], rtol=1e-13, atol=0)
    for cs in (curves, few):
        burst = [c for c in cs if c["limit"] is not None]
        assert burst and all(np.isnan(c["inner_stretch"][c["pressure"] >= c["limit"].pressure]).all() for c in burst)
        assert all(np.isfinite(c["inner_stretch"][c["pressure"] < c["limit"].pressure]).all() for c in burst)


def test_spheroid_table_and_plot(tmp_path, capsys):
    out = tmp_path / "s.png"
    assert cli.main(["spheroid", "--out", str(out), "--equilibrium", "hertz"]) == 0
    text = capsys.readouterr().out
    assert out.stat().st_size > 10_000
    # Hertz, Fig. 10 case: F(1500 s) ~ F_eq (1 + 0.4 e^-7.5) = 4.4731 uN
    row = [ln for ln in text.splitlines() if ln.split()[:1] == ["1500"]][0]
    assert float(row.split()[1]) == pytest.approx(4.47314, abs=1e-4)  # printed with 5 significant digits
    # a short ramp: every time readable (fixed 2 decimals printed 0.00 three times for a 1 ms ramp)
    assert cli.main(["spheroid", "--out", str(out), "--equilibrium", "hertz", "--ramp-time", "0.001"]) == 0
    times = [ln.split()[0] for ln in capsys.readouterr().out.splitlines()[2:5]]
    assert times == ["0.00025", "0.0005", "0.001"]


@pytest.mark.parametrize(
    "argv, match",
    [
        (["blastula", "--inner-radius-um", "80"], "--inner-radius-um 80 must be below 52 um"),
        (["spheroid", "--alpha", "5"], "--alpha 5 is outside the FE-calibrated table"),
        (["spheroid", "--end-time", "0.1"], "--end-time (0.1 s) must be >= --ramp-time (0.2 s)"),
        (["spheroid", "--displacement-um", "400"], "--equilibrium hertz"),
    ],
)
def test_bad_input_gives_one_line_error(tmp_path, capsys, argv, match):
    assert cli.main(argv + ["--out", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and match in err[0] and "Traceback" not in err[0]


def test_argparse_rejects_negative_modulus(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["spheroid", "--C", "-5"])
    assert e.value.code == 2
    assert "must be positive" in capsys.readouterr().err


def test_cli_has_report_subcommand(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["report", "--help"])
    assert exc.value.code == 0
    assert "--quick" in capsys.readouterr().out


def test_output_paths_are_checked_before_computing(tmp_path, capsys):
    folder = tmp_path / "adir"
    folder.mkdir()
    assert cli.main(["spheroid", "--out", str(folder)]) == 2
    assert "is a folder" in capsys.readouterr().err
    assert cli.main(["blastula", "--out", str(tmp_path / "missing" / "b.png")]) == 2
    assert "does not exist" in capsys.readouterr().err
    afile = tmp_path / "afile"
    afile.write_text("x")
    assert cli.main(["report", "--out", str(afile)]) == 2
    assert "exists and is a file" in capsys.readouterr().err
    # a name without an extension is written, and reported, as .png
    assert cli.main(["spheroid", "--equilibrium", "hertz", "--out", str(tmp_path / "noext")]) == 0
    assert f"wrote {tmp_path / 'noext.png'}" in capsys.readouterr().out
    assert (tmp_path / "noext.png").stat().st_size > 10_000


def test_version_and_bench_help_do_not_run_anything(capsys):
    import tissuemech

    with pytest.raises(SystemExit) as e:
        cli.main(["--version"])
    assert e.value.code == 0 and tissuemech.__version__ in capsys.readouterr().out
    assert cli.main(["bench", "fem-spheroid", "--help"]) == 0
    out = capsys.readouterr().out
    ran_nothing = "wall time min" not in out  # the help text only, no benchmark table
    assert "Benchmark of the FE spheroid" in out and ran_nothing


def test_bench_reference_json_needs_its_path_and_reference(capsys):
    """``--json PATH`` goes with ``--reference``; without the path or the flag the bench stops with exit code 2
    and says so (before computing anything)."""
    for argv in (["fem-spheroid", "--reference", "--json"], ["fem-spheroid", "--json", "ref.json"]):
        with pytest.raises(SystemExit) as e:
            cli.main(["bench", *argv])
        assert e.value.code == 2
        assert "--json PATH" in capsys.readouterr().err


def test_checks_cli_rejects_bad_options(capsys):
    for argv in (["--mesh", "bogus"], ["--spheroid-random", "-3"], ["--skip", "foo"]):
        with pytest.raises(SystemExit) as e:
            cli.main(["checks", *argv])
        assert e.value.code == 2
    assert "unknown table(s) foo" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv, match",
    [
        (["blastula", "--C", "nan"], "tissuemech blastula: error: argument --C: must be positive, got nan"),
        (["fit", "x.csv"], "tissuemech fit: error: the following arguments are required: --radius-um, --ramp-time"),
        (["spheroid", "--alpha", "nan"], "tissuemech spheroid: error: argument --alpha: must be a finite number"),
        (["bogus"], "tissuemech: error: argument COMMAND: invalid choice: 'bogus'"),
    ],
)
def test_argparse_errors_are_one_line(capsys, argv, match):
    """Every subcommand's bad arguments: one line, exit code 2 (argparse printed its usage block first: 4-7 lines)."""
    with pytest.raises(SystemExit) as e:
        cli.main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(match), err


@pytest.mark.parametrize("name", [n for n, _ in cli.COMMANDS])
def test_every_command_help_prints(name, capsys):
    """``tissuemech NAME --help`` prints its usage and exits 0 for every command (argparse %-formats help strings:
    a literal '%' in a help text, e.g. a scenario named 'misfit 0.5 %', crashed ``coverage --help``)."""
    with pytest.raises(SystemExit) as e:
        cli.main([name, "--help"])
    assert e.value.code == 0
    assert f"usage: tissuemech {name}" in capsys.readouterr().out


def test_console_script_returns_the_commands_exit_code(tmp_path):
    """The console script (``console_main``: ``main``, then the objects frozen out of the collector for a fast
    exit) keeps the command's exit code and its one-line error."""
    import subprocess
    import sys

    code = "import sys; from tissuemech.compare.cli import console_main; sys.exit(console_main())"
    run = subprocess.run(
        [sys.executable, "-c", code, "blastula", "--step", "2000", "--max-pressure", "1000"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert run.returncode == 2
    assert "--step 2000 Pa must not exceed --max-pressure 1000 Pa" in run.stderr
    ok = subprocess.run([sys.executable, "-c", code, "--version"], capture_output=True, text=True, cwd=tmp_path)
    assert ok.returncode == 0 and ok.stdout.strip()
