"""A crashing, hanging, NaN-producing, step-failing FMU: penalised, restarted, reported."""

import dataclasses
import os
import time

import numpy as np
import pytest
from conftest import inspected
from fmus.hostile import adapter, measurement

from pydiag.core.errors import EstimationError, PlantError
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.build import build_problem
from pydiag.fmu.isolation import IsolatedPool
from pydiag.fmu.plant import FmuPlant


def test_plant_reports_nan_and_failed_step(hostile_fmu):
    with FmuPlant(hostile_fmu, ("y",), sample_rate_hz=100.0) as plant:
        with pytest.raises(PlantError, match="non-finite"):
            plant.simulate({"k": 1.3}, 0.1, 0.0)
        with pytest.raises(PlantError, match="failed"):
            plant.simulate({"k": 1.1}, 0.1, 0.0)
        assert np.isfinite(plant.simulate({"k": 0.5}, 0.1, 0.0)).all()  # still usable


def test_fit_survives_crashes_hangs_nans_and_failed_steps(hostile_fmu):
    est = FaultEstimator(n_particles=8, iterations=4, polish_evaluations=10, polish_starts=1,
                         seed=2, n_workers=2, eval_timeout_s=2.0)
    r = est.fit(build_problem(str(hostile_fmu), measurement(hostile_fmu, 0.4), adapter(0.0, 2.0)))
    assert abs(r.parameters["k"] - 0.4) < 0.02
    assert r.failed_evaluations > 0
    reasons = " | ".join(r.failure_reasons)
    assert "SIGSEGV" in reasons, reasons
    assert r.evaluations > r.failed_evaluations


def test_consecutive_failures_stop_with_the_cause(hostile_fmu):
    est = FaultEstimator(n_particles=4, iterations=3, polish_evaluations=0, n_workers=2,
                         eval_timeout_s=1.0, max_consecutive_failures=4)
    problem = build_problem(str(hostile_fmu), measurement(hostile_fmu, 0.4), adapter(1.65, 2.0))
    with pytest.raises(EstimationError, match=r"4 evaluations failed in a row; last: .*SIGSEGV"):
        est.fit(problem)


def test_an_fmu_that_hangs_from_the_start_stops_after_one_timeout_per_worker(hostile_fmu):
    """Not after max_consecutive_failures timeouts (20 x 60 s / 2 workers = 10 min by default).
    The timeout comes from the adapter here."""
    est = FaultEstimator(n_particles=8, iterations=3, polish_evaluations=0, n_workers=2,
                         max_consecutive_failures=20)
    slow = dataclasses.replace(adapter(1.45, 1.55), eval_timeout_s=1.0)
    problem = build_problem(str(hostile_fmu), measurement(hostile_fmu, 0.4), slow)
    started = time.monotonic()
    with pytest.raises(EstimationError, match=r"the first 2 evaluations all exceeded 1 s: the FMU "
                                              r"hangs"):
        est.fit(problem)
    assert time.monotonic() - started < 10


def test_cosimulation_divergence_is_detected_and_the_step_chosen_from_bands(tmp_path):
    """Explicit Euler inside doStep: stable at 1e-5 s steps, explodes at 1e-4 s (lambda*h = 3)."""
    pytest.importorskip("pythonfmu")
    from fmus import build_pythonfmu
    fmu = build_pythonfmu(tmp_path, "Stiff", '''
import math
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class Stiff(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.lam = 30000.0
        self.y = 0.0
        self.x = 0.0
        self.register_variable(Real("lam", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, t, dt):
        u = math.sin(2 * math.pi * 50 * t)
        self.x += dt * self.lam * (u - self.x)
        self.y = self.x
        return True
''')
    inspected(fmu)
    with FmuPlant(fmu, ("y",), sample_rate_hz=10_000.0) as plant:
        with pytest.raises(PlantError, match=r"diverged \(Co-Simulation communication step 0.0001"):
            plant.simulate({}, 0.05, 0.0)
    # the estimator's rule, 20 steps per period of the highest analysed frequency (500 Hz):
    with FmuPlant(fmu, ("y",), sample_rate_hz=10_000.0, cs_step_s=1 / (20 * 500.0)) as plant:
        assert plant.substeps == 1  # 1e-4 s already meets 20 x 500 Hz: still unstable
    with FmuPlant(fmu, ("y",), sample_rate_hz=10_000.0, cs_step_s=1e-5) as plant:
        y = plant.simulate({}, 0.05, 0.0)[0]
        assert plant.substeps == 10 and np.max(np.abs(y)) < 1.1


def test_a_swarm_whose_every_simulation_fails_stops_with_the_first_cause(hostile_fmu):
    """Fewer failures than the consecutive limit, yet no finite cost: a clean stop naming
    the first failure (pyswarms used to fail on an empty best position here)."""
    est = FaultEstimator(n_particles=4, iterations=3, polish_evaluations=0, n_workers=2,
                         eval_timeout_s=1.0, max_consecutive_failures=100)
    problem = build_problem(str(hostile_fmu), measurement(hostile_fmu, 0.4), adapter(1.65, 2.0))
    with pytest.raises(EstimationError, match=r"every simulation of the plant failed \(4 "
                                              r"evaluations\); the first failed with: .*SIGSEGV"):
        est.fit(problem)


class SlowToLoad:
    """An objective whose loading takes longer than an evaluation's time limit (an FMU on
    a loaded machine), whose evaluations are quick, and which crashes its worker at x < 0."""

    def __init__(self, load_s: float) -> None:
        self.load_s = load_s
        self.loaded = False

    def prepare(self) -> None:  # loads once, as ProblemObjective opens its plant
        if not self.loaded:
            time.sleep(self.load_s)
            self.loaded = True

    def residuals(self, x: np.ndarray) -> np.ndarray:
        self.prepare()
        if x[0] < 0:
            os._exit(1)
        return np.asarray(x, dtype=float)


def test_an_evaluation_is_timed_from_when_its_worker_has_loaded_its_model():
    """A worker's loading is not its first evaluation's time: with loading three times the
    limit, every evaluation gives its answer, the first workers' and a replaced one's."""
    with IsolatedPool(SlowToLoad(0.6), n_workers=2, timeout_s=0.2) as pool:
        results = pool.map(np.array([[1.0], [2.0], [-1.0], [3.0], [4.0]]))
        assert [None if r is None else float(r[0]) for r in results] == [1.0, 2.0, None, 3.0, 4.0]
        assert pool.timeouts == 0 and pool.failures.count == 1  # the crash alone
