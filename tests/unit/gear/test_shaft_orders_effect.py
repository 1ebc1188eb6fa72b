"""The pinion shaft's orders: which lines they claim and which amplitudes are fitted."""

from pydiag.gear.effects import EFFECTS, SHAFT_ORDERS
from pydiag.gear.kinematic_map import kinematic_map, match
from pydiag.gear.kinematics import GearKinematics

SHAFT = EFFECTS["pinion_shaft_orders"]


def weights(kin: GearKinematics) -> dict[int, float]:
    """The effect's weight at each pinion order it claims (1: its own line, 0.5: the gear's
    shaft turns at it too)."""
    lines = kinematic_map(kin, 2000.0)
    out = {k: SHAFT.weight(match(k * kin.f_pinion_hz, lines, 0.1), k * kin.f_pinion_hz,
                           kin.f_mesh_hz) for k in range(1, 40)}
    return {k: w for k, w in out.items() if w > 0}


def test_it_claims_its_first_orders_and_those_the_gear_shaft_shares_at_half_weight():
    # 32/80 teeth: even pinion orders are gear orders (2x pinion = 5x gear)
    assert weights(GearKinematics(32, 80, 30.0)) == {k: 1.0 if k % 2 else 0.5
                                                     for k in range(1, SHAFT_ORDERS + 1)}
    # 14/21: the same (2x pinion = 3x gear), and 8x to 10x pinion are the mesh's 6th to
    # 4th lower sidebands
    assert weights(GearKinematics(14, 21, 25.0)) == {1: 1.0, 2: 0.5, 3: 1.0, 4: 0.5, 5: 1.0,
                                                     6: 0.5, 7: 1.0}
    # 32/96 (the PHM09 box's first stage): every pinion order is a gear order, none its own
    assert weights(GearKinematics(32, 96, 30.0)) == dict.fromkeys(range(1, SHAFT_ORDERS + 1),
                                                                  0.5)
    # 19/41: no gear order and no sideband falls on one of the first ten pinion orders
    assert weights(GearKinematics(19, 41, 25.0)) == dict.fromkeys(range(1, SHAFT_ORDERS + 1),
                                                                  1.0)


def test_the_amplitudes_of_orders_it_does_not_claim_are_not_fitted():
    for kin in (GearKinematics(14, 21, 25.0), GearKinematics(19, 41, 25.0)):
        fitted = [p.name for p in SHAFT.bounds([], 0.1, kin)]
        assert fitted == [f"A_s{k}" for k in weights(kin)]
    assert len(SHAFT.bounds([], 0.1, None)) == SHAFT_ORDERS  # no kinematics: all of them
