"""The swing of a tacho's angle once a turn of a slower shaft (pydiag.signal.angle)."""

import math

import numpy as np
import pytest

from pydiag.signal.angle import once_a_turn_swing, tacho_revolutions

FS, INPUT_HZ, PULSES = 20_000.0, 25.0, 10


def tacho_angle(swing_rev: float, ratio: float = 1 / 3, duration_s: float = 8.0,
                wheel_rev: float = 0.002) -> np.ndarray:
    """The input's angle as a 10-pulse tacho sees it: a speed rising 0.5 % over the record,
    the angle swinging by ``swing_rev`` once a turn of a shaft at ``ratio``, and a wheel
    whose pulses sit up to ``wheel_rev`` off their places (an error at the input's
    orders)."""
    t = np.arange(int(FS * duration_s)) / FS
    speed = INPUT_HZ * (1 + 0.005 * t / duration_s)
    revs = np.cumsum(speed) / FS
    revs = revs + swing_rev * np.sin(2 * np.pi * ratio * revs + 0.7)
    wheel = wheel_rev * np.sin(2 * np.pi * revs) + 0.5 * wheel_rev * np.cos(6 * np.pi * revs)
    pulses = (np.mod(PULSES * (revs + wheel), 1.0) < 0.5).astype(float)
    return tacho_revolutions(pulses, PULSES)


def test_a_swing_once_a_slower_turn_is_measured_through_the_tachos_pulses():
    revs = tacho_angle(0.002)
    assert once_a_turn_swing(revs, 1 / 3) == pytest.approx(0.002, rel=0.01)
    # neither another shaft's speed nor the wheel's errors at the input's orders
    assert once_a_turn_swing(revs, 0.2) < 0.02 * 0.002


def test_a_steady_drive_with_slip_and_an_uneven_wheel_has_no_swing():
    revs = tacho_angle(0.0)
    assert once_a_turn_swing(revs, 1 / 3) < 0.02 * 0.002


def test_too_few_turns_of_the_slower_shaft_give_nan_and_a_ratio_not_below_one_is_refused():
    revs = tacho_angle(0.002, duration_s=0.2)  # 5 input turns: 1.7 of the slower shaft
    assert math.isnan(once_a_turn_swing(revs, 1 / 3))
    with pytest.raises(ValueError):
        once_a_turn_swing(revs, 1.0)
