"""Kinematic bands and the spectral feature vector of the paper (Section 4), made noise-robust.

The paper keeps 10 bands: 4 mesh harmonics, 5 pinion-shaft harmonics and the
assembly-phase frequency, and takes the maximum inside each band. Band edges here
come from the kinematics: a mesh band spans h*f_mesh +- f_mesh/2 (so it holds every
shaft-order sideband the faulty tooth creates), a shaft band and the assembly band
span +- half a line spacing around their line.

Two feature modes:

- ``"lines"`` (default): every period-synchronous line inside the bands is a feature.
  The sidebands that carry the faulty tooth and the transmission errors stay visible.
- ``"paper"``: the maximum line inside each band, 10 features, as in the paper.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pydiag.kinematics import GearKinematics
from pydiag.spectrum import SyncSpectrum, sync_spectrum

N_MESH_HARMONICS = 4
N_SHAFT_HARMONICS = 5
FEATURE_MODES = ("lines", "paper")


@dataclass(frozen=True)
class Band:
    name: str
    low_hz: float
    high_hz: float


def paper_bands(kin: GearKinematics) -> list[Band]:
    """The paper's ten bands, with edges derived from the kinematics."""
    half_line = 0.5 * kin.f_hunting_hz
    bands = [Band(f"mesh{h}", (h - 0.5) * kin.f_mesh_hz, (h + 0.5) * kin.f_mesh_hz)
             for h in range(1, N_MESH_HARMONICS + 1)]
    bands += [Band(f"shaft{k}", k * kin.f_pinion_hz - half_line, k * kin.f_pinion_hz + half_line)
              for k in range(1, N_SHAFT_HARMONICS + 1)]
    bands.append(Band("assembly", kin.f_assembly_hz - half_line, kin.f_assembly_hz + half_line))
    return bands


def max_band_freq_hz(kin: GearKinematics) -> float:
    return max(b.high_hz for b in paper_bands(kin))


@dataclass(frozen=True)
class Features:
    """Feature amplitudes and what they are.

    Attributes:
        amplitude: feature amplitudes (signal units)
        freq_hz: frequency of each feature (the line, or the band's maximum in paper mode)
        noise_power: mean squared amplitude of a noise-only line (0 if unknown)
    """

    amplitude: np.ndarray
    freq_hz: np.ndarray
    noise_power: float


def features_from_spectrum(spec: SyncSpectrum, kin: GearKinematics, mode: str = "lines") -> Features:
    if mode not in FEATURE_MODES:
        raise ValueError(f"feature mode must be one of {FEATURE_MODES}, got {mode!r}")
    bands = paper_bands(kin)
    if bands[-1].high_hz > spec.freq_hz[-1] + 1e-9 and max(b.high_hz for b in bands) > spec.freq_hz[-1]:
        raise ValueError(f"the spectrum stops at {spec.freq_hz[-1]:.1f} Hz but the bands reach "
                         f"{max(b.high_hz for b in bands):.1f} Hz: raise the sample rate")
    masks = [(spec.freq_hz >= b.low_hz) & (spec.freq_hz < b.high_hz) for b in bands]
    if mode == "lines":
        keep = np.any(masks, axis=0)
        return Features(spec.amplitude[keep], spec.freq_hz[keep], spec.noise_power)
    idx = [np.flatnonzero(m)[np.argmax(spec.amplitude[m])] for m in masks]
    return Features(spec.amplitude[idx], spec.freq_hz[idx], spec.noise_power)


def signal_features(signal: np.ndarray, sample_rate_hz: float, kin: GearKinematics,
                    mode: str = "lines") -> Features:
    """Features of a time signal sampled at ``sample_rate_hz``."""
    spec = sync_spectrum(signal, sample_rate_hz, kin.period_s, max_freq_hz=max_band_freq_hz(kin))
    return features_from_spectrum(spec, kin, mode)


# ---------------------------------------------------------------------- featurizers
def _window(signal: np.ndarray, sample_rate_hz: float, duration_s: float, what: str) -> np.ndarray:
    """The first ``duration_s`` of ``signal``, mean removed; a shorter record is an error."""
    n = int(round(duration_s * sample_rate_hz))
    signal = np.asarray(signal, dtype=float)
    if signal.size < n:
        raise ValueError(f"record of {signal.size / sample_rate_hz:.4g} s is shorter than {what}")
    return signal[:n] - np.mean(signal[:n])


