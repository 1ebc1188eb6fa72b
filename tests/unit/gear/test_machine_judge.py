"""Every stage of a two-stage machine judged against its own healthy records
(:mod:`truth.gearbox`: written from the shafts' angles, not by the model), a broken tooth
on one gear or none."""

import pytest
from boxes import MACHINE, SHORT_MACHINE
from truth.gearbox import INPUT_HZ, SHORT_BOX, gearbox_record as record

from pydiag.core.errors import MeasurementError
from pydiag.gear.machine_indicators import machine_record
from pydiag.gear.speed import SpeedSettings
from pydiag.gear.machine_report import machine_report
from pydiag.gear.stage_judge import judge_stages


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
    return machine_record(record(1, box=SHORT_BOX), SHORT_MACHINE,
                          SpeedSettings("mesh"), INPUT_HZ)


def judged_short(baseline, **fault):
    faulty = machine_record(record(3, box=SHORT_BOX, **fault), SHORT_MACHINE,
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
    # but not beyond the idler, so stage 1 names the idler (its gear's shaft) or no
    # suspect, never the input
    first, second = judged_short(short_baseline, faulty_shaft=1, stage=1)
    assert first.changed and first.suspect in (None, "gear"), first
    assert second.changed and second.suspect == "pinion", second


def test_a_fault_on_each_of_two_stages_names_each_stages_own_shaft(short_baseline):
    first, second = judged_short(short_baseline, faulty_shaft=0, stage=0, also=((1, 1),))
    assert (first.suspect, second.suspect) == ("pinion", "pinion"), (first, second)


def test_a_chipped_pinion_is_named_though_the_idlers_other_gear_runs_out(short_baseline):
    # the PHM09 spur 2 case's shape: the input pinion's tooth broken, the idler's pinion of
    # stage 2 running out. The runout moves the idler's residual energy more than the
    # broken tooth moves the input's (the energies alone named the idler, the wrong
    # shaft); the broken tooth makes the input's TSA impulsive, the runout does not
    first, second = judged_short(short_baseline, faulty_shaft=0, stage=0, runout=((1, 1, 0.2),))
    assert first.gear.change_db > first.pinion.change_db + first.threshold_db, first
    assert first.pinion.fm4_change > first.fm4_threshold > first.gear.fm4_change, first
    assert (first.suspect, first.suspect_by) == ("pinion", "impulsiveness"), first
    assert (second.suspect, second.suspect_by) == ("pinion", "residual energy"), second


def test_a_runout_alone_is_named_by_its_energy_not_its_impulsiveness(short_baseline):
    # the output gear running out: its shaft carries one gear, and no kurtosis rises
    first, second = judged_short(short_baseline, runout=((2, 1, 0.2),))
    assert abs(second.gear.fm4_change) < second.fm4_threshold, second
    assert (second.suspect, second.suspect_by) == ("gear", "residual energy"), second
    assert not first.changed, first


@pytest.mark.parametrize("shaft, other", [(1, 2), (2, 1)])
def test_a_drive_that_swings_once_a_turn_of_a_shaft_is_seen_by_the_tacho_at_that_shaft(
        shaft, other):
    tacho = SpeedSettings("tacho", tacho="tacho", pulses_per_rev=10)
    steady = machine_record(record(1, tacho_pulses=10), MACHINE, tacho, INPUT_HZ)
    swinging = record(2, tacho_pulses=10, swing=((shaft, 0.002),))
    report = machine_report(swinging, MACHINE, tacho, INPUT_HZ, [steady])
    swing = [s.swing_deg for s in report.record.shafts]
    assert swing[0] is None  # the tacho's own shaft: its wheel's errors are there
    assert swing[shaft] == pytest.approx(360 * 0.002, rel=0.05)
    assert swing[other] < 0.05 * swing[shaft]
    names = list(MACHINE.shafts)
    assert report.swing_change_db[names[shaft]] > 20
    data = report.to_dict()["shafts"]
    assert data[shaft]["swing_deg"] == swing[shaft] and data[0]["swing_change_db"] is None
    # along the mesh's angle nothing is measured: the mesh's phase does not hold the swing
    along_mesh = machine_record(swinging, MACHINE, SpeedSettings("mesh", tacho="tacho"),
                                INPUT_HZ)
    assert all(s.swing_deg is None for s in along_mesh.shafts)


def test_a_baseline_of_another_speed_or_other_units_is_refused_not_judged(baseline):
    """A healthy record 8 % faster (the same samples at a higher rate) is no change to
    judge: the baseline is refused, naming both speeds; a record read at a sensitivity
    (m/s2) against a baseline whose level is unknown (volts) is refused too; a baseline
    kept before units were kept is asked to be kept again."""
    import dataclasses

    fast = record(2)
    fast = dataclasses.replace(fast, sample_rate_hz=fast.sample_rate_hz * 1.08)
    faster = machine_record(fast, MACHINE, SpeedSettings("mesh"), INPUT_HZ * 1.08)
    with pytest.raises(MeasurementError, match=r"runs at 24\.7\d Hz, 7 % from the record's 26\.7"):
        judge_stages(MACHINE, faster, [baseline])
    volts = dataclasses.replace(baseline, units={c: "V (level unknown)" for c in baseline.units})
    healthy = machine_record(record(2), MACHINE, SpeedSettings("mesh"), INPUT_HZ)
    with pytest.raises(MeasurementError, match="read as as recorded in the record and as V"):
        judge_stages(MACHINE, healthy, [volts])
    with pytest.raises(MeasurementError, match="kept without its channels' units"):
        judge_stages(MACHINE, healthy, [dataclasses.replace(baseline, units=None)])


def test_a_tacho_of_other_pulses_than_said_is_caught_by_the_meshes():
    """Ten pulses a turn read as one: the tacho says ten times the speed, the meshes say
    the nominal; one line says how many pulses the tacho gives (issue 59.6). With the
    mesh chosen as the method, a tacho that is there checks it (issue 59.5)."""
    from pydiag.gear.speed import estimate_speed
    m = record(2, tacho_pulses=10)
    kin = MACHINE.stage_kinematics(0, INPUT_HZ)
    with pytest.raises(MeasurementError, match=r"about 10 pulses a turn"):
        estimate_speed(m, kin, SpeedSettings("auto", tacho="tacho", pulses_per_rev=1),
                       machine=MACHINE)
    right = estimate_speed(m, kin, SpeedSettings("auto", tacho="tacho", pulses_per_rev=10),
                           machine=MACHINE)
    assert right.warning() is None and right.speed_hz == pytest.approx(0.99 * INPUT_HZ, 1e-3)
    mesh = estimate_speed(m, kin, SpeedSettings("mesh", tacho="tacho", pulses_per_rev=10),
                          machine=MACHINE)
    assert mesh.tacho_speed_hz == pytest.approx(mesh.speed_hz, 1e-4) and mesh.warning() is None
    off = estimate_speed(m, kin, SpeedSettings("mesh", tacho="tacho", pulses_per_rev=11),
                         machine=MACHINE)
    assert "from the tacho's" in off.warning()


def test_the_tacho_stands_in_when_no_mesh_line_stands_out():
    """--speed mesh on a record whose meshes are lost in noise, a tacho beside them: the
    tacho's speed, said to be the tacho's, not a refusal (issue 59.9)."""
    import numpy as np

    from pydiag.core.measurement import Measurement
    from pydiag.gear.speed import SpeedSource, estimate_speed
    with_tacho = record(2, tacho_pulses=10)
    noise = np.random.default_rng(0).standard_normal(with_tacho.n_samples)
    m = Measurement({"acc": noise, "tacho": with_tacho.channels["tacho"]},
                    with_tacho.sample_rate_hz)
    kin = MACHINE.stage_kinematics(0, INPUT_HZ)
    alone = Measurement({"acc": noise}, with_tacho.sample_rate_hz)
    with pytest.raises(MeasurementError, match="no mesh line stands out"):
        estimate_speed(alone, kin, SpeedSettings("mesh"), machine=MACHINE)
    found = estimate_speed(m, kin, SpeedSettings("mesh", tacho="tacho", pulses_per_rev=10),
                           machine=MACHINE)
    assert found.source is SpeedSource.TACHO and "no mesh line stood out" in found.method
    assert found.speed_hz == pytest.approx(0.99 * INPUT_HZ, 1e-3)


@pytest.mark.parametrize("shaft, defect", [(0, "outer"), (1, "inner")])
def test_a_bearings_strikes_change_no_stage(short_baseline, shaft, defect):
    """Strong strikes of a race defect land in every shaft's TSA residual, averaged down
    and not away, and raise its energy; the synchronous part, the energy less what the
    record's non-synchronous vibration leaves in a TSA of that many turns, stays."""
    faulty = machine_record(record(3, box=SHORT_BOX, bearing=((shaft, defect, 6.0),)),
                            SHORT_MACHINE, SpeedSettings("mesh"), INPUT_HZ)
    shafts = faulty.shafts
    assert all(s.residual_energy["acc"] > b.residual_energy["acc"]
               for s, b in zip(shafts, short_baseline.shafts))  # the strikes are in it
    verdicts, _ = judge_stages(SHORT_MACHINE, faulty, [short_baseline])
    assert not any(v.changed for v in verdicts), verdicts


def test_a_baseline_kept_before_the_noise_was_read_is_judged_by_the_whole_energy(
        short_baseline):
    """Such a baseline reads back without its shafts' noise: the record is judged by the
    residual's whole energy against one threshold, K x the healthy spread, as it was."""
    from pydiag.gear.machine_indicators import MachineRecord
    from pydiag.gear.stage_judge import K_SPREAD
    old = short_baseline.to_dict()
    for s in old["shafts"]:
        del s["noise"], s["noise_halves"], s["residual_orders"]
    old = MachineRecord.from_dict(old)
    faulty = machine_record(record(3, box=SHORT_BOX, faulty_shaft=0, stage=0), SHORT_MACHINE,
                            SpeedSettings("mesh"), INPUT_HZ)
    verdicts, spread = judge_stages(SHORT_MACHINE, faulty, [old])
    assert verdicts[0].threshold_db == pytest.approx(K_SPREAD * spread)
    assert all(v.pinion.threshold_db != v.pinion.threshold_db for v in verdicts)  # nan
    assert verdicts[0].changed and verdicts[0].suspect == "pinion", verdicts[0]
    new, _ = judge_stages(SHORT_MACHINE, faulty, [short_baseline])
    assert new[0].changed and new[0].pinion.threshold_db > 0
