"""SIGTERM unwinds the process once: a TERM during the cleanup waits for it; a TERM after
one Python dropped (its exception raised in a finaliser) unwinds it again."""

import signal
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pytest

from pydiag.core.termination import stop_pool

CODE = """
import os, signal, time
from pydiag.app import batch, cli
signal.signal(signal.SIGTERM, {handler})

class Finaliser:
    def __del__(self):  # a TERM here raises where Python drops the exception
        os.kill(os.getpid(), signal.SIGTERM)
        for _ in range(10000):
            pass

Finaliser()
print("dropped")
try:
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(1)
    print("not raised")
except {raised}:
    os.kill(os.getpid(), signal.SIGTERM)  # in the cleanup
    time.sleep(0.2)
    print("cleaned up")
"""


@pytest.mark.parametrize("handler, raised", [
    ("batch._worker_terminated", "batch._WorkerTerminated"),  # a local batch worker: the
    # executor's TERM once another worker has ended, and the parent's death signal, follow
    ("cli._raise_terminated", "cli.Terminated"),  # the command: a supervisor's second TERM
])
def test_a_term_unwinds_once_and_again_after_a_dropped_one(handler, raised):
    res = subprocess.run([sys.executable, "-c", CODE.format(handler=handler, raised=raised)],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr[-300:]
    assert res.stdout.split() == ["dropped", "cleaned", "up"], res.stdout
    assert "Exception ignored" in res.stderr  # the first one was dropped indeed


def _deaf(marker: str) -> None:
    """A task whose worker does not end on SIGTERM (as when Python dropped it)."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    Path(marker).touch()
    time.sleep(120)


def test_a_worker_that_does_not_end_on_term_is_killed(tmp_path):
    pool = ProcessPoolExecutor(1)
    pool.submit(_deaf, str(tmp_path / "started"))
    end = time.monotonic() + 60
    while not (tmp_path / "started").exists() and time.monotonic() < end:
        time.sleep(0.02)
    workers = list(pool._processes.values())
    started = time.monotonic()
    stop_pool(pool, stop_s=0.5)
    assert time.monotonic() - started < 10
    assert workers and not any(p.is_alive() for p in workers)


FORK = """
import multiprocessing as mp, os, signal, time
from pydiag.app import cli
from pydiag.core.termination import deferred
signal.signal(signal.SIGTERM, cli._raise_terminated)

def term_during_the_fork():  # as a TERM that lands while the process forks
    os.kill(os.getpid(), signal.SIGTERM)
    for _ in range(10000):
        pass

os.register_at_fork(after_in_parent=term_during_the_fork)
try:
    {guard}
        child = mp.get_context("fork").Process(target=time.sleep, args=(0,))
        child.start()
    time.sleep(0.5)
    print("ran on")
except cli.Terminated:
    print("raised after the fork")
child.join()
"""


@pytest.mark.parametrize("guard, said", [("with deferred():", "raised after the fork"),
                                         ("if True:", "ran on")])
def test_a_term_during_a_fork_is_raised_after_it(guard, said):
    """Python drops an exception raised in a fork's hooks: unguarded, the process runs on
    (the control case); inside deferred() the TERM is raised once the fork has returned."""
    res = subprocess.run([sys.executable, "-c", FORK.format(guard=guard)], capture_output=True,
                         text=True, timeout=60)
    assert res.returncode == 0, res.stderr[-300:]
    assert res.stdout.strip() == said, (res.stdout, res.stderr[-300:])
