"""The weighted spectral error of the paper's Eq. (12), made aware of measurement noise.

Eq. (12):  E = sqrt( sum_f ( |S(f)|/max|S| + 1 )^2 (S(f) - R(f))^2 ),
S the model's (simulated) features, R the reference (measured) ones.

Noise: a measured line of true amplitude A in complex Gaussian noise of power P
(per line) has E|R|^2 = A^2 + P, so a noise-free model line is compared as
S' = sqrt(S^2 + P). Without this, every small line is biased upwards by the noise
floor and the optimiser inflates small fault parameters to match noise (the failure
the diagnose issue measured). The error is divided by sqrt(sum R^2), so E is a
relative error: 0 is a perfect fit, 1 is as large as the measured features.
"""

from __future__ import annotations

import numpy as np


def spectral_residuals(model: np.ndarray, reference: np.ndarray,
                       noise_power: float | np.ndarray = 0.0) -> np.ndarray:
    """The terms of Eq. (12) before squaring: E = ||residuals||.

    ``residual_i = (S'_i/max S' + 1) (S'_i - R_i) / sqrt(sum R^2)`` with
    ``S' = sqrt(S^2 + noise_power)``. Smooth in S, so least-squares solvers apply.
    ``noise_power``: one for every bin, or one per bin (a floor that is not flat).
    """
    model = np.asarray(model, dtype=float)
    reference = np.asarray(reference, dtype=float)
    if model.shape != reference.shape:
        raise ValueError(f"feature shapes differ: model {model.shape}, reference {reference.shape}")
    expected = np.sqrt(model ** 2 + np.maximum(noise_power, 0.0))
    peak = np.max(expected)
    weight = expected / peak + 1.0 if peak > 0 else np.ones_like(expected)
    scale = np.sqrt(np.sum(reference ** 2))
    return weight * (expected - reference) / (scale if scale > 0 else 1.0)


def spectral_error(model: np.ndarray, reference: np.ndarray,
                   noise_power: float | np.ndarray = 0.0) -> float:
    """Eq. (12), noise-aware and relative (see the module docstring)."""
    return float(np.linalg.norm(spectral_residuals(model, reference, noise_power)))


def rician_mean(amplitude: np.ndarray, noise_power: float | np.ndarray) -> np.ndarray:
    """E|A + n| for a line of amplitude A in complex Gaussian noise of power P per line
    (one P for every line, or one per line; |A| where P is 0).

    Rician with nu = A, sigma^2 = P/2: sigma sqrt(pi/2) L_1/2(-q), q = A^2/P, written
    with exponentially scaled Bessel functions so large q does not overflow.
    """
    from scipy.special import i0e, i1e

    a = np.asarray(amplitude, dtype=float)
    p = np.broadcast_to(np.asarray(noise_power, dtype=float), a.shape)
    if not np.any(p > 0):
        return np.abs(a)
    noisy = p > 0
    q = np.where(noisy, a ** 2 / np.where(noisy, p, 1.0), 0.0)
    laguerre = (1 + q) * i0e(q / 2) + q * i1e(q / 2)
    return np.where(noisy, np.sqrt(np.maximum(p, 0.0) / 2) * np.sqrt(np.pi / 2) * laguerre,
                    np.abs(a))


def noise_corrected_error(model: np.ndarray, reference: np.ndarray,
                          noise_power: float | np.ndarray) -> float:
    """Eq. (12) with the part that noise alone would produce taken out.

    For a perfect model each measured line is Rician around the model line, so the
    expected squared term is ``2 S'^2 - 2 S' E|S + n|`` with ``S' = sqrt(S^2 + P)``; the
    weighted sum of these, relative like Eq. (12), is subtracted from E^2. Expected value
    0 for a perfect model (up to the noise's spread), whatever the number of bins.
    """
    model = np.asarray(model, dtype=float)
    reference = np.asarray(reference, dtype=float)
    raw = spectral_error(model, reference, noise_power)
    noise = np.broadcast_to(np.maximum(noise_power, 0.0), reference.shape)
    expected = np.sqrt(model ** 2 + noise)
    peak = np.max(expected)
    weight = (expected / peak + 1.0) ** 2 if peak > 0 else np.ones_like(expected)
    noise_sq = np.sum(weight * (2 * expected ** 2 - 2 * expected * rician_mean(model, noise_power)))
    measured_sq = np.sum(reference ** 2) or 1.0
    residual_sq = raw ** 2 * measured_sq  # the weighted squared residual of Eq. (12)
    # one P for every bin: N x P, as it always was (a sum of N copies differs in the last bit)
    noise_total = (reference.size * max(float(noise_power), 0.0) if np.ndim(noise_power) == 0
                   else float(np.sum(noise)))
    signal_sq = max(measured_sq - noise_total, 1e-3 * measured_sq)
    return float(np.sqrt(max(residual_sq - noise_sq, 0.0) / signal_sq))
