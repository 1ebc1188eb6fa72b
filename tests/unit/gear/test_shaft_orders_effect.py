"""The pinion shaft's orders: which lines they claim and which amplitudes are fitted."""

from pydiag.gear.effects import EFFECTS
from pydiag.gear.kinematic_map import SHAFT_ORDERS
from pydiag.gear.kinematic_map import kinematic_map, match
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.peaks import Peak

SHAFT = EFFECTS["pinion_shaft_orders"]


def weights(kin: GearKinematics) -> dict[int, float]:
    """The effect's weight at each pinion order it claims (1: its own line, 0.5: the gear's
    shaft turns at it too)."""
    lines = kinematic_map(kin, 2000.0)
    out = {k: SHAFT.weight(match(k * kin.f_pinion_hz, lines, 0.1), k * kin.f_pinion_hz, kin)
           for k in range(1, 40)}
    return {k: w for k, w in out.items() if w > 0}


def test_it_claims_its_own_orders_and_shared_ones_only_where_it_has_none_of_its_own():
    # 32/80 teeth: even pinion orders are gear orders (2x pinion = 5x gear); the odd ones
    # are its own, the evidence of its vibration, and a shared one is left to neither
    assert weights(GearKinematics(32, 80, 30.0)) == {k: 1.0 for k in (1, 3, 5, 7, 9)}
    # 14/21: the same (2x pinion = 3x gear), and 8x to 10x pinion are the mesh's 6th to
    # 4th lower sidebands
    assert weights(GearKinematics(14, 21, 25.0)) == {1: 1.0, 3: 1.0, 5: 1.0, 7: 1.0}
    # 32/96 (the PHM09 box's first stage): every pinion order is a gear order, none its
    # own: each is claimed at half weight
    assert weights(GearKinematics(32, 96, 30.0)) == dict.fromkeys(range(1, SHAFT_ORDERS + 1),
                                                                  0.5)
    # 19/41: no gear order and no sideband falls on one of the first ten pinion orders
    assert weights(GearKinematics(19, 41, 25.0)) == dict.fromkeys(range(1, SHAFT_ORDERS + 1),
                                                                  1.0)


def test_the_amplitudes_of_orders_it_does_not_claim_are_not_fitted():
    for kin in (GearKinematics(14, 21, 25.0), GearKinematics(19, 41, 25.0),
                GearKinematics(32, 96, 30.0)):
        # without a spectrum every order it claims may be fitted; with one that has no
        # line, those another shaft shares are not (nothing stands out of its comb)
        assert [p.name for p in SHAFT.bounds([], 0.0, kin)] == [f"A_s{k}" for k in weights(kin)]
        fitted = [p.name for p in SHAFT.bounds([], 0.1, kin)]
        assert fitted == [f"A_s{k}" for k, w in weights(kin).items() if w == 1.0]
    assert len(SHAFT.bounds([], 0.1, None)) == SHAFT_ORDERS  # no kinematics: all of them


def peak(freq_hz: float, excess: float) -> Peak:
    return Peak("acc", freq_hz, excess, excess, 0.0, "pinion", None, "", 0.0)


def test_a_shared_order_is_fitted_where_its_line_stands_out_of_the_other_shafts_comb():
    # 14/42: pinion order k is gear order 3k. A gear's faulty tooth puts a comb on every
    # gear order; the pinion's own 1x and 2x stand out of it where a coupling adds them
    kin = GearKinematics(14, 42, 25.0)
    fg, bin_hz = kin.f_gear_hz, 0.05
    comb = [peak(j * fg, 1.0) for j in range(1, 33)]
    assert {p.name for p in SHAFT.bounds(comb, bin_hz, kin)} == set()
    coupling = [p if round(p.freq_hz / fg) not in (3, 6) else peak(p.freq_hz, 3.0)
                for p in comb]
    assert [p.name for p in SHAFT.bounds(coupling, bin_hz, kin)] == ["A_s1", "A_s2"]
    # only a little above the comb: not enough to tell it from the gear's own line
    slight = [p if round(p.freq_hz / fg) != 3 else peak(p.freq_hz, 1.5) for p in comb]
    assert SHAFT.bounds(slight, bin_hz, kin) == ()
