"""The run folder of a pool of workers: the janitor waits for the workers it killed (a
zombie has ended, a running process not), and a TERM while the pool starts or replaces a
worker leaves nothing behind."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pydiag.fmu.isolation import _gone


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_a_zombie_has_ended_and_a_running_process_has_not():
    running = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    try:
        while not Path(f"/proc/{ended.pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z":
            time.sleep(0.01)  # exited, not reaped: a zombie
        assert _gone(ended.pid) and not _gone(running.pid)
    finally:
        running.kill()
        running.wait()
        ended.wait()
    assert _gone(ended.pid)


TERM_DURING = """
import os, signal, tempfile, time
from pathlib import Path
from pydiag.app import cli
from pydiag.fmu import isolation
signal.signal(signal.SIGTERM, cli._raise_terminated)


class Objective:
    def residuals(self, x):
        return x


def term_now():  # as a TERM that lands at this very moment
    os.kill(os.getpid(), signal.SIGTERM)
    for _ in range(10000):
        pass


where, forks = {where!r}, []
if where == "mkdtemp":  # the run folder made, its name not yet kept
    made = tempfile.mkdtemp
    def mkdtemp(*args, **kwargs):
        path = made(*args, **kwargs)
        term_now()
        return path
    tempfile.mkdtemp = mkdtemp
else:  # the n-th fork (1: the janitor, 2 and 3: the workers) has returned in the parent
    def after_fork():
        forks.append(1)
        if len(forks) == int(where):
            term_now()
    os.register_at_fork(after_in_parent=after_fork)
try:
    isolation.IsolatedPool(Objective(), 2, 10.0)
    print("not raised")
except cli.Terminated:
    pass
end = time.monotonic() + 5
while time.monotonic() < end:
    alive = [p for p in Path("/proc/self/task").glob("*/children") if p.read_text().split()]
    left = list(Path(tempfile.gettempdir()).iterdir())
    if not alive and not left:
        break
    time.sleep(0.05)
print("left:", [p.read_text() for p in alive], [p.name for p in left])
"""


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux /proc")
@pytest.mark.parametrize("where", ["mkdtemp", "1", "2", "3"])
def test_a_term_while_a_pool_starts_leaves_no_worker_and_no_folder(tmp_path, where):
    """A TERM that lands as the run folder is made or a process is forked is raised once
    the pool has recorded what it made, so the cleanup it triggers removes all of it (an
    unrecorded worker ran on, extracting its FMU into a folder the pool had removed)."""
    env = {**os.environ, "TMPDIR": str(tmp_path)}
    res = subprocess.run([sys.executable, "-c", TERM_DURING.format(where=where)], env=env,
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr[-500:]
    assert res.stdout.strip() == "left: [] []", (res.stdout, res.stderr[-500:])


class _Echo:
    def residuals(self, x):
        return x


def test_a_pool_closes_with_a_worker_reaped_and_not_yet_replaced(tmp_path, monkeypatch):
    """A TERM between a worker's reaping and its replacement leaves a reaped worker in the
    pool: its cleanup goes past it."""
    import tempfile

    from pydiag.fmu.isolation import IsolatedPool

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    pool = IsolatedPool(_Echo(), 2, 10.0)
    pool._reap(*pool.workers[0])
    pool.close()
    assert not any(tmp_path.iterdir())
