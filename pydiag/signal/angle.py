"""Shaft angle from a record: tacho pulses, or the phase of a tone that turns with the shaft;
and computed order tracking (resampling at equal angle increments).

Angles are in revolutions of the shaft whose phase is tracked, as a function of the sample
index: ``revs[n]`` at time ``n / sample_rate_hz``.

scipy.interpolate and scipy.signal are imported where they are used: together they take
0.6 s of the start of every command, most of which never track an angle.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from pydiag.core.errors import MeasurementError

#: Order tracking interpolates on the record upsampled by this factor (band-limited,
#: scipy.signal.resample_poly with :func:`_interpolation_filter`), then with a 4-point
#: cubic: the amplitude error is below 0.1 % up to 0.4 of the original sample rate
#: (measured 1e-4 at 0.4, 5 % at 0.45; tests/unit/gear/test_speed.py).
UPSAMPLE = 8


def tacho_revolutions(pulses: np.ndarray, pulses_per_rev: int) -> np.ndarray:
    """Shaft revolutions at every sample from a tacho signal (one pulse train).

    Pulses are the rising crossings of the level midway between the 2nd and 98th
    percentiles, located between samples by linear interpolation; pulse k is revolution
    k/pulses_per_rev; samples between pulses by monotone cubic (PCHIP) interpolation, and
    beyond the first and last pulse by the mean speed of the two nearest revolutions.
    """
    x = np.asarray(pulses, dtype=float)
    low, high = np.percentile(x, [2, 98])
    if not high > low:
        raise MeasurementError("the tacho channel is constant: no pulses")
    level = 0.5 * (low + high)
    above = x >= level
    k = np.flatnonzero(~above[:-1] & above[1:])  # x[k] < level <= x[k+1]
    if k.size < 2 * pulses_per_rev + 1:
        raise MeasurementError(f"the tacho channel has {k.size} pulses: need at least two "
                               f"revolutions ({2 * pulses_per_rev + 1} pulses)")
    times = k + (level - x[k]) / (x[k + 1] - x[k])  # in samples
    gaps = np.diff(times)
    if pulses_per_rev == 1 and np.max(gaps) > 1.5 * np.median(gaps):
        worst = float(np.max(gaps) / np.median(gaps))
        raise MeasurementError(f"the tacho misses pulses (a gap of {worst:.2f} pulse "
                               "intervals); check the channel and --pulses-per-rev")
    revs = np.arange(times.size) / pulses_per_rev
    from scipy.interpolate import PchipInterpolator

    n = np.arange(x.size, dtype=float)
    out = PchipInterpolator(times, revs, extrapolate=False)(n)
    edge = max(pulses_per_rev, 1)
    head = (revs[edge] - revs[0]) / (times[edge] - times[0])
    tail = (revs[-1] - revs[-1 - edge]) / (times[-1] - times[-1 - edge])
    before, after = n < times[0], n > times[-1]
    out[before] = revs[0] + (n[before] - times[0]) * head
    out[after] = revs[-1] + (n[after] - times[-1]) * tail
    return out


#: tone_phase leaves out this many 1/bandwidth at each end, where its filter wraps.
EDGE_BANDWIDTHS = 1.5


def tone_phase(signal: np.ndarray, sample_rate_hz: float, carrier_hz: float,
               bandwidth_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Phase (cycles) of the tone near ``carrier_hz`` by complex demodulation.

    The band ``carrier_hz +- bandwidth_hz`` is cut from the record's FFT with a Tukey
    taper, shifted to zero and transformed back at a reduced rate. Returns
    ``(sample_index, cycles)`` on that reduced grid; the first and last 1.5/bandwidth
    seconds, where the circular filter wraps, are left out.
    """
    x = np.asarray(signal, dtype=float)
    n = x.size
    spectrum = np.fft.rfft(x - x.mean())
    k0 = int(round(carrier_hz * n / sample_rate_hz))
    half = max(int(np.ceil(bandwidth_hz * n / sample_rate_hz)), 2)
    if k0 - half < 1 or k0 + half >= spectrum.size:
        raise MeasurementError(f"the band {carrier_hz:.1f} +- {bandwidth_hz:.1f} Hz does not fit "
                               f"the record's spectrum (0 - {sample_rate_hz / 2:.1f} Hz)")
    j = np.arange(-half, half + 1)
    taper = 0.5 * (1 + np.cos(np.pi * np.clip((np.abs(j) - 0.5 * half) / (0.5 * half), 0, 1)))
    length = 1 << int(np.ceil(np.log2(8 * half + 8)))
    baseband = np.zeros(length, dtype=complex)
    baseband[j % length] = spectrum[k0 + j] * taper
    z = np.fft.ifft(baseband)
    index = np.arange(length) * (n / length)
    cycles = np.unwrap(np.angle(z)) / (2 * np.pi) + k0 * np.arange(length) / length
    margin = EDGE_BANDWIDTHS / bandwidth_hz * sample_rate_hz
    keep = (index >= margin) & (index <= n - 1 - margin)
    if np.count_nonzero(keep) < 4:
        raise MeasurementError(f"record of {n / sample_rate_hz:.3g} s is too short to follow the "
                               f"phase of a {carrier_hz:.1f} Hz line within +-{bandwidth_hz:.2g} Hz")
    return index[keep], cycles[keep]


