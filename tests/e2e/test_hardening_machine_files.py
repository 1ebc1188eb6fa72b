"""Hardening, third pass (issue 59): what a careful but unlucky user gives pydiag, one clear
line each, and nothing the reader would rather say itself left to scipy. Each fails on the
code before the fix."""

import io

import numpy as np
import pytest
from conftest import run_cli, write_csv

from pydiag.core.errors import MachineError, UsageError
from pydiag.gear.machine_file import machine_from_dict
from pydiag.io.readers import read_measurement
from pydiag.io.units import sensitivity_factor

BOX = {"name": "box", "input_rpm": 1800,
       "stages": [{"pinion_teeth": 32, "gear_teeth": 96}]}


def test_bearings_whose_balls_cannot_sit_on_their_pitch_circle_are_refused():
    crowded = {**BOX, "bearings": [{"shaft": "input", "n_balls": 40,
                                    "ball_diameter_mm": 7.94, "pitch_diameter_mm": 39}]}
    with pytest.raises(MachineError, match=r"bearings\[0\]\.n_balls: 40 balls of 7\.94 "
                                           r"mm do not fit .*at most 15 balls"):
        machine_from_dict(crowded, "box.toml")
    fits = {**BOX, "bearings": [{"shaft": "input", "n_balls": 8, "ball_diameter_mm": 7.9375,
                                 "pitch_diameter_mm": 33.5026}]}  # PHM09's ER-10K
    assert machine_from_dict(fits, "box.toml").bearings[0].n_balls == 8
    res = run_cli("-m", "pydiag", "compare", "--measurement", "m.csv", "--bearing",
                  "40,7.94,39", "--fmu", "x.fmu")
    assert res.returncode == 2 and "do not fit on a pitch circle" in res.stderr


def test_a_sensitivity_of_two_values_or_for_the_tacho_is_refused(tmp_path):
    with pytest.raises(UsageError, match="one value"):
        sensitivity_factor("V", "100mV/g=3")
    path = tmp_path / "r.csv"
    t = np.arange(2000) / 1000.0
    write_csv(path, ["time_s", "ch1", "tacho"],
              np.column_stack([t, np.sin(2 * np.pi * 50 * t), (t * 30 % 1 < 0.1) * 5.0]))
    res = run_cli("-m", "pydiag", "indicators", "--measurement", str(path), "--teeth", "32,96",
                  "--rpm", "1800", "--tacho", "tacho", "--unit", "V",
                  "--sensitivity", "tacho=100mV/g")
    assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1, res.stderr
    assert "the tacho's channel" in res.stderr


def test_a_mat_file_with_a_variable_twice_is_read_with_one_note_in_pydiags_words(tmp_path):
    import scipy.io
    buffer = io.BytesIO()
    scipy.io.savemat(buffer, {"x": np.sin(np.arange(4000.0)), "fs": 1000.0})
    data = buffer.getvalue()
    path = tmp_path / "twice.mat"
    path.write_bytes(data + data[128:])  # every variable written again after the header
    m = read_measurement(path)
    assert m.metadata["read_notes"] == ["variable(s) fs, x appear more than once in the "
                                        "file; the last of each is read"]
    res = run_cli("-m", "pydiag", "indicators", "--measurement", str(path), "--teeth",
                  "32,96", "--rpm", "1800", "--speed", "nominal")
    said = [line for line in res.stderr.splitlines() if "more than once" in line]
    assert len(said) == 1 and said[0].startswith("pydiag indicators: warning:"), res.stderr
    assert "MatReadWarning" not in res.stderr and "Duplicate variable" not in res.stderr


