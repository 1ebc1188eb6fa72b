"""The run history: an unusable file is refused before any work, never after it."""

import dataclasses

import pytest

from pydiag.core.errors import OutputError
from pydiag.loop import history, history_plot


def test_a_file_that_is_not_a_history_is_refused_and_kept(tmp_path):
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes, not a database\n" * 100)
    with pytest.raises(OutputError, match="cannot use .*notes.txt as the run history"):
        history.check(notes)
    assert notes.read_text().startswith("my notes")
    with pytest.raises(OutputError, match="is a folder"):
        history.check(tmp_path)


def test_checking_a_new_history_creates_nothing(tmp_path):
    history.check(tmp_path / "h.sqlite")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(OutputError, match="does not exist"):
        history.check(tmp_path / "no" / "h.sqlite")


def test_history_plot_follows_the_output_policy(tmp_path):
    rows = [{"id": 1, "error": 0.5, "model_name": "GearPair", "fmu": "a.fmu"},
            {"id": 2, "error": 0.1, "model_name": "WithRunout", "fmu": "b.fmu"}]
    out = history_plot.plot(rows, tmp_path / "h.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(OutputError, match="exists"):
        history_plot.plot(rows, out)
    assert history_plot.plot(rows, tmp_path / "h.svg").read_text().lstrip().startswith("<?xml")


class _Run:
    """The fields of a comparison the history records."""

    def __init__(self, fmu):
        self.fmu, self.peaks, self.suggested_effects = fmu, [], []
        self.parameters, self.error = {"a_f": 0.3}, 0.25


def test_a_run_is_recorded_only_when_its_outputs_were_written(tmp_path):
    db, fmu = tmp_path / "h.sqlite", tmp_path / "m.fmu"
    fmu.write_bytes(b"not really an FMU")
    with history.recording(db, _Run(fmu), "rec.csv", "GearPair") as (run_id, rows):
        assert [r["id"] for r in rows] == [run_id]  # the report sees this run
    with pytest.raises(OutputError, match="disk is full"):
        with history.recording(db, _Run(fmu), "rec.csv", "GearPair"):
            raise OutputError("disk is full")  # e.g. writing the report
    assert [r["id"] for r in history.runs(db)] == [run_id]


def test_a_history_that_cannot_take_the_run_is_the_users_problem(tmp_path, monkeypatch):
    import sqlite3

    db, fmu = tmp_path / "h.sqlite", tmp_path / "m.fmu"
    fmu.write_bytes(b"x")
    real = history._connect

    class FullDisk:
        def __init__(self, con):
            self.con = con

        def commit(self):
            raise sqlite3.OperationalError("database or disk is full")

        def __getattr__(self, name):
            return getattr(self.con, name)

        def __setattr__(self, name, value):
            if name == "con":
                object.__setattr__(self, name, value)
            else:
                setattr(self.con, name, value)

    monkeypatch.setattr(history, "_connect", lambda path, table=None: FullDisk(real(path, table)))
    with pytest.raises(OutputError, match="outputs are written, but the run could not be"):
        with history.recording(db, _Run(fmu), "rec.csv", "GearPair"):
            pass
    monkeypatch.undo()
    assert history.runs(db) == []


def test_plot_formats_are_checked_by_suffix(tmp_path):
    with pytest.raises(OutputError, match="written as .png"):
        history_plot.check_plot(tmp_path / "p.txt")
    history_plot.check_plot(tmp_path / "p.PDF")


def test_a_healthy_model_is_found_again_by_its_machine_and_fingerprint(tmp_path):
    """Kept as plain data (JSON in SQLite) and read back whole; another fingerprint (say
    other baselines) or another machine finds none."""
    import tomllib
    from pathlib import Path

    from pydiag.gear.machine_file import machine_from_dict
    from pydiag.loop.own_changes import HealthyModel

    text = (Path(__file__).resolve().parents[3] / "examples" / "phm09_spur.toml").read_text()
    spur = machine_from_dict(tomllib.loads(text))
    other = machine_from_dict(tomllib.loads(text.replace('name = "PHM09 spur gearbox"',
                                                         'name = "another spur box"', 1)))
    assert other.identity != spur.identity
    model = HealthyModel({"input_stage.A_s1": 247.0, "acc_gain": 1.5}, 0.01,
                         {("input stage", "pinion_shaft_orders"): 0.9},
                         ({("input stage", "pinion_shaft_orders"): 11.8},
                          {("input stage", "pinion_shaft_orders"): -2.0}),
                         ("bearing_outer_race",), (("input stage", "bearing_outer_race"),))
    db = tmp_path / "h.sqlite"
    assert history.kept_healthy_model(db, spur, "abc") is None  # no history yet
    kept = history.keep_healthy_model(db, spur, "abc", ["/b/run2.zip", "/b/run1.zip"], model)
    again = history.kept_healthy_model(db, spur, "abc")
    assert again == kept and again.model == model
    assert again.baselines == ("/b/run2.zip", "/b/run1.zip")
    assert history.kept_healthy_model(db, spur, "abd") is None
    assert history.kept_healthy_model(db, other, "abc") is None
    # the newest of one fingerprint is the one found
    newer = history.keep_healthy_model(db, spur, "abc", ["/b/run2.zip", "/b/run1.zip"],
                                       dataclasses.replace(model, false_alarm_rate=0.02))
    assert history.kept_healthy_model(db, spur, "abc").id == newer.id > kept.id
