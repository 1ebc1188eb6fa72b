"""The model's verdict on the healthy model's own effects (pydiag.loop.own_changes): a
record's rise of held-out z held to a healthy repeat's, named on the part its change
sizes. The rows are written here as refit_own_effects returns them: what is checked is
the rule and the naming, not a fit."""

import dataclasses
import math
import tomllib

import pytest
from conftest import ROOT

from pydiag.gear.effect import MESH
from pydiag.gear.machine_file import machine_from_dict
from pydiag.loop.machine_model import machine_model
from pydiag.loop.own_changes import (HealthyModel, effect_covers, lacking_tries, own_changes,
                                     part_components)
from pydiag.loop.results import HeldOut, Suggestion


@pytest.fixture(scope="module")
def spur():
    data = tomllib.loads((ROOT / "examples" / "phm09_spur.toml").read_text())
    data["effects"] = [{"key": "pinion_shaft_orders", "stage": "input stage"},
                       {"key": "mesh_modulation", "stage": "output stage"}]
    machine = machine_from_dict(data, "spur with the loop's effects")
    return machine, machine_model(machine, ROOT / "modelica")


def row(stage, effect, z, **fitted):
    return Suggestion(effect, stage=stage, held_out=HeldOut(effect, z, 2.3, 0.5, 0.8, 0.7,
                                                            dict(fitted)))


def test_a_rise_beyond_four_repeats_names_the_part_that_changed(spur):
    machine, model = spur
    inp, out = (f"{s}." for s in model.stages)
    healthy = {out + "m_p": 0.263, out + "m_g": 0.483, inp + "A_s1": 275.0, inp + "A_s2": 122.0}
    baseline = [row("output stage", "mesh_modulation", -0.4),
                row("input stage", "pinion_shaft_orders", 0.9)]
    repeat = [row("output stage", "mesh_modulation", 10.6),
              row("input stage", "pinion_shaft_orders", 11.8)]
    record = [row("output stage", "mesh_modulation", 83.6,
                  **{out + "m_p": 0.499, out + "m_g": 0.444, out + "phi_p": 1.25}),
              row("input stage", "pinion_shaft_orders", 30.0,
                  **{inp + "A_s1": 123.0, inp + "A_s2": 23.6})]
    found = own_changes(machine, model, healthy, record, baseline, [repeat])
    modulation, orders = found  # the largest margin first
    assert modulation.effect == "mesh_modulation" and modulation.changed
    assert modulation.margin == pytest.approx(84.0 / (4 * 11.0))
    assert modulation.part == "pinion" and modulation.components == ("48T pinion of output stage",)
    assert modulation.values[out + "m_p"] == (0.263, 0.499)
    assert out + "phi_p" not in modulation.values  # a phase sizes nothing
    # the orders fell: the record asks for other values, and names no fault of the shaft
    assert orders.part is None and orders.components == () and orders.covers == ("input",)
    assert not orders.changed  # 29.1 over 4 x 10.9
    # the repeat against itself: no rise; without a repeat, no verdict
    assert not any(c.changed for c in own_changes(machine, model, healthy, repeat, baseline,
                                                  [repeat]))
    alone = own_changes(machine, model, healthy, record, baseline)
    assert all(math.isnan(c.margin) and not c.changed and c.repeat_rise is None for c in alone)


def test_a_repeat_that_barely_moves_is_held_to_a_z_of_one(spur):
    machine, model = spur
    base = [row("output stage", "mesh_modulation", 0.0)]
    record = [row("output stage", "mesh_modulation", 4.5)]
    for repeat_z, changed in ((0.2, True), (1.2, False)):
        c, = own_changes(machine, model, {}, record, base,
                         [[row("output stage", "mesh_modulation", repeat_z)]])
        assert c.changed is changed and c.part is None  # no values: no part
    # two repeats: held to their RMS rise, sqrt((1^2 + 1.2^2) / 2) = 1.105
    c, = own_changes(machine, model, {}, record, base,
                     [[row("output stage", "mesh_modulation", z)] for z in (1.0, -1.2)])
    assert c.repeat_rise == pytest.approx(1.1045, abs=1e-4)
    assert c.margin == pytest.approx(4.5 / (4 * 1.1045), abs=1e-3) and c.changed


