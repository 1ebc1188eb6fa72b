"""Regression check of exported FMUs against golden spectra."""

import json

import numpy as np
import pytest

from conftest import inspected, run_cli

from fmu_build import build_fmu
from pydiag.fmu.plant import FmuPlant
from pydiag.model import regress

GOLDEN = "tests/golden/GearPair.json"


def test_shipped_fmu_matches_golden(gear_fmu):
    report = regress.check(gear_fmu, GOLDEN)
    assert report.cases == 8 and report.sensors == ["acc", "disp"]
    assert report.passed, report.mismatches
    assert report.worst_relative < regress.DEFAULT_RTOL


def test_changed_model_default_fails_regression(tmp_path, modelica_copy):
    """Changing one default (the mesh damping, by 10 %, in the law GearPair extends) must fail."""
    law = modelica_copy / "GearDiag" / "Interfaces" / "PartialMeshLaw.mo"
    text = law.read_text()
    assert 'c(unit="N.s/m") = 1000' in text
    law.write_text(text.replace('c(unit="N.s/m") = 1000', 'c(unit="N.s/m") = 1100'))
    fmu = inspected(build_fmu(modelica_copy / "GearDiag" / "GearPair.mo", "GearDiag.GearPair",
                              tmp_path / "Perturbed.fmu"))
    report = regress.check(fmu, GOLDEN)
    assert not report.passed
    res = run_cli("-m", "pydiag", "regress", "--fmu", str(fmu), "--golden", GOLDEN)
    assert res.returncode == 1 and "FAIL" in res.stdout


def test_bless_and_check_any_fmu_without_gear_parameters(tmp_path):
    """A model with neither fault parameters nor kinematics: one case at its defaults, FFT spectrum."""
    source = """model Osc
  parameter Real w(unit="rad/s") = 300;
  parameter Real d = 0.05;
  Real x(start = 1, fixed = true);
  Real v(start = 0, fixed = true);
  output Real y(unit="m");
equation
  der(x) = v;
  der(v) = -w*w*x - 2*d*w*v + 50*sin(700*time);
  y = x;
end Osc;
"""
    mo = tmp_path / "Osc.mo"
    mo.write_text(source)
    fmu = inspected(build_fmu(mo, "Osc", tmp_path / "Osc.fmu"))
    golden = tmp_path / "osc.json"
    res = run_cli("-m", "pydiag", "regress", "--fmu", str(fmu), "--golden", str(golden), "--bless")
    assert res.returncode == 0, res.stderr
    data = json.loads(golden.read_text())
    assert list(data["cases"]) == ["defaults"] and data["kinematics"] is None
    res = run_cli("-m", "pydiag", "regress", "--fmu", str(fmu), "--golden", str(golden))
    assert res.returncode == 0 and res.stdout.startswith("PASS"), res.stdout + res.stderr
    # a golden blessed from a model whose default damping differs fails
    (tmp_path / "v2").mkdir()
    mo2 = tmp_path / "v2" / "Osc.mo"
    mo2.write_text(source.replace("d = 0.05", "d = 0.08"))
    with FmuPlant(inspected(build_fmu(mo2, "Osc", tmp_path / "v2" / "Osc.fmu")), ("y",)) as plant:
        regress.bless(plant, golden)
    assert not regress.check(fmu, golden).passed
    # start values recorded at blessing are applied by the check
    with FmuPlant(fmu, ("y",), fixed_values={"d": 0.08}) as plant:
        regress.bless(plant, golden)
    assert json.loads(golden.read_text())["start_values"] == {"d": 0.08}
    assert regress.check(fmu, golden).passed


def test_missing_golden_is_a_clear_error(gear_fmu, tmp_path):
    res = run_cli("-m", "pydiag", "regress", "--fmu", str(gear_fmu), "--golden",
                  str(tmp_path / "none.json"))
    assert res.returncode == 2 and "create it with --bless" in res.stderr
    assert "Traceback" not in res.stderr


def test_a_machines_own_model_is_blessed_checked_and_is_the_pairs(tmp_path):
    """`regress --machine`: the machine's own model, written and built, blessed and checked
    on Table 1's cases (on its stage's fault parameters). The paper's pair as a machine of
    one stage gives the pair FMU's golden spectra within the check's tolerance (one model,
    two routes to it); the same file at another speed fails the check."""
    golden = tmp_path / "pair.json"
    build = ["--build-dir", str(tmp_path / "build")]
    res = run_cli("-m", "pydiag", "regress", "--machine", "examples/paper_pair.toml",
                  "--golden", str(golden), "--bless", *build)
    assert res.returncode == 0, res.stderr
    mine, pair = json.loads(golden.read_text()), json.loads(open(GOLDEN).read())
    assert mine["synchronous"]["period_s"] == pytest.approx(0.12)
    assert list(mine["cases"]) == list(pair["cases"])
    for name, case in pair["cases"].items():
        assert mine["cases"][name]["parameters"] == {
            f"pair.{k}": v for k, v in case["parameters"].items()}
        for sensor, ref in case["spectra"].items():
            g = np.asarray(ref["amplitude"])
            a = np.asarray(mine["cases"][name]["spectra"][f"{sensor}_{sensor}"]["amplitude"])
            assert a.shape == g.shape and np.max(np.abs(a - g)) < regress.DEFAULT_RTOL * g.max()
    res = run_cli("-m", "pydiag", "regress", "--machine", "examples/paper_pair.toml",
                  "--golden", str(golden), *build)
    assert res.returncode == 0 and res.stdout.startswith("PASS: 8 cases x 2 sensors"), res.stdout
    faster = tmp_path / "faster.toml"
    faster.write_text(open("examples/paper_pair.toml").read().replace("input_rpm = 1500",
                                                                     "input_rpm = 1530"))
    res = run_cli("-m", "pydiag", "regress", "--machine", str(faster), "--golden", str(golden),
                  *build)
    assert res.returncode == 1 and "FAIL" in res.stdout, res.stdout + res.stderr
    res = run_cli("-m", "pydiag", "regress", "--machine", "examples/paper_pair.toml",
                  "--golden", str(golden), "--adapter", "x.toml", *build)
    assert res.returncode == 2 and "--adapter" in res.stderr and "Traceback" not in res.stderr
