"""Diagnosis end to end on noisy Table 1 measurements (SNR 10, acc + disp channels)."""

import json

import numpy as np
import pytest

from conftest import run_cli
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import ProblemObjective, build_problem
from pydiag.gear.conventions import kinematics_from
from pydiag.core.measurement import Measurement
from pydiag.signal.noise import add_white_noise
from pydiag.gear.paper_cases import TABLE1, case
from pydiag.fmu.plant import FmuPlant

NAMES = ("a_f", "f_f", "f_ate", "f_dte")
SENSORS = ("acc", "disp")


def noisy_measurement(fmu, number: int, seed: int, periods: int = 10) -> Measurement:
    with FmuPlant(fmu, SENSORS) as plant:
        kin = kinematics_from(plant.parameters())
        clean = plant.simulate(case(number).parameters, periods * kin.period_s, 0.05)
    rng = np.random.default_rng(1000 * number + seed)
    return Measurement({s: add_white_noise(clean[i], 10.0, rng) for i, s in enumerate(SENSORS)},
                       10_000.0)


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


@pytest.mark.parametrize("number", [3, 6])
def test_fast_diagnosis_recovers_parameters_mode_and_severity(gear_fmu, number):
    c = case(number)
    est = FaultEstimator(n_particles=8, iterations=6, polish_evaluations=100, polish_starts=2,
                         seed=1)
    r = est.fit(build_problem(gear_fmu, noisy_measurement(gear_fmu, number, 0)))
    errors = {n: abs(r.parameters[n] - c.parameters[n]) for n in NAMES}
    assert max(errors.values()) <= 0.03, errors
    assert (r.fault_mode, r.severity) == (c.fault_mode, c.severity)
    assert r.evaluations <= 8 * 6 + 2 * 100
    assert r.best_error_history == sorted(r.best_error_history, reverse=True)


def test_result_does_not_depend_on_worker_count(gear_fmu):
    m = build_problem(gear_fmu, noisy_measurement(gear_fmu, 5, 0, periods=2))
    kwargs = dict(n_particles=4, iterations=2, polish_evaluations=10, polish_starts=1, seed=3)
    one = FaultEstimator(n_workers=1, **kwargs).fit(m)
    two = FaultEstimator(n_workers=2, **kwargs).fit(m)
    assert one.parameters == two.parameters and one.error == two.error
    other_seed = FaultEstimator(n_workers=2, **{**kwargs, "seed": 4}).fit(m)
    assert other_seed.parameters != one.parameters


def test_cli_diagnose_json_contract(gear_fmu, tmp_path):
    meas = tmp_path / "m.csv"
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(gear_fmu), "--set", "f_ate=0.4",
                  "--set", "f_dte=0.4", "--duration", "0.48", "--snr", "10", "--out", str(meas))
    assert res.returncode == 0, res.stderr
    out = tmp_path / "r.json"
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement", str(meas),
                  "--json", str(out), "--particles", "4", "--iterations", "2", "--polish", "0",
                  "--quiet")
    assert res.returncode == 0, res.stderr
    data = json.loads(out.read_text())
    assert {"parameters", "fault_mode", "severity", "error", "evaluations", "elapsed_s"} <= set(data)
    assert set(data["parameters"]) == set(NAMES)
    assert data["evaluations"] == 8 and data["error"] > 0
    assert "fault mode" in res.stdout and res.stderr == ""


@pytest.mark.slow
@pytest.mark.parametrize("number", [c.number for c in TABLE1])
def test_paper_case_full_diagnosis(gear_fmu, number):
    c = case(number)
    r = FaultEstimator(seed=0).fit(build_problem(gear_fmu, noisy_measurement(gear_fmu, number, 0)))
    assert max(abs(r.parameters[n] - c.parameters[n]) for n in NAMES) <= 0.03
    assert (r.fault_mode, r.severity) == (c.fault_mode, c.severity)


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
