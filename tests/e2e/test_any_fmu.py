"""Bring your own FMU: other exporters (CasADi direct, pythonfmu, OpenModelica) diagnosed
through adapters, inspect, schema warnings. Every FMU here is built or fetched by the test run."""

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, inspected, run_cli
from fmus import casadi_gear, pythonfmu_gear

from pydiag.core.errors import AdapterError, PlantError
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.build import build_problem
from pydiag.diagnose.diagnosis import diagnose
from pydiag.fmu.inspect import describe
from pydiag.fmu.plant import FmuPlant
from pydiag.io.readers import read_measurement
from pydiag.model.adapter import check_against_fmu, load_adapter, parse_adapter

# ---------------------------------------------------------------------- adapters

MINIMAL = {"sensor": [{"variable": "y"}], "fault_parameter": [{"variable": "k", "low": 0, "high": 1}],
           "spectrum": {"window_s": 1.0, "max_freq_hz": 10.0}}






# ---------------------------------------------------------------------- CasADi, other names

@pytest.fixture(scope="module")
def vendor_gear(tmp_path_factory):
    folder = tmp_path_factory.mktemp("vendor_gear")
    fmu = casadi_gear.build(folder / "VendorGear.fmu")
    adapter = folder / "vendor.toml"
    adapter.write_text(casadi_gear.ADAPTER)
    return fmu, adapter


def test_inspect_runs_on_every_fmu_the_tests_build(gear_fmu, vendor_gear, pythonfmu_fmu,
                                                  tmp_path):
    from fmus import hostile
    fmus = [gear_fmu, vendor_gear[0], pythonfmu_fmu[0], hostile.build(tmp_path)]
    res = run_cli("-m", "pydiag", "inspect", *map(str, fmus))
    assert res.returncode == 0, res.stderr
    blocks = res.stdout.split("\n\n")
    assert [b.splitlines()[0] for b in blocks] == list(map(str, fmus))  # one block each, in order
    assert "FMI 3.0" in blocks[0] and "made by CasADi" in blocks[1] and "PythonFMU" in blocks[2]
    assert "a_f" in blocks[0] and "Fault_Amplitude" in blocks[2]


def test_casadi_vendor_gear_diagnosed_through_its_adapter(vendor_gear, tmp_path):
    fmu, adapter = vendor_gear
    meas = tmp_path / "m.csv"
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(fmu), "--adapter", str(adapter),
                  "--set", "tooth_amp=0.35", "--set", "runout_um=10", "--snr", "10",
                  "--out", str(meas), "--quiet")
    assert res.returncode == 0, res.stderr
    m = read_measurement(meas)
    assert list(m.channels) == ["acc", "disp"]
    assert 5e-6 < np.mean(m.channels["disp"]) < 1e-5  # probe in um, channel in m (scale 1e-6)
    out = tmp_path / "r.json"
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(fmu), "--adapter", str(adapter),
                  "--measurement", str(meas), "--json", str(out), "--particles", "8",
                  "--iterations", "6", "--polish", "60", "--quiet")
    assert res.returncode == 0, res.stderr
    result = json.loads(out.read_text())
    assert abs(result["parameters"]["a_f"] - 0.35) <= 0.03
    assert abs(result["parameters"]["f_ate"] - 0.2) <= 0.03  # runout 10 um = 0.2 x 50 um
    assert result["fault_mode"] == "combined"


def test_adapter_names_must_exist_and_be_settable(vendor_gear, tmp_path):
    fmu, _ = vendor_gear
    with FmuPlant(fmu, ("housing_acc",)) as plant:
        variables = plant.variables
    text = casadi_gear.ADAPTER.replace('variable = "tooth_amp"', 'variable = "no_such"')
    with pytest.raises(AdapterError, match="fault parameter 'no_such' is not in the FMU"):
        check_against_fmu(parse_adapter(__import__("tomllib").loads(text)), variables)
    text = casadi_gear.ADAPTER.replace('variable = "tooth_amp"', 'variable = "housing_acc"')
    with pytest.raises(AdapterError, match="causality 'output'"):
        check_against_fmu(parse_adapter(__import__("tomllib").loads(text)), variables)


# ---------------------------------------------------------------------- pythonfmu, FMI 2 CS

@pytest.fixture(scope="module")
def pythonfmu_fmu(tmp_path_factory):
    pytest.importorskip("pythonfmu")
    folder = tmp_path_factory.mktemp("pyfmu")
    fmu = pythonfmu_gear.build(folder)
    adapter = folder / "pygear.toml"
    adapter.write_text(pythonfmu_gear.ADAPTER)
    return fmu, adapter


