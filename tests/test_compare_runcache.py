"""The on-disk run cache (compare.runcache): a second call reads the stored result and the stored times; any change
of an input is a new key; prefetched runs are collected; uncacheable arguments run uncached."""

from __future__ import annotations

import concurrent.futures as cf
import threading

import numpy as np
import pytest

from tissuemech.compare import runcache

CALLS: list[dict] = []


def square(*, x, scale=1.0):
    CALLS.append(dict(x=x, scale=scale))
    factor = scale() if callable(scale) else scale if isinstance(scale, float) else 1.0
    return np.asarray(x) ** 2 * factor


@pytest.fixture()
def cache(tmp_path):
    with runcache.settings(tmp_path, True):
        CALLS.clear()
        yield tmp_path


def test_a_second_call_reads_the_result_and_the_times(cache):
    first = runcache.call(square, dict(x=np.arange(3.0)), repeats=2)
    recorded = first.walls  # the runs' own times, kept with the result (their values are not checked)
    assert not first.cached and len(recorded) == 2 and len(CALLS) == 2
    again = runcache.call(square, dict(x=np.arange(3.0)), repeats=2)
    same_record = again.walls == recorded
    assert again.cached and same_record and len(CALLS) == 2
    np.testing.assert_array_equal(again.result, [0.0, 1.0, 4.0])
    assert runcache.clear() == 1 and not runcache.call(square, dict(x=np.arange(3.0)), repeats=2).cached


def test_every_input_is_in_the_key(cache):
    base = runcache.key(square, dict(x=np.arange(3.0)))
    assert runcache.key(square, dict(x=np.arange(3.0))) == base
    for other in (
        dict(x=np.arange(3.0) + 1e-15 * np.arange(3.0)),
        dict(x=np.arange(3)),
        dict(x=np.arange(3.0), scale=2.0),
    ):
        assert runcache.key(square, other) != base
    assert runcache.key(square, dict(x=0.1)) != runcache.key(square, dict(x=0.1 + 1e-17 + 1e-16))


def test_off_and_uncacheable_run_every_time(cache):
    with runcache.settings(cache, False):
        runcache.call(square, dict(x=1.0))
        assert not runcache.call(square, dict(x=1.0)).cached
    assert not runcache.call(square, dict(x=1.0, scale=lambda: 1.0)).cached  # a callable: run, never cached
    n = len(CALLS)
    runcache.call(square, dict(x=2.0, scale=object()))
    runcache.call(square, dict(x=2.0, scale=object()))
    assert len(CALLS) == n + 2  # an argument without a faithful text form: never cached


def test_prefetched_runs_are_collected(cache):
    with cf.ThreadPoolExecutor(1) as pool:
        assert runcache.prefetch(pool, [(square, dict(x=3.0), 1)]) == 1
        got = runcache.call(square, dict(x=3.0))
    assert float(got.result) == 9.0 and len(CALLS) == 1
    assert runcache.call(square, dict(x=3.0)).cached
    runcache.cancel_pending()


def test_counts_say_where_each_run_came_from(cache):
    runcache.counts(reset=True)
    runcache.call(square, dict(x=3.0))
    runcache.call(square, dict(x=3.0))
    assert runcache.counts() == {"run here": 1, "cached": 1}
    assert runcache.counts(reset=True) and runcache.counts() == {}


STARTED = threading.Event()
RELEASE = threading.Event()


def blocking(*, x):
    """A run that starts over there and waits until the run that releases it has been done (here)."""
    STARTED.set()
    assert RELEASE.wait(20), "the release run never ran"
    return x


def release(*, x):
    CALLS.append(dict(x=x, thread=threading.get_ident()))
    RELEASE.set()
    return x


class AcceptingExecutor:
    """Accepts every run at once and marks it running, as a process pool's call queue does with the runs it takes
    ahead of its workers (they can no longer be cancelled), and runs them one after another in one thread."""

    def __init__(self):
        self.pool = cf.ThreadPoolExecutor(1)

    def submit(self, fn, /, *args, **kwargs):
        fut: cf.Future = cf.Future()
        fut.set_running_or_notify_cancel()

        def run():
            try:
                fut.set_result(fn(*args, **kwargs))
            except BaseException as exc:
                fut.set_exception(exc)

        self.pool.submit(run)
        return fut

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        RELEASE.set()  # a failed test must not leave the thread waiting
        self.pool.shutdown()


@pytest.mark.parametrize("executor", [lambda: cf.ThreadPoolExecutor(1), AcceptingExecutor], ids=["queue", "accepting"])
def test_waiting_for_a_run_in_progress_does_the_last_queued_runs_here(cache, executor):
    """While this process waits for a prefetched run that has started over there, it takes back the queued runs from
    the end of the queue (the farthest from starting there) and runs them itself; their own calls then return those
    results without running them again. The runs are handed over one per free worker, so that this holds also for an
    executor that accepts (and marks running) more runs than it runs."""
    STARTED.clear()
    RELEASE.clear()
    runcache.counts(reset=True)
    here = threading.get_ident()
    with executor() as pool:
        jobs = [(blocking, dict(x=1.0), 1), (release, dict(x=2.0), 1), (square, dict(x=3.0), 1)]
        assert runcache.prefetch(pool, jobs) == 3
        assert STARTED.wait(60)
        first = runcache.call(blocking, dict(x=1.0))  # running there: square, then release run here meanwhile
        assert first.result == 1.0 and not first.cached
        assert [c["x"] for c in CALLS] == [3.0, 2.0]  # from the back of the queue
        assert CALLS[1]["thread"] == here
        n = len(CALLS)
        assert float(runcache.call(square, dict(x=3.0)).result) == 9.0
        assert runcache.call(release, dict(x=2.0)).result == 2.0
        assert len(CALLS) == n  # taken back and run while waiting: not run again
    assert runcache.counts() == {"prefetched": 1, "taken back": 2, "run here": 2}
    runcache.cancel_pending()
