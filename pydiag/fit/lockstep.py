"""Several sequential searches run together, their simulations batched.

A least-squares polish asks for one batch of simulations at a time: its Jacobian's
columns, then a single trial step, which leaves all but one worker idle. Several polishes
(from the swarm's distinct starts, or one a tooth) are independent, so each runs in a
thread of its own and the calling thread simulates, in rounds, one request of every
polish still running as a single batch. A polish takes the same steps as it would alone
and returns the same result; only the workers are kept busy. The batch is put together
in the polishes' order, whichever thread asked first.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import TypeVar

import numpy as np

T = TypeVar("T")
Evaluate = Callable[[np.ndarray], list]


class _Stopped(Exception):
    """A search's request after the batch it waited for failed: the calling thread
    raises the failure itself."""


def run_in_lockstep(evaluate: Evaluate, tasks: Sequence[Callable[[Evaluate], T]]) -> list[T]:
    """Each ``task(ask)`` in a thread of its own, where ``ask(xs)`` returns
    ``evaluate(xs)``'s rows for ``xs``; every round, the requests of all the tasks still
    running go to ``evaluate`` as one batch, from the calling thread (so that a signal
    or a failure there stops every task). Returns the tasks' results in their order; the
    first task's exception (by order) is raised."""
    if len(tasks) <= 1:
        return [task(evaluate) for task in tasks]
    cond = threading.Condition()
    requests: dict[int, np.ndarray] = {}
    answers: dict[int, list] = {}
    state = {"running": len(tasks), "failed": False}
    results: list = [None] * len(tasks)
    errors: list[BaseException | None] = [None] * len(tasks)

    def ask(i: int, xs: np.ndarray) -> list:
        with cond:
            if state["failed"]:
                raise _Stopped()
            requests[i] = np.atleast_2d(xs)
            cond.notify_all()
            cond.wait_for(lambda: i in answers or state["failed"])
            if i not in answers:
                raise _Stopped()
            return answers.pop(i)

    def body(i: int, task: Callable[[Evaluate], T]) -> None:
        try:
            results[i] = task(lambda xs: ask(i, xs))
        except BaseException as err:  # handed to the calling thread
            errors[i] = err
        finally:
            with cond:
                state["running"] -= 1
                cond.notify_all()

    threads = [threading.Thread(target=body, args=(i, task), daemon=True)
               for i, task in enumerate(tasks)]
    for t in threads:
        t.start()
    try:
        while True:
            with cond:
                cond.wait_for(lambda: state["running"] == 0
                              or len(requests) == state["running"])
                if state["running"] == 0:
                    break
                batch = sorted(requests.items())
                requests.clear()
            out = evaluate(np.vstack([xs for _, xs in batch]))
            with cond:
                start = 0
                for i, xs in batch:
                    answers[i] = out[start:start + len(xs)]
                    start += len(xs)
                cond.notify_all()
    except BaseException:
        with cond:
            state["failed"] = True
            cond.notify_all()
        for t in threads:
            t.join()
        raise
    for t in threads:
        t.join()
    for err in errors:
        if err is not None:
            raise err
    return results
