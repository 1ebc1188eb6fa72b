"""Period-synchronous spectra: exact line amplitudes and the noise floor between lines.

A record that spans a whole number M of the fundamental period T0 has every
kinematic line on a DFT bin (bin index a multiple of M), so no window is needed and
line amplitudes are read without leakage. The bins between the lines hold only
noise (and non-synchronous content); their mean power is the noise floor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SyncSpectrum:
    """Single-sided amplitude spectrum at the harmonics of 1/period.

    Attributes:
        freq_hz: line frequencies, k/period for k = 0..n_lines-1
        amplitude: peak amplitudes of the lines (signal units)
        noise_power: mean squared amplitude of a noise-only bin (signal units squared)
        n_periods: whole periods in the record
    """

    freq_hz: np.ndarray
    amplitude: np.ndarray
    noise_power: float
    n_periods: int


def whole_periods(n_samples: int, sample_rate_hz: float, period_s: float) -> tuple[int, int]:
    """(periods, samples) of the longest prefix that holds a whole number of periods."""
    n_periods = int(np.floor(n_samples / (sample_rate_hz * period_s) + 1e-9))
    return n_periods, int(round(n_periods * period_s * sample_rate_hz))


def sync_spectrum(signal: np.ndarray, sample_rate_hz: float, period_s: float,
                  max_freq_hz: float | None = None) -> SyncSpectrum:
    """Amplitude spectrum of ``signal`` at the harmonics of ``1/period_s``.

    The record is cut to its longest whole number of periods. If a period is not a
    whole number of samples, the cut is rounded to the nearest sample and the lines
    fall within a small fraction of a bin of the DFT grid; amplitudes are then
    evaluated at the exact line frequencies by a direct DFT.
    """
    signal = np.asarray(signal, dtype=float)
    n_periods, n = whole_periods(signal.size, sample_rate_hz, period_s)
    if n_periods < 1:
        raise ValueError(f"record of {signal.size / sample_rate_hz:.4g} s is shorter than one "
                         f"fundamental period ({period_s:.4g} s)")
    x = signal[:n] - np.mean(signal[:n])
    nyquist = sample_rate_hz / 2
    top = nyquist if max_freq_hz is None else min(max_freq_hz, nyquist)
    n_lines = int(np.floor(top * period_s + 1e-9)) + 1
    freqs = np.arange(n_lines) / period_s
    spec = np.fft.rfft(x)
    exact = abs(n_periods * period_s * sample_rate_hz - n) < 1e-6
    if exact:
        lines = spec[np.arange(n_lines) * n_periods]
    else:
        t = np.arange(n) / sample_rate_hz
        lines = np.exp(-2j * np.pi * np.outer(freqs, t)) @ x
    amplitude = 2.0 * np.abs(lines) / n
    amplitude[0] = 0.0  # mean removed
    if n_periods > 1:
        bins = np.arange(1, spec.size - 1)
        off = bins[bins % n_periods != 0]
        noise_power = float(np.mean((2.0 * np.abs(spec[off]) / n) ** 2)) if off.size else 0.0
    else:
        noise_power = 0.0  # one period: no bin between lines, floor unknown
    return SyncSpectrum(freqs, amplitude, noise_power, n_periods)
