"""The pinion shaft's orders: which lines they claim and which amplitudes are fitted."""

from pydiag.gear.effects import EFFECTS, SHAFT_ORDERS
from pydiag.gear.kinematic_map import kinematic_map, match
from pydiag.gear.kinematics import GearKinematics

SHAFT = EFFECTS["pinion_shaft_orders"]


def claimed_orders(kin: GearKinematics) -> list[int]:
    lines = kinematic_map(kin, 2000.0)
    return [k for k in range(1, 40)
            if SHAFT.weight(match(k * kin.f_pinion_hz, lines, 0.1), k * kin.f_pinion_hz,
                            kin.f_mesh_hz) > 0]


def test_it_claims_the_first_orders_the_gear_shaft_has_no_line_at():
    # 32/80 teeth: even pinion orders are gear orders (2x pinion = 5x gear)
    assert claimed_orders(GearKinematics(32, 80, 30.0)) == [1, 3, 5, 7, 9]
    # 14/21: the same (2x pinion = 3x gear), and 9x pinion is the mesh's 5th lower sideband
    assert claimed_orders(GearKinematics(14, 21, 25.0)) == [1, 3, 5, 7]
    # 19/41: no gear order and no sideband falls on one of the first ten pinion orders
    assert claimed_orders(GearKinematics(19, 41, 25.0)) == list(range(1, SHAFT_ORDERS + 1))


def test_the_amplitudes_of_orders_it_does_not_claim_are_not_fitted():
    for kin in (GearKinematics(14, 21, 25.0), GearKinematics(19, 41, 25.0)):
        fitted = [p.name for p in SHAFT.bounds([], 0.1, kin)]
        assert fitted == [f"A_s{k}" for k in claimed_orders(kin)]
    assert len(SHAFT.bounds([], 0.1, None)) == SHAFT_ORDERS  # no kinematics: all of them
