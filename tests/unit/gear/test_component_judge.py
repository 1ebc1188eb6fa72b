"""Every gear, bearing and shaft of a two-stage box judged against its healthy record, on
records of the independent gearbox simulator (:mod:`truth.gearbox`: faults written from
the shafts' angles and the bearing's own geometry, not by pydiag): a healthy record has
every component good; a shaft's unbalance, a bend, a chipped, broken or eccentric gear,
a race's and a ball's defect are each named on their component."""

from dataclasses import replace

import pytest
from truth.gearbox import BOX, INPUT_HZ, SHAFT_NAMES, SHORT_BOX, described, gearbox_record

from pydiag.gear.component import components
from pydiag.gear.component_judge import judge_components
from pydiag.gear.machine_file import machine_from_dict
from pydiag.gear.machine_indicators import machine_record
from pydiag.gear.speed import SpeedSettings
from pydiag.gear.stage_judge import judge_stages

SHAFTS = list(SHAFT_NAMES)


def machine_of(box):
    """The box as its user would describe it: its teeth and a bearing on each shaft, of
    the geometry its maker's sheet gives."""
    return machine_from_dict(described(box))


def judged(box, seed, **fault):
    """Every component of ``box`` in a record of ``seed`` with ``fault`` against seed 1's
    healthy record; with ``tacho_pulses``, both have a tacho and the speed is its."""
    machine = machine_of(box)
    pulses = fault.get("tacho_pulses", 0)
    speed = SpeedSettings(tacho="tacho", pulses_per_rev=pulses) if pulses else SpeedSettings("mesh")
    record = machine_record(gearbox_record(seed, box=box, **fault), machine, speed, INPUT_HZ)
    baseline = machine_record(gearbox_record(1, box=box, tacho_pulses=pulses), machine, speed,
                              INPUT_HZ)
    verdicts, _ = judge_stages(machine, record, [baseline])
    return {v.component.name: v for v in judge_components(machine, record, [baseline],
                                                          verdicts)}


def faulty(found):
    return {name: v.state for name, v in found.items() if v.faulty}


def test_every_gear_bearing_and_shaft_is_a_component_with_its_shaft():
    listed = components(machine_of(BOX))
    gears = [(c.shaft, c.teeth, c.role) for c in listed if c.kind == "gear"]
    assert gears == [("input", 20, "pinion"), ("intermediate", 64, "gear"),
                     ("intermediate", 24, "pinion"), ("output", 54, "gear")]
    assert [(c.name, c.shaft) for c in listed if c.kind == "bearing"] == [
        (f"{s} bearing", s) for s in SHAFTS]
    assert [c.name for c in listed if c.kind == "shaft"] == SHAFTS


@pytest.mark.parametrize("box", [BOX, SHORT_BOX])
@pytest.mark.parametrize("seed", [2, 3, 4])
def test_a_healthy_record_has_every_component_good(box, seed):
    found = judged(box, seed)
    assert not faulty(found), faulty(found)
    data = found["input"].to_dict()
    assert data["kind"] == "shaft" and data["state"] == "good" and data["margin"] < 1


@pytest.mark.parametrize("seed", [2, 3, 4])
@pytest.mark.parametrize("fault, named", [
    (dict(unbalance=((2, 0.3),)), {"output": "imbalance"}),
    (dict(bend=((0, 0.3),)), {"input": "bent"}),
    (dict(faulty_shaft=2, stage=1), {"54T gear of stage 2": "changed"}),
    (dict(faulty_shaft=0, stage=0, depth=0.3), {"20T pinion of stage 1": "changed"}),
    (dict(runout=((2, 1, 0.2),)), {"54T gear of stage 2": "changed"})])
def test_a_shafts_fault_a_chip_a_break_and_a_runout_are_named_on_their_component(
        seed, fault, named):
    """A gear alone on its shaft (the input's pinion, the output's gear): a chip (its mesh
    dipping by 0.3 once a turn), a broken tooth (0.8) and a runout are each its gear's."""
    assert faulty(judged(BOX, seed, **fault)) == named


