"""Evaluate an objective in worker processes that may crash, hang or fail.

Each worker holds its own copy of the objective (and so its own FMU instance). A task
that segfaults its worker, runs past ``timeout_s``, or returns no result (a NaN output,
a failed ``doStep``) comes back as ``None``: the optimiser penalises it, the dead or hung
worker is killed and replaced, and the run goes on. ``max_consecutive_failures`` failed
evaluations in a row stop the run with :class:`TooManyFailures`, naming the last cause.
Results do not depend on the number of workers: each task is evaluated alone.

Nothing outlives the pool. Each pool owns a run folder (``pydiag_run_*`` in the temp
folder); its workers put their temporary files there (the extracted FMU included), and
:meth:`IsolatedPool.close` removes it with the workers. A worker keeps only its own end of
its pipe (not the parent's end, nor other workers' pipes). If the main process dies
without closing the pool (``kill -TERM`` with no handler, ``kill -KILL``, a crash), a
janitor process forked first, which holds nothing but the read end of a pipe from the
parent, sees that pipe close: it kills the workers the parent reported and removes the run
folder, so no worker is left under PID 1 and no extracted FMU is left on disk. Where the
janitor dies too (SIGKILL of the whole process group), the folder, which names its owner,
is removed by the next pool that starts (:func:`pydiag.core.leftovers.reclaim`).

A pool whose first evaluations all time out (a hanging FMU, or a warm-up far too long)
stops after one timeout per worker instead of after ``max_consecutive_failures`` of them.

An evaluation's time starts when its worker is ready: a new worker first prepares its
objective (``objective.prepare()`` if it has one: the FMU extracted and loaded) and says
so, within :data:`STARTUP_S`, so that loading, which a busy machine stretches, never counts
against an evaluation's limit.
"""

from __future__ import annotations

import faulthandler
import multiprocessing as mp
import os
import shutil
import signal
import tempfile
import time
from dataclasses import dataclass, field
from multiprocessing.connection import wait
from typing import Any

import numpy as np

from pydiag.core.errors import TooManyFailures
from pydiag.core.leftovers import owner_tag, reclaim
from pydiag.core.termination import deferred

#: The run folders' names begin with this, then their owner (:mod:`pydiag.core.leftovers`).
RUN_PREFIX = "pydiag_run_"
#: Wall time a new worker has to prepare its objective (load its FMU) before it is failed.
STARTUP_S = 120.0
#: Wall time the run folder's removal is retried while a process that was just killed may
#: still be writing or removing in it.
REMOVE_S = 2.0


@dataclass
class FailureLog:
    count: int = 0
    consecutive: int = 0
    reasons: dict[str, int] = field(default_factory=dict)
    first: str = ""
    last: str = ""

    def add(self, reason: str) -> None:
        self.first = self.first or reason
        self.count += 1
        self.consecutive += 1
        self.last = reason
        self.reasons[reason] = self.reasons.get(reason, 0) + 1


def _keep_only(fds: list[int]) -> None:
    """Close inherited descriptors of the pool that this process must not hold."""
    for fd in fds:
        try:
            os.close(fd)
        except OSError:
            pass


def _use_run_folder(folder: str) -> None:
    """Temporary files of this worker (the extracted FMU, an FMU's own) go to the run folder.

    The worker is a process of its own, so changing its temp folder touches no one else.
    """
    os.environ["TMPDIR"] = folder
    tempfile.tempdir = folder


def _worker_loop(conn, objective, inherited: list[int], folder: str) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    faulthandler.disable()  # a crashing FMU is reported by the parent, not dumped to stderr
    _keep_only(inherited)
    _use_run_folder(folder)
    try:
        _serve(conn, objective)
    finally:
        close = getattr(objective, "close", None)
        if close is not None:
            close()


def _serve(conn, objective) -> None:
    prepare = getattr(objective, "prepare", None)
    if prepare is not None:
        try:
            prepare()
        except Exception:  # noqa: BLE001 (the first evaluation meets it again, and says so)
            pass
    conn.send(("ready", None))
    while True:
        try:
            task = conn.recv()
        except EOFError:
            return
        if task is None:
            return
        try:
            result = objective.residuals(task)
            conn.send(("ok", result))
        except Exception as err:  # report, keep the worker
            conn.send(("error", f"{type(err).__name__}: {err}"))


