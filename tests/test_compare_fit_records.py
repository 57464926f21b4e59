"""compare.fit.records: the CSV reader (headers, units, separators, comments), forces turned into nominal stress,
and record errors that name the file."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tissuemech.compare import fit


def test_read_table_header_comments_and_separators(tmp_path):
    f = tmp_path / "a.csv"
    f.write_text("# displacement_um: 75\n# note = whatever\ntime_s;force_N\n0.1;1e-6\n0.2;2e-6\n\n0.3;3e-6\n")
    t = fit.read_table(f)
    assert t.header == ("time_s", "force_N") and t.values.shape == (3, 2) and t.meta["displacement_um"] == "75"
    assert t.lines == (4, 5, 7)
    g = tmp_path / "b.txt"
    g.write_text("0.1 1.0\n0.2\t2.0\n")
    assert fit.read_table(g).values.shape == (2, 2)


@pytest.mark.parametrize(
    "header, force",
    [
        ("time [s],stress [Pa]", False),
        ("time [s];force [N]", True),
        ("time [s]\tforce [N]", True),
        ("time [s] stress [Pa]", False),
        ("time [s]  force [N]", True),
        ("time_s,stress_Pa", False),
        ("time_s force_N", True),
    ],
)
def test_unit_bracket_headers_are_read(tmp_path, header, force):
    sep = "," if "," in header else (";" if ";" in header else ("\t" if "\t" in header else " "))
    f = tmp_path / "h.csv"
    f.write_text(header + "\n" + f"0.1{sep}1e-6\n0.2{sep}2e-6\n0.3{sep}3e-6\n")
    t = fit.read_table(f)
    assert len(t.header) == 2 and t.values.shape == (3, 2)
    assert t.header[0] in ("time [s]", "time_s")
    (rec,), forces = fit.load_records([str(f)], radius=500e-6, displacements=[100e-6], ramp_time=0.2)
    assert forces == [force]
    assert np.allclose(rec[0], [0.1, 0.2, 0.3])


def test_force_is_converted_with_the_incompressible_midplane(tmp_path):
    f = tmp_path / "force.csv"
    t = np.array([0.1, 0.2, 10.0])
    F = np.array([1e-6, 2e-6, 1.5e-6])
    f.write_text("time_s,force_N\n" + "".join(f"{a},{b}\n" for a, b in zip(t, F)))
    (rec,), forces = fit.load_records([str(f)], radius=500e-6, displacements=[100e-6], ramp_time=0.2)
    assert forces == [True]
    x = np.minimum(t / 0.2, 1.0) * 100e-6 / 1e-3
    assert np.allclose(rec[1], F / (math.pi * (500e-6 / np.sqrt(1 - x)) ** 2), rtol=1e-14)


@pytest.mark.parametrize(
    "header, t_si, y_si, force",
    [
        ("time_ms,stress_kPa", 1e-3, 1e3, False),
        ("time_s,force_mN", 1.0, 1e-3, True),
        ("t [s],F [uN]", 1.0, 1e-6, True),  # `tissuemech spheroid`'s own column names
        ("time (min); stress (Pa)", 60.0, 1.0, False),
        ("time,stress", 1.0, 1.0, False),  # known names without units: SI
    ],
)
def test_header_units_are_converted(tmp_path, header, t_si, y_si, force):
    """The header is where a file states its units: they are converted to SI, not dropped (a `time_ms,stress_kPa`
    file was fitted as s and Pa, `force_mN` as N, `F [uN]` as a stress in Pa, all with exit code 0)."""
    sep = ";" if ";" in header else ","
    f = tmp_path / "u.csv"
    f.write_text(header + "\n" + "".join(f"{a}{sep}{b}\n" for a, b in ((0.1, 3.0), (0.2, 6.0), (30.0, 5.0))))
    (rec,), forces = fit.load_records([str(f)], radius=500e-6, displacements=[100e-6], ramp_time=0.2)
    assert forces == [force]
    assert np.allclose(rec[0], np.array([0.1, 0.2, 30.0]) * t_si, rtol=1e-15)
    if not force:
        assert np.allclose(rec[1], np.array([3.0, 6.0, 5.0]) * y_si, rtol=1e-15)
    else:  # a force in N over the incompressible midplane area
        t = np.array([0.1, 0.2, 30.0]) * t_si
        x = np.minimum(t / 0.2, 1.0) * 100e-6 / 1e-3
        assert np.allclose(rec[1], np.array([3.0, 6.0, 5.0]) * y_si / (math.pi * (500e-6 / np.sqrt(1 - x)) ** 2))


def test_header_column_order_and_unknown_units(tmp_path):
    """Columns are taken by their header names (a `stress_Pa,time_s` file had its columns swapped); a unit the reader
    does not know, or a header contradicting --quantity, stops with one line naming the column."""
    ok = tmp_path / "ok.csv"
    ok.write_text("time_s,stress_Pa\n0.1,3\n0.2,6\n30,5\n")
    sw = tmp_path / "sw.csv"
    sw.write_text("stress_Pa,time_s\n3,0.1\n6,0.2\n5,30\n")
    kw = dict(radius=500e-6, displacements=[100e-6], ramp_time=0.2)
    (a,), _ = fit.load_records([str(ok)], **kw)
    (b,), _ = fit.load_records([str(sw)], **kw)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    bad = tmp_path / "bad.csv"
    bad.write_text("time [fortnights],stress [Pa]\n0.1,3\n0.2,6\n")
    with pytest.raises(ValueError, match=r"column 'time \[fortnights\]': unit 'fortnights' is not one"):
        fit.load_records([str(bad)], **kw)
    with pytest.raises(ValueError, match=r"--quantity force but the header names column 'stress_Pa' a stress"):
        fit.load_records([str(ok)], **kw, quantity="force")
    assert fit.read_csv(str(sw), displacement=1e-4, time_column="time_s", stress_column="stress_Pa").time[-1] == 30.0


def test_record_errors_name_the_file(tmp_path):
    """A file with one row, a constant or a tension-positive column is named in the message (the fit's own checks
    said "record 2")."""
    kw = dict(radius=500e-6, displacements=[100e-6], ramp_time=0.2)
    for body, match in (("0.1,3\n", "1 sample"), ("0.1,3\n0.2,3\n", "constant"), ("0.1,-3\n0.2,-4\n", "positive")):
        f = tmp_path / "r.csv"
        f.write_text("time_s,stress_Pa\n" + body)
        with pytest.raises(ValueError, match=rf"r\.csv: .*{match}"):
            fit.load_records([str(f)], **kw)


# ---------------------------------------------------------------- traps of lab-style files (issue 34)

KW = dict(radius=500e-6, displacements=[100e-6], ramp_time=5.0)


def _lab_record(n: int = 600, t_end: float = 1200.0, ramp: float = 5.0, seed: int = 0):
    """(time s, nominal stress Pa) of a relaxation record sampled like a lab instrument (uniform), 1 % noise."""
    from tissuemech.reduced import spheroid

    t = np.linspace(t_end / n, t_end, n)
    y = np.asarray(
        spheroid.nominal_stress(
            t, radius=500e-6, C=150.0, alpha=0.2, branches=[(0.4, 200.0)], displacement=100e-6, ramp_time=ramp
        )
    )
    return t, y * (1 + 0.01 * np.random.default_rng(seed).standard_normal(n))


def _write(path, header, rows, sep=",", crlf=True):
    nl = "\r\n" if crlf else "\n"
    text = (header + nl if header else "") + nl.join(sep.join(f"{v:.6g}" for v in r) for r in rows) + nl + nl
    path.write_bytes(text.encode())
    return str(path)


def test_lab_style_file_with_units_crlf_and_trailing_blank_line_is_read(tmp_path):
    """`time [min],force [uN]`, CRLF, a blank last line: minutes and micronewtons are converted to s and N."""
    t, y = _lab_record()
    F = y * math.pi * (500e-6) ** 2  # any force column will do: its conversion is what is checked
    f = _write(tmp_path / "lab.csv", "time [min],force [uN]", zip(t / 60, F * 1e6))
    (rec,), forces = fit.load_records([f], **KW)
    assert forces == [True] and np.allclose(rec[0], t, rtol=1e-5)


def test_time_running_backwards_names_file_line_column_and_swap(tmp_path):
    """A headerless file with the columns swapped (stress first: it falls as the tissue relaxes) was fitted with exit
    code 0 and success=True; now one line naming the file, the line, the column and the likely swap."""
    t, y = _lab_record()
    f = _write(tmp_path / "swapped.csv", "", zip(y[10:], t[10:]))
    with pytest.raises(ValueError) as exc:
        fit.load_records([f], **KW)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"{f}, line ")
    assert "time runs backwards in column 1 (no header)" in msg and "swapped" in msg
    with pytest.raises(ValueError, match=r"record 0: time runs backwards at sample 2 \(2 s, then 1 s\)"):
        fit.relaxation([(np.array([1.0, 2.0, 1.0]), np.array([1.0, 2.0, 3.0]), 1e-4)], radius=5e-4, ramp_time=1.0)


def test_duplicated_times_are_refused(tmp_path):
    f = _write(tmp_path / "dup.csv", "time_s,stress_Pa", [(0.1, 1.0), (0.2, 2.0), (0.2, 2.1), (0.3, 2.0)], crlf=False)
    with pytest.raises(
        ValueError, match=r"dup\.csv, lines 3 and 4: the time 0\.2 s appears twice in column 1 \('time_s'\)"
    ):
        fit.load_records([f], **KW)


def test_minutes_read_as_seconds_are_refused(tmp_path):
    """Minute times without a unit were read as seconds and fitted silently: the record then peaks early in the stated
    ramp and falls before its end, which no loading ramp does. With the unit in the header the same file is fine."""
    t, y = _lab_record()
    bad = _write(tmp_path / "minutes.csv", "time,stress", zip(t / 60, y))
    with pytest.raises(ValueError) as exc:
        fit.load_records([bad], **KW)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"{bad}: the stress peaks at t = ")
    assert "column 1 ('time')" in msg and "Minutes read as seconds" in msg and "'time [min]'" in msg
    good = _write(tmp_path / "minutes_ok.csv", "time [min],stress [Pa]", zip(t / 60, y))
    (rec,), _ = fit.load_records([good], **KW)
    assert np.allclose(rec[0], t, rtol=1e-5)
    # the other way round: milliseconds read as seconds keep rising long after the stated ramp
    ms = _write(tmp_path / "ms.csv", "time,stress", zip(t[t < 60] * 1000, y[t < 60]))
    with pytest.raises(ValueError, match=r"still rises until t = .*\(milliseconds read as seconds\?\)"):
        fit.load_records([ms], **KW)


def test_one_displacement_for_two_levels_is_refused(tmp_path):
    """One --displacement-um for the 50 and 200 um example files fitted both at 50 um and advised "add records at two
    or more compression levels"; their long-time stresses differ ~9-fold: one line saying what to give instead."""
    from pathlib import Path

    ex = Path(__file__).resolve().parents[1] / "examples" / "data"
    files = [str(ex / "spheroid_50um.csv"), str(ex / "spheroid_200um.csv")]
    with pytest.raises(ValueError) as exc:
        fit.load_records(files, radius=500e-6, displacements=[50e-6], ramp_time=0.2)
    msg = str(exc.value)
    assert "\n" not in msg and "--displacement-um 50 was given once for 2 files" in msg
    assert "spheroid_50um.csv" in msg and "spheroid_200um.csv" in msg and "--displacement-um D1 D2" in msg
    recs, _ = fit.load_records(files, radius=500e-6, displacements=[50e-6, 200e-6], ramp_time=0.2)
    assert [r[2] for r in recs] == [50e-6, 200e-6]


@pytest.mark.parametrize("sep", [";", "\t", " "])
def test_decimal_commas_are_named(tmp_path, sep):
    """`0,2;8,61` reported "ragged rows": now the file, the line, what decimal commas are and how to read them."""
    f = tmp_path / "comma.csv"
    f.write_bytes(f"time [min]{sep}force [uN]\r\n0,2{sep}8,61\r\n0,4{sep}8,59\r\n".encode())
    with pytest.raises(ValueError) as exc:
        fit.read_table(f)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"{f}, line 2: ")
    assert "decimal commas" in msg and "decimal=','" in msg
    # a plain comma-separated file, also with spaces after the commas, is no decimal-comma file
    g = tmp_path / "plain.csv"
    g.write_text("1, 2\n3, 4\n")
    assert fit.read_table(g).values.shape == (2, 2)