@pytest.mark.parametrize("seed", [2, 3, 4])
@pytest.mark.parametrize("box, fault, named, other", [
    (BOX, dict(runout=((1, 1, 0.2),)), "24T pinion of stage 2", "64T gear of stage 1"),
    (SHORT_BOX, dict(faulty_shaft=1, stage=0, depth=0.3), "36T gear of stage 1",
     "20T pinion of stage 2")])
def test_an_idlers_gear_is_told_from_its_other_gear_by_its_own_sidebands(seed, box, fault,
                                                                        named, other):
    """The intermediate shaft carries stage 1's gear and stage 2's pinion, and its
    residual rises with either one's fault: the sidebands of the faulty gear's mesh
    harmonics that are none of the other's rose, the other's did not."""
    found = judged(box, seed, **fault)
    assert faulty(found) == {named: "changed"}, faulty(found)
    assert "its mesh's own sidebands rose" in found[named].reason
    assert "its mesh's own sidebands did not" in found[other].reason, found[other]


@pytest.mark.parametrize("seed", [2, 3, 4])
def test_a_slower_shafts_broken_tooth_on_a_faster_shafts_lines_is_the_slower_ones(seed):
    """The short box's output turns once in five input turns: its broken tooth strikes at
    one input angle every fifth input turn, on every input order, so the input's TSA
    keeps a fifth of it and its residual rises beyond its threshold. The output's change,
    read in its own TSA beside those lines, accounts for that rise: the input's pinion is
    good, the output's gear changed."""
    machine = machine_of(SHORT_BOX)
    record, baseline = (machine_record(gearbox_record(s, box=SHORT_BOX, **fault), machine,
                                       SpeedSettings("mesh"), INPUT_HZ)
                        for s, fault in ((seed, dict(faulty_shaft=2, stage=1)), (1, {})))
    verdicts, _ = judge_stages(machine, record, [baseline])
    first = verdicts[0].pinion
    assert first.change_db > first.threshold_db and first.explained_by == ("output",), first
    said = judge_components(machine, record, [baseline], verdicts)
    assert {v.component.name: v.state for v in said if v.faulty} == {
        "50T gear of stage 2": "changed"}
    pinion = next(v for v in said if v.component.name == "18T pinion of stage 1")
    assert "the output shaft's change accounts for its shaft's rise" in pinion.reason, pinion
    # a kept baseline reads back to the same verdict; one kept before the TSAs' power by
    # order was, without the explanation (the rise judged whole, as before)
    from pydiag.gear.machine_indicators import MachineRecord
    kept = MachineRecord.from_dict(baseline.to_dict())
    assert judge_stages(machine, record, [kept])[0][0].pinion == first
    old = baseline.to_dict()
    for shaft in old["shafts"]:
        del shaft["power"]
    again = judge_stages(machine, record, [MachineRecord.from_dict(old)])[0][0]
    assert again.pinion.explained_by == () and again.changed, again


@pytest.mark.parametrize("seed", [2, 3, 4])
@pytest.mark.parametrize("shaft, defect", [(1, "inner"), (0, "outer"), (2, "ball"),
                                           (0, "ball")])
def test_a_races_defect_is_named_on_its_bearing(seed, shaft, defect):
    """Strong impacts (peaks 20 times the noise): the bearing's own line rises beyond its
    threshold, and no other bearing is named. A spalled ball's lines are other bearings'
    too: the output turns once in five input turns, so the tenth harmonic of its ball's
    spin is the input bearing's ball line (4.73 input orders), which rises more than the
    output's own; the input's ball strikes its races
    unequally, so its envelope has a line at the spin (2.37), which is the intermediate's
    ball line (twice its spin, at half the input's speed). Each is named on the bearing
    whose comb's first line rose (:func:`pydiag.gear.bearing_judge._explainer`)."""
    found = judged(SHORT_BOX, seed, bearing=((shaft, defect, 6.0),))
    bearings = {name: v.state for name, v in found.items() if v.component.kind == "bearing"}
    assert bearings == {f"{s} bearing": defect if k == shaft else "good"
                        for k, s in enumerate(SHAFTS)}, bearings
    if defect == "ball":  # the other bearing whose line rose says whose comb it is
        other = "input bearing" if shaft == 2 else "intermediate bearing"
        assert f"harmonic of {SHAFTS[shaft]} bearing's ball comb" in found[other].reason, \
            found[other]


