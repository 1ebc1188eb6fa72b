"""Feature vectors: what the objective compares, and the featurizer for any model.

A featurizer turns a signal into features, a :class:`pydiag.signal.spectra.Spectrum`; it has ``duration_s`` (the signal it
needs), ``max_freq_hz`` (the highest frequency it reads), ``describe_duration()`` (for
messages) and ``__call__(signal, sample_rate_hz)``. Gear models use the kinematic
featurizers of :mod:`pydiag.gear.features`; any other model the windowed FFT here.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from pydiag.core.errors import MeasurementError
from pydiag.signal.spectra import Spectrum, amplitude_spectrum, noise_power


class Featurizer(Protocol):
    duration_s: float
    max_freq_hz: float

    def describe_duration(self) -> str: ...

    def __call__(self, signal: np.ndarray, sample_rate_hz: float) -> Spectrum: ...


def first_window(signal: np.ndarray, sample_rate_hz: float, duration_s: float,
                 what: str) -> np.ndarray:
    """The first ``duration_s`` of ``signal``; a shorter record is an error naming ``what``."""
    n = int(round(duration_s * sample_rate_hz))
    signal = np.asarray(signal, dtype=float)
    if signal.size < n:
        raise MeasurementError(f"record of {signal.size / sample_rate_hz:.4g} s is shorter "
                               f"than {what}")
    return signal[:n]


class SpectrumFeaturizer:
    """Any model: Hann-windowed FFT magnitudes of the first ``window_s`` up to ``max_freq_hz``.

    The noise power per bin is estimated from the bins between ``max_freq_hz`` and the
    Nyquist frequency (robust: median power / ln 2), so a band-limited signal's lines do
    not inflate it.
    """

    def __init__(self, window_s: float, max_freq_hz: float) -> None:
        self.duration_s = window_s
        self.max_freq_hz = max_freq_hz

    def describe_duration(self) -> str:
        return f"the analysis window ({self.duration_s:.4g} s)"

    def __call__(self, signal: np.ndarray, sample_rate_hz: float) -> Spectrum:
        x = first_window(signal, sample_rate_hz, self.duration_s, self.describe_duration())
        freqs, amp = amplitude_spectrum(x, sample_rate_hz, "hann")
        keep = (freqs > 0) & (freqs <= self.max_freq_hz)
        noise = noise_power(amp[freqs > self.max_freq_hz], robust=True, min_bins=9)
        return Spectrum(freqs[keep], amp[keep], noise)
