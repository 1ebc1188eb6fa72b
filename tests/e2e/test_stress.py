"""The worker pool under stress: thousands of evaluations of an FMU that crashes, hangs,
returns NaN and fails its steps, and nothing of the pool left behind (the pool's unit
tests: tests/unit/fmu/test_isolation.py)."""

import os
import tempfile

import numpy as np
import pytest
from conftest import children
from fmus.hostile import adapter, measurement

from pydiag.fit.build import build_problem
from pydiag.fit.problem import ProblemObjective
from pydiag.fmu.isolation import IsolatedPool


def _open_fds() -> set[str]:
    return set(os.listdir("/proc/self/fd"))


@pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="needs Linux /proc")
def test_two_thousand_hostile_evaluations_leave_no_process_folder_or_descriptor(
        hostile_fmu, tmp_path, monkeypatch):
    """Crashes, NaN outputs, failed steps and hangs mixed into 2,000 evaluations: every good
    one gives its answer, every bad one is counted, and nothing of the pool remains."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    rng = np.random.default_rng(7)
    kind = rng.choice(["good", "fail", "nan", "crash", "hang"], size=2000,
                      p=[0.82, 0.06, 0.05, 0.06, 0.01])
    kind[0] = "good"
    k = np.select([kind == "good", kind == "fail", kind == "nan", kind == "crash"],
                  [rng.uniform(0.1, 1.0, 2000), 1.1, 1.3, 1.8], 1.5)
    problem = build_problem(str(hostile_fmu), measurement(hostile_fmu, 0.4), adapter(0.0, 2.0))
    objective = ProblemObjective(problem)
    before_fds, before_children = _open_fds(), children(os.getpid())
    with IsolatedPool(objective, n_workers=2, timeout_s=0.5,
                      max_consecutive_failures=10_000) as pool:
        results = pool.map(k[:, None])
    good = kind == "good"
    assert all((r is not None) == g for r, g in zip(results, good))
    assert pool.failures.count == int((~good).sum())
    reasons = " | ".join(pool.failures.reasons)
    assert all(s in reasons for s in ("SIGSEGV", "exceeded 0.5 s", "non-finite", "failed"))
    # the good ones are right: the residual is smallest at the true k
    errors = {round(float(x), 3): float(np.linalg.norm(r)) for x, r in zip(k, results)
              if r is not None}
    assert abs(min(errors, key=errors.get) - 0.4) < 0.01
    assert children(os.getpid()) == before_children
    assert _open_fds() == before_fds
    assert not any(scratch.iterdir()), list(scratch.rglob("*"))[:10]