def test_a_bearings_line_on_a_shafts_order_is_not_judged_on_that_line():
    """8 balls of 10 mm on a 40 mm pitch circle strike a defect of the inner race 5 times a
    turn exactly (8/2 x (1 + 10/40)), of the outer race 3 times: on the shaft's 5th and 3rd
    orders, whose envelope lines the turn's modulation of the noise makes; those lines are
    not judged, the ball's and the cage's are."""
    machine = machine_from_dict({
        "name": SHORT_BOX.name,
        "stages": [{"pinion_teeth": p, "gear_teeth": g} for p, g in SHORT_BOX.teeth],
        "bearings": [{"name": "b", "shaft": "input", "n_balls": 8,
                      "ball_diameter_mm": 10.0, "pitch_diameter_mm": 40.0}]})
    record, baseline = (machine_record(gearbox_record(seed, box=SHORT_BOX), machine,
                                       SpeedSettings("mesh"), INPUT_HZ) for seed in (2, 1))
    verdicts, _ = judge_stages(machine, record, [baseline])
    bearing = next(v for v in judge_components(machine, record, [baseline], verdicts)
                   if v.component.kind == "bearing")
    assert bearing.reason == ("outer: its line lies on the input shaft's 3x; inner: its "
                              "line lies on the input shaft's 5x")
    assert set(bearing.evidence) == {"ball_db", "cage_db"}


def test_a_lines_deviation_is_how_much_it_varies_in_noise():
    """An envelope of white noise, read at a slow shaft's line (few bins) and a fast one's
    (many): over many records each level varies by the deviation it is reported with, so
    one threshold of deviations holds every line to the same false-alarm rate."""
    import numpy as np

    from pydiag.gear.bearing_lines import _levels_db
    lines = {"b": {"slow": 0.37, "fast": 4.73}}
    shafts = np.arange(1.0, 7.0)
    rng = np.random.default_rng(0)
    read = [_levels_db(rng.standard_normal(64 * 160), 64, lines, shafts)["b"]
            for _ in range(400)]
    for line in ("slow", "fast"):
        levels, deviations = zip(*(r[line] for r in read))
        assert np.ptp(deviations) == 0  # the bins it is read on do not depend on the record
        assert 0.85 < np.std(levels) / deviations[0] < 1.15, (line, np.std(levels),
                                                                deviations[0])
    assert read[0]["slow"][1] > 1.5 * read[0]["fast"][1]


def test_a_baseline_kept_before_the_components_were_read_judges_only_the_gears():
    """A kept baseline written before pydiag read the shafts' orders and the bearings'
    lines reads back without them: gears are judged, bearings and shafts say why not."""
    from pydiag.gear.machine_indicators import MachineRecord
    machine = machine_of(SHORT_BOX)
    record, baseline = (machine_record(gearbox_record(seed, box=SHORT_BOX), machine,
                                       SpeedSettings("mesh"), INPUT_HZ) for seed in (2, 1))
    old = baseline.to_dict()
    del old["bearings"]
    for shaft in old["shafts"]:
        del shaft["orders"], shaft["order_halves"]
    old = MachineRecord.from_dict(old)
    verdicts, _ = judge_stages(machine, record, [old])
    states = {v.component.kind: (v.state, v.reason)
              for v in judge_components(machine, record, [old], verdicts)}
    assert states["gear"][0] == "good"
    for kind in ("bearing", "shaft"):
        assert states[kind][0] == "not judged" and "keep it again" in states[kind][1]
    # kept after the bearings' lines were read, before their deviations were
    old = baseline.to_dict()
    for bearing in old["bearings"]:
        del bearing["sd_db"], bearing["halves_sd_db"]
    old = MachineRecord.from_dict(old)
    bearings = [v for v in judge_components(machine, record, [old], verdicts)
                if v.component.kind == "bearing"]
    assert all(v.state == "not judged" and "keep it again" in v.reason for v in bearings)


