"""The estimator on our own FMU: the objective prefers the truth, results do not depend on
the worker count, a fit writes nothing."""

import dataclasses

import numpy as np
import pytest
from conftest import NAMES, noisy_measurement

from pydiag.core.errors import UsageError
from pydiag.core.parameters import Parameter
from pydiag.fit import estimator as estimator_module
from pydiag.fit.estimator import DISCRETE_FINALISTS, FINALIST_TIE, FaultEstimator, finalists
from pydiag.fit.build import build_problem
from pydiag.fit.problem import ProblemObjective
from pydiag.fmu.isolation import IsolatedPool
from pydiag.gear.paper_cases import case


def test_objective_is_lowest_at_the_truth(gear_fmu):
    """Before trusting an optimiser: the truth must beat every nearby wrong answer."""
    c = case(8)
    objective = ProblemObjective(build_problem(gear_fmu, noisy_measurement(gear_fmu, 8, 0)))
    truth = np.array([c.parameters[n] for n in NAMES])
    e_true = objective(truth)
    for i, name in enumerate(NAMES):
        for delta in (-0.05, 0.05):
            x = truth.copy()
            x[i] += delta
            assert objective(x) > e_true, f"{name}{delta:+}: truth is not preferred"
    objective.close()


def test_result_does_not_depend_on_worker_count(gear_fmu):
    m = build_problem(gear_fmu, noisy_measurement(gear_fmu, 5, 0, periods=2))
    kwargs = dict(n_particles=4, iterations=2, polish_evaluations=10, polish_starts=1, seed=3)
    one = FaultEstimator(n_workers=1, **kwargs).fit(m)
    two = FaultEstimator(n_workers=2, **kwargs).fit(m)
    assert one.parameters == two.parameters and one.error == two.error
    other_seed = FaultEstimator(n_workers=2, **{**kwargs, "seed": 4}).fit(m)
    assert other_seed.parameters != one.parameters



def test_the_swarm_ranks_at_its_own_tolerance_and_the_answer_is_at_the_problems(
        gear_fmu, monkeypatch):
    """The swarm's simulations run at ``swarm_tolerance`` (the native engine), the polish's
    and the starts' again at the problem's (1e-6), and the error reported is the
    problem's at the estimate, not the swarm's. A problem that asks for a tolerance of its
    own is simulated at it throughout."""
    problem = build_problem(gear_fmu, noisy_measurement(gear_fmu, 8, 0, periods=2))
    tolerances = []  # (tolerance, batch size) of every batch, in order
    pool_map = IsolatedPool.map

    def spy(self, xs):
        spec = self.objective.problem.spec
        tolerances.append((spec.relative_tolerance or spec.native_tolerance, len(xs)))
        return pool_map(self, xs)

    monkeypatch.setattr(IsolatedPool, "map", spy)
    settings = dict(n_particles=4, iterations=3, polish_evaluations=30, polish_starts=2,
                    n_workers=2, swarm_tolerance=1e-3)
    r = FaultEstimator(**settings).fit(problem)
    assert [t for t, _ in tolerances[:3]] == [1e-3] * 3  # the swarm's three iterations
    assert tolerances[3] == (1e-6, 2)  # its two best distinct positions, again
    assert {t for t, _ in tolerances[3:]} == {1e-6}
    objective = ProblemObjective(problem)
    at_estimate = objective(np.array([r.parameters[n] for n in NAMES]))
    objective.close()
    assert r.error == pytest.approx(at_estimate, rel=1e-12)
    coarse = ProblemObjective(dataclasses.replace(problem, spec=dataclasses.replace(
        problem.spec, native_tolerance=1e-3)))
    assert coarse(np.array([r.parameters[n] for n in NAMES])) != pytest.approx(at_estimate,
                                                                               rel=1e-9)
    coarse.close()

    tolerances.clear()
    own = dataclasses.replace(problem, spec=dataclasses.replace(problem.spec,
                                                                relative_tolerance=1e-7))
    FaultEstimator(**settings).fit(own)
    assert {t for t, _ in tolerances} == {1e-7}
    with pytest.raises(UsageError, match="swarm's tolerance must be positive"):
        FaultEstimator(swarm_tolerance=0.0).fit(problem)


