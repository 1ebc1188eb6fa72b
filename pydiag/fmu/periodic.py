"""A periodic model simulated over one period (or two) and repeated: a gear model driven
only by inputs synchronous with its fundamental period settles to a response of that
period."""

from __future__ import annotations

import numpy as np

from pydiag.fmu.plant import FmuPlant

#: Two consecutive simulated fundamental periods that differ by no more than this share of
#: the channel's peak make the model periodic (:func:`simulate_periodic`). Measured on
#: GearPair and the effect models at rest: 2e-5 to 4e-5 (the integrator's tolerance); a
#: component that is not periodic and stays below this lies 60 dB under the peak.
PERIODIC_TOLERANCE = 1e-3

#: Every state back at its start after one period, and the derivatives and outputs the
#: same at the same state a period later, each to within this share of its range over the
#: period (and ten times the integrator's error), make the model periodic without a
#: second period (:func:`simulate_periodic`). Measured on GearPair at rest and with
#: faults: misses of 4e-10 to 3e-6 of the ranges; the second period differs from the first
#: by the integrator's error, 3e-5 to 4e-4 of the peak.
STATE_TOLERANCE = 1e-4


def simulate_periodic(plant: FmuPlant, values: dict[str, float], duration_s: float,
                      warmup_s: float, period_s: float | None) -> np.ndarray:
    """``plant.simulate(values, duration_s, warmup_s)``, from one period when the model is
    periodic.

    A gear model whose inputs are all synchronous with the fundamental period settles to a
    response of that period: then, from the warm-up on, one period is simulated and
    repeated when the native engine finds that the response repeats from there
    (:meth:`~pydiag.fmu.plant.FmuPlant.simulate_periods`, :data:`STATE_TOLERANCE`); else
    two, and when they agree (:data:`PERIODIC_TOLERANCE`) the second is repeated. A record
    of 33 periods then costs 1 or 2 simulated periods instead of 33.
    Anything that is not periodic in ``period_s`` (a bearing's strikes, a ripple at a free
    frequency, a subharmonic, a transient still decaying) makes the periods differ, and
    the whole duration is simulated; where only the outputs differ (the states and
    derivatives repeat: a bearing's strikes added at the sensor), the native engine
    integrates one period and reads the later outputs from its states, in the same run
    (:meth:`~pydiag.fmu.plant.FmuPlant.simulate_periods`' ``total``).
    """
    fs = plant.sample_rate_hz
    total = int(round(duration_s * fs))
    if period_s is not None and total > 3 * period_s * fs:
        y = simulate_period(plant, values, warmup_s, period_s, total=total)
        if y is not None:
            return y if y.shape[1] == total else np.tile(y, (1, -(-total // y.shape[1])))[:, :total]
    return plant.simulate(values, duration_s, warmup_s)


def simulate_period(plant: FmuPlant, values: dict[str, float], warmup_s: float,
                    period_s: float, oversample: int = 1, total: int | None = None
                    ) -> np.ndarray | None:
    """One period of the model's response from the warm-up on, sampled at ``oversample``
    times the plant's rate (:func:`simulate_periodic`'s tests of a response that repeats),
    or None when the response does not repeat in ``period_s`` or the period is no whole
    number of samples. ``total`` (samples): where only the outputs do not repeat, the
    record of ``total`` samples read from one period's states instead
    (:meth:`~pydiag.fmu.plant.FmuPlant.simulate_periods`)."""
    per = period_s * plant.sample_rate_hz * oversample
    n = int(round(per))
    if n <= 1 or abs(per - n) > 1e-6 * per:
        return None
    y = plant.simulate_periods(values, n, warmup_s, STATE_TOLERANCE, oversample, total)
    if y.shape[1] in (n, total):
        return y
    first, last = y[:, :n], y[:, n:2 * n]
    peak = np.max(np.abs(last), axis=1)
    if np.all(np.max(np.abs(last - first), axis=1) <= PERIODIC_TOLERANCE * peak):
        return last
    return None
