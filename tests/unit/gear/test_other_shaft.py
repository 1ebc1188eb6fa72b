"""Another shaft of the machine: its orders in the kinematic map, which the effect claims
and fits, and what a line no shaft explains is said to be."""

import pytest

from pydiag.core.errors import UsageError
from pydiag.gear.effects import EFFECTS
from pydiag.gear.kinematic_map import SHAFT_ORDERS, kinematic_map, match
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.peaks import Peak
from pydiag.loop.residual import describe_non_kinematic

OTHER = EFFECTS["other_shaft_orders"]
MOTOR = 29 / 17  # a motor shaft whose 17 teeth drive 29 on the pinion's shaft


def peaks_at(kin, orders):
    """Unexplained peaks of the residual at the other shaft's ``orders``, as compare names them."""
    f = kin.f_other_shaft_hz
    return [Peak("acc", k * f, 1.0, 1.0, 0.0, "other_shaft", k, f"{k}x other shaft", 0.1)
            for k in orders]


def fitted(kin, orders, bin_hz=0.4):
    return [p.name for p in OTHER.bounds(peaks_at(kin, orders), bin_hz, kin)]


def test_the_other_shafts_first_orders_are_kinematic_lines_when_its_ratio_is_given():
    kin = GearKinematics(14, 21, 25.0, other_shaft_ratio=MOTOR)
    lines = [ln for ln in kinematic_map(kin, 2000.0) if ln.family == "other_shaft"]
    assert [ln.order for ln in lines] == list(range(1, SHAFT_ORDERS + 1))
    assert lines[1].freq_hz == pytest.approx(2 * 25.0 * MOTOR)
    assert lines[1].label == "2x other shaft"
    assert match(2 * 25.0 * MOTOR, kinematic_map(kin, 2000.0), 0.2).family == "other_shaft"
    # without the ratio the same frequency is no line of the machine
    assert match(2 * 25.0 * MOTOR, kinematic_map(GearKinematics(14, 21, 25.0), 2000.0), 0.2) is None


def test_it_claims_and_fits_the_orders_no_line_of_the_pair_falls_on():
    kin = GearKinematics(14, 21, 25.0, other_shaft_ratio=MOTOR)
    lines = kinematic_map(kin, 2000.0)
    claimed = [ln.order for ln in lines if OTHER.weight(ln, ln.freq_hz, kin) > 0]
    assert claimed == list(range(1, SHAFT_ORDERS + 1))
    # only the orders the residual has a peak at are fitted (the others, not synchronous
    # with the pair, would take noise peaks of a half by their leakage)
    assert fitted(kin, claimed) == [f"A_o{k}" for k in claimed]
    assert fitted(kin, [1, 2, 3]) == ["A_o1", "A_o2", "A_o3"]
    assert fitted(kin, []) == []
    # at 1.5 x the pinion's speed its even orders are pinion orders (2x = 3x pinion): which
    # shaft makes those lines the record does not say, so they are neither claimed nor fitted
    half = GearKinematics(14, 21, 25.0, other_shaft_ratio=1.5)
    lines = kinematic_map(half, 2000.0)
    claimed = [ln.order for ln in lines if OTHER.weight(ln, ln.freq_hz, half) > 0]
    assert claimed == [1, 3, 5, 7, 9]
    assert fitted(half, range(1, 11)) == ["A_o1", "A_o3", "A_o5", "A_o7", "A_o9"]
    # within half a bin of a pinion order is on its bin: at 1.505 x 25 Hz, its 2x is 0.25 Hz
    # off 3x pinion
    near = GearKinematics(14, 21, 25.0, other_shaft_ratio=1.505)
    assert fitted(near, [2], 0.4) == ["A_o2"]
    assert fitted(near, [2], 0.6) == []


def test_without_the_ratio_it_has_no_line_and_nothing_to_fit_and_says_what_it_needs():
    kin = GearKinematics(14, 21, 25.0)
    assert OTHER.bounds(peaks_at(GearKinematics(14, 21, 25.0, other_shaft_ratio=MOTOR),
                                 [1, 2]), 0.4, kin) == ()
    assert OTHER.unknown_lines(kin) == ("its lines are not known without the other shaft's "
                                        "speed ratio")
    assert OTHER.unknown_lines(GearKinematics(14, 21, 25.0, other_shaft_ratio=MOTOR)) == ""
    assert OTHER.values_from(GearKinematics(14, 21, 25.0, other_shaft_ratio=MOTOR)) \
        == {"r_other": MOTOR}
    assert OTHER.values_from(kin) == {}


def test_a_line_no_shaft_explains_is_described_against_the_other_shaft_too():
    kin = GearKinematics(14, 21, 25.0, other_shaft_ratio=MOTOR)
    text = describe_non_kinematic(100.0, kin, 0.4)
    assert f"{100 / (25 * MOTOR):.3g}x other shaft" in text
    assert "x other shaft" not in describe_non_kinematic(100.0, GearKinematics(14, 21, 25.0), 0.4)


@pytest.mark.parametrize("ratio", [0.0, -1.0, float("nan"), float("inf")])
def test_a_ratio_that_is_no_speed_is_refused(ratio):
    with pytest.raises(UsageError, match="speed ratio must be positive"):
        GearKinematics(14, 21, 25.0, other_shaft_ratio=ratio)
