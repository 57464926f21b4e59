"""compare.batch.jobs: chunks of a points table, the array index, local points tables only, the functions a batch
may run, and what collect says about a store."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from tissuemech.compare import batch

HERE = Path(__file__).resolve().parent


def doubled(*, x: float) -> dict:
    """A user's own function (this test module is the user's code)."""
    return {"y": 2.0 * x}


def test_chunks_partition_the_points():
    n, N = 23, 5
    seen = sorted(i for k in range(N) for i in batch.chunk(n, k, N))
    assert seen == list(range(n))
    assert batch.chunk(n, 2, N) == [2, 7, 12, 17, 22]
    with pytest.raises(ValueError, match="--index"):
        batch.chunk(n, 5, N)


@pytest.mark.parametrize(
    "spec, match",
    [
        ("os:system", "standard library"),
        ("subprocess:run", "standard library"),
        ("builtins:eval", "standard library"),
        ("shutil:rmtree", "standard library"),
        ("numpy:sum", "not a Python function"),
        ("pandas:read_csv", "installed package"),
        ("tissuemech.compare.cli:main", "batches run only"),
        ("..x:f", "expected one of"),
        ("x:", "expected one of"),
        ("a b:f", "expected one of"),
        ("nowhere_at_all:f", "cannot be imported"),
        ("test_batch_jobs:nothing", "has no function 'nothing'"),
        ("test_batch_jobs:HERE", "not a Python function"),
    ],
)
def test_a_batch_runs_only_fe_points_and_the_users_own_functions(spec, match):
    with pytest.raises(ValueError, match=match) as info:
        batch.resolve_function(spec)
    assert repr(spec) in str(info.value) and "\n" not in str(info.value)


def test_the_users_function_is_named_in_a_warning():
    assert batch.resolve_function("fe-spheroid") is batch.fe_spheroid
    assert batch.resolve_function("tissuemech.compare.batch.points:fe_blastula") is batch.fe_blastula
    with pytest.warns(batch.UserFunctionWarning, match="every column of the points table becomes one of its keyword"):
        assert batch.resolve_function("test_batch_jobs:doubled") is doubled


def test_a_user_module_reexporting_a_stdlib_function_is_refused(tmp_path, monkeypatch):
    (tmp_path / "sneaky_mod.py").write_text("from subprocess import run as go\nfrom os import system\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ValueError, match="defined in subprocess"):
        batch.resolve_function("sneaky_mod:go")
    with pytest.raises(ValueError, match="not a Python function"):
        batch.resolve_function("sneaky_mod:system")


@pytest.mark.parametrize(
    "where, match",
    [
        ("http://example.org/points.csv", "a URL"),
        ("file:///etc/passwd", "a URL"),
        ("missing.csv", "no such file"),
    ],
)
def test_points_tables_are_local_files(tmp_path, where, match):
    path = where if "://" in where else tmp_path / where
    with pytest.raises(ValueError, match=match) as info:
        batch.read_points(path)
    assert "points table" in str(info.value) and str(path) in str(info.value)


def test_a_semicolon_table_is_named_as_such(tmp_path):
    f = tmp_path / "p.csv"
    f.write_text("C;alpha\n100;0.2\n")
    with pytest.raises(ValueError, match="separated by ';'") as info:
        batch.read_points(f)
    assert str(f) in str(info.value) and "'C,alpha'" in str(info.value)


@pytest.mark.parametrize(
    "env, want",
    [
        ({"SGE_TASK_ID": "0"}, "SGE_TASK_ID=0 is not a valid array index: SGE_TASK_ID counts from 1"),
        ({"LSB_JOBINDEX": "0"}, "LSB_JOBINDEX=0 is not a valid array index"),
        ({"SLURM_ARRAY_TASK_ID": "x"}, "SLURM_ARRAY_TASK_ID='x' is not an integer"),
    ],
)
def test_a_bad_array_index_names_its_variable(monkeypatch, env, want):
    for name, _ in batch.jobs.ARRAY_INDEX:
        monkeypatch.delenv(name, raising=False)
    for k, v in env.items():
        monkeypatch.setenv(k, v)
    with pytest.raises(ValueError) as info:
        batch.array_index()
    assert want in str(info.value) and "-1" not in str(info.value)


def test_array_index_of_each_scheduler(monkeypatch):
    for name, _ in batch.jobs.ARRAY_INDEX:
        monkeypatch.delenv(name, raising=False)
    assert batch.array_index() is None
    monkeypatch.setenv("SGE_TASK_ID", "1")
    assert batch.array_task() == (0, "SGE_TASK_ID")
    monkeypatch.setenv("SLURM_ARRAY_TASK_ID", "3")
    assert batch.array_task() == (3, "SLURM_ARRAY_TASK_ID")


def test_collect_with_the_wrong_function_says_what_the_store_holds(tmp_path):
    points = [dict(x=1.0), dict(x=2.0)]
    with pytest.warns(batch.UserFunctionWarning):
        fn = batch.resolve_function("test_batch_jobs:doubled")
    batch.run(fn, points, executor="serial", store=tmp_path / "s", progress=False)
    table = batch.collect(points, tmp_path / "s", fn)
    assert table["stored"].all() and list(table["y"]) == [2.0, 4.0]
    with pytest.raises(ValueError) as info:
        batch.collect(points, tmp_path / "s", batch.fe_spheroid)
    msg = str(info.value)
    assert "holds 2 results of test_batch_jobs.doubled" in msg and "fe_spheroid" in msg and str(tmp_path / "s") in msg
    # an empty (or new) store is no error: nothing is stored yet
    assert not batch.collect(points, tmp_path / "empty", fn)["stored"].any()


def test_collect_does_not_serve_a_file_copied_under_another_points_key(tmp_path):
    points = [dict(x=1.0), dict(x=2.0)]
    batch.run(doubled, points, executor="serial", store=tmp_path / "s", progress=False)
    a, b = (tmp_path / "s" / f"{batch.point_key(doubled, p)}.npz" for p in points)
    shutil.copy(a, b)
    with pytest.warns(batch.StoreWarning, match=f"{b.name} holds the result of"):
        table = batch.collect(points, tmp_path / "s", doubled)
    assert list(table["stored"]) == [True, False] and table["y"].iloc[0] == 2.0
