"""The swarm: pyswarms' GlobalBestPSO step for step, without process-wide state."""

import importlib.util
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from pydiag.fit.pso import global_best_pso, periodic

LOWS, HIGHS = np.array([0.1, 0.0, 0.0, 0.0]), np.array([0.9, 0.95, 1.0, 1.0])


def rugged(xs: np.ndarray) -> np.ndarray:
    return np.sum((xs - 0.3) ** 2, axis=1) + 0.1 * np.sin(17 * xs[:, 0]) * np.cos(11 * xs[:, 1])


def start(seed: int, n: int = 16) -> np.ndarray:
    return LOWS + np.random.default_rng(seed).random((n, LOWS.size)) * (HIGHS - LOWS)


PYSWARMS = """
import sys, numpy as np
from pyswarms.single import GlobalBestPSO
lows, highs = np.array([0.1, 0.0, 0.0, 0.0]), np.array([0.9, 0.95, 1.0, 1.0])
def rugged(xs):
    return np.sum((xs - 0.3) ** 2, axis=1) + 0.1 * np.sin(17 * xs[:, 0]) * np.cos(11 * xs[:, 1])
out = {}
for seed in range(4):
    init = lows + np.random.default_rng(seed).random((16, 4)) * (highs - lows)
    np.random.seed(seed)
    pso = GlobalBestPSO(16, 4, options={"c1": 1.49618, "c2": 1.49618, "w": 0.7298},
                        bounds=(lows, highs), init_pos=init)
    pso.optimize(rugged, iters=12, verbose=False)
    out[f"pos{seed}"], out[f"cost{seed}"] = pso.swarm.pbest_pos, pso.swarm.pbest_cost
    out[f"hist{seed}"] = np.array(pso.cost_history)
    np.random.seed(seed)  # the early stop
    pso = GlobalBestPSO(16, 4, options={"c1": 1.49618, "c2": 1.49618, "w": 0.7298},
                        bounds=(lows, highs), init_pos=init, ftol=1e-4, ftol_iter=2)
    pso.optimize(rugged, iters=60, verbose=False)
    out[f"stop_pos{seed}"], out[f"stop_hist{seed}"] = pso.swarm.pbest_pos, np.array(pso.cost_history)
np.savez(sys.argv[1], **out)
"""


def test_equals_pyswarms_bit_for_bit(tmp_path):
    if importlib.util.find_spec("pyswarms") is None:  # importing it here would write report.log
        pytest.skip("pyswarms is not installed (pip install .[test])")
    # pyswarms configures logging and writes report.log: run it in its own process and folder
    res = subprocess.run([sys.executable, "-c", PYSWARMS, str(tmp_path / "ref.npz")],
                         cwd=tmp_path, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    ref = np.load(tmp_path / "ref.npz")
    for seed in range(4):
        ours = global_best_pso(rugged, start(seed), LOWS, HIGHS, 12, seed)
        assert np.array_equal(ours.pbest_pos, ref[f"pos{seed}"])
        assert np.array_equal(ours.pbest_cost, ref[f"cost{seed}"])
        assert ours.best_cost_history == list(ref[f"hist{seed}"])
        stopped = global_best_pso(rugged, start(seed), LOWS, HIGHS, 60, seed, ftol=1e-4,
                                  ftol_iter=2)
        assert len(stopped.best_cost_history) < 60  # it did stop early, where pyswarms does
        assert stopped.best_cost_history == list(ref[f"stop_hist{seed}"])
        assert np.array_equal(stopped.pbest_pos, ref[f"stop_pos{seed}"])


def test_same_seed_same_swarm_in_concurrent_threads():
    def slow(xs):
        time.sleep(0.002)  # let the threads interleave
        return rugged(xs)

    serial = {seed: global_best_pso(slow, start(seed), LOWS, HIGHS, 8, seed) for seed in (1, 2)}
    results: dict[int, list] = {1: [], 2: []}

    def run(seed):
        results[seed].append(global_best_pso(slow, start(seed), LOWS, HIGHS, 8, seed))

    threads = [threading.Thread(target=run, args=(s,)) for s in (1, 2, 1, 2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for seed, runs in results.items():
        for r in runs:
            assert np.array_equal(r.pbest_pos, serial[seed].pbest_pos)
    assert not np.array_equal(serial[1].pbest_pos, serial[2].pbest_pos)


def test_a_swarm_whose_every_evaluation_fails_stops_without_a_best():
    r = global_best_pso(lambda xs: np.full(len(xs), np.inf), start(0), LOWS, HIGHS, 5, 0)
    assert r.best_cost_history == [] and np.all(np.isinf(r.pbest_cost))


def test_periodic_wraps_into_the_box():
    x = np.array([[0.05, 1.0, -0.25, 1.5], [0.5, 0.5, 0.5, 0.5]])
    w = periodic(x, LOWS, HIGHS)
    assert np.all((w >= LOWS) & (w <= HIGHS))
    assert w[0] == pytest.approx([0.85, 0.05, 0.75, 0.5])
    assert np.array_equal(w[1], x[1])