class KinematicFeaturizer:
    """Gear models: features at the kinematic lines of one fundamental period."""

    def __init__(self, kinematics: GearKinematics, mode: str = "lines") -> None:
        if mode not in FEATURE_MODES:
            raise ValueError(f"feature mode must be one of {FEATURE_MODES}, got {mode!r}")
        self.kinematics = kinematics
        self.mode = mode
        self.duration_s = kinematics.period_s

    @property
    def max_freq_hz(self) -> float:
        return max_band_freq_hz(self.kinematics)

    def describe_duration(self) -> str:
        k = self.kinematics
        return (f"one fundamental period ({k.period_s:.4g} s = {k.n_assembly_phases} pinion "
                "turns)")

    def __call__(self, signal: np.ndarray, sample_rate_hz: float) -> Features:
        return signal_features(signal, sample_rate_hz, self.kinematics, self.mode)


class SpectrumFeaturizer:
    """Any model: Hann-windowed FFT magnitudes of the first ``window_s`` up to ``max_freq_hz``.

    The noise power per bin is estimated from the bins between ``max_freq_hz`` and the
    Nyquist frequency (median power / ln 2, the mean of an exponential distribution), so a
    band-limited signal's lines do not inflate it.
    """

    def __init__(self, window_s: float, max_freq_hz: float) -> None:
        self.duration_s = window_s
        self.max_freq_hz = max_freq_hz

    def describe_duration(self) -> str:
        return f"the analysis window ({self.duration_s:.4g} s)"

    def __call__(self, signal: np.ndarray, sample_rate_hz: float) -> Features:
        x = _window(signal, sample_rate_hz, self.duration_s, self.describe_duration())
        n = x.size
        window = np.hanning(n)
        amp = 2.0 * np.abs(np.fft.rfft(x * window)) / np.sum(window)
        freqs = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
        keep = (freqs > 0) & (freqs <= self.max_freq_hz)
        high = freqs > self.max_freq_hz
        noise = float(np.median(amp[high] ** 2) / np.log(2)) if np.count_nonzero(high) > 8 else 0.0
        return Features(amp[keep], freqs[keep], noise)


class FullSpectrumFeaturizer:
    """Full-resolution amplitudes of ``n_periods`` whole periods, at selected bins.

    Used by ``compare``: ``bins`` is a boolean mask over the bins from 1/(n_periods T0) to
    ``max_freq_hz``; the measurement defines it (synchronous lines plus its own peaks), so
    every model is scored on the same bins. The noise power is the median power of the
    bins between synchronous lines over ln 2 (the mean of an exponential distribution),
    robust to the non-synchronous peaks a missing effect leaves there.
    """

    def __init__(self, kinematics: GearKinematics, n_periods: int, max_freq_hz: float,
                 bins: np.ndarray | None = None) -> None:
        self.kinematics = kinematics
        self.n_periods = n_periods
        self.max_freq_hz = max_freq_hz
        self.duration_s = n_periods * kinematics.period_s
        self.bins = bins

    def describe_duration(self) -> str:
        return f"{self.n_periods} fundamental periods ({self.duration_s:.4g} s)"

    def spectrum(self, signal: np.ndarray, sample_rate_hz: float) -> tuple[np.ndarray, np.ndarray, float]:
        """(freq_hz, amplitude, noise_power) over all bins up to max_freq_hz."""
        x = _window(signal, sample_rate_hz, self.duration_s, self.describe_duration())
        n = x.size
        amp = 2.0 * np.abs(np.fft.rfft(x)) / n
        freqs = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
        keep = (freqs > 0) & (freqs <= self.max_freq_hz)
        idx = np.flatnonzero(keep)
        off = idx[idx % self.n_periods != 0]
        noise = float(np.median(amp[off] ** 2) / np.log(2)) if off.size else 0.0
        return freqs[keep], amp[keep], noise

    def __call__(self, signal: np.ndarray, sample_rate_hz: float) -> Features:
        freqs, amp, noise = self.spectrum(signal, sample_rate_hz)
        mask = self.bins if self.bins is not None else np.ones(freqs.size, dtype=bool)
        return Features(amp[mask], freqs[mask], noise)