@pytest.mark.parametrize("by, output_gear", [("residual energy", "changed"),
                                             ("impulsiveness", "good")])
def test_a_shafts_only_gear_changes_with_its_shaft_beside_a_suspect_idler(by, output_gear):
    """The PHM09 spur 4 case's shape: stage 2's idler (two gears) moved 5.35 x its
    threshold and the output (one gear) 2.77 x, each on its own. The idler is the
    suspect by the larger move, but the output's gear is the only one its shaft could
    have changed by, so it is changed too; FM4 naming the idler instead (a local fault's
    impulsiveness, the specific evidence) leaves it good."""
    from pydiag.gear.stage_judge import ShaftChange, StageVerdict
    machine = machine_of(BOX)
    quiet = ShaftChange("input", 0.1, {"acc": 0.1}, 0.0, 1.0)
    idler = ShaftChange("intermediate", 5.35, {"acc": 5.35}, 0.0, 1.0)
    output = ShaftChange("output", 2.77, {"acc": 2.77}, 0.0, 1.0)
    verdicts = [StageVerdict("stage 1", 20, 64, 500.0, quiet, idler, 1.0, True, "gear", 0.5,
                             "residual energy"),
                StageVerdict("stage 2", 24, 54, 300.0, idler, output, 1.0, True, "pinion", 0.5,
                             by)]
    from pydiag.gear.component_judge import _gears
    states = {v.component.name: v.state for v in _gears(machine, verdicts)}
    assert states == {"20T pinion of stage 1": "good", "64T gear of stage 1": "changed",
                      "24T pinion of stage 2": "changed", "54T gear of stage 2": output_gear}


@pytest.mark.parametrize("seed", [2, 3, 4])
@pytest.mark.parametrize("shaft, named, other", [
    (1, "24T pinion of stage 2", "64T gear of stage 1"), (2, "54T gear of stage 2", None)])
def test_a_runout_that_swings_the_drive_is_an_eccentric_gear_where_a_tacho_sees_it(
        seed, shaft, named, other):
    """The runout (its mesh swinging by 0.2 once its turn) swings the whole drive by 0.002
    of an input turn, which a 10-pulse tacho on the input sees: the gear is "eccentric",
    and the idler's other gear, whose own mesh's sidebands did not rise, good."""
    found = judged(BOX, seed, tacho_pulses=10, runout=((shaft, 1, 0.2),),
                   swing=((shaft, 0.002),))
    assert found[named].state == "eccentric", found[named]
    assert "swing rose at 1x" in found[named].reason
    assert found[named].evidence["swing_1x_deg"] == pytest.approx(0.72, rel=0.05)  # 0.002 turn
    if other:
        assert found[other].state == "good", found[other]


@pytest.mark.parametrize("seed", [2, 3, 4])
def test_a_healthy_record_with_a_tacho_has_every_component_good(seed):
    found = judged(BOX, seed, tacho_pulses=10)
    assert not faulty(found), faulty(found)
    assert "swing_1x_db" not in found["24T pinion of stage 2"].evidence  # none rose


def test_a_swing_that_repeats_more_than_once_a_turn_is_a_change_not_an_eccentric_gear():
    """The idler's swing rising at its 2x (a transmission error twice a turn: an oval gear,
    a loose fit) changes its gears without naming them eccentric."""
    machine = machine_of(BOX)
    speed = SpeedSettings(tacho="tacho", pulses_per_rev=10)
    baseline = machine_record(gearbox_record(1, box=BOX, tacho_pulses=10), machine, speed,
                              INPUT_HZ)
    record = machine_record(gearbox_record(2, box=BOX, tacho_pulses=10), machine, speed,
                            INPUT_HZ)
    idler = record.shafts[1]
    lines = list(idler.swing_lines_deg)
    lines[1] = (lines[1][0] + 20 * lines[1][1], lines[1][1])
    record = replace(record, shafts=(record.shafts[0], replace(idler, swing_lines_deg=tuple(
        lines)), record.shafts[2]))
    verdicts, _ = judge_stages(machine, record, [baseline])
    found = {v.component.name: v for v in judge_components(machine, record, [baseline],
                                                           verdicts)}
    assert {n: found[n].state for n in ("64T gear of stage 1", "24T pinion of stage 2")} == {
        "64T gear of stage 1": "changed", "24T pinion of stage 2": "changed"}
    assert "2x" in found["24T pinion of stage 2"].reason


