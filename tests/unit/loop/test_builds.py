"""Several builds at once (pydiag.loop.builds)."""

import threading

import pytest

from pydiag.loop.builds import each_built


def test_builds_run_side_by_side_and_come_back_in_the_items_order():
    both = threading.Barrier(2, timeout=10)  # broken unless two builds wait here at once

    def build(item: int) -> int:
        if item < 2:
            both.wait()
        return 10 * item

    assert each_built(build, [0, 1, 2, 3], n_jobs=2) == [0, 10, 20, 30]


def test_one_job_builds_one_after_the_other_in_this_thread():
    here = threading.get_ident()
    assert each_built(lambda item: threading.get_ident() == here, [1, 2], n_jobs=1) == [True, True]


def test_a_failed_build_is_raised_after_those_under_way_and_no_other_starts():
    started, ended = [], []
    release = threading.Event()

    def build(item: int) -> int:
        started.append(item)
        if item == 0:
            raise RuntimeError("no compiler")
        release.wait(5)  # item 1 is under way when item 0's error is raised
        ended.append(item)
        return item

    threading.Timer(0.5, release.set).start()
    with pytest.raises(RuntimeError, match="no compiler"):
        each_built(build, list(range(40)), n_jobs=2)
    assert ended and set(ended) <= set(started)  # what was under way ended first
    assert len(started) < 40  # the queue was dropped
