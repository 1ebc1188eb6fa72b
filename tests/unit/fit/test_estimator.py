"""The estimator on our own FMU: the objective prefers the truth, results do not depend on
the worker count, a fit writes nothing."""

import numpy as np
from conftest import NAMES, noisy_measurement

from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import ProblemObjective, build_problem
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


def test_fit_writes_no_files_and_leaves_logging_alone(gear_fmu, tmp_path):
    """A fit writes nothing in the current folder and leaves the root logger alone (pyswarms
    added root-logger handlers and wrote ./report.log; the swarm no longer uses it)."""
    import subprocess
    import sys
    script = f"""
import logging, numpy as np
from pydiag.core.measurement import Measurement
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import build_problem
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