def test_an_effect_not_tried_on_the_healthy_records_is_held_to_no_rise_there(spur):
    """A lacking effect whose lines stood out of no healthy record (an output bearing's
    strikes) was not tried there: a z of 0 on the baseline and the repeats, so the record's
    change is held to the floor of a z of 1, not left without a verdict."""
    machine, model = spur
    out = f"{model.stages[1]}."
    record = [row("output stage", "gear_bearing_outer_race", 30.0, **{out + "A_b": 9.4})]
    c, = own_changes(machine, model, {}, record, [], [[], []])
    assert (c.baseline_z, c.repeat_rise) == (0.0, 0.0) and c.margin == pytest.approx(30.0 / 4)
    assert c.changed and c.fault == "outer" and c.components == ("OS:IS", "OS:OS")


def test_a_part_is_the_machines_components():
    machine = machine_from_dict(tomllib.loads(
        (ROOT / "examples" / "phm09_spur.toml").read_text()))
    assert part_components(machine, 0, MESH) == ("32T pinion of input stage",
                                                 "96T gear of input stage")
    assert part_components(machine, 1, "gear shaft") == ("output",)
    assert part_components(machine, 1, "pinion bearing") == ("ID:IS", "ID:OS")
    assert part_components(machine, 0, None) == ()
    # the other shaft: the next downstream of the gear, else the one upstream of the pinion
    assert part_components(machine, 0, "other shaft") == ("output",)
    assert part_components(machine, 1, "other shaft") == ("input",)


def test_the_shaft_no_pinion_sits_on_is_judged_through_the_other_shaft(spur):
    """The output shaft carries no stage's pinion: its orders are the input stage's other
    shaft's. A sheared key that lets it slip makes its first three orders rise: looseness,
    on the output shaft."""
    machine, model = spur
    inp = f"{model.stages[0]}."
    base = [row("input stage", "other_shaft_orders", 0.3)]
    repeat = [row("input stage", "other_shaft_orders", 1.4)]
    record = [row("input stage", "other_shaft_orders", 30.0,
                  **{inp + "A_o1": 40.0, inp + "A_o2": 35.0, inp + "A_o3": 30.0,
                     inp + "A_o4": 2.0})]
    c, = own_changes(machine, model, {}, record, base, [repeat])
    assert c.changed and (c.part, c.fault) == ("other shaft", "looseness")
    assert c.components == c.covers == ("output",)


def test_a_change_says_the_fault_its_effect_names_and_what_it_covers(spur):
    """Orders of the input shaft that rose at 1x and 2x are a bend; the output stage's
    modulation covers both its gears and tells no fault."""
    machine, model = spur
    inp, out = (f"{s}." for s in model.stages)
    healthy = {inp + "A_s1": 100.0, inp + "A_s2": 50.0, inp + "A_s3": 20.0,
               out + "m_p": 0.2, out + "m_g": 0.1}
    base = [row("input stage", "pinion_shaft_orders", 0.0),
            row("output stage", "mesh_modulation", 0.0)]
    repeat = [row("input stage", "pinion_shaft_orders", 1.0),
              row("output stage", "mesh_modulation", 1.0)]
    record = [row("input stage", "pinion_shaft_orders", 40.0,
                  **{inp + "A_s1": 300.0, inp + "A_s2": 190.0, inp + "A_s3": 25.0}),
              row("output stage", "mesh_modulation", 40.0, **{out + "m_g": 0.3})]
    found = {c.effect: c for c in own_changes(machine, model, healthy, record, base, [repeat])}
    orders, modulation = found["pinion_shaft_orders"], found["mesh_modulation"]
    assert orders.fault == "bent" and orders.covers == ("input",)
    assert modulation.fault == "changed" and modulation.components == ("80T gear of output stage",)
    assert modulation.covers == ("48T pinion of output stage", "80T gear of output stage")


def test_an_effect_the_healthy_model_lacks_is_sized_from_off(spur):
    """The first question's row (discover_machine's): the input stage's outer race, which
    the healthy model has not, grew from no strike to the record's."""
    machine, model = spur
    inp = f"{model.stages[0]}."
    base = [row("input stage", "bearing_outer_race", 0.5)]
    repeat = [row("input stage", "bearing_outer_race", 1.5)]
    record = [row("input stage", "bearing_outer_race", 60.0, **{inp + "A_b": 58.9})]
    c, = own_changes(machine, model, {}, record, base, [repeat])
    assert c.changed and c.values == {inp + "A_b": (0.0, 58.9)}
    assert (c.part, c.fault, c.components) == ("pinion bearing", "outer", ("IS:IS", "IS:OS"))


