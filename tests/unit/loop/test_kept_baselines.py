"""Baselines kept per machine in the history (:mod:`pydiag.loop.history`): a record of a
two-stage box (:mod:`truth.gearbox`, written from the shafts' angles) kept, found again by
its machine alone, and judging a record as the record it was made from does."""

import dataclasses
import sqlite3

import pytest
from boxes import MACHINE
from truth.gearbox import INPUT_HZ, gearbox_record as record

from pydiag.core.errors import OutputError, UsageError
from pydiag.gear.machine_indicators import MachineRecord, machine_record
from pydiag.gear.speed import SpeedSettings
from pydiag.gear.comparable import at_speed
from pydiag.gear.stage_judge import judge_stages
from pydiag.loop import history


@pytest.fixture(scope="module")
def healthy():
    return machine_record(record(1), MACHINE, SpeedSettings("mesh"), INPUT_HZ)


def test_a_kept_baseline_judges_as_the_record_it_was_kept_from(tmp_path, healthy):
    db = tmp_path / "h.sqlite"
    kept = history.keep_baseline(db, MACHINE, healthy, "healthy.csv")
    (again,) = history.kept_baselines(db, MACHINE)
    assert (again.id, again.measurement, again.machine) == (kept.id, "healthy.csv", MACHINE.name)
    assert again.record.shafts == healthy.shafts
    assert again.record.speed.speed_hz == healthy.speed.speed_hz
    faulty = machine_record(record(3, 0, 0), MACHINE, SpeedSettings("mesh"), INPUT_HZ)
    assert judge_stages(MACHINE, faulty, [again.record]) == judge_stages(MACHINE, faulty, [healthy])


def test_a_baseline_kept_before_fm4s_halves_were_judges_by_energy_alone(healthy):
    data = healthy.to_dict()
    for shaft in data["shafts"]:
        del shaft["fm4_halves"]
    old = MachineRecord.from_dict(data)
    faulty = machine_record(record(3, 0, 0), MACHINE, SpeedSettings("mesh"), INPUT_HZ)
    verdicts, _ = judge_stages(MACHINE, faulty, [old])
    assert [v.fm4_threshold for v in verdicts] == [None, None]
    assert verdicts[0].suspect == "pinion" and verdicts[0].suspect_by == "residual energy"
    assert judge_stages(MACHINE, faulty, [healthy])[0][0].fm4_threshold > 0


def test_baselines_are_the_machines_own_and_can_be_forgotten(tmp_path, healthy):
    db = tmp_path / "h.sqlite"
    first = history.keep_baseline(db, MACHINE, healthy, "a.csv")
    second = history.keep_baseline(db, MACHINE, healthy, "b.csv")
    twin = dataclasses.replace(MACHINE, name="the other box of the same design")
    assert history.kept_baselines(db, twin) == []
    # the sensors, effects or comments of the file may change: the kinematics find it
    assert len(history.kept_baselines(db, dataclasses.replace(MACHINE, source="x.toml"))) == 2
    with pytest.raises(UsageError, match=f"its baselines: {first.id}, {second.id}"):
        history.forget_baseline(db, MACHINE, 99)
    with pytest.raises(UsageError, match="its baselines: none"):
        history.forget_baseline(db, twin, first.id)
    assert history.forget_baseline(db, MACHINE, first.id).measurement == "a.csv"
    assert [b.id for b in history.kept_baselines(db, MACHINE)] == [second.id]


def test_a_baseline_is_of_a_records_operating_point_within_a_few_percent(healthy):
    found = healthy.speed.speed_hz  # 1 % below the nominal 25 Hz
    assert at_speed([healthy], INPUT_HZ) == [healthy]
    assert at_speed([healthy], found * 1.06) == []
    assert at_speed([healthy], found / 0.96) == [healthy]


def test_a_history_of_runs_keeps_them_and_a_foreign_database_is_refused(tmp_path, healthy):
    db = tmp_path / "runs.sqlite"
    con = sqlite3.connect(db)
    con.execute(history.SCHEMA["runs"])
    con.execute("INSERT INTO runs VALUES (1, 't', 'm', 'f', 's', NULL, NULL, '{}', 0.5, 0, "
                "'[]', '[]')")
    con.commit()
    con.close()
    assert history.kept_baselines(db, MACHINE) == []
    history.keep_baseline(db, MACHINE, healthy, "a.csv")
    assert [r["error"] for r in history.runs(db)] == [0.5]
    other = tmp_path / "other.sqlite"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE baselines (id INTEGER, what TEXT)")
    con.commit()
    con.close()
    with pytest.raises(OutputError, match="another pydiag version .* no column time_utc"):
        history.keep_baseline(other, MACHINE, healthy, "a.csv")


def test_a_record_is_plain_data_and_back(healthy):
    import json
    data = json.loads(json.dumps(healthy.to_dict()))
    back = MachineRecord.from_dict(data)
    assert back.shafts == healthy.shafts and back.file == healthy.file
    assert back.speed.to_dict() == healthy.speed.to_dict()


def test_a_tacho_records_swing_is_kept_and_a_baseline_kept_before_it_has_none():
    tacho = SpeedSettings("tacho", tacho="tacho", pulses_per_rev=10)
    kept = machine_record(record(1, tacho_pulses=10, swing=((1, 0.002),)), MACHINE, tacho,
                          INPUT_HZ)
    data = kept.to_dict()
    assert MachineRecord.from_dict(data).shafts == kept.shafts
    assert kept.shafts[1].swing_deg > 0.5
    assert kept.shafts[1].swing_lines_deg[0][0] == kept.shafts[1].swing_deg
    assert 0 < kept.shafts[1].swing_lines_deg[0][1] < 0.05 * kept.shafts[1].swing_deg
    for shaft in data["shafts"]:
        del shaft["swing_deg"], shaft["swing_lines_deg"]
    assert [(s.swing_deg, s.swing_lines_deg) for s in MachineRecord.from_dict(data).shafts
            ] == [(None, ())] * 3
