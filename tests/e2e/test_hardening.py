"""Hardening, second pass (issue 31): a history is an input checked before the fit, a fit
that explains nothing is no diagnosis, a record without a signal or a library that is not
there stop the run at once. Each fails on the code before the fix."""

import json
import sqlite3

import numpy as np
import pytest
from conftest import run_cli, write_csv

SMALL = ["--particles", "6", "--iterations", "3", "--polish", "10", "--quiet"]


@pytest.fixture(scope="module")
def record(tmp_path_factory, gear_fmu):
    path = tmp_path_factory.mktemp("meas") / "m.csv"
    res = run_cli("-m", "pydiag", "simulate", "--fmu", str(gear_fmu), "--set", "a_f=0.3",
                  "--snr", "10", "--out", str(path), "--quiet")
    assert res.returncode == 0, res.stderr
    return path


def one_line_error(res, *words):
    assert res.returncode == 2, (res.returncode, res.stdout, res.stderr)
    assert "Traceback" not in res.stderr and "internal error" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1, res.stderr
    for w in words:
        assert w in res.stderr, res.stderr


@pytest.mark.parametrize("tables, words", [
    ({"customers": "id, name"}, ("not a pydiag run history", "customers")),
    ({"runs": "id INTEGER PRIMARY KEY, when_utc TEXT, err REAL"},
     ("another pydiag version", "time_utc")),
])
def test_a_foreign_or_older_history_is_refused_before_the_fit_and_kept(gear_fmu, record,
                                                                       tmp_path, tables,
                                                                       words):
    db = tmp_path / "other.sqlite"
    with sqlite3.connect(db) as con:
        for name, columns in tables.items():
            con.execute(f"CREATE TABLE {name} ({columns})")
    before = db.read_bytes()
    res = run_cli("-m", "pydiag", "compare", "--fmu", str(gear_fmu), "--measurement",
                  str(record), "--history", str(db), "--json", str(tmp_path / "c.json"), *SMALL)
    one_line_error(res, *words)
    assert db.read_bytes() == before
    assert not (tmp_path / "c.json").exists()


def test_history_plot_refuses_a_format_it_cannot_write(tmp_path):
    res = run_cli("-m", "pydiag", "history", "--history", str(tmp_path / "h.sqlite"),
                  "--plot", str(tmp_path / "p.txt"))
    one_line_error(res, "p.txt", ".png")


def test_a_fit_that_explains_nothing_is_no_diagnosis(gear_fmu, record, tmp_path):
    out = tmp_path / "d.json"
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
                  str(record), "--rpm", "1000", "--speed", "nominal", "--json", str(out),
                  *SMALL)
    assert res.returncode == 1, res.stderr
    data = json.loads(out.read_text())
    assert data["fault_mode"] == "no_diagnosis" and data["severity"] == "unknown"
    assert "explains none" in res.stderr


def test_a_channel_of_one_value_with_a_glitch_is_no_signal(gear_fmu, tmp_path):
    x = np.zeros(20000)
    x[777] = 1.0
    path = write_csv(tmp_path / "z.csv", ["time_s", "acc"], zip(np.arange(x.size) / 1e4, x))
    for command in (["diagnose", "--fmu", str(gear_fmu), "--speed", "nominal", *SMALL],
                    ["indicators", "--rpm", "1500", "--teeth", "14,21"]):
        res = run_cli("-m", "pydiag", *command, "--measurement", str(path))
        one_line_error(res, "one value", "all but 1 of its 20000")


def test_discover_without_the_modelica_library_stops_before_any_work(gear_fmu, record,
                                                                     tmp_path):
    res = run_cli("-m", "pydiag", "discover", "--fmu", str(gear_fmu), "--measurement",
                  str(record), "--modelica", str(tmp_path / "nonexistent"), *SMALL)
    one_line_error(res, "no Modelica library of effects", "--modelica")


@pytest.mark.parametrize("unit, words", [("acc=furlong", ("displacement unit", "acceleration")),
                                         ("disp=g", ("acceleration unit", "displacement"))])