def test_of_two_changes_that_claim_the_same_lines_the_larger_names_them(spur):
    """An input bearing's outer-race strikes: their lines are every other line of the idler
    bearing's at a third of its speed, so the output stage's outer race rises too; the
    larger change explains them."""
    machine, model = spur
    inp, out = (f"{s}." for s in model.stages)

    def race(stage, z, a_b, lines):
        prefix = inp if stage == "input stage" else out
        r = row(stage, "bearing_outer_race", z, **{prefix + "A_b": a_b})
        return dataclasses.replace(r, held_out=dataclasses.replace(r.held_out, claimed=lines))
    base = [race("input stage", 0.5, 0.0, ()), race("output stage", 0.4, 0.0, ())]
    repeat = [race("input stage", 1.0, 0.0, ()), race("output stage", 1.0, 0.0, ())]
    both = ("acc envelope 310.00 Hz", "acc envelope 620.00 Hz")
    record = [race("input stage", 90.0, 58.9, both),
              race("output stage", 40.0, 13.2, both[1:] + ("acc envelope 103.30 Hz",))]
    first, second = own_changes(machine, model, {}, record, base, [repeat])
    assert first.stage == "input stage" and first.changed and first.components == (
        "IS:IS", "IS:OS")
    assert second.margin > 1 and not second.changed
    assert second.beaten_by == "bearing_outer_race on input stage"
    # lines of their own: both stand
    record[1] = race("output stage", 40.0, 13.2, ("acc envelope 103.30 Hz",))
    assert all(c.changed for c in own_changes(machine, model, {}, record, base, [repeat]))


def test_a_rise_whose_fit_leaves_its_own_lines_worse_names_nothing(spur):
    """The short box's input outer race: the intermediate bearing's ball effect rose 7 in
    z beside it, its fit leaving 2.6 times more residual on its own lines of the held-out
    half (explained -2.6): its z came from the outer race's lines."""
    machine, model = spur
    inp = f"{model.stages[0]}."
    base = [row("input stage", "bearing_ball", 0.6)]
    repeat = [row("input stage", "bearing_ball", 1.6)]
    ball = row("input stage", "bearing_ball", 8.9, **{inp + "A_b": 7.5})
    worse = dataclasses.replace(ball, held_out=dataclasses.replace(ball.held_out,
                                                                   explained=-2.6))
    c, = own_changes(machine, model, {}, [worse], base, [repeat])
    assert c.margin > 1 and not c.changed and c.explained == -2.6
    c, = own_changes(machine, model, {}, [ball], base, [repeat])  # explained 0.5
    assert c.changed and c.components == ("IS:IS", "IS:OS")


def test_an_effect_covers_the_components_its_parts_are_on_its_stage(spur):
    """What a record's verdict asks of the model (record_changes' ``asked``) picks the
    stages an effect is tried on by these: a bearing's race the bearings of the shaft its
    stage's pinion (or, on the last stage, gear) turns, a tooth the stage's gears, a
    shaft's orders its shaft."""
    machine, model = spur
    inp, out = (model.stage_effects(k) for k in (0, 1))
    assert effect_covers(machine, 0, inp["bearing_inner_race"]) == ("IS:IS", "IS:OS")
    assert effect_covers(machine, 1, out["bearing_inner_race"]) == ("ID:IS", "ID:OS")
    assert effect_covers(machine, 1, out["gear_bearing_ball"]) == ("OS:IS", "OS:OS")
    assert set(effect_covers(machine, 1, out["gear_tooth_fault"])) == {"80T gear of output stage"}
    assert effect_covers(machine, 0, inp["pinion_shaft_orders"]) == ("input",)


def test_a_record_is_asked_for_the_lacking_effects_that_could_name_what_changed(spur):
    """lacking_tries: the (stage, effect) pairs of the healthy model's lacking effects a
    record is asked for, where they could name a component asked about; the healthy
    model's own effects are not among them (the output stage has its modulation)."""
    machine, model = spur
    healthy = HealthyModel({}, 0.01, {}, (), ("bearing_outer_race", "gear_tooth_fault",
                                              "mesh_modulation"))
    assert lacking_tries(healthy, machine, model, {"IS:OS"}) == {
        ("input stage", "bearing_outer_race")}
    assert lacking_tries(healthy, machine, model, {"80T gear of output stage", "ID:IS"}) == {
        ("output stage", "gear_tooth_fault"), ("output stage", "bearing_outer_race")}
    assert lacking_tries(healthy, machine, model, set()) == set()
    assert lacking_tries(healthy, machine, model, None) == {
        (stage, key) for stage in ("input stage", "output stage")
        for key in ("bearing_outer_race", "gear_tooth_fault")} | {
        ("input stage", "mesh_modulation")}
