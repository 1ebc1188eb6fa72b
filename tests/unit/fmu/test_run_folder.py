"""The janitor waits for the workers it killed: a zombie has ended, a running process not."""

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
