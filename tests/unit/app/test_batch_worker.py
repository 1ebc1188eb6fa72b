"""A local batch worker's cleanup is not cut short by the signals that follow the first."""

import subprocess
import sys


def test_a_batch_worker_finishes_its_cleanup_through_a_second_term():
    """The first SIGTERM unwinds the task; the executor's and the parent's death signal
    that follow must not cut the cleanup (its pool's close) short."""
    code = """
import os, signal, time
from pydiag.app import batch
signal.signal(signal.SIGTERM, batch._worker_terminated)
try:
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(1)
except batch._WorkerTerminated:
    os.kill(os.getpid(), signal.SIGTERM)  # in the cleanup
    time.sleep(0.2)
    print("cleaned up")
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60)
    assert res.returncode == 0 and res.stdout.strip() == "cleaned up", (res.returncode,
                                                                        res.stderr[-300:])
