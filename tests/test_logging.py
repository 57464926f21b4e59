"""Library code does not print: messages go through module loggers, progress bars can be switched off."""

import ast
import logging
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
# command-line entry points may print (they configure the output); nothing else may
ENTRY_FUNCTIONS = {"main", "run_cli", "run"}
ENTRY_MODULES = {"scenes.py", "__main__.py"}  # scenes: the CLI's table printers


def _prints(path: Path):
    tree = ast.parse(path.read_text())
    out = []

    def visit(node, func):
        for child in ast.iter_child_nodes(node):
            f = child.name if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) else func
            if isinstance(child, ast.Call) and isinstance(child.func, ast.Name) and child.func.id == "print":
                # print(..., file=stream) to a stream the caller passed in is fine; bare print() is not
                if not any(k.arg == "file" for k in child.keywords):
                    out.append((child.lineno, func))
            visit(child, f)

    visit(tree, None)
    return out


def test_reduced_and_fem_never_print():
    found = [(p.name, ln) for d in ("reduced", "fem") for p in (ROOT / d).rglob("*.py") for ln, _ in _prints(p)]
    assert found == []


def test_compare_prints_only_in_entry_points():
    found = []
    for p in (ROOT / "compare").rglob("*.py"):
        if p.name in ENTRY_MODULES or "bench" in p.parts or "cli" in p.parts:
            continue  # command-line modules print their tables; benchmarks print their reports
        found += [(p.name, ln, f) for ln, f in _prints(p) if f not in ENTRY_FUNCTIONS]
    assert found == []


def test_fem_steps_go_to_the_logger_not_stdout(capsys, caplog):
    from tissuemech.fem.spheroid import compress

    with caplog.at_level(logging.DEBUG, logger="tissuemech.fem"):
        r = compress(
            radius=500e-6,
            C=150.0,
            alpha=0.2,
            branches=[(0.4, 200.0)],
            displacement=50e-6,
            ramp_time=0.2,
            end_time=100.0,
            mesh="coarse",
            n_hold=4,
        )
    steps = [
        rec for rec in caplog.records if rec.name == "tissuemech.fem.timestepping" and "converged" in rec.getMessage()
    ]
    assert len(steps) == len(r.time)
    assert np.allclose([float(rec.args[0]) for rec in steps], r.time)
    assert capsys.readouterr().out == ""


def test_load_cut_backs_are_logged(caplog):
    from tissuemech.fem.blastula import LimitPointError, inflate

    # neo-Hookean shell: the step past the limit point (197.41 Pa) fails and is cut back until it gives up
    with caplog.at_level(logging.DEBUG, logger="tissuemech.fem.continuation"):
        try:
            inflate(inner_radius=50e-6, outer_radius=75e-6, C=200.0, alpha=0.0, pressures=[100.0, 250.0], mesh=(2, 4))
        except LimitPointError:
            pass
        else:
            raise AssertionError("expected a LimitPointError")
    cuts = [rec.getMessage() for rec in caplog.records if "cut back" in rec.getMessage()]
    assert len(cuts) == 12  # max_cuts of load_control
    assert "Pa" in cuts[0]


def test_batch_progress_bar_can_be_switched_off(tmp_path, capsys):
    from tissuemech.compare import batch

    res = batch.run(dict, [dict(a=1.0), dict(a=2.0)], executor="serial", store=tmp_path, progress=False)
    assert [float(r["a"]) for r in res] == [1.0, 2.0]
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err == ""


def test_cut_back_steps_raise_no_runtime_warnings():
    import warnings

    from tissuemech.fem.blastula import inflate

    # large load steps: trial states whose residual overflows are cut back silently (no numpy warnings)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        r = inflate(
            inner_radius=50e-6,
            outer_radius=75e-6,
            C=200.0,
            alpha=0.2,
            pressures=np.linspace(100.0, 1000.0, 4),
            mesh=(2, 4),
        )
    assert r.inner_stretch[-1] > 3.0