def _remove_folder(folder: str, timeout_s: float = REMOVE_S) -> None:
    """Remove ``folder`` and what it holds, retried for ``timeout_s``: a worker killed a
    moment ago may still be removing its own files there (or writing them), so that one
    pass finds a folder not empty that is empty an instant later."""
    end = time.monotonic() + timeout_s
    while True:
        shutil.rmtree(folder, ignore_errors=True)
        if not os.path.lexists(folder) or time.monotonic() >= end:
            return
        time.sleep(0.02)


def _gone(pid: int) -> bool:
    """Whether process ``pid`` has ended (a zombie, not yet reaped, has)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            return f.read().rsplit(b")", 1)[1].split()[0] == b"Z"
    except FileNotFoundError:
        return True
    except OSError:  # no /proc: ask the kernel whether the pid is still there
        try:
            os.kill(pid, 0)
        except OSError:
            return True
        return False


def _janitor(read_fd: int, inherited: list[int], folder: str) -> None:
    """Wait for the parent's pipe to close; then kill the workers it named, remove the folder.

    The parent writes ``+PID`` when it starts a worker and ``-PID`` when it has reaped one.
    """
    class Terminated(Exception):
        pass

    def terminated(signum, frame):
        raise Terminated

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    signal.signal(signal.SIGTERM, terminated)  # a TERM to the whole group: clean up now
    _keep_only(inherited)
    pids: set[int] = set()
    pending = b""
    try:
        while chunk := os.read(read_fd, 4096):
            pending += chunk
            *lines, pending = pending.split(b"\n")
            for line in lines:
                pid = int(line[1:])
                (pids.add if line[:1] == b"+" else pids.discard)(pid)
    except Terminated:
        pass
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a second TERM must not stop the cleanup
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
    end = time.monotonic() + REMOVE_S  # a killed worker runs on until the kill lands
    while not all(_gone(pid) for pid in pids) and time.monotonic() < end:
        time.sleep(0.01)
    _remove_folder(folder)


def _describe_exit(code: int | None) -> str:
    if code is not None and code < 0:
        try:
            return f"worker killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"worker killed by signal {-code}"
    return f"worker exited with status {code}"


class IsolatedPool:
    """``map(xs)`` evaluates ``objective.residuals(x)`` for each row, isolated.

    Args:
        objective: picklable-by-fork object with ``residuals(x) -> array | None``
        n_workers: worker processes
        timeout_s: wall-time limit of one evaluation
        max_consecutive_failures: stop after this many failures in a row
    """

    def __init__(self, objective: Any, n_workers: int = 1, timeout_s: float = 60.0,
                 max_consecutive_failures: int = 20) -> None:
        self.objective = objective
        self.timeout_s = timeout_s
        self.max_consecutive_failures = max_consecutive_failures
        self.ctx = mp.get_context("fork")
        self.failures = FailureLog()
        self.successes = 0
        self.timeouts = 0
        reclaim(tempfile.gettempdir(), RUN_PREFIX)  # folders of runs killed outright
        self.folder = ""
        self.workers: list[tuple[Any, Any]] = []
        self.starting: dict[int, float] = {}  # worker -> when it was started, until ready
        self._janitor_fd = -1
        self._janitor = None
        try:  # from the folder on: an exception (a SIGTERM) on the way removes what was made
            with deferred():  # a TERM meanwhile is raised once all this is recorded
                self.folder = tempfile.mkdtemp(prefix=f"{RUN_PREFIX}{owner_tag()}_")
                read_fd, self._janitor_fd = os.pipe()
                self._janitor = self.ctx.Process(target=_janitor, daemon=True, args=(
                    read_fd, [self._janitor_fd], self.folder))
                self._janitor.start()
                os.close(read_fd)
            for i in range(max(1, n_workers)):
                self._start(i)
        except BaseException:
            self.close()
            raise

    def _tell_janitor(self, message: str) -> None:
        try:
            os.write(self._janitor_fd, f"{message}\n".encode())
        except OSError:
            pass

    def _start(self, i: int) -> None:
        """Start worker ``i``: a new one at the end, or in the place of one reaped. A TERM
        meanwhile is raised once the pool and the janitor know the worker, so that the
        cleanup it starts stops the worker too."""
        parent, child = self.ctx.Pipe()
        inherited = [self._janitor_fd, parent.fileno()] + [c.fileno() for _, c in self.workers
                                                       if not c.closed]
        proc = self.ctx.Process(target=_worker_loop, daemon=True,
                                args=(child, self.objective, inherited, self.folder))
        with deferred():
            proc.start()
            child.close()
            self._tell_janitor(f"+{proc.pid}")
            if i < len(self.workers):
                self.workers[i] = (proc, parent)
            else:
                self.workers.append((proc, parent))
            self.starting[i] = time.monotonic()

    def _reap(self, proc, conn) -> None:
        if proc.is_alive():
            proc.kill()
        proc.join(5)
        with deferred():  # a TERM meanwhile is raised once the janitor forgot the pid
            conn.close()
            self._tell_janitor(f"-{proc.pid}")
            if not proc.is_alive():
                proc.close()  # its sentinel descriptor

    def _replace(self, i: int) -> None:
        self._reap(*self.workers[i])
        self._start(i)

    def map(self, xs: np.ndarray) -> list[np.ndarray | None]:
        xs = list(xs)
        results: list[np.ndarray | None] = [None] * len(xs)
        pending = list(range(len(xs)))
        busy: dict[int, tuple[int, float]] = {}  # worker -> (task, started)
        while pending or busy:
            for w in range(len(self.workers)):
                if w not in busy and w not in self.starting and pending:
                    task = pending.pop(0)
                    self.workers[w][1].send(xs[task])
                    busy[w] = (task, time.monotonic())
            conns = {self.workers[w][1]: w for w in list(busy) + list(self.starting)}
            now = time.monotonic()
            deadline = min([started + self.timeout_s for _, started in busy.values()]
                           + [began + STARTUP_S for began in self.starting.values()])
            ready = wait(list(conns), timeout=max(0.0, deadline - now))
            for conn in ready:
                w = conns[conn]
                if w in self.starting:  # its "ready", or its death while preparing
                    self._started(w)
                    continue
                task, _ = busy.pop(w)
                try:
                    status, payload = conn.recv()
                except (EOFError, OSError):
                    self.workers[w][0].join(1)
                    self._fail(_describe_exit(self.workers[w][0].exitcode))
                    self._replace(w)
                    continue
                if status == "ok" and payload is not None:
                    results[task] = payload
                    self.successes += 1
                    self.failures.consecutive = 0
                else:
                    self._fail(payload if status == "error" else "simulation failed (non-finite "
                               "output or a failed step)")
            now = time.monotonic()
            for w, (_, started) in list(busy.items()):
                if now - started > self.timeout_s and self.workers[w][1] not in ready:
                    busy.pop(w)
                    self.timeouts += 1
                    self._replace(w)
                    self._fail(f"evaluation exceeded {self.timeout_s:g} s")
            for w, began in list(self.starting.items()):
                if now - began > STARTUP_S and self.workers[w][1] not in ready:
                    self._replace(w)
                    self._fail(f"a worker took over {STARTUP_S:g} s to load its model")
        return results

    def _started(self, w: int) -> None:
        """Worker ``w`` said it is ready, or died preparing (then it is replaced)."""
        try:
            self.workers[w][1].recv()
            del self.starting[w]
        except (EOFError, OSError):
            self.workers[w][0].join(1)
            why = _describe_exit(self.workers[w][0].exitcode)
            self._replace(w)
            self._fail(f"{why} while loading its model")

    def _fail(self, reason: str) -> None:
        self.failures.add(reason)
        if self.successes == 0 and self.timeouts >= len(self.workers) and \
                self.timeouts == self.failures.count:
            raise TooManyFailures(f"the first {self.timeouts} evaluations all exceeded "
                                  f"{self.timeout_s:g} s: the FMU hangs, or its warm-up or "
                                  "window is far too long (or raise the evaluation timeout)",
                                  self.failures.count, self.failures.consecutive, reason)
        if self.failures.consecutive >= self.max_consecutive_failures:
            raise TooManyFailures(f"{self.failures.consecutive} evaluations failed in a row; "
                                  f"last: {reason}", self.failures.count,
                                  self.failures.consecutive, reason)

    def close(self) -> None:
        """Stop the workers (each removes its files), then the janitor; remove the run folder."""
        running = [(p, c) for p, c in self.workers if not c.closed]  # not those reaped already
        for _, conn in running:
            try:
                conn.send(None)
            except (OSError, BrokenPipeError):
                pass
        for proc, conn in running:
            proc.join(5)
            self._reap(proc, conn)
        self.workers = []
        if self.folder:
            _remove_folder(self.folder)
        if self._janitor_fd >= 0:
            os.close(self._janitor_fd)  # the janitor finds nothing left to do, and exits
            self._janitor_fd = -1
        if self._janitor is not None and self._janitor.pid is not None:
            self._janitor.join(5)
            if not self._janitor.is_alive():
                self._janitor.close()
            self._janitor = None

    def __enter__(self) -> "IsolatedPool":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