@pytest.mark.parametrize("slow", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_the_loop_writes_its_copy_where_out_says_and_never_over_the_machine_file(tmp_path,
                                                                                   slow):
    """An existing <name>.loop.toml is refused with the option that chooses another
    (--out); --out the machine file itself is refused as an input; --out elsewhere runs."""
    from truth.gearbox import SHORT_BOX, gearbox_record

    from pydiag.io.measurements import write_measurement
    rec = tmp_path / "box.csv"
    write_measurement(rec, gearbox_record(4, box=SHORT_BOX))
    machine = tmp_path / "box.toml"
    machine.write_text('name = "short box"\ninput_rpm = 1500\n'
                       '[[stages]]\npinion_teeth = 18\ngear_teeth = 36\n'
                       '[[stages]]\npinion_teeth = 20\ngear_teeth = 50\n')
    (tmp_path / "box.loop.toml").write_text("# an earlier loop's\n")
    common = ("-m", "pydiag", "loop", "--machine", str(machine), "--measurement", str(rec),
              "--speed", "mesh", "--history", str(tmp_path / "h.sqlite"), "--quiet",
              "--particles", "4", "--iterations", "1", "--polish", "5", "--max-steps", "1",
              "--build-dir", str(tmp_path / "build"))
    res = run_cli(*common)
    assert res.returncode == 2 and "--out names another" in res.stderr, res.stderr
    assert (tmp_path / "box.loop.toml").read_text() == "# an earlier loop's\n"
    res = run_cli(*common, "--out", str(machine))
    assert res.returncode == 2 and "would overwrite an input file" in res.stderr
    if slow:  # the loop itself, a minute on 2 cores
        res = run_cli(*common, "--out", str(tmp_path / "again.toml"))
        assert res.returncode == 0, res.stderr
        assert (tmp_path / "again.toml").read_text().startswith(machine.read_text())


def test_a_cache_that_is_a_file_is_said_for_builds_and_worked_around_for_the_engine(
        gear_fmu, tmp_path):
    """XDG_CACHE_HOME a regular file: a command that builds models says so in one line
    (give --build-dir); one that only runs an FMU compiles its engine for itself."""
    import os
    import subprocess
    import sys

    from conftest import ROOT
    record = tmp_path / "m.csv"
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(gear_fmu), "--set", "a_f=0.3",
                  "--duration", "0.48", "--out", str(record), "--quiet")
    assert res.returncode == 0, res.stderr
    cache = tmp_path / "cache"
    cache.write_text("not a folder")
    env = {**os.environ, "XDG_CACHE_HOME": str(cache)}

    def run(*args):
        return subprocess.run([sys.executable, "-m", "pydiag", *args], cwd=ROOT, env=env,
                              capture_output=True, text=True)

    res = run("compare", "--machine", str(ROOT / "examples" / "paper_pair.toml"),
              "--measurement", str(record), "--history", str(tmp_path / "h.sqlite"),
              "--quiet")
    assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1, res.stderr
    assert "cannot build models in" in res.stderr and "--build-dir" in res.stderr
    res = run("diagnose", "--fmu", str(gear_fmu), "--measurement", str(record), "--quiet",
              "--particles", "4", "--iterations", "2", "--polish", "10")
    assert res.returncode in (0, 1) and "internal error" not in res.stderr, res.stderr
    assert "fault mode" in res.stdout


def test_a_damaged_cached_fmu_is_built_again_not_read(tmp_path):
    """A cached FMU cut short (a build killed, a disk that filled) is no zip: the next use
    builds it again, for an effect's FMU and a model pydiag wrote alike."""
    from conftest import ROOT

    from pydiag.fmu.archive import usable_cache
    from pydiag.gear.machine_file import load_machine
    from pydiag.loop.discover import effect_fmu
    from pydiag.loop.machine_model import machine_fmu
    modelica = ROOT / "modelica"
    effect = effect_fmu("gear_eccentricity", modelica, tmp_path / "effects")
    _, built = machine_fmu(load_machine(ROOT / "examples" / "paper_pair.toml"), modelica,
                           tmp_path / "build")
    for fmu in (effect, built.fmu):
        fmu.write_bytes(fmu.read_bytes()[:1000])
        assert not usable_cache(fmu)
    assert usable_cache(effect_fmu("gear_eccentricity", modelica, tmp_path / "effects"))
    _, again = machine_fmu(load_machine(ROOT / "examples" / "paper_pair.toml"), modelica,
                           tmp_path / "build")
    assert again.fmu == built.fmu and usable_cache(again.fmu)


def test_a_bad_record_inside_a_zip_is_named_by_the_zip_not_a_temporary_copy(tmp_path):
    import zipfile

    from pydiag.core.errors import MeasurementError
    inner = tmp_path / "inner.csv"
    write_csv(inner, ["time_s", "a1"], np.column_stack([np.arange(100) / 1e3,
                                                        np.ones(100)]))
    with zipfile.ZipFile(tmp_path / "rec.zip", "w") as z:
        z.write(inner, "rec.csv")
    with pytest.raises(MeasurementError) as err:
        read_measurement(tmp_path / "rec.zip")
    assert f"{tmp_path / 'rec.zip'}:rec.csv" in str(err.value), err.value
    assert "pydiag_zip_" not in str(err.value) and "constant" in str(err.value)
