"""Amplitude spectra, noise floors and local maxima: the signal processing every stage shares.

Period-synchronous spectra: a record that spans a whole number M of the fundamental
period T0 has every kinematic line on a DFT bin (bin index a multiple of M), so no window
is needed and line amplitudes are read without leakage. The bins between the lines hold
only noise (and non-synchronous content); their mean power is the noise floor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pydiag.core.errors import MeasurementError
from pydiag.signal.angle import resample_at

#: The top of the band a bearing's envelope is taken in, as a share of the sample rate (its
#: bottom: the top of the gear's analysed bands): below the Nyquist frequency by the
#: anti-alias filter's usual margin.
ENVELOPE_TOP = 0.45

WINDOWS = ("boxcar", "hann")


def amplitude_spectrum(signal: np.ndarray, sample_rate_hz: float,
                       window: str = "boxcar") -> tuple[np.ndarray, np.ndarray]:
    """Single-sided peak-amplitude spectrum of ``signal`` with its mean removed.

    Returns ``(freq_hz, amplitude)`` over the ``rfft`` bins; a tone of amplitude A on a bin
    reads A (the window's coherent gain is divided out). ``window``: "boxcar" (none: exact
    for period-synchronous records) or "hann" (leakage-suppressing, for any record).
    """
    x = np.asarray(signal, dtype=float)
    x = x - np.mean(x)
    if window == "boxcar":
        amplitude = 2.0 * np.abs(np.fft.rfft(x)) / x.size
    elif window == "hann":
        w = np.hanning(x.size)
        amplitude = 2.0 * np.abs(np.fft.rfft(x * w)) / np.sum(w)
    else:
        raise ValueError(f"window must be one of {WINDOWS}, got {window!r}")
    return np.fft.rfftfreq(x.size, 1.0 / sample_rate_hz), amplitude


def without_synchronous(signal: np.ndarray, n_periods: int) -> np.ndarray:
    """``signal`` (``n_periods`` whole periods) without the lines of its period: the DFT
    bins at multiples of ``n_periods`` (the period's harmonics, and the mean) set to zero.
    What is left is what does not repeat every period (the discrete/random separation of
    bearing diagnostics: a gear's lines all repeat each fundamental period, a bearing's
    strikes do not; the same as subtracting the time-synchronous average when the period
    is whole samples)."""
    x = np.asarray(signal, dtype=float)
    spectrum = np.fft.rfft(x)
    spectrum[::max(int(n_periods), 1)] = 0.0
    return np.fft.irfft(spectrum, n=x.size)


def band_envelope(signal: np.ndarray, sample_rate_hz: float,
                  band_hz: tuple[float, float]) -> np.ndarray:
    """The envelope of ``signal`` in the band ``band_hz`` = (low, high), Hz: the magnitude
    of the analytic signal (Hilbert transform) of the signal band-passed (Butterworth,
    order 4, forward and backward: no phase shift). Same length and rate as ``signal``.

    Envelope analysis (McFadden and Smith 1984; Randall and Antoni 2011): a bearing's
    strikes ring a structural mode kHz above the gear's lines, so the spectrum shows a hump
    at the mode, smeared by the rolling elements' slip, while the envelope of the band
    around the mode beats at the strike frequency and its low harmonics, as lines.
    """
    return np.abs(band_analytic(signal, sample_rate_hz, band_hz))


def band_analytic(signal: np.ndarray, sample_rate_hz: float,
                  band_hz: tuple[float, float]) -> np.ndarray:
    """The analytic signal whose magnitude :func:`band_envelope` is: complex, linear in
    ``signal`` (what a fit of a model affine in its parameters combines before the
    magnitude is taken)."""
    low, high = band_hz
    if not 0 < low < high < sample_rate_hz / 2:
        raise ValueError(f"the band must lie inside (0, {sample_rate_hz / 2:g}) Hz with low < "
                         f"high, got {low:g}-{high:g} Hz")
    import scipy.signal  # here: importing it takes 0.6 s of every command's start

    sos = scipy.signal.butter(4, [low, high], btype="bandpass", fs=sample_rate_hz, output="sos")
    return scipy.signal.hilbert(scipy.signal.sosfiltfilt(sos, np.asarray(signal, float)))


def noise_power(amplitude: np.ndarray, robust: bool = False, min_bins: int = 1) -> float:
    """Mean squared amplitude of a noise-only bin, from bins that hold only noise.

    For complex Gaussian noise the squared amplitude of a bin is exponentially
    distributed. ``robust=False``: the sample mean (efficient when the bins are pure
    noise). ``robust=True``: median / ln 2 (the exponential's median is its mean x ln 2),
    insensitive to the few bins a non-synchronous line or a missing effect occupies.
    Fewer than ``min_bins`` bins: 0.0 (the floor is unknown).
    """
    power = np.asarray(amplitude, dtype=float) ** 2
    if power.size < max(min_bins, 1):
        return 0.0
    return float(np.median(power) / np.log(2)) if robust else float(np.mean(power))


def local_maxima(values: np.ndarray) -> np.ndarray:
    """Boolean mask of entries not below either neighbour (an edge has one neighbour)."""
    v = np.asarray(values, dtype=float)
    left = np.concatenate([[-np.inf], v[:-1]])
    right = np.concatenate([v[1:], [-np.inf]])
    return (v >= left) & (v >= right)


@dataclass(frozen=True)
class Spectrum:
    """Single-sided amplitude spectrum at some frequencies (a record's bins, the lines of a
    machine, the features a fit compares), and the noise beside them.

    Attributes:
        freq_hz: the frequencies
        amplitude: peak amplitudes there (signal units)
        noise_power: mean squared amplitude of a noise-only bin (signal units squared; 0
            when unknown)
    """

    freq_hz: np.ndarray
    amplitude: np.ndarray
    noise_power: float


@dataclass(frozen=True)
class SyncSpectrum(Spectrum):
    """A :class:`Spectrum` at the harmonics of 1/period, k/period for k = 0..n_lines-1,
    over ``n_periods`` whole periods of the record."""

    n_periods: int = 0


def whole_periods(n_samples: int, sample_rate_hz: float, period_s: float) -> tuple[int, int]:
    """(periods, samples) of the longest prefix that holds a whole number of periods, to
    within half a sample (a period of 0.06 s is a 0.06 s record, however it rounds)."""
    n_periods = int(np.floor((n_samples + 0.5) / (sample_rate_hz * period_s)))
    return n_periods, int(round(n_periods * period_s * sample_rate_hz))


def sync_spectrum(signal: np.ndarray, sample_rate_hz: float, period_s: float,
                  max_freq_hz: float | None = None) -> SyncSpectrum:
    """Amplitude spectrum of ``signal`` at the harmonics of ``1/period_s``.

    The record is cut to its longest whole number of periods. If a period is not a whole
    number of samples (a real record at its measured speed), those periods are first
    resampled onto ceil(period x rate) samples each (band-limited,
    :func:`pydiag.signal.angle.resample_at`), so the lines fall on DFT bins again; cost
    O(n), whatever the record's length.
    """
    signal = np.asarray(signal, dtype=float)
    n_periods, n = whole_periods(signal.size, sample_rate_hz, period_s)
    if n_periods < 1:
        raise MeasurementError(f"record of {signal.size / sample_rate_hz:.4g} s is shorter than "
                               f"one fundamental period ({period_s:.4g} s)")
    nyquist = sample_rate_hz / 2
    top = nyquist if max_freq_hz is None else min(max_freq_hz, nyquist)
    n_lines = int(np.floor(top * period_s + 1e-9)) + 1
    freqs = np.arange(n_lines) / period_s
    per_period = period_s * sample_rate_hz
    if abs(n_periods * per_period - n) < 1e-6:
        x = signal[:n]
    else:
        samples = int(np.ceil(per_period))
        x = resample_at(signal, np.arange(n_periods * samples) * (per_period / samples))
    _, bins = amplitude_spectrum(x, sample_rate_hz)
    amplitude = bins[np.arange(n_lines) * n_periods]
    amplitude[0] = 0.0  # mean removed
    k = np.arange(1, bins.size - 1)
    # one period: no bin between lines, the floor is unknown (0)
    noise = noise_power(bins[k[k % n_periods != 0]]) if n_periods > 1 else 0.0
    return SyncSpectrum(freqs, amplitude, noise, n_periods)