def test_pythonfmu_cosimulation_gear_diagnosed(pythonfmu_fmu):
    fmu, adapter_path = pythonfmu_fmu
    info = describe(fmu)
    assert info.fmi_version == "2.0" and info.interfaces == ["CoSimulation"]
    adapter = load_adapter(adapter_path)
    with FmuPlant(fmu, ("Accel",)) as plant:
        assert plant.engine == "fmpy"  # CS: the native engine does not apply
        y = plant.simulate({"Fault_Amplitude": 0.4}, 0.36, 0.02)[0]
    rng = np.random.default_rng(3)
    from pydiag.core.measurement import Measurement
    from pydiag.signal.noise import add_white_noise
    m = Measurement({"acc": add_white_noise(y, 10.0, rng)}, 10_000.0)
    r = diagnose(build_problem(str(fmu), m, adapter),
                 FaultEstimator(n_particles=4, iterations=3, polish_evaluations=16,
                                polish_starts=1, seed=0))
    assert abs(r.parameters["a_f"] - 0.4) <= 0.03
    assert r.fault_mode == "tooth_fault"


# ---------------------------------------------------------------------- OpenModelica (vendor)

@pytest.fixture(scope="module")
def openmodelica_fmus(tmp_path_factory):
    """Linux FMUs exported by OpenModelica 1.19-1.21, from the gemseo-fmu wheel (LGPL)."""
    folder = tmp_path_factory.mktemp("gemseo")
    res = subprocess.run([sys.executable, "-m", "pip", "download", "--quiet", "--no-deps",
                          "--disable-pip-version-check", "-d", str(folder), "gemseo-fmu==3.1.1"],
                         capture_output=True, text=True, timeout=300)
    wheels = list(folder.glob("gemseo_fmu-*.whl"))
    if res.returncode != 0 or not wheels:
        pytest.skip(f"cannot download gemseo-fmu from PyPI: {res.stderr.strip()[-200:]}")
    fmus = {}
    with zipfile.ZipFile(wheels[0]) as z:
        for name in z.namelist():
            if name.startswith("gemseo_fmu/problems/fmu_files/linux/") and name.endswith(".fmu"):
                target = folder / Path(name).name
                target.write_bytes(z.read(name))
                fmus[target.stem] = target
    return fmus


def test_inspect_runs_on_every_vendor_fmu(openmodelica_fmus):
    """The wheel holds OpenModelica FMI 2.0 FMUs and one PythonFMU3 FMI 3.0 CS FMU."""
    assert {"Mass_Damper", "MassSpringSystem", "FMU3Model"} <= set(openmodelica_fmus)
    for name, fmu in openmodelica_fmus.items():
        res = run_cli("-m", "pydiag", "inspect", str(fmu))
        assert res.returncode == 0, res.stderr
        expected = "FMI 3.0, CoSimulation" if name == "FMU3Model" else "OpenModelica"
        assert expected in res.stdout, res.stdout
    info = describe(openmodelica_fmus["Mass_Damper"])
    settable = {v.name: (v.settable, v.note) for v in info.variables}
    assert settable["spring.c"][0] == "before init"
    assert settable["damper.flange_b.s"][0] == "no" and "calculatedParameter" in settable["damper.flange_b.s"][1]


def test_openmodelica_spring_constant_recovered_with_the_readme_adapter(openmodelica_fmus,
                                                                        tmp_path):
    """The README's 'bring your own FMU' commands, with examples/mass_spring.toml."""
    fmu = openmodelica_fmus["MassSpringSystem"]
    adapter = ROOT / "examples" / "mass_spring.toml"
    meas = tmp_path / "m.csv"
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(fmu), "--adapter", str(adapter),
                  "--set", "k1=1.7", "--sample-rate", "20", "--snr", "100", "--out", str(meas),
                  "--quiet")
    assert res.returncode == 0, res.stderr
    out = tmp_path / "r.json"
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(fmu), "--adapter", str(adapter),
                  "--measurement", str(meas), "--json", str(out), "--particles", "6",
                  "--iterations", "4", "--polish", "30", "--quiet")
    assert res.returncode == 0, res.stderr
    result = json.loads(out.read_text())
    assert result["parameters"]["k1"] == pytest.approx(1.7, abs=0.02)
    assert result["fault_mode"] == "not_classified" and "stages" not in result  # no gears