def test_refine_polishes_from_its_start_and_stays_in_its_basin(gear_fmu):
    """refine: the polish alone, from a given start: it lowers the error of a start off the
    truth towards the truth, and stops near the start when that is already the minimum."""
    c = case(5)
    problem = build_problem(gear_fmu, noisy_measurement(gear_fmu, 5, 0, periods=2))
    truth = {n: c.parameters[n] for n in NAMES}
    off = {**truth, "a_f": truth["a_f"] + 0.04, "f_ate": truth["f_ate"] - 0.04}
    objective = ProblemObjective(problem)
    start_error = objective(np.array([off[n] for n in NAMES]))
    objective.close()
    est = FaultEstimator(polish_evaluations=60, n_workers=2)
    r = est.refine(problem, off)
    assert r.error < 0.5 * start_error
    assert abs(r.parameters["a_f"] - truth["a_f"]) < 0.02
    assert abs(r.parameters["f_ate"] - truth["f_ate"]) < 0.02
    assert r.evaluations <= 1 + 60 + len(NAMES) + 1  # its budget (one last Jacobian over)
    with pytest.raises(UsageError, match="start value of f_dte"):
        est.refine(problem, {k: v for k, v in off.items() if k != "f_dte"})


def test_a_stepped_parameter_is_fitted_on_its_multiples(gear_fmu, monkeypatch):
    """A parameter with a step (a tooth's index) is simulated only at its multiples and
    estimated as one; the swarm grows to one particle per multiple, so each is tried from
    the first iteration (here f_ate in steps of 0.1: 11 particles for 3 asked)."""
    problem = build_problem(gear_fmu, noisy_measurement(gear_fmu, 8, 0, periods=2),
                            parameters=(Parameter("f_ate", 0.0, 1.0, step=0.1),),
                            fixed_values={"a_f": 0.3, "f_f": 0.6, "f_dte": 0.2})
    batches = []
    pool_map = IsolatedPool.map

    def spy(self, xs):
        batches.append(np.array(xs)[:, 0])
        return pool_map(self, xs)

    monkeypatch.setattr(IsolatedPool, "map", spy)
    r = FaultEstimator(n_particles=3, iterations=2, polish_evaluations=20, polish_starts=1,
                       n_workers=2).fit(problem)
    assert sorted(batches[0]) == pytest.approx([k / 10 for k in range(11)])
    tried = np.concatenate(batches)
    assert np.allclose(tried * 10, np.round(tried * 10), atol=1e-9)
    assert r.parameters["f_ate"] == pytest.approx(0.2)  # case 8's
    assert r.evaluations == tried.size >= 11 * 2