def extend_linearly(index: np.ndarray, values: np.ndarray, n_samples: int) -> np.ndarray:
    """``values`` known at ``index`` (increasing), at every sample 0..n_samples-1: cubic
    (PCHIP) inside, straight lines with the end slopes of a least-squares fit outside."""
    from scipy.interpolate import PchipInterpolator

    n = np.arange(n_samples, dtype=float)
    out = PchipInterpolator(index, values, extrapolate=False)(n)
    slope = np.polyfit(index, values, 1)[0]
    before, after = n < index[0], n > index[-1]
    out[before] = values[0] + (n[before] - index[0]) * slope
    out[after] = values[-1] + (n[after] - index[-1]) * slope
    return out


#: A swing's deviation in noise is read at up to this many rates either side of its
#: line, within half an order of it (farther, a slow drift of the speed is read) ...
SWING_NOISE_RATES = 8
#: ... spaced this many steps of the record's resolution (one over its whole turns of the
#: slower shaft) apart: the Hann window's main lobe spans two either side, so rates three
#: apart read nearly independent noise ...
SWING_NOISE_SPACING = 3
#: ... leaving out those within this many steps of a line of any shaft (its main lobe).
SWING_NOISE_GUARD = 2.5


def turn_swing(revs: np.ndarray, ratio: float, rates) -> np.ndarray:
    """How far an angle swings at each of ``rates`` (multiples of a slower shaft's turning
    rate; 1: once its turn): the amplitude, in revolutions of the tracked shaft, of its
    deviation from uniform rotation demodulated along the slower shaft's angle (``ratio``
    times ``revs``, 0 < ratio < 1) over that shaft's whole turns; nan where ``revs`` holds
    fewer than two of them.

    A runout or an eccentric gear on the slower shaft is a transmission error once its
    turn, which swings the whole drive: a tacho on a faster shaft measures it. The
    tracked shaft's own orders (a tacho wheel's unevenly spaced pulses) are none of the
    slower shaft's. The deviation is from the straight line fitted over those turns, and
    weighted by a Hann window across them, so that the speed's drift (a motor's slip) and
    other shafts' swings leak little into the line read."""
    if not 0 < ratio < 1:
        raise ValueError(f"the slower shaft turns 0 to 1 times a turn, got {ratio}")
    rates = np.atleast_1d(np.asarray(rates, dtype=float))
    revs = np.asarray(revs, dtype=float)
    turn = ratio * revs
    if whole_turns(revs, ratio) < 2:
        return np.full(rates.shape, math.nan)
    span = np.flatnonzero((turn >= np.ceil(turn[0])) & (turn < np.floor(turn[-1])))
    n = span.astype(float)
    deviation = revs[span] - np.polyval(np.polyfit(n, revs[span], 1), n)
    weight = np.hanning(span.size)
    phase = np.exp(-2j * np.pi * np.outer(rates, turn[span]))
    return 2 * np.abs(phase @ (weight * deviation)) / np.sum(weight)


def whole_turns(revs: np.ndarray, ratio: float) -> int:
    """The whole turns of the slower shaft (``ratio`` turns a turn of the tracked one) that
    ``revs`` holds: what a swing is read over."""
    turn = ratio * np.asarray(revs, dtype=float)
    return int(np.floor(turn[-1]) - np.ceil(turn[0])) if turn.size else 0


