"""The native engine's periodicity check: a model whose response repeats after one period
of its forcing (every state back at its start, the derivatives and outputs the same a
period later) is simulated over that period alone; one that does not (a transient left,
a period that is not the forcing's, a strike of another period) over two; one whose
states repeat and whose outputs do not (a strike added at the sensor) is integrated over
one period and its later outputs read from that period's states."""

import numpy as np
import pytest
from conftest import ROOT

from pydiag.fmu.periodic import PERIODIC_TOLERANCE, STATE_TOLERANCE, simulate_periodic
from pydiag.fmu.plant import FmuPlant
from pydiag.gear.paper_cases import TABLE1
from pydiag.loop.discover import effect_fmu

SENSORS = ("acc", "disp")
PERIOD_S = 0.12  # GearPair's 14/21 teeth at 25 Hz: 3 pinion turns, 2 gear turns


@pytest.mark.parametrize("case", [TABLE1[0], TABLE1[7]], ids=lambda c: f"case{c.number}")
def test_a_settled_gear_pair_is_simulated_over_one_period_that_each_later_one_repeats(
        gear_fmu, case):
    with FmuPlant(gear_fmu, SENSORS) as plant:
        n = int(round(PERIOD_S * plant.sample_rate_hz))
        one = plant.simulate_periods(case.parameters, n, 0.05, STATE_TOLERANCE)
        whole = plant.simulate(case.parameters, 3 * PERIOD_S, 0.05)
    assert one.shape == (len(SENSORS), n)
    peak = np.max(np.abs(whole), axis=1, keepdims=True)
    for k in range(3):
        assert np.all(np.abs(whole[:, k * n:(k + 1) * n] - one) <= PERIODIC_TOLERANCE * peak)


@pytest.mark.parametrize("warmup_s, period_s", [(0.0, PERIOD_S), (0.05, PERIOD_S / 3)],
                         ids=["start-up transient", "not the forcing's period"])
def test_a_response_that_does_not_repeat_is_simulated_over_two_periods(gear_fmu, warmup_s,
                                                                       period_s):
    with FmuPlant(gear_fmu, SENSORS) as plant:
        n = int(round(period_s * plant.sample_rate_hz))
        y = plant.simulate_periods(TABLE1[7].parameters, n, warmup_s, STATE_TOLERANCE)
        assert y.shape == (len(SENSORS), 2 * n)
        np.testing.assert_array_equal(y, plant.simulate(TABLE1[7].parameters,
                                                        2 * n / plant.sample_rate_hz, warmup_s))


def test_fmpy_gives_no_states_and_always_two_periods(gear_fmu):
    with FmuPlant(gear_fmu, SENSORS, engine="fmpy") as plant:
        n = int(round(PERIOD_S * plant.sample_rate_hz))
        assert plant.simulate_periods(TABLE1[0].parameters, n, 0.05,
                                      STATE_TOLERANCE).shape == (len(SENSORS), 2 * n)


@pytest.mark.parametrize("strike_m_s2, periods", [(0.0, 1), (1.0, 2)])
def test_a_strike_of_another_period_is_caught_though_the_states_return(effects_dir,
                                                                       strike_m_s2, periods):
    """The outer race's strikes come at the bearing's own rate and ring out between two
    of them: at the period's end the states may be back, but the outputs one period later
    at the same state are not the same, so two periods are simulated (one without them)."""
    fmu = effect_fmu("bearing_outer_race", ROOT / "modelica", effects_dir)
    with FmuPlant(fmu, SENSORS) as plant:
        n = int(round(PERIOD_S * plant.sample_rate_hz))
        y = plant.simulate_periods({**TABLE1[7].parameters, "A_b": strike_m_s2}, n, 0.05,
                                   STATE_TOLERANCE)
    assert y.shape == (len(SENSORS), periods * n)


#: A record read from one period's states against the same record integrated: they differ
#: by the integrator's error (measured 7.0e-5 to 7.8e-5 of the peak on the three bearing
#: effects at rtol 1e-6), far below a strike's lines (the strike is 60 m/s2).
READ_AGREEMENT = 5e-4


@pytest.mark.parametrize("effect", ["bearing_outer_race", "bearing_ball"])
def test_a_strike_added_at_the_sensor_is_read_from_one_periods_states(effects_dir, effect):
    """A bearing's strikes are added at the sensor at the bearing's own rate; the mesh's
    dynamics do not see them, so its states and derivatives repeat after one period while
    its outputs do not. The record is then integrated over about one period, and every
    later sample read at its own time from the state whole periods earlier: the same
    record as integrating it all, at a fraction of the right-hand sides; the strikes are
    there (the record is not one period tiled)."""
    fmu = effect_fmu(effect, ROOT / "modelica", effects_dir)
    values = {**TABLE1[7].parameters, "A_b": 60.0}
    with FmuPlant(fmu, SENSORS) as plant:
        n = int(round(PERIOD_S * plant.sample_rate_hz))
        whole = plant.simulate(values, 20 * PERIOD_S, 0.05)
        integrated = plant._native.n_rhs
        read = simulate_periodic(plant, values, 20 * PERIOD_S, 0.05, PERIOD_S)
        assert plant._native.n_rhs - integrated < 0.25 * integrated
    peak = np.max(np.abs(whole), axis=1, keepdims=True)
    assert read.shape == whole.shape
    assert np.all(np.abs(read - whole) <= READ_AGREEMENT * peak)
    acc = SENSORS.index("acc")
    assert np.max(np.abs(read[acc, n:2 * n] - read[acc, :n])) > 0.1 * peak[acc, 0]


def test_a_response_whose_states_do_not_repeat_stops_after_two_periods_with_a_total(gear_fmu):
    """A start-up transient left in the states: asked for a record of four periods, the run
    stops after two (the caller compares them), the same two periods as a run of two but
    for its last samples, which a step not cut at their end interpolates (measured: the last
    one by 1.7e-6 of the peak, the engine's tolerance 1e-6)."""
    with FmuPlant(gear_fmu, SENSORS) as plant:
        n = int(round(PERIOD_S * plant.sample_rate_hz))
        values = TABLE1[7].parameters
        y = plant.simulate_periods(values, n, 0.0, STATE_TOLERANCE, total=4 * n)
        two = plant.simulate_periods(values, n, 0.0, STATE_TOLERANCE)
    assert y.shape == two.shape == (len(SENSORS), 2 * n)
    peak = np.max(np.abs(two), axis=1, keepdims=True)
    assert np.all(np.abs(y - two) <= 1e-5 * peak)
    assert np.array_equal(y[:, :n], two[:, :n])