def test_a_unit_of_another_quantity_than_the_output_is_refused(gear_fmu, record, unit, words):
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
                  str(record), "--unit", unit, *SMALL)
    one_line_error(res, *words, "--unit")


def test_a_level_off_by_a_unit_factor_is_named(gear_fmu, record, tmp_path):
    # a record pydiag simulate made is in m/s2 and its level is the model's: read as g, it
    # is 9.81x too high, and no gain is fitted on such records
    out = tmp_path / "d.json"
    res = run_cli("-m", "pydiag", "diagnose", "--fmu", str(gear_fmu), "--measurement",
                  str(record), "--channel", "acc", "--unit", "acc=g", "--json", str(out),
                  "--quiet", "--particles", "8", "--iterations", "6", "--polish", "60")
    assert "g read as m/s2" in res.stderr, res.stderr
    assert json.loads(out.read_text())["fault_mode"] == "no_diagnosis"


def test_an_output_may_not_replace_a_baseline_or_the_machine_file(record, tmp_path):
    machine = tmp_path / "box.toml"
    machine.write_text("input_rpm = 1500\n[[stages]]\npinion_teeth = 14\ngear_teeth = 21\n")
    for target in (record, machine):
        before = target.read_bytes()
        res = run_cli("-m", "pydiag", "indicators", "--machine", str(machine), "--measurement",
                      str(record), "--baseline", str(record), "--json", str(target), "--force")
        one_line_error(res, "would overwrite an input file")
        assert target.read_bytes() == before


def test_the_housing_is_not_applied_to_a_model_that_has_it(record, housing_fmu, gear_fmu,
                                                            tmp_path):
    """housing_sensor is a transfer path applied to the base model's output: given the
    Modelica model that has the mode already, compare refuses before the fit, where it
    would pass the signal through the mode twice."""
    res = run_cli("-m", "pydiag", "compare", "--fmu", str(housing_fmu),
                  "--effect", "housing_sensor", "--measurement", str(record), "--history",
                  str(tmp_path / "h.sqlite"), *SMALL)
    one_line_error(res, "housing_sensor is a transfer path", "give --fmu the base model")
    assert not (tmp_path / "h.sqlite").exists()
    # given the base model, the housing's mode is fitted on its output
    out = tmp_path / "c.json"
    res = run_cli("-m", "pydiag", "compare", "--fmu", str(gear_fmu), "--effect",
                  "housing_sensor", "--measurement", str(record), "--history",
                  str(tmp_path / "h.sqlite"), "--no-validate", "--json", str(out), *SMALL)
    assert res.returncode == 0, res.stderr
    fitted = json.loads(out.read_text())["parameters"]
    assert 20 <= fitted["f_housing"] <= 10_000 and 0.005 <= fitted["zeta_housing"] <= 0.5


def test_indicators_say_a_speed_that_swings_past_what_the_mesh_can_follow(tmp_path):
    """A 32/80 pair whose speed swings +-0.55 % once over 30 s: the mesh phase is followed
    within +-0.625 %, and the speed comes out off; indicators say so (they said nothing)."""
    fs, duration = 6400.0, 30.0
    t = np.arange(int(fs * duration)) / fs
    revs = np.cumsum(29.9 * (1 + 0.0055 * np.sin(2 * np.pi * t / duration))) / fs
    acc = sum(np.cos(2 * np.pi * h * 32 * revs + h) / h for h in range(1, 3))
    acc = acc + np.random.default_rng(0).standard_normal(t.size)
    path = write_csv(tmp_path / "swing.csv", ["time", "acc"], zip(t, acc.round(5)))
    res = run_cli("-m", "pydiag", "indicators", "--measurement", str(path), "--rpm", "1800",
                  "--teeth", "32,80")
    assert res.returncode == 0, res.stderr
    assert "warning: the speed swings by +-" in res.stderr, (res.stdout, res.stderr)
    assert "near the +-0.625 % the mesh line's phase is followed in" in res.stderr
