"""Diagnosis end to end on noisy Table 1 measurements (SNR 10, acc + disp channels)."""

import json
from pathlib import Path

import pytest
from conftest import NAMES, noisy_measurement, run_cli

from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.build import build_problem
from pydiag.gear.paper_cases import TABLE1, case
from pydiag.diagnose.diagnosis import diagnose


@pytest.mark.parametrize("number", [3, 6])
def test_fast_diagnosis_recovers_parameters_mode_and_severity(gear_fmu, number):
    c = case(number)
    est = FaultEstimator(n_particles=8, iterations=6, polish_evaluations=100, polish_starts=2,
                         seed=1)
    r = diagnose(build_problem(gear_fmu, noisy_measurement(gear_fmu, number, 0)), est)
    errors = {n: abs(r.parameters[n] - c.parameters[n]) for n in NAMES}
    assert max(errors.values()) <= 0.03, errors
    assert (r.fault_mode, r.severity) == (c.fault_mode, c.severity)
    assert r.fit.evaluations <= 8 * 6 + 2 * 100


def test_cli_diagnose_json_contract(gear_fmu, tmp_path):
    meas = tmp_path / "m.csv"
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(gear_fmu), "--set", "f_ate=0.4",
                  "--set", "f_dte=0.4", "--duration", "0.48", "--snr", "10", "--out", str(meas))
    assert res.returncode == 0, res.stderr
    out = tmp_path / "r.json"
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement", str(meas),
                  "--json", str(out), "--particles", "4", "--iterations", "2", "--polish", "0",
                  "--quiet")
    data = json.loads(out.read_text())
    # eight evaluations may explain none of the record: then it is no diagnosis, exit 1
    assert res.returncode == (1 if data["fault_mode"] == "no_diagnosis" else 0), res.stderr
    assert {"parameters", "fault_mode", "severity", "error", "evaluations", "elapsed_s"} <= set(data)
    assert set(data["parameters"]) == set(NAMES)
    # the swarm's 8 at its own tolerance, then its best distinct positions (3 at most) again
    assert 8 < data["evaluations"] <= 8 + 3 and data["error"] > 0
    # a pair is a machine of one stage: the JSON of a machine's diagnosis, one stage
    (stage,) = data["stages"]
    assert (stage["pinion_teeth"], stage["gear_teeth"]) == (14, 21)  # GearPair's defaults
    assert stage["mesh_hz"] == pytest.approx(14 * data["speed_hz"])
    assert (stage["fault_mode"], stage["severity"]) == (data["fault_mode"], data["severity"])
    assert stage["model"]["parameters"] == data["parameters"] and stage["baseline"] is None
    assert data["baselines"] == [] and "no baseline" in data["severity_scale"]
    assert "fault mode" in res.stdout
    # eight evaluations are too few to trust: whatever is warned is in the JSON as well
    warned = res.stderr.splitlines()
    assert all(w.startswith("pydiag diagnose: warning: ") for w in warned), res.stderr
    assert [w.removeprefix("pydiag diagnose: warning: ") for w in warned] == data["warnings"]


@pytest.mark.slow
@pytest.mark.parametrize("number", [c.number for c in TABLE1])
def test_paper_case_full_diagnosis(gear_fmu, number):
    c = case(number)
    r = diagnose(build_problem(gear_fmu, noisy_measurement(gear_fmu, number, 0)),
                 FaultEstimator(seed=0))
    assert max(abs(r.parameters[n] - c.parameters[n]) for n in NAMES) <= 0.03
    assert (r.fault_mode, r.severity) == (c.fault_mode, c.severity)




#: The paper's pair as a machine file of one stage: a sensor for each output it records.
PAIR_MACHINE = Path(__file__).resolve().parents[2] / "examples" / "paper_pair.toml"


def test_cli_diagnose_a_machine_file_without_an_fmu(gear_fmu, tmp_path):
    """Table 1 case 8 through a machine file of one stage and no --fmu: the machine's own
    model is written, built and fitted; the stage is combined/medium with its parameters
    near the truth; without --fmu and without --machine, one line says what to give."""
    c = case(8)
    meas, machine, out = tmp_path / "m.csv", PAIR_MACHINE, tmp_path / "r.json"
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(gear_fmu), "--snr", "10",
                  *[a for n, v in c.parameters.items() for a in ("--set", f"{n}={v}")],
                  "--out", str(meas))
    assert res.returncode == 0, res.stderr
    res = run_cli("-m", "pydiag", "diagnose", "--machine", str(machine), "--measurement",
                  str(meas), "--json", str(out), "--quiet")
    assert res.returncode == 0, res.stderr
    stage = json.loads(out.read_text())["stages"][0]
    assert (stage["fault_mode"], stage["severity"]) == (c.fault_mode, c.severity), stage
    fitted = stage["model"]["parameters"]
    errors = {n: abs(fitted[f"pair.{n}"] - c.parameters[n]) for n in NAMES}
    assert max(errors.values()) <= 0.03, errors
    assert stage["transmission_error"] == {n: fitted[f"pair.{n}"] for n in ("f_ate", "f_dte")}
    assert "combined" in res.stdout and "medium" in res.stdout
    res = run_cli("-m", "pydiag", "diagnose", "--measurement", str(meas), "--quiet")
    assert res.returncode == 2
    assert "give --machine FILE" in res.stderr and len(res.stderr.strip().splitlines()) == 1
    # --teeth and --rpm without --fmu: the same machine of one stage, written from them
    short = tmp_path / "short.json"
    res = run_cli("-m", "pydiag", "diagnose", "--teeth", "14,21", "--rpm", "1500",
                  "--measurement", str(meas), "--json", str(short), "--quiet")
    assert res.returncode == 0, res.stderr
    again = json.loads(short.read_text())["stages"][0]
    assert (again["fault_mode"], again["severity"]) == (c.fault_mode, c.severity), again
    assert again["model"]["parameters"] == pytest.approx(fitted)
