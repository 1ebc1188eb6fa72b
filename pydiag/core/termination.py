"""SIGTERM as an exception that unwinds the process, once.

A handler that raises on SIGTERM lets every ``finally`` run (workers stopped, temporary
files removed). Two things can go wrong with a plain ``raise``: a second TERM (a
supervisor's, an executor's, the parent's death signal) raises again inside that
cleanup and cuts it short; and an exception raised where Python cannot propagate it (an
``os.fork`` hook, a finaliser) is printed and dropped, so the TERM is lost. The handler
here raises unless the exception of an earlier TERM is still being handled: a TERM during
the cleanup waits for it to finish, and a TERM after a lost one raises again.
"""

from __future__ import annotations

import sys
from typing import Callable


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
    """A signal handler that raises ``exc_type``, unless one is being handled already."""
    def handler(signum: int, frame: object) -> None:
        if not unwinding(exc_type):
            raise exc_type()
    return handler
