"""Measurement noise."""

from __future__ import annotations

import numpy as np

from pydiag.core.errors import UsageError


def add_white_noise(signal: np.ndarray, snr: float, rng: np.random.Generator) -> np.ndarray:
    """Add Gaussian white noise at a signal-to-noise *power* ratio ``snr`` (10 means 10 dB).

    Signal power is the variance of ``signal`` (its mean does not count).
    """
    if not snr > 0:
        raise UsageError(f"SNR must be positive, got {snr}")
    signal = np.asarray(signal, dtype=float)
    sigma = np.sqrt(np.var(signal) / snr)
    return signal + rng.normal(0.0, sigma, signal.shape)
