"""The first SIGTERM starts the cleanup; the ones that follow it do not cut it short."""

import subprocess
import sys

import pytest


@pytest.mark.parametrize("handler, raised", [
    ("batch._worker_terminated", "batch._WorkerTerminated"),  # a local batch worker: the
    # executor's TERM once another worker has ended, and the parent's death signal, follow
    ("cli._raise_terminated", "cli.Terminated"),  # the command: a supervisor's second TERM
])
def test_the_cleanup_runs_through_a_second_term(handler, raised):
    code = f"""
import os, signal, time
from pydiag.app import batch, cli
signal.signal(signal.SIGTERM, {handler})
try:
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(1)
except {raised}:
    os.kill(os.getpid(), signal.SIGTERM)  # in the cleanup
    time.sleep(0.2)
    print("cleaned up")
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60)
    assert res.returncode == 0 and res.stdout.strip() == "cleaned up", (res.returncode,
                                                                        res.stderr[-300:])
