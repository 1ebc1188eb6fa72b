"""Fits side by side (discover's, validation's on a machine) stop when their process is
stopped: Ctrl-C or SIGTERM in the main process ends the workers now, not after every fit
still queued."""

import os
import signal
import time
from pathlib import Path

import pytest
from conftest import alive, children

from pydiag.fit.estimator import FaultEstimator
from pydiag.loop.discover import side_by_side


class Stop(BaseException):
    """What the command's SIGTERM handler raises (a BaseException, as Ctrl-C's)."""


#: The processes running when the stop landed.
RUNNING: set[int] = set()


def _raise_stop(signum, frame):
    RUNNING.update(children(os.getpid()))
    raise Stop


@pytest.mark.skipif(not (hasattr(signal, "setitimer") and Path("/proc/self/task").exists()),
                    reason="needs POSIX timers and Linux /proc")
def test_a_stop_in_the_main_process_ends_the_fits_side_by_side_at_once():
    before = children(os.getpid())
    RUNNING.clear()
    previous = signal.signal(signal.SIGALRM, _raise_stop)
    started = time.monotonic()
    signal.setitimer(signal.ITIMER_REAL, 1.0)  # the stop lands while four 30 s tasks run
    try:
        with pytest.raises(Stop):
            side_by_side(lambda task, one: (time.sleep, (task,)), [30.0] * 4,
                         FaultEstimator(n_workers=2), None)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    took = time.monotonic() - started
    workers = RUNNING - before
    end = time.monotonic() + 10
    while any(alive(p) for p in workers) and time.monotonic() < end:
        time.sleep(0.05)
    assert took < 10, took  # the queue would have taken 60 s
    assert len(workers) == 2 and not [p for p in workers if alive(p)], workers
