"""One simulated period stands for the record only when the model is periodic."""

import numpy as np
import pytest

from pydiag.fmu.periodic import PERIODIC_TOLERANCE, simulate_periodic

RATE_HZ, PERIOD_S = 1000.0, 0.1


class Plant:
    """A plant whose output is ``signal(t)``; it records the durations it was asked for.
    Like fmpy's, it has no states to check: two periods when asked for periods, unless
    ``states_return`` (the native engine's check passed: one)."""

    sample_rate_hz = RATE_HZ

    def __init__(self, signal, states_return: bool = False):
        self.signal = signal
        self.durations = []
        self.states_return = states_return

    def simulate_periods(self, values, period_samples, start_s, state_tolerance, oversample=1,
                         total=None):
        assert oversample == 1
        periods = 1 if self.states_return else 2
        return self.simulate(values, periods * period_samples / RATE_HZ, start_s)

    def simulate(self, values, duration_s, start_s=0.0):
        self.durations.append(duration_s)
        n = int(round(duration_s * RATE_HZ))
        t = start_s + np.arange(n) / RATE_HZ
        return np.vstack([self.signal(t), 2 * self.signal(t)])


def test_a_periodic_model_is_simulated_over_two_periods_and_repeated():
    plant = Plant(lambda t: np.sin(2 * np.pi * 30 * t) + 0.3 * np.cos(2 * np.pi * 10 * t))
    whole = Plant(plant.signal).simulate({}, 3.3, 0.05)
    y = simulate_periodic(plant, {}, 3.3, 0.05, PERIOD_S)
    assert plant.durations == [pytest.approx(2 * PERIOD_S)]
    assert y.shape == whole.shape
    np.testing.assert_allclose(y, whole, atol=1e-9)


def test_a_model_whose_states_return_after_one_period_is_simulated_over_one():
    plant = Plant(lambda t: np.sin(2 * np.pi * 30 * t) + 0.3 * np.cos(2 * np.pi * 10 * t),
                  states_return=True)
    whole = Plant(plant.signal).simulate({}, 3.3, 0.05)
    y = simulate_periodic(plant, {}, 3.3, 0.05, PERIOD_S)
    assert plant.durations == [pytest.approx(PERIOD_S)]
    np.testing.assert_allclose(y, whole, atol=1e-9)


@pytest.mark.parametrize("signal", [
    lambda t: np.sin(2 * np.pi * 30 * t) + 0.1 * np.sin(2 * np.pi * 7.3 * t),  # a ripple of its own
    lambda t: np.sin(2 * np.pi * 30 * t) + np.exp(-t / 0.05),  # a transient still decaying
    lambda t: np.sin(2 * np.pi * 5 * t),  # half the period: a subharmonic
])
def test_anything_not_periodic_is_simulated_whole(signal):
    plant = Plant(signal)
    y = simulate_periodic(plant, {}, 3.3, 0.05, PERIOD_S)
    assert plant.durations[-1] == 3.3
    np.testing.assert_array_equal(y, Plant(signal).simulate({}, 3.3, 0.05))


def test_a_component_below_the_tolerance_is_dropped_and_one_above_kept():
    def plant_with(level):
        return Plant(lambda t: np.sin(2 * np.pi * 30 * t) + level * np.sin(2 * np.pi * 7.3 * t))
    small, large = plant_with(0.2 * PERIODIC_TOLERANCE), plant_with(5 * PERIODIC_TOLERANCE)
    simulate_periodic(small, {}, 3.3, 0.05, PERIOD_S)
    simulate_periodic(large, {}, 3.3, 0.05, PERIOD_S)
    assert len(small.durations) == 1 and len(large.durations) == 2


def test_no_period_or_a_period_off_the_sample_grid_or_a_short_record_is_simulated_whole():
    for period_s, duration_s in ((None, 3.3), (0.10005, 3.3), (PERIOD_S, 0.25)):
        plant = Plant(lambda t: np.sin(2 * np.pi * 30 * t))
        simulate_periodic(plant, {}, duration_s, 0.0, period_s)
        assert plant.durations == [duration_s]