@pytest.mark.parametrize("seed", [2, 3, 4])
def test_a_shaft_whose_gear_swings_it_is_not_called_faulty_for_its_orders(seed):
    """An eccentric idler pinion whose mass turns off the axis: the idler's 1x at the
    sensor rises with the swing. The gear is named, the shaft is good and says why; the
    same 1x without the swing is the shaft's imbalance."""
    fault = dict(tacho_pulses=10, unbalance=((1, 0.3),))
    swinging = judged(BOX, seed, runout=((1, 1, 0.2),), swing=((1, 0.002),), **fault)
    assert swinging["24T pinion of stage 2"].state == "eccentric"
    assert swinging["intermediate"].state == "good", swinging["intermediate"]
    assert "orders risen: 1x, with its swing (1x)" in swinging["intermediate"].reason
    assert judged(BOX, seed, **fault)["intermediate"].state == "imbalance"


def test_a_baseline_kept_before_the_swing_was_read_says_so_on_the_gears_it_would_judge():
    """The eccentric idler pinion swinging the drive, judged against a tacho baseline kept
    before pydiag read the swing's lines: the gears are judged as without a tacho, and
    those on the slower shafts say that their shaft's swing was not."""
    from pydiag.gear.machine_indicators import MachineRecord
    machine = machine_of(BOX)
    speed = SpeedSettings(tacho="tacho", pulses_per_rev=10)
    record = machine_record(gearbox_record(2, box=BOX, tacho_pulses=10, runout=((1, 1, 0.2),),
                                           swing=((1, 0.002),)), machine, speed, INPUT_HZ)
    old = machine_record(gearbox_record(1, box=BOX, tacho_pulses=10), machine, speed,
                         INPUT_HZ).to_dict()
    for shaft in old["shafts"]:
        del shaft["swing_lines_deg"]
    old = MachineRecord.from_dict(old)
    verdicts, _ = judge_stages(machine, record, [old])
    found = {v.component.name: v for v in judge_components(machine, record, [old], verdicts)}
    assert found["24T pinion of stage 2"].state == "changed"  # by its sidebands, not eccentric
    for name in ("64T gear of stage 1", "24T pinion of stage 2", "54T gear of stage 2"):
        assert "swing not judged" in found[name].reason and "keep it again" in found[name].reason
    assert "swing" not in found["20T pinion of stage 1"].reason  # the input has none


def test_a_shaft_whose_order_fell_beyond_its_threshold_is_good_and_says_so():
    """A fault makes a shaft's orders larger: one that fell, however far, names no fault,
    and the line says why its change is beyond the threshold (before, such a shaft was
    said good with no word)."""
    machine = machine_of(BOX)
    speed = SpeedSettings("mesh")
    baseline = machine_record(gearbox_record(1, box=BOX), machine, speed, INPUT_HZ)
    record = machine_record(gearbox_record(2, box=BOX), machine, speed, INPUT_HZ)
    shaft = record.shafts[0]
    fallen = {ch: tuple(a / 100 if k == 1 else a for k, a in enumerate(o))
              for ch, o in shaft.orders.items()}  # its 2x 40 dB down on every channel
    record = replace(record, shafts=(replace(shaft, orders=fallen), *record.shafts[1:]))
    verdicts, _ = judge_stages(machine, record, [baseline])
    found = {v.component.name: v for v in judge_components(machine, record, [baseline],
                                                           verdicts)}
    said = found[SHAFTS[0]]
    assert said.state == "good" and said.margin > 1, said
    assert said.reason == "orders fell: 2x (a fall names no fault)"
