"""Regression check of exported FMUs against golden spectra."""

import json

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
