"""The CLI on bad input: one line, non-zero exit, nothing lost."""

import json
import re

import numpy as np
import pytest
from conftest import run_cli, write_csv

from pydiag.io.readers import read_measurement


@pytest.fixture(scope="module")
def short_measurement(tmp_path_factory, gear_fmu):
    path = tmp_path_factory.mktemp("meas") / "m.csv"
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(gear_fmu), "--set", "a_f=0.3",
                  "--duration", "0.25", "--snr", "10", "--out", str(path), "--quiet")
    assert res.returncode == 0, res.stderr
    return path


def test_simulate_writes_channels_and_operating_point(short_measurement):
    m = read_measurement(short_measurement)
    assert list(m.channels) == ["acc", "disp"] and m.n_samples == 2500
    assert m.metadata["set"] == {"a_f": 0.3} and m.metadata["snr"] == 10
    assert m.metadata["kinematics"] == {"Np": 14, "Ng": 21, "f_pinion": 25.0}


@pytest.mark.parametrize("extra,message", [
    (["--column", "nope"], "not in the file"),
    (["--column", "acc", "--particles", "1"], "--particles: 1 must be >= 2"),
])
def test_diagnose_rejects_bad_requests(gear_fmu, short_measurement, extra, message):
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
                  str(short_measurement), "--quiet", *extra)
    assert res.returncode == 2, res.stdout
    assert message in res.stderr and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


def test_diagnose_rejects_low_rate_short_and_unknown_channel(gear_fmu, tmp_path):
    t = np.arange(0, 1.0, 1 / 2000.0)
    low = write_csv(tmp_path / "low.csv", ["time_s", "acc"], zip(t, np.sin(t)))
    t = np.arange(0, 0.05, 1e-4)
    short = write_csv(tmp_path / "short.csv", ["time_s", "acc"], zip(t, np.sin(t)))
    t = np.arange(0, 0.5, 1e-4)
    other = write_csv(tmp_path / "other.csv", ["time_s", "mystery"], zip(t, np.sin(t)))
    for path, message in ((low, "below twice the highest band"),
                          (short, "shorter than one fundamental period"),
                          (other, "sensor 'mystery' is not a variable")):
        res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
                      str(path), "--quiet")
        assert res.returncode == 2 and message in res.stderr, res.stderr
        assert "Traceback" not in res.stderr


def test_json_may_not_replace_the_measurement(gear_fmu, short_measurement):
    before = short_measurement.read_text()
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
                  str(short_measurement), "--json", str(short_measurement), "--quiet")
    assert res.returncode == 2 and "would overwrite an input file" in res.stderr
    assert short_measurement.read_text() == before


def test_an_unusable_history_stops_compare_before_the_fit(gear_fmu, short_measurement, tmp_path):
    notes = tmp_path / "notes.txt"
    notes.write_text("not a database\n" * 50)
    res = run_cli("-m", "pydiag", "compare", "--fmu", str(gear_fmu), "--measurement",
                  str(short_measurement), "--history", str(notes), "--quiet")
    assert res.returncode == 2 and "cannot use" in res.stderr and "run history" in res.stderr
    assert notes.read_text() == "not a database\n" * 50
    assert len(res.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("gain,message", [
    ("fixed", r"the fit's error is [\d.]+ per channel \(1 = as large as the measured lines\): the model explains none"),
    ("fit", r"channel acc: the model had to be scaled by \d{3,4} to match the record's level"),
])
def test_a_record_in_the_wrong_units_gets_a_warning_not_a_silent_diagnosis(
        gear_fmu, short_measurement, tmp_path, gain, message):
    """The record's acceleration in mm/s^2 read as m/s^2: 1000 times the model's level."""
    m = read_measurement(short_measurement)
    t = np.arange(m.n_samples) / m.sample_rate_hz
    scaled = write_csv(tmp_path / "mm.csv", ["time_s", "acc"], zip(t, 1000 * m.channels["acc"]))
    out = tmp_path / "d.json"
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
                  str(scaled), "--gain", gain, "--particles", "6", "--iterations", "3",
                  "--polish", "10", "--json", str(out), "--quiet")
    assert res.returncode == 0, res.stderr
    assert re.search("pydiag diagnose: warning: " + message, res.stderr), res.stderr
    assert "check the units (--unit)" in res.stderr
    assert re.search(message, " ".join(json.loads(out.read_text())["warnings"]))
    # the record as made, fitted with the default budget: no warning
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
                  str(short_measurement), "--gain", gain, "--quiet")
    assert res.returncode == 0 and "warning" not in res.stderr, res.stderr
