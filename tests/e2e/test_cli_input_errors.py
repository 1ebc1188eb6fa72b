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
    (["--baseline", "b.csv"], "give --machine FILE (a machine of one stage will do)"),
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
    ("fixed", r"the fit's error is [\d.]+ per channel \(1 = as large as the measured lines\): "
              r"the model explains none.*\n.*channel acc: with its level free the model fits "
              r"at \d{3,4}x the level it predicts, a unit factor \(a milli- prefix missed\?\)"),
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
                  str(scaled), "--gain", gain, "--json", str(out), "--particles", "8",
                  "--iterations", "6", "--polish", "60", "--quiet")
    data = json.loads(out.read_text())
    # held to the model's level, the fit explains nothing: no diagnosis (exit 1)
    assert (res.returncode, data["fault_mode"] == "no_diagnosis") == \
        ((1, True) if gain == "fixed" else (0, False)), res.stderr
    assert re.search("pydiag diagnose: warning: " + message, res.stderr), res.stderr
    assert "check the units (--unit)" in res.stderr
    assert re.search(message.replace(r".*\n.*", ".*"), " ".join(data["warnings"]))
    # the record as made, fitted with the default budget: no warning
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
                  str(short_measurement), "--gain", gain, "--quiet")
    assert res.returncode == 0 and "warning" not in res.stderr, res.stderr


def test_a_tacho_channel_works_with_our_own_fmus(gear_fmu, short_measurement, tmp_path):
    """--tacho with the built-in adapter: the tacho is the speed's channel, not a sensor the
    FMU must have (it was 'sensor variable tacho is not in the FMU')."""
    m = read_measurement(short_measurement)
    t = np.arange(m.n_samples) / m.sample_rate_hz
    pulses = (np.mod(t * 25.0 * 10, 1.0) < 0.2).astype(float)  # 10 a turn at 25 Hz
    path = write_csv(tmp_path / "tacho.csv", ["time_s", "acc", "disp", "tacho"],
                     zip(t, m.channels["acc"], m.channels["disp"], pulses))
    out = tmp_path / "r.json"
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement", str(path),
                  "--tacho", "tacho", "--pulses-per-rev", "10", "--particles", "4",
                  "--iterations", "2", "--polish", "0", "--json", str(out), "--quiet")
    assert res.returncode == 0, res.stderr
    data = json.loads(out.read_text())
    assert data["speed_method"] == "tacho" and data["channels"] == ["acc", "disp"]
    assert data["speed_hz"] == pytest.approx(25.0, rel=1e-3)


def test_two_outputs_may_not_name_one_file_nor_the_history(gear_fmu, short_measurement,
                                                           tmp_path):
    """Refused before any work, whatever --force says: nothing is written."""
    out, db = tmp_path / "x", tmp_path / "h.sqlite"
    base = ["-m", "pydiag", "compare", "--fmu", str(gear_fmu), "--measurement",
            str(short_measurement), "--quiet", "--force"]
    res = run_cli(*base, "--json", str(out), "--report", str(out))
    assert res.returncode == 2 and "--report and --json name the same file" in res.stderr
    res = run_cli(*base, "--json", str(db), "--history", str(db))
    assert res.returncode == 2 and "would overwrite an input file" in res.stderr
    assert not out.exists() and not db.exists()


def test_bless_keeps_an_existing_golden_without_force(gear_fmu, tmp_path):
    golden = tmp_path / "g.json"
    golden.write_text("{}")
    args = ["-m", "pydiag", "regress", "--fmu", str(gear_fmu), "--golden", str(golden),
            "--bless"]
    res = run_cli(*args)
    assert res.returncode == 2 and "exists" in res.stderr and golden.read_text() == "{}"
    res = run_cli(*args, "--force")
    assert res.returncode == 0, res.stderr
    assert json.loads(golden.read_text())


def test_batch_refuses_a_results_name_of_another_format(gear_fmu, short_measurement, tmp_path):
    """Parquet bytes in a .xlsx file would be a file the user's tools cannot open."""
    out = tmp_path / "r.xlsx"
    res = run_cli("-m", "pydiag", "batch", "--fmu", str(gear_fmu), "--measurements",
                  str(short_measurement), "--out", str(out), "--quiet")
    assert res.returncode == 2 and "name it .parquet or .csv" in res.stderr, res.stderr
    assert not out.exists()


def test_an_adapter_without_its_fmu_is_refused(short_measurement):
    """The machine's own model needs no adapter: one given without --fmu is a mistake said
    in one line, not silently unused."""
    res = run_cli("-m", "pydiag", "diagnose", "--teeth", "14,21", "--rpm", "1500",
                  "--measurement", str(short_measurement), "--adapter", "a.toml", "--quiet")
    assert res.returncode == 2 and "give it with --fmu" in res.stderr, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