def test_a_discrete_parameter_is_searched_exhaustively(gear_fmu, monkeypatch):
    """Each value of a stepped parameter keeps its own particles (the swarm never moves
    them off it) and takes a least-squares step over the continuous parameters, and the
    best few after it are polished on, so the value found does not depend on where the
    swarm's random start put the continuous ones: the same tooth (here f_ate in steps of
    0.1) for every seed, with a_f fitted beside it."""
    problem = build_problem(gear_fmu, noisy_measurement(gear_fmu, 8, 0, periods=2),
                            parameters=(Parameter("f_ate", 0.0, 1.0, step=0.1),
                                        Parameter("a_f", 0.0, 1.0)),
                            fixed_values={"f_f": 0.6, "f_dte": 0.2})
    batches = []
    pool_map = IsolatedPool.map

    def spy(self, xs):
        batches.append(np.array(xs))
        return pool_map(self, xs)

    monkeypatch.setattr(IsolatedPool, "map", spy)
    rounds = []
    side_by_side = estimator_module.run_in_lockstep

    def counted(evaluate, tasks):
        rounds.append(len(tasks))
        return side_by_side(evaluate, tasks)

    monkeypatch.setattr(estimator_module, "run_in_lockstep", counted)
    found = set()
    for seed in (0, 1, 2):
        batches.clear()
        r = FaultEstimator(n_particles=3, iterations=3, polish_evaluations=30, polish_starts=1,
                           n_workers=2, seed=seed).fit(problem)
        swarm = batches[:3]  # the 11 values' particles, 3 iterations
        assert all(len(b) == 11 and np.array_equal(b[:, 0], swarm[0][:, 0]) for b in swarm)
        # every value's best position stepped: some simulations at each value after the
        # swarm; the best few after that step polished on (DISCRETE_FINALISTS)
        polished = np.concatenate(batches[3:])[:, 0]
        assert set(np.round(polished, 6)) == {round(k / 10, 6) for k in range(11)}
        assert rounds == [11, DISCRETE_FINALISTS]  # searches run side by side, each round
        rounds.clear()
        assert r.parameters["a_f"] == pytest.approx(0.3, abs=0.05)
        found.add(round(r.parameters["f_ate"], 9))
    assert found == {0.2}


def test_replace_gives_a_new_estimator_with_other_settings():
    est = FaultEstimator(n_particles=8, polish_evaluations=60)
    other = est.replace(polish_evaluations=0)
    assert (other.n_particles, other.polish_evaluations) == (8, 0)
    assert est.polish_evaluations == 60
    with pytest.raises(UsageError, match="no setting polish_budget"):
        est.replace(polish_budget=1)

def test_fit_writes_no_files_and_leaves_logging_alone(gear_fmu, tmp_path):
    """A fit writes nothing in the current folder and leaves the root logger alone (pyswarms
    added root-logger handlers and wrote ./report.log; the swarm no longer uses it)."""
    import subprocess
    import sys
    script = f"""
import logging, numpy as np
from pydiag.core.measurement import Measurement
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.build import build_problem
from pydiag.fmu.plant import FmuPlant
with FmuPlant({str(gear_fmu)!r}, ("acc",)) as p:
    y = p.simulate({{}}, 0.24, 0.05)[0]
FaultEstimator(n_particles=4, iterations=2, polish_evaluations=0, n_workers=1).fit(
    build_problem({str(gear_fmu)!r}, Measurement({{"acc": y}}, 1e4)))
print(len(logging.getLogger().handlers))
"""
    import os

    from conftest import ROOT
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    res = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True,
                         text=True, env=env)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "0"
    assert list(tmp_path.iterdir()) == []


def test_the_finalists_keep_a_near_tie_at_the_cut_whole():
    """Which tooth values are polished on must not hang on rounding: a value within
    FINALIST_TIE of the last finalist goes on too, one clearly behind does not."""
    n = DISCRETE_FINALISTS
    best = [float(k) for k in range(n, 0, -1)]  # n finalists, listed worst first
    last = float(n)
    tied = best + [last * (1 + FINALIST_TIE / 10), 9.0 * n, np.inf]
    assert finalists(tied) == list(range(n - 1, -1, -1)) + [n]
    # the tie's two members in either order, each a rounding away from the other
    swapped = best[1:] + [last * (1 + FINALIST_TIE / 10), last, 9.0 * n]
    assert sorted(finalists(swapped)) == list(range(n + 1))
    clear = best + [last * (1 + 10 * FINALIST_TIE), 9.0 * n]
    assert finalists(clear) == list(range(n - 1, -1, -1))
    assert finalists([np.inf] * (n + 2)) == list(range(n))
    assert finalists(best[:-1]) == list(range(n - 2, -1, -1))  # fewer: every one
