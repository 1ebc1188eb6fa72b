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


def descendants(pid: int) -> set[int]:
    found, todo = set(), [pid]
    while todo:
        for child in children(todo.pop()):
            if child not in found:
                found.add(child)
                todo.append(child)
    return found


def slow_diagnose(gear_fmu, record, scratch, *extra, **popen):
    env = {**os.environ, "TMPDIR": str(scratch)}
    return subprocess.Popen(
        [sys.executable, "-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
         str(record), "--particles", "4", "--iterations", "100000", "--workers", "2",
         "--quiet", *extra], cwd=ROOT, env=env, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True, **popen)


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux /proc")
def test_a_run_folder_left_by_a_killed_process_group_is_reclaimed_by_the_next_run(
        gear_fmu, record, tmp_path):
    """SIGKILL of the whole group (a scheduler's way) kills the janitor too: the folder
    stays, naming its owner, until the next run removes it."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    main = slow_diagnose(gear_fmu, record, scratch, start_new_session=True)
    try:
        assert wait_for(lambda: len(list(scratch.glob("pydiag_run_*/pydiag_fmu_*"))) >= 2, 60)
        os.killpg(main.pid, signal.SIGKILL)
        main.communicate(timeout=30)
    finally:
        if main.poll() is None:
            main.kill()
            main.wait()
    left = list(scratch.glob("pydiag_run_*"))
    assert len(left) == 1, left  # nothing ran to remove it
    again = slow_diagnose(gear_fmu, record, scratch)
    try:
        assert wait_for(lambda: not left[0].exists(), 60), list(scratch.iterdir())
    finally:
        again.kill()
        again.wait()


def test_a_temporary_file_of_a_killed_writer_is_removed_by_the_next_write(gear_fmu, tmp_path):
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    from pydiag.core.leftovers import owner_tag
    stale = tmp_path / f".m.csv.{owner_tag(gone.pid)}.x1y2z3.tmp"
    stale.write_text("half a record")
    live = tmp_path / f".m.csv.{owner_tag()}.a1b2c3.tmp"  # this process's: it is running
    live.write_text("being written")
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(gear_fmu), "--duration", "0.1",
                  "--out", str(tmp_path / "m.csv"), "--quiet")
    assert res.returncode == 0, res.stderr
    assert not stale.exists() and live.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["m.csv", live.name])


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux /proc")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_a_killed_batch_leaves_no_worker(gear_fmu, record, tmp_path, sig):
    folder = tmp_path / "records"
    folder.mkdir()
    for i in range(4):
        (folder / f"r{i}.csv").write_bytes(record.read_bytes())
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = {**os.environ, "TMPDIR": str(scratch)}
    main = subprocess.Popen(
        [sys.executable, "-m", "pydiag", "batch", "--fmu", str(gear_fmu), "--measurements",
         str(folder), "--out", str(tmp_path / "r.csv"), "--workers", "2", "--particles", "4",
         "--iterations", "100000", "--quiet"], cwd=ROOT, env=env, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True)
    try:
        assert wait_for(lambda: len(list(scratch.glob("pydiag_run_*/pydiag_fmu_*"))) >= 2, 60)
        started = descendants(main.pid)
        assert len(started) >= 4, started  # two pool workers, each with its own workers
        t0 = time.monotonic()
        main.send_signal(sig)
        main.communicate(timeout=30)
        took = time.monotonic() - t0
    finally:
        if main.poll() is None:
            main.kill()
            main.wait()
    assert wait_for(lambda: not any(alive(p) for p in started), 15), \
        [p for p in started if alive(p)]
    if sig == signal.SIGTERM:
        assert main.returncode == 143 and took < 10, (main.returncode, took)
    assert wait_for(lambda: not any(scratch.iterdir()), 15), list(scratch.rglob("*"))[:10]
