"""Killing pydiag leaves nothing behind: no worker process, no extracted FMU.

Fault injection on the real CLI: a diagnose is started with its own temp folder, killed
(TERM, then KILL) once its workers are simulating, and the test then looks for any process
the run started and anything left in that temp folder.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import ROOT, alive, children, run_cli


def wait_for(condition, timeout_s: float) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


@pytest.fixture(scope="module")
def record(gear_fmu, tmp_path_factory):
    out = tmp_path_factory.mktemp("record") / "case8.csv"
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(gear_fmu), "--set", "a_f=0.3",
                  "--set", "f_f=0.5", "--snr", "10", "--out", str(out), "--quiet")
    assert res.returncode == 0, res.stderr
    return out


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux /proc")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL])
def test_a_killed_diagnose_leaves_no_worker_and_no_extracted_fmu(gear_fmu, record, tmp_path, sig):
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = {**os.environ, "TMPDIR": str(scratch)}
    main = subprocess.Popen(
        [sys.executable, "-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
         str(record), "--particles", "4", "--iterations", "100000", "--workers", "2", "--quiet"],
        cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        # simulating: the run folder holds an extracted FMU of each worker
        assert wait_for(lambda: len(list(scratch.glob("pydiag_run_*/pydiag_fmu_*"))) >= 2, 60), \
            (main.poll(), list(scratch.rglob("*"))[:5])
        started = children(main.pid)
        assert len(started) >= 3, started  # two workers and the janitor
        main.send_signal(sig)
        _, err = main.communicate(timeout=30)
    finally:
        if main.poll() is None:
            main.kill()
            main.wait()
    if sig == signal.SIGTERM:
        assert main.returncode == 143 and "pydiag: terminated" in err, err
    assert wait_for(lambda: not any(alive(p) for p in started), 10), \
        [p for p in started if alive(p)]
    assert wait_for(lambda: not any(scratch.iterdir()), 10), list(scratch.rglob("*"))[:10]
