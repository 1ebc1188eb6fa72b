"""The bearings of the shaft no stage's pinion turns (a gearbox's output shaft): the last
stage's gear-bearing effects model them, at that shaft's speed, and name them."""

import tomllib

import numpy as np
import pytest
import scipy.signal
from conftest import ROOT

from pydiag.fmu.plant import FmuPlant
from pydiag.gear.effects import EFFECTS
from pydiag.gear.kinematic_map import kinematic_map, match
from pydiag.gear.kinematics import Bearing, GearKinematics
from pydiag.gear.machine_file import machine_from_dict
from pydiag.gear.paper_cases import TABLE1
from pydiag.loop.discover import effect_fmu
from pydiag.loop.own_changes import part_components


@pytest.fixture(scope="module")
def spur():
    return machine_from_dict(tomllib.loads((ROOT / "examples" / "phm09_spur.toml").read_text()))


def test_the_last_stage_models_the_output_shafts_bearing(spur):
    """PHM09's spur box has two bearings on each of its three shafts: the input's and the
    idler's are the first and second stages' pinion bearings, the output's the second
    stage's gear bearing (named by the map at the output's speed, no longer another
    bearing of the machine's); the first stage has none on its gear's shaft (the idler is
    the second stage's pinion shaft)."""
    first, last = spur.stage_kinematics(0, 30.0), spur.stage_kinematics(1, 30.0)
    assert first.gear_bearing is None and first.bearing.name == "IS:IS"
    assert (last.bearing.name, last.bearing.shaft) == ("ID:IS", "pinion")
    assert (last.gear_bearing.name, last.gear_bearing.shaft) == ("OS:IS", "gear")
    assert "OS:IS" not in {b.name for b in last.surroundings.bearings}
    output_hz = 30.0 * 32 / 96 * 48 / 80
    bpfo = last.gear_bearing.frequencies(output_hz)["bpfo"]
    line = match(bpfo, kinematic_map(last, 2000.0), 1e-6)
    assert line.family == "gear_bpfo" and line.label == "1x BPFO (gear's bearing)"
    outer, gear_outer = EFFECTS["bearing_outer_race"], EFFECTS["gear_bearing_outer_race"]
    assert outer.values_from(last)["r_shaft"] == 1.0
    assert gear_outer.values_from(last)["r_shaft"] == pytest.approx(48 / 80)
    assert gear_outer.unknown_lines(first) and not gear_outer.unknown_lines(last)
    assert gear_outer.weight(line, bpfo, last) == 1.0 and outer.weight(line, bpfo, last) == 0.0
    # the idler turns 5/3 as fast as the output: the idler bearing's 3rd BPFO is the
    # output's 5th, named for the idler's (the pair's own), claimed by both bearings' races
    shared = match(5 * bpfo, kinematic_map(last, 2000.0), 1e-6)
    assert (shared.family, shared.order) == ("bpfo", 3) and "gear_bpfo" in shared.also
    assert gear_outer.weight(shared, 5 * bpfo, last) == outer.weight(shared, 5 * bpfo, last) == 1
    assert part_components(spur, 1, "gear bearing") == ("OS:IS", "OS:OS")
    assert gear_outer.fault == outer.fault == "outer"


def test_a_pairs_bearing_on_the_gears_shaft_strikes_at_the_gears_speed():
    """A gear pair's bearing may be on the gear's shaft: its effect's model is told the
    shaft's speed (r_shaft), as the map names its lines."""
    kin = GearKinematics(14, 21, 25.0, bearing=Bearing(9, 7.94e-3, 39.04e-3, shaft="gear"))
    assert EFFECTS["bearing_inner_race"].values_from(kin)["r_shaft"] == pytest.approx(14 / 21)


def _envelope_at(acc: np.ndarray, rate_hz: float, freqs_hz: list[float]) -> list[float]:
    """The envelope spectrum's amplitude at the bin nearest each of ``freqs_hz``."""
    env = np.abs(scipy.signal.hilbert(acc - acc.mean()))
    amp = np.abs(np.fft.rfft(env - env.mean()))
    bins = np.fft.rfftfreq(env.size, 1.0 / rate_hz)
    return [float(amp[np.argmin(np.abs(bins - f))]) for f in freqs_hz]


def test_the_strikes_come_at_the_rate_of_the_bearings_shaft(effects_dir):
    """The outer race's strikes on the pinion's shaft come at its BPFO; told the bearing
    turns with the gear (r_shaft 14/21), at the gear shaft's: the record's envelope says
    so (the strikes alone, the mesh's own response taken off), each line ten times the
    other's there."""
    fmu = effect_fmu("bearing_outer_race", ROOT / "modelica", effects_dir)
    bearing = Bearing(9, 7.94e-3, 39.04e-3)
    lines = [bearing.frequencies(25.0)["bpfo"], bearing.frequencies(25.0 * 14 / 21)["bpfo"]]
    with FmuPlant(fmu, ("acc",)) as plant:
        rate = plant.sample_rate_hz
        quiet = plant.simulate({**TABLE1[7].parameters, "A_b": 0.0}, 2.4, 0.05)[0]
        at = []
        for r_shaft in (1.0, 14 / 21):
            acc = plant.simulate({**TABLE1[7].parameters, "A_b": 60.0, "r_shaft": r_shaft},
                                 2.4, 0.05)[0]
            at.append(_envelope_at(acc - quiet, rate, lines))
    (pinion_at_own, pinion_at_gears), (gear_at_pinions, gear_at_own) = at
    assert pinion_at_own > 10 * pinion_at_gears and gear_at_own > 10 * gear_at_pinions, at
