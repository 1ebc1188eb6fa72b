"""The swing of a tacho's angle once a turn of a slower shaft (pydiag.signal.angle)."""

import math

import numpy as np
import pytest

from pydiag.signal.angle import swing_noise, tacho_revolutions, turn_swing

FS, INPUT_HZ, PULSES = 20_000.0, 25.0, 10


def once_a_turn(revs: np.ndarray, ratio: float) -> float:
    """The swing once a turn of the slower shaft (turn_swing's first order)."""
    return float(turn_swing(revs, ratio, [1.0])[0])


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
    assert once_a_turn(revs, 1 / 3) == pytest.approx(0.002, rel=0.01)
    # neither another shaft's speed nor the wheel's errors at the input's orders
    assert once_a_turn(revs, 0.2) < 0.02 * 0.002


def test_a_steady_drive_with_slip_and_an_uneven_wheel_has_no_swing():
    revs = tacho_angle(0.0)
    assert once_a_turn(revs, 1 / 3) < 0.02 * 0.002


def test_too_few_turns_of_the_slower_shaft_give_nan_and_a_ratio_not_below_one_is_refused():
    revs = tacho_angle(0.002, duration_s=0.2)  # 5 input turns: 1.7 of the slower shaft
    assert math.isnan(once_a_turn(revs, 1 / 3))
    with pytest.raises(ValueError):
        once_a_turn(revs, 1.0)


def test_the_swings_noise_is_the_speeds_wander_beside_the_line_and_no_shafts_line():
    """An angle wandering as white noise of 1e-4 turns a sample: the swing read beside the
    slower shaft's 2x is what that noise gives a Hann-weighted line (2 sigma sqrt(sum w^2)
    / sum w), and another shaft's strong line among the rates is left out."""
    rng = np.random.default_rng(3)
    t = np.arange(int(FS * 8.0)) / FS
    sigma = 1e-4
    revs = INPUT_HZ * t + sigma * rng.standard_normal(t.size)
    n = int(np.floor(revs[-1] / 3))  # the slower shaft's whole turns (a third of the input)
    weight = np.hanning(3 * n * int(FS / INPUT_HZ))
    expected = 2 * sigma * np.sqrt(np.sum(weight ** 2)) / np.sum(weight)
    assert swing_noise(revs, 1 / 3, 2.0, [1.0, 2.0, 3.0]) == pytest.approx(expected, rel=0.3)
    # a line 0.3 order away, 30 dB over that noise (a faster shaft's, as the input's 1x is
    # at an idler's 3x)
    size = 30 * expected
    line = revs + size * np.sin(2 * np.pi * (1 / 3) * 2.3 * revs)
    assert turn_swing(line, 1 / 3, [2.3])[0] == pytest.approx(size, rel=0.1)
    assert swing_noise(line, 1 / 3, 2.0, [2.3]) == pytest.approx(expected, rel=0.3)
    assert swing_noise(line, 1 / 3, 2.0, []) > 2 * swing_noise(line, 1 / 3, 2.0, [2.3])
