"""SIGTERM as an exception that unwinds the process, once.

A handler that raises on SIGTERM lets every ``finally`` run (workers stopped, temporary
files removed). Four things can go wrong with a plain ``raise``: a second TERM (a
supervisor's, an executor's, the parent's death signal) raises again inside that cleanup
and cuts it short; a TERM that arrives while the process forks is handled in the fork's
hooks (``os.register_at_fork``: logging has one), where Python prints the exception and
drops it, so the process runs on; the same in a finaliser; and a TERM can land
between making a thing and recording it (a folder made, its name not yet kept; a worker
forked, not yet in the pool's list), and the cleanup then misses it. The handler here
(:func:`raise_once`) raises unless the exception of an earlier TERM is being handled, so a
TERM during the cleanup waits for it and a TERM after a lost one raises again; and inside
:func:`deferred` it holds the TERM until the block ends, then raises it.

A signal handler is the process's, so what it shares with :func:`deferred` is too: one
module-level record, reset in every forked child.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from multiprocessing.connection import wait
from typing import Callable


class _Held:
    """The :func:`deferred` blocks under way in this process and the TERM held until they
    end."""

    def __init__(self) -> None:
        self.depth = 0
        self.pending: type[BaseException] | None = None


_HELD = _Held()
os.register_at_fork(after_in_child=_HELD.__init__)


def unwinding(exc_type: type[BaseException]) -> bool:
    """Whether an ``exc_type`` is being handled now: propagating through a ``finally`` or
    an ``__exit__``, or caught by an ``except`` that runs (or in the context of one raised
    there)."""
    err = sys.exc_info()[1]
    while err is not None:
        if isinstance(err, exc_type):
            return True
        err = err.__context__
    return False


def raise_once(exc_type: type[BaseException]) -> Callable[[int, object], None]:
    """A signal handler that raises ``exc_type``, unless one is being handled already;
    inside :func:`deferred`, once the block has ended."""
    def handler(signum: int, frame: object) -> None:
        if unwinding(exc_type):
            return
        if _HELD.depth:
            _HELD.pending = exc_type
            return
        raise exc_type()
    return handler


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """A TERM :func:`raise_once` handles in the block is raised when the block ends. Around
    a fork (a multiprocessing start), so that it is not lost in the fork's hooks; around
    making a thing and recording it, so that the cleanup the TERM starts finds it. Keep the
    block short: it is a TERM's delay."""
    _HELD.depth += 1
    try:
        yield
    finally:
        _HELD.depth -= 1
        if not _HELD.depth and _HELD.pending is not None:
            exc_type, _HELD.pending = _HELD.pending, None
            if not unwinding(exc_type):
                raise exc_type()


#: Wall time a pool's worker has to end after a SIGTERM (its task's cleanup: its fit's
#: workers joined, 5 s each at most) before it is sent another, and then killed.
STOP_S = 15.0


def stop_pool(pool: ProcessPoolExecutor, stop_s: float = STOP_S) -> None:
    """End the pool's workers and drop its queue, now rather than after its tasks (Ctrl-C,
    SIGTERM in the process that owns it): a SIGTERM each (its task's cleanup runs),
    another to those still running after ``stop_s`` (Python drops a TERM whose exception
    is raised in a fork hook or a finaliser), then SIGKILL (the janitor of a killed
    worker's run folder removes what it held, :mod:`pydiag.fmu.isolation`)."""
    running = [p for p in list((getattr(pool, "_processes", None) or {}).values())
               if p.is_alive()]
    for send in ("terminate", "terminate", "kill"):
        for proc in running:
            getattr(proc, send)()
        end = time.monotonic() + stop_s
        while running and time.monotonic() < end:  # a sentinel is ready once its worker ended
            ended = wait([p.sentinel for p in running], end - time.monotonic())
            running = [p for p in running if p.sentinel not in ended]
        if not running:
            break
    pool.shutdown(wait=True, cancel_futures=True)
