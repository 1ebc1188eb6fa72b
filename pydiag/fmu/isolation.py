"""Evaluate an objective in worker processes that may crash, hang or fail.

Each worker holds its own copy of the objective (and so its own FMU instance). A task
that segfaults its worker, runs past ``timeout_s``, or returns no result (a NaN output,
a failed ``doStep``) comes back as ``None``: the optimiser penalises it, the dead or hung
worker is killed and replaced, and the run goes on. ``max_consecutive_failures`` failed
evaluations in a row stop the run with :class:`TooManyFailures`, naming the last cause.
Results do not depend on the number of workers: each task is evaluated alone.
"""

from __future__ import annotations

import faulthandler
import multiprocessing as mp
import signal
import time
from dataclasses import dataclass, field
from multiprocessing.connection import wait
from typing import Any

import numpy as np

from pydiag.core.errors import TooManyFailures


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


def _worker_loop(conn, objective) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C
    faulthandler.disable()  # a crashing FMU is reported by the parent, not dumped to stderr
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
        self.workers: list[tuple[Any, Any]] = [self._spawn() for _ in range(max(1, n_workers))]

    def _spawn(self):
        parent, child = self.ctx.Pipe()
        proc = self.ctx.Process(target=_worker_loop, args=(child, self.objective), daemon=True)
        proc.start()
        child.close()
        return proc, parent

    def _replace(self, i: int) -> None:
        proc, conn = self.workers[i]
        if proc.is_alive():
            proc.kill()
        proc.join(5)
        conn.close()
        self.workers[i] = self._spawn()

    def map(self, xs: np.ndarray) -> list[np.ndarray | None]:
        xs = list(xs)
        results: list[np.ndarray | None] = [None] * len(xs)
        pending = list(range(len(xs)))
        busy: dict[int, tuple[int, float]] = {}  # worker -> (task, started)
        while pending or busy:
            for w in range(len(self.workers)):
                if w not in busy and pending:
                    task = pending.pop(0)
                    self.workers[w][1].send(xs[task])
                    busy[w] = (task, time.monotonic())
            conns = {self.workers[w][1]: w for w in busy}
            now = time.monotonic()
            deadline = min(started + self.timeout_s for _, started in busy.values())
            ready = wait(list(conns), timeout=max(0.0, deadline - now))
            for conn in ready:
                w = conns[conn]
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
                    self.failures.consecutive = 0
                else:
                    self._fail(payload if status == "error" else "simulation failed (non-finite "
                               "output or a failed step)")
            now = time.monotonic()
            for w, (task, started) in list(busy.items()):
                if now - started > self.timeout_s and self.workers[w][1] not in ready:
                    busy.pop(w)
                    self._fail(f"evaluation exceeded {self.timeout_s:g} s")
                    self._replace(w)
        return results

    def _fail(self, reason: str) -> None:
        self.failures.add(reason)
        if self.failures.consecutive >= self.max_consecutive_failures:
            raise TooManyFailures(f"{self.failures.consecutive} evaluations failed in a row; "
                                  f"last: {reason}", self.failures.count,
                                  self.failures.consecutive, reason)

    def close(self) -> None:
        for proc, conn in self.workers:
            try:
                conn.send(None)
            except (OSError, BrokenPipeError):
                pass
        for proc, conn in self.workers:
            proc.join(2)
            if proc.is_alive():
                proc.kill()
                proc.join(2)
            conn.close()
        self.workers = []

    def __enter__(self) -> "IsolatedPool":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