@pytest.mark.parametrize("name, sensors, params", [
    ("MassSpringSystem", ("x1", "x2", "v1"), {"k2": 2.0, "m1": 1.5}),
    ("Mass_Damper", ("y",), {"spring.c": 2.0}),
])
def test_openmodelica_fmi2_model_exchange_runs_on_the_native_engine(openmodelica_fmus, name,
                                                                    sensors, params):
    """OpenModelica's FMI 2.0 ME FMUs have no event indicators: the compiled engine runs
    them (default rtol 1e-6) and agrees with fmpy's CVode at rtol 1e-10 to 1e-4 of the
    peak (measured <= 1e-5), for default and changed parameters on one instance."""
    fmu = openmodelica_fmus[name]
    with FmuPlant(fmu, sensors, 100.0) as native, \
            FmuPlant(fmu, sensors, 100.0, 1e-10, engine="fmpy") as reference:
        assert native.engine == "native"
        for values in ({}, params, {}):
            a, b = native.simulate(values, 5.0), reference.simulate(values, 5.0)
            dev = np.max(np.abs(a - b), axis=1) / np.max(np.abs(b), axis=1)
            assert np.all(dev < 1e-4), (values, dev)
        assert not np.allclose(native.simulate(params, 5.0), native.simulate({}, 5.0))


def test_adapter_refuses_calculated_parameter(openmodelica_fmus):
    with FmuPlant(openmodelica_fmus["Mass_Damper"], ("y",)) as plant:
        variables = plant.variables
    data = {**MINIMAL, "sensor": [{"variable": "y"}],
            "fault_parameter": [{"variable": "damper.flange_b.s", "low": 0, "high": 1}]}
    with pytest.raises(AdapterError, match="calculatedParameter.*set those instead"):
        check_against_fmu(parse_adapter(data), variables)


# ---------------------------------------------------------------------- safe archives


def test_schema_problems_are_warnings_and_the_fmu_still_runs(gear_fmu, tmp_path):
    """Vendor FMUs often fail fmpy's validation yet run (here: units without UnitDefinitions)."""
    import re
    broken = tmp_path / "NoUnits.fmu"
    with zipfile.ZipFile(gear_fmu) as src, zipfile.ZipFile(broken, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename == "modelDescription.xml":
                data = re.sub(rb"\s*<UnitDefinitions>.*?</UnitDefinitions>", b"", data, flags=re.S)
            dst.writestr(item, data)
    inspected(broken)
    with FmuPlant(broken, ("acc",)) as plant:
        assert any("is not defined" in w for w in plant.validation_warnings)
        assert np.isfinite(plant.simulate({}, 0.01, 0.0)).all()
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(broken), "--duration", "0.12",
                  "--out", str(tmp_path / "m.csv"))
    assert res.returncode == 0, res.stderr
    assert "warning:" in res.stderr and "is not defined" in res.stderr
    assert (tmp_path / "m.csv").exists()


def test_missing_platform_binary_names_what_the_fmu_has(gear_fmu, tmp_path):
    windows_only = tmp_path / "WinOnly.fmu"
    with zipfile.ZipFile(gear_fmu) as src, zipfile.ZipFile(windows_only, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            name = item.filename.replace("x86_64-linux", "x86_64-windows").replace(".so", ".dll")
            dst.writestr(name, data)
    assert describe(windows_only).platforms == ["x86_64-windows", "sources"]
    with pytest.raises(PlantError, match=r"no binary for this platform \(x86_64-linux\); it has: "
                                         r"x86_64-windows"):
        FmuPlant(windows_only, ("acc",))
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(windows_only), "--out",
                  str(tmp_path / "m.csv"))
    assert res.returncode == 2 and "x86_64-windows" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


def test_compare_without_gear_kinematics_is_a_clear_error(openmodelica_fmus, tmp_path):
    fmu = openmodelica_fmus["MassSpringSystem"]
    adapter = ROOT / "examples" / "mass_spring.toml"
    meas = tmp_path / "m.csv"
    assert run_cli("-m", "pydiag", "simulate", "--fmu", str(fmu), "--adapter", str(adapter),
                   "--sample-rate", "20", "--out", str(meas), "--quiet").returncode == 0
    res = run_cli("-m", "pydiag", "compare", "--fmu", str(fmu), "--adapter", str(adapter),
                  "--measurement", str(meas), "--history", str(tmp_path / "h.sqlite"), "--quiet")
    assert res.returncode == 2 and "gear kinematics" in res.stderr
    assert "internal error" not in res.stderr
