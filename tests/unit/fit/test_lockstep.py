"""Sequential searches run side by side (:mod:`pydiag.fit.lockstep`): each gets what it
would get alone, and their requests reach the evaluator together."""

import numpy as np
import pytest

from pydiag.fit.lockstep import run_in_lockstep


def square_rows(xs: np.ndarray) -> list:
    return [float(x[0]) ** 2 for x in xs]


def search(start: float, steps: int):
    """A search whose next request depends on its last answer (as a polish's does)."""
    def task(ask):
        x, seen = start, []
        for _ in range(steps):
            answer = ask(np.array([[x], [x + 1]]))
            seen.append(tuple(answer))
            x = answer[0] % 7 + start
        return seen
    return task


def test_each_search_gets_what_it_gets_alone_and_the_requests_go_together():
    tasks = [search(s, n) for s, n in ((1.0, 4), (2.0, 2), (3.0, 5))]
    alone = [task(square_rows) for task in tasks]
    batches = []

    def recording(xs):
        batches.append([float(x[0]) for x in xs])
        return square_rows(xs)

    assert run_in_lockstep(recording, tasks) == alone
    # every round one request of each search still running, in the searches' order
    assert [len(b) for b in batches] == [6, 6, 4, 4, 2]
    assert batches[0] == [1.0, 2.0, 2.0, 3.0, 3.0, 4.0]


def test_a_failed_batch_stops_every_search_and_is_raised():
    calls = []

    def failing(xs):
        calls.append(len(xs))
        if len(calls) == 2:
            raise RuntimeError("the pool gave up")
        return square_rows(xs)

    with pytest.raises(RuntimeError, match="gave up"):
        run_in_lockstep(failing, [search(1.0, 5), search(2.0, 5)])
    assert calls == [4, 4]


def test_a_failed_search_is_raised_after_the_others_finish():
    def broken(ask):
        ask(np.array([[1.0]]))
        raise ValueError("search 1 failed")

    finished = []

    def long(ask):
        for _ in range(3):
            ask(np.array([[2.0]]))
        finished.append(True)
        return "done"

    with pytest.raises(ValueError, match="search 1"):
        run_in_lockstep(square_rows, [broken, long])
    assert finished == [True]
