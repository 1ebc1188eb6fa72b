"""The kinematic map names every line of a gear pair and its bearing."""

import random

import numpy as np
import pytest

from pydiag.gear.kinematic_map import (KinematicLine, coinciding, kinematic_map, match,
                                       match_each)
from pydiag.gear.kinematics import Bearing, GearKinematics

BASE = dict(a_f=0.3, f_f=0.6, f_ate=0.1, f_dte=0.1)
BEARING = Bearing(9, 7.94e-3, 39.04e-3)
HIDDEN = {"bearing_outer_race": "BearingOuterRace", "gear_eccentricity": "GearEccentricity",
          "load_fluctuation": "LoadFluctuation"}
FAST = dict(n_particles=10, iterations=8, polish_evaluations=100, polish_starts=2)


def test_kinematic_map_names_the_lines():
    kin = GearKinematics(14, 21, 25.0, bearing=BEARING)
    lines = kinematic_map(kin, 1000.0)
    assert match(350.0, lines, 0.5).label == "1x mesh"  # mesh wins over 14x pinion
    assert match(375.0, lines, 0.5).family == "mesh_sb_pinion"
    assert match(350 - 350 / 21, lines, 0.5).label == "1x mesh - 1x gear"
    assert match(25.0, lines, 0.5).label == "1x pinion"
    bpfo = BEARING.frequencies(25.0)["bpfo"]
    assert bpfo == pytest.approx(4.5 * 25 * (1 - 7.94 / 39.04))
    assert match(bpfo, lines, 0.5).family == "bpfo"
    assert match(7.3, lines, 0.5) is None
    # 2x pinion is 3x gear (50 Hz): named for the pinion, the gear's line told it is there
    assert match(50.0, lines, 0.5).label == "2x pinion" and "gear" in match(50.0, lines, 0.5).also
    assert "gear" not in match(75.0, lines, 0.5).also  # 3x pinion is 4.5x gear: no gear line
    assert "pinion" in match(350.0, lines, 0.5).also  # the mesh is a pinion and a gear order
    freqs = BEARING.frequencies(25.0)
    assert freqs["ftf"] < 25 < freqs["bpfo"] < freqs["bpfi"]


def test_each_bin_of_a_spectrum_is_matched_as_one_frequency_is():
    """match_each answers what match does for every frequency, ties too: on lines in no
    order (a map joined from stages), at bins on the lines, beside them and between."""
    lines = kinematic_map(GearKinematics(14, 21, 25.0, bearing=BEARING), 2000.0)
    random.Random(1).shuffle(lines)
    on = np.array([ln.freq_hz for ln in lines])
    freqs = np.concatenate([np.random.default_rng(1).uniform(0, 2000, 2000), on, on + 0.25])
    for tolerance_hz in (0.05, 0.25, 0.5, 2.0):
        each = match_each(freqs, lines, tolerance_hz)
        assert each == [match(f, lines, tolerance_hz) for f in freqs]
        assert sum(m is not None for m in each) > len(lines)
    tie = [KinematicLine(101.0, "pinion", 5, "5x pinion"), KinematicLine(100.0, "pinion", 4, "4x pinion")]
    assert match_each([100.5], tie, 1.0) == [match(100.5, tie, 1.0)] == [tie[0]]


def test_lines_within_the_tolerance_are_told_of_each_other():
    """In a spectrum of joined halves (10 periods of 0.12 s: 0.83 Hz bins) 2x BPFO of a
    6205 on a 25 Hz shaft shows at 175.15 Hz: on the bin of 7x pinion."""
    pinion, bpfo = KinematicLine(175.0, "pinion", 7, "7x pinion"), \
        KinematicLine(175.15, "bpfo", 2, "2x BPFO")
    far = KinematicLine(176.0, "gear", 10, "10x gear")
    told = coinciding([far, bpfo, pinion], 0.5 / 1.2)
    assert [ln.label for ln in told] == ["7x pinion", "2x BPFO", "10x gear"]  # sorted
    assert told[0].also == ("bpfo",) and told[1].also == ("pinion",) and told[2].also == ()
    assert coinciding([pinion, bpfo])[0].also == ()  # exactly the same frequency only