def swing_noise(revs: np.ndarray, ratio: float, rate: float, lines) -> float:
    """How much noise moves :func:`turn_swing` at ``rate``: the RMS of the swing at up to
    :data:`SWING_NOISE_RATES` rates either side of it within half an order,
    :data:`SWING_NOISE_SPACING` steps of the record's resolution apart, none within
    :data:`SWING_NOISE_GUARD` steps of any of ``lines`` (every shaft's orders, in turns of
    the slower shaft: a line is no noise); revolutions of the tracked shaft, nan when no
    rate is left or the record is too short. It is the speed's own wander near the line (a
    motor's control, a load's), read in the record itself."""
    step = 1.0 / max(whole_turns(revs, ratio), 1)
    lines = np.asarray(lines, dtype=float)
    rates = [rate + j * SWING_NOISE_SPACING * step
             for j in range(-SWING_NOISE_RATES, SWING_NOISE_RATES + 1) if j]
    rates = [r for r in rates if abs(r - rate) < 0.5 and (
        lines.size == 0 or np.min(np.abs(lines - r)) > SWING_NOISE_GUARD * step)]
    if not rates:
        return math.nan
    return float(np.sqrt(np.mean(np.square(turn_swing(revs, ratio, rates)))))


def _cubic_at(y: np.ndarray, position: np.ndarray) -> np.ndarray:
    """``y`` at fractional indices by 4-point cubic (Lagrange) interpolation."""
    i = np.clip(np.floor(position).astype(np.int64), 1, y.size - 3)
    f = position - i
    ym1, y0, y1, y2 = y[i - 1], y[i], y[i + 1], y[i + 2]
    return (y0 + f * (0.5 * (y1 - ym1) + f * (ym1 - 2.5 * y0 + 2 * y1 - 0.5 * y2
                                              + f * (1.5 * (y0 - y1) + 0.5 * (y2 - ym1)))))


@lru_cache(maxsize=1)
def _interpolation_filter() -> np.ndarray:
    """Low-pass FIR of the upsampler: 32 taps per phase, Kaiser (beta 9), cut-off at the
    original Nyquist frequency (resample_poly scales it by the upsampling factor)."""
    from scipy.signal import firwin

    return firwin(32 * UPSAMPLE + 1, 1.0 / UPSAMPLE, window=("kaiser", 9.0))


def upsample(signal: np.ndarray) -> np.ndarray:
    """``signal`` upsampled by :data:`UPSAMPLE` with a band-limited filter: what
    :func:`resample_at` reads (made once for a signal read at several grids)."""
    from scipy.signal import resample_poly

    return resample_poly(np.asarray(signal, dtype=float), UPSAMPLE, 1,
                         window=_interpolation_filter())


def resample_at(signal: np.ndarray, position: np.ndarray,
                upsampled: np.ndarray | None = None) -> np.ndarray:
    """``signal`` at fractional sample ``position``s: upsampled by :data:`UPSAMPLE` with a
    band-limited filter (or ``upsampled``, :func:`upsample` of it), then read by a 4-point
    cubic."""
    up = upsample(signal) if upsampled is None else upsampled
    return _cubic_at(up, np.asarray(position, dtype=float) * UPSAMPLE)


def angular_resample(signals: list[np.ndarray], revs: np.ndarray, samples_per_rev: int,
                     first_rev: float, n_revs: int,
                     upsampled: list[np.ndarray] | None = None) -> list[np.ndarray]:
    """Computed order tracking: every signal at ``samples_per_rev`` equal angle steps per
    revolution, for ``n_revs`` revolutions from ``first_rev``.

    ``revs`` (revolutions at each sample) must increase strictly. Each signal is upsampled
    by :data:`UPSAMPLE` with a band-limited filter (``upsampled``: :func:`upsample` of
    each, made once for several shafts' grids), then read at the sample positions of the
    angle grid by a 4-point cubic.
    """
    if np.any(np.diff(revs) <= 0):
        raise MeasurementError("the shaft angle does not increase over the record: the speed "
                               "estimate failed (wrong nominal speed, or no mesh line?)")
    grid = first_rev + np.arange(n_revs * samples_per_rev) / samples_per_rev
    if grid[0] < revs[0] or grid[-1] > revs[-1]:
        raise MeasurementError("the angle grid leaves the record")
    position = np.interp(grid, revs, np.arange(revs.size, dtype=float))
    ups = upsampled if upsampled is not None else [None] * len(signals)
    return [resample_at(s, position, up) for s, up in zip(signals, ups)]
