"""The model's verdict on the healthy model's own effects (pydiag.loop.own_changes): a
record's rise of held-out z held to a healthy repeat's, named on the part its change
sizes. The rows are written here as refit_own_effects returns them: what is checked is
the rule and the naming, not a fit."""

import math
import tomllib

import pytest
from conftest import ROOT

from pydiag.gear.effect import MESH
from pydiag.gear.machine_file import machine_from_dict
from pydiag.loop.machine_model import machine_model
from pydiag.loop.own_changes import own_changes, part_components
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
    assert orders.part == "pinion shaft" and orders.components == ("input",)
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


def test_a_part_is_the_machines_components():
    machine = machine_from_dict(tomllib.loads(
        (ROOT / "examples" / "phm09_spur.toml").read_text()))
    assert part_components(machine, 0, MESH) == ("32T pinion of input stage",
                                                 "96T gear of input stage")
    assert part_components(machine, 1, "gear shaft") == ("output",)
    assert part_components(machine, 1, "pinion bearing") == ("ID:IS", "ID:OS")
    assert part_components(machine, 0, None) == ()