def test_a_stage_of_a_gearbox_names_every_other_stage_shaft_and_bearing():
    """A machine's stage (PHM09's 32/96 then 48/80, a third stage and a bearing added):
    the other stages' mesh harmonics, their sidebands at their own shafts, their assembly
    and hunting lines, the other shafts' orders and their bearings are kinematic lines of
    their own families, which no effect of the pair claims."""
    from pydiag.gear.machine_file import machine_from_dict
    machine = machine_from_dict({
        "name": "box", "shafts": ["input", "idler", "output", "drum"],
        "stages": [{"pinion_teeth": 32, "gear_teeth": 96, "name": "first"},
                   {"pinion_teeth": 48, "gear_teeth": 80, "name": "second"},
                   {"pinion_teeth": 19, "gear_teeth": 47, "name": "third"}],
        "bearings": [{"shaft": "output", "n_balls": 9, "ball_diameter_mm": 7.94,
                      "pitch_diameter_mm": 39.04}]})
    kin = machine.stage_kinematics(0, 30.0)
    assert (kin.n_pinion, kin.n_gear, kin.f_pinion_hz) == (32, 96, 30.0)
    assert kin.other_shaft_ratio == pytest.approx(0.2)  # the output, next to the idler
    lines = kinematic_map(kin, 2000.0)
    tol = 1e-6

    def named(f):
        return match(f, lines, tol)

    second_mesh, idler, output = 16 * 30.0, 10.0, 6.0
    assert named(second_mesh).label == "1x second mesh"  # not the pair's 16x pinion
    assert "pinion" in named(second_mesh).also
    assert named(2 * second_mesh).label == "1x mesh"  # this box's 2x second mesh
    assert "stage_mesh" in named(2 * second_mesh).also
    assert named(3 * second_mesh).label == "3x second mesh"
    assert named(second_mesh + idler).label == "1x second mesh + 1x idler"  # not 49x gear
    assert named(second_mesh - 2 * output).family == "stage_mesh_sb"
    assembly = [ln for ln in lines if ln.family == "stage_assembly"]  # 5 phases: 96 Hz
    assert any(ln.label == "1x second assembly phase" and ln.freq_hz == pytest.approx(96.0)
               for ln in assembly)
    assert "stage_assembly" in named(96.0).also  # and the third mesh's sideband there
    drum = output * 19 / 47
    third_mesh = 19 * output
    assert named(third_mesh).label == "1x third mesh"
    assert named(third_mesh + drum).label == "1x third mesh + 1x drum"
    assert named(output).family == "other_shaft" and named(output).label == "1x other shaft"
    assert named(3 * drum).label == "3x drum" and named(3 * drum).family == "machine_shaft"
    bpfo = BEARING.frequencies(output)["bpfo"]
    assert named(bpfo).family == "machine_bearing" and "output" in named(bpfo).label
    assert named(30.0 * 33).family == "mesh_sb_pinion"  # the pair's own lines stay its own
    pair = kinematic_map(kin.pair, 2000.0)
    assert match(second_mesh, pair, tol).family == "pinion"
    assert not {ln.family for ln in pair} & {"stage_mesh", "stage_mesh_sb", "stage_assembly",
                                              "machine_shaft", "machine_bearing"}
    # the middle stage's other shaft is downstream, the last stage's upstream of its pinion
    assert machine.stage_kinematics(1, 30.0).other_shaft_ratio == pytest.approx(0.6 * 19 / 47)
    last = machine.stage_kinematics(2, 30.0)
    assert last.other_shaft_ratio == pytest.approx(10 / 6)
    assert last.bearing.n_balls == 9 and last.surroundings.bearings == ()  # on its pinion shaft
