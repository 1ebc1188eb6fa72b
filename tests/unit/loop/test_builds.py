"""Several builds at once (pydiag.loop.builds)."""

import threading
import time

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
    """Item 0 fails once item 1 is under way: the error is raised after item 1 (and any
    other started) has ended, and the queue is dropped. Each build after item 0 takes
    0.2 s, so the 40 would take 4 s on two threads: the drop has seconds, not a race."""
    started, ended = [], []
    one_under_way = threading.Event()

    def build(item: int) -> int:
        started.append(item)
        if item == 0:
            one_under_way.wait(10)
            raise RuntimeError("no compiler")
        one_under_way.set()
        time.sleep(0.2)
        ended.append(item)
        return item

    with pytest.raises(RuntimeError, match="no compiler"):
        each_built(build, list(range(40)), n_jobs=2)
    assert 1 in ended and sorted(ended) == sorted(set(started) - {0})  # none cut short
    assert len(started) < 40  # the queue was dropped
