"""The kinematic map names every line of a gear pair and its bearing."""

import pytest

from pydiag.gear.kinematic_map import KinematicLine, coinciding, kinematic_map, match
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
