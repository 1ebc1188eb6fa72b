"""Every stage of a two-stage machine judged against its own healthy records
(:mod:`truth.gearbox`: written from the shafts' angles, not by the model), a broken tooth
on one gear or none."""

import pytest
from truth.gearbox import INPUT_HZ, MACHINE, SHORT_MACHINE, gearbox_record as record

from pydiag.core.errors import MeasurementError
from pydiag.gear.machine_indicators import judge_stages, machine_record, machine_report
from pydiag.gear.speed import SpeedSettings


@pytest.fixture(scope="module")
def baseline():
    return machine_record(record(1), MACHINE, SpeedSettings("mesh"), INPUT_HZ)


def test_a_healthy_record_changes_no_stage(baseline):
    healthy = machine_record(record(2), MACHINE, SpeedSettings("mesh"), INPUT_HZ)
    verdicts, spread = judge_stages(MACHINE, healthy, [baseline])
    assert spread > 0
    assert [v.changed for v in verdicts] == [False, False], verdicts


@pytest.mark.parametrize("stage, shaft, suspect", [(0, 0, "pinion"), (1, 2, "gear")])
def test_a_local_tooth_fault_changes_its_stage_and_names_its_shaft(baseline, stage, shaft,
                                                                    suspect):
    faulty = machine_record(record(3, shaft, stage), MACHINE, SpeedSettings("mesh"), INPUT_HZ)
    verdicts, _ = judge_stages(MACHINE, faulty, [baseline])
    assert verdicts[stage].changed and verdicts[stage].suspect == suspect, verdicts[stage]
    other = verdicts[1 - stage]
    assert not (other.changed and other.suspect == ("gear" if stage == 0 else "pinion"))


def test_the_report_judges_nothing_without_a_baseline_and_is_plain_data():
    report = machine_report(record(2), MACHINE, SpeedSettings("mesh"), INPUT_HZ)
    data = report.to_dict()
    assert data["stages"] == [] and data["healthy_spread_db"] is None
    assert [s["teeth"] for s in data["shafts"]] == [[20], [64, 24], [54]]
    assert data["speed_hz"] == pytest.approx(INPUT_HZ * 0.99, rel=1e-3)
    with pytest.raises(MeasurementError, match="needs a baseline"):
        judge_stages(MACHINE, report.record, [])


@pytest.fixture(scope="module")
def short_baseline():
    return machine_record(record(1, machine=SHORT_MACHINE), SHORT_MACHINE,
                          SpeedSettings("mesh"), INPUT_HZ)


def judged_short(baseline, **fault):
    faulty = machine_record(record(3, machine=SHORT_MACHINE, **fault), SHORT_MACHINE,
                            SpeedSettings("mesh"), INPUT_HZ)
    return judge_stages(SHORT_MACHINE, faulty, [baseline])[0]


def test_a_faster_shafts_fault_is_not_the_slower_shafts_whose_turn_holds_whole_turns_of_it(
        short_baseline):
    # the input turns 2 times an idler turn and 5 times an output turn: its broken tooth's
    # lines survive both their TSAs, and are the input's alone
    first, second = judged_short(short_baseline, faulty_shaft=0, stage=0)
    assert first.changed and first.suspect == "pinion", first
    assert abs(first.gear.change_db) < first.threshold_db, first
    assert not second.changed, second


def test_a_slower_shafts_fault_is_not_called_the_faster_ones(short_baseline):
    # its lines on every 2nd idler order are input orders too: the input changes as well,
    # but not beyond the idler, so stage 1 names no suspect rather than the wrong one
    first, second = judged_short(short_baseline, faulty_shaft=1, stage=1)
    assert first.changed and first.suspect is None, first
    assert second.changed and second.suspect == "pinion", second


def test_a_fault_on_each_of_two_stages_names_each_stages_own_shaft(short_baseline):
    first, second = judged_short(short_baseline, faulty_shaft=0, stage=0, also=((1, 1),))
    assert (first.suspect, second.suspect) == ("pinion", "pinion"), (first, second)
