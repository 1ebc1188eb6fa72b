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

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from pydiag.core.errors import MeasurementError, UsageError
from pydiag.gear.kinematics import GearKinematics
from pydiag.signal.features import first_window
from pydiag.signal.spectra import (Spectrum, SyncSpectrum, amplitude_spectrum, band_analytic,
                                   noise_power, sync_spectrum, without_synchronous)

N_MESH_HARMONICS = 4
N_SHAFT_HARMONICS = 5
FEATURE_MODES = ("lines", "paper")


@dataclass(frozen=True)
class Band:
    name: str
    low_hz: float
    high_hz: float


def paper_bands(kin: GearKinematics) -> list[Band]:
    """The paper's ten bands, with edges derived from the kinematics; of a modelled machine
    (:attr:`~pydiag.gear.kinematics.GearKinematics.modelled_machine`), every stage's ten
    (the stage's number before each band's name from the second on)."""
    if kin.modelled_machine:
        return [dataclasses.replace(b, name=b.name if k == 0 else f"stage{k + 1}:{b.name}")
                for k, stage in enumerate(kin.stages()) for b in paper_bands(stage)]
    half_line = 0.5 * kin.f_hunting_hz
    bands = [Band(f"mesh{h}", (h - 0.5) * kin.f_mesh_hz, (h + 0.5) * kin.f_mesh_hz)
             for h in range(1, N_MESH_HARMONICS + 1)]
    bands += [Band(f"shaft{k}", k * kin.f_pinion_hz - half_line, k * kin.f_pinion_hz + half_line)
              for k in range(1, N_SHAFT_HARMONICS + 1)]
    bands.append(Band("assembly", kin.f_assembly_hz - half_line, kin.f_assembly_hz + half_line))
    return bands


def max_band_freq_hz(kin: GearKinematics) -> float:
    return max(b.high_hz for b in paper_bands(kin))


def _check_mode(mode: str) -> None:
    if mode not in FEATURE_MODES:
        raise UsageError(f"feature mode must be one of {FEATURE_MODES}, got {mode!r}")


def features_from_spectrum(spec: SyncSpectrum, kin: GearKinematics, mode: str = "lines",
                           exclude_hz: tuple[float, ...] = ()) -> Spectrum:
    """The features of ``spec``: every line in the bands (or each band's largest), without
    the lines within half a line spacing of ``exclude_hz`` (another stage's lines) that are
    none of the pair's own (:func:`own_lines`)."""
    _check_mode(mode)
    bands = paper_bands(kin)
    top = max(b.high_hz for b in bands)
    spacing = spec.freq_hz[1] - spec.freq_hz[0] if spec.freq_hz.size > 1 else np.inf
    if spec.freq_hz[-1] + spacing < top - 1e-9:  # a line inside the bands is missing
        raise MeasurementError(f"the spectrum stops at {spec.freq_hz[-1]:.1f} Hz but the bands "
                               f"reach {top:.1f} Hz: raise the sample rate")
    masks = [(spec.freq_hz >= b.low_hz) & (spec.freq_hz < b.high_hz) for b in bands]
    if len(exclude_hz):
        others = other_stages_lines(spec.freq_hz, kin, exclude_hz, top)
        masks = [m & ~others for m in masks]
    if mode == "lines":
        keep = np.any(masks, axis=0)
        return Spectrum(spec.freq_hz[keep], spec.amplitude[keep], spec.noise_power)
    idx = [np.flatnonzero(m)[np.argmax(spec.amplitude[m])] for m in masks if np.any(m)]
    return Spectrum(spec.freq_hz[idx], spec.amplitude[idx], spec.noise_power)


def other_stages_lines(freqs: np.ndarray, kin: GearKinematics, exclude_hz: tuple[float, ...],
                       max_freq_hz: float) -> np.ndarray:
    """Which of ``freqs`` a stage leaves out: within half a line spacing of ``exclude_hz``
    (another stage's lines) and of none of the pair's own lines (:func:`own_lines`)."""
    tolerance = 0.5 * kin.f_hunting_hz
    return (_near(freqs, np.asarray(exclude_hz, dtype=float), tolerance)
            & ~_near(freqs, own_lines(kin, max_freq_hz), tolerance))


def own_lines(kin: GearKinematics, max_freq_hz: float) -> np.ndarray:
    """The pair's own lines up to ``max_freq_hz``: the mesh harmonics and their sidebands
    (:meth:`~pydiag.gear.kinematics.GearKinematics.mesh_lines_hz`), the shafts' first
    :data:`N_SHAFT_HARMONICS` orders and the assembly phase's harmonics below the mesh (the
    paper's bands; a high order of a shaft is another stage's mesh as often as not)."""
    fp, fg, fm, fa = kin.f_pinion_hz, kin.f_gear_hz, kin.f_mesh_hz, kin.f_assembly_hz
    orders = np.arange(1, N_SHAFT_HARMONICS + 1)
    out = np.concatenate([orders * fp, orders * fg, np.arange(1, fm / fa) * fa,
                          np.array(kin.mesh_lines_hz(max_freq_hz))])
    return out[(out > 0) & (out <= max_freq_hz)]


def _near(freqs: np.ndarray, lines: np.ndarray, tolerance_hz: float) -> np.ndarray:
    """Which of ``freqs`` lie within ``tolerance_hz`` of one of ``lines``."""
    if lines.size == 0:
        return np.zeros(freqs.size, dtype=bool)
    lines = np.sort(lines)
    i = np.clip(np.searchsorted(lines, freqs), 1, lines.size - 1)
    return np.minimum(np.abs(freqs - lines[i - 1]), np.abs(freqs - lines[i])) < tolerance_hz


def signal_features(signal: np.ndarray, sample_rate_hz: float, kin: GearKinematics,
                    mode: str = "lines", exclude_hz: tuple[float, ...] = ()) -> Spectrum:
    """Features of a time signal sampled at ``sample_rate_hz``."""
    spec = sync_spectrum(signal, sample_rate_hz, kin.period_s, max_freq_hz=max_band_freq_hz(kin))
    return features_from_spectrum(spec, kin, mode, exclude_hz)


class KinematicFeaturizer:
    """Gear models: features at the kinematic lines of one fundamental period; a stage of a
    machine leaves out the lines of the other stages (``exclude_hz``) that are not its own."""

    def __init__(self, kinematics: GearKinematics, mode: str = "lines",
                 exclude_hz: tuple[float, ...] = ()) -> None:
        _check_mode(mode)
        self.kinematics = kinematics
        self.mode = mode
        self.exclude_hz = tuple(exclude_hz)
        self.duration_s = kinematics.period_s

    @property
    def max_freq_hz(self) -> float:
        return max_band_freq_hz(self.kinematics)

    def describe_duration(self) -> str:
        k = self.kinematics
        return (f"one fundamental period ({k.period_s:.4g} s = "
                f"{k.period_s * k.f_pinion_hz:.4g} pinion turns)")

    def __call__(self, signal: np.ndarray, sample_rate_hz: float) -> Spectrum:
        return signal_features(signal, sample_rate_hz, self.kinematics, self.mode,
                               self.exclude_hz)


def _whole_samples_per_period(x: np.ndarray, sample_rate_hz: float, period_s: float
                              ) -> tuple[np.ndarray, float]:
    """``x`` (whole periods of ``period_s``) and its sample rate, resampled where a period is
    no whole number of samples to the next whole number above it (Fourier interpolation,
    exact for the periodic part of a window of whole periods).

    Cutting such a record into periods needs it: cut at the nearest samples, its periods
    differ by a sample; cut to one length, every joint skips a fraction of a sample, so
    each line shows too high by that fraction of a period (0.12 % at 660.8 samples: 3.8 Hz
    at the 3178 Hz mesh, off its bin once a half holds more than about 20 periods) and
    the high harmonics smear."""
    samples = period_s * sample_rate_hz
    if abs(samples - round(samples)) < 1e-6 * samples:
        return x, sample_rate_hz
    from scipy.signal import resample  # here: importing it takes 0.6 s of every command's start

    n = int(round(x.size / samples)) * math.ceil(samples)
    return resample(x, n), sample_rate_hz * n / x.size


class FullSpectrumFeaturizer:
    """Full-resolution amplitudes of ``n_periods`` whole periods, at selected bins.

    Used by ``compare``: ``bins`` is a boolean mask over the bins from 1/(n_periods T0) to
    ``max_freq_hz``; the measurement defines it (synchronous lines plus its own peaks), so
    every model is scored on the same bins. The noise power is robust (median power of
    the bins between synchronous lines over ln 2), so the non-synchronous peaks a missing
    effect leaves there do not inflate it.

    Held-out validation: ``half`` 0 or 1 analyses every other period of the first
    ``2 n_periods`` (periods 0, 2, 4, ... or 1, 3, 5, ..., joined): two records of the same
    machine with independent noise. Joined whole periods keep every synchronous line on a
    bin; a non-synchronous line is spread the same way in model and measurement.

    ``envelope_band_hz`` (low, high): the spectrum is the envelope's, of the part of the
    signal that does not repeat every period (:func:`pydiag.signal.spectra.without_synchronous`:
    the gear's lines removed, which a bearing's envelope must not beat against) in that band
    (:func:`pydiag.signal.spectra.band_envelope`), taken over the whole window before the
    periods are cut: where a bearing's strikes show as lines.
    """

    def __init__(self, kinematics: GearKinematics, n_periods: int, max_freq_hz: float,
                 bins: np.ndarray | None = None, half: int | None = None,
                 envelope_band_hz: tuple[float, float] | None = None) -> None:
        if half not in (None, 0, 1):
            raise ValueError(f"half must be None, 0 or 1, got {half!r}")
        self.kinematics = kinematics
        self.n_periods = n_periods
        self.max_freq_hz = max_freq_hz
        self.half = half
        self.duration_s = n_periods * kinematics.period_s * (1 if half is None else 2)
        self.bins = bins
        self.envelope_band_hz = envelope_band_hz

    def describe_duration(self) -> str:
        return f"{self.duration_s / self.kinematics.period_s:.0f} fundamental periods " \
               f"({self.duration_s:.4g} s)"

    def _analysed(self, signal: np.ndarray, sample_rate_hz: float) -> tuple[np.ndarray, float]:
        """The samples the spectrum is taken of, and their rate."""
        z = self.analytic(signal, sample_rate_hz)
        return self._halved(first_window(signal, sample_rate_hz, self.duration_s,
                                         self.describe_duration()) if z is None else np.abs(z),
                            sample_rate_hz)

    def analytic(self, signal: np.ndarray, sample_rate_hz: float) -> np.ndarray | None:
        """The analytic signal whose magnitude is the envelope the spectrum is taken of
        (:func:`pydiag.signal.spectra.band_analytic`), linear in ``signal``; None for a
        spectrum of the signal itself."""
        if self.envelope_band_hz is None:
            return None
        x = first_window(signal, sample_rate_hz, self.duration_s, self.describe_duration())
        periods = int(round(self.duration_s / self.kinematics.period_s))
        return band_analytic(without_synchronous(x, periods), sample_rate_hz,
                             self.envelope_band_hz)

    def of_analytic(self, analytic: np.ndarray, sample_rate_hz: float) -> Spectrum:
        """What this featurizer makes of a signal whose :meth:`analytic` is ``analytic``."""
        return self._masked(self._spectrum_of(*self._halved(np.abs(analytic), sample_rate_hz)))

    def _halved(self, x: np.ndarray, sample_rate_hz: float) -> tuple[np.ndarray, float]:
        """The samples of ``x`` (the analysed window) the spectrum is taken of: every other
        period for a half."""
        if self.half is not None:
            x, sample_rate_hz = _whole_samples_per_period(x, sample_rate_hz,
                                                          self.kinematics.period_s)
            length = x.size // (2 * self.n_periods)
            x = np.concatenate([x[k * length:(k + 1) * length]
                                for k in range(self.half, 2 * self.n_periods, 2)])
        return x, sample_rate_hz

    def spectrum(self, signal: np.ndarray, sample_rate_hz: float) -> Spectrum:
        """Every bin up to max_freq_hz, and the noise between the synchronous lines."""
        return self._spectrum_of(*self._analysed(signal, sample_rate_hz))

    def _spectrum_of(self, x: np.ndarray, sample_rate_hz: float) -> Spectrum:
        """:meth:`spectrum` of the analysed samples ``x``."""
        freqs, amp = amplitude_spectrum(x, sample_rate_hz)
        keep = (freqs > 0) & (freqs <= self.max_freq_hz)
        idx = np.flatnonzero(keep)
        noise = noise_power(amp[idx[idx % self.n_periods != 0]], robust=True)
        return Spectrum(freqs[keep], amp[keep], noise)

    def joined_freq_hz(self, freq_hz: float) -> float:
        """Where a line at ``freq_hz`` of the record shows in this featurizer's spectrum.

        The whole record: there. A half joins every other period: a line that is not
        synchronous (f T0 not an integer) jumps in phase by 2 pi f T0 at every joint, which
        moves most of its power (a share sinc^2(e) >= 40 %, e = f T0 - round(f T0)) to
        f + e/T0; a synchronous line stays where it is."""
        if self.half is None:
            return freq_hz
        period = self.kinematics.period_s
        cycles = freq_hz * period
        return freq_hz + (cycles - round(cycles)) / period

    def with_bins(self, bins: np.ndarray) -> "FullSpectrumFeaturizer":
        return FullSpectrumFeaturizer(self.kinematics, self.n_periods, self.max_freq_hz, bins,
                                      self.half, self.envelope_band_hz)

    def other_half(self) -> "FullSpectrumFeaturizer":
        if self.half is None:
            raise ValueError("a whole-record featurizer has no other half")
        return FullSpectrumFeaturizer(self.kinematics, self.n_periods, self.max_freq_hz,
                                      self.bins, 1 - self.half, self.envelope_band_hz)

    def linear(self, signal: np.ndarray, sample_rate_hz: float) -> np.ndarray | None:
        """Complex values at this featurizer's bins whose moduli are its amplitudes: linear
        in ``signal`` (so a model affine in its parameters is affine here, and its
        amplitudes are had without a spectrum each); None for an envelope's spectrum,
        which is not."""
        if self.envelope_band_hz is not None:
            return None
        x, sample_rate_hz = self._analysed(signal, sample_rate_hz)
        spectrum = 2.0 * np.fft.rfft(x - np.mean(x)) / x.size
        freqs = np.fft.rfftfreq(x.size, 1.0 / sample_rate_hz)
        keep = (freqs > 0) & (freqs <= self.max_freq_hz)
        values = spectrum[keep]
        return values if self.bins is None else values[self.bins]

    def __call__(self, signal: np.ndarray, sample_rate_hz: float) -> Spectrum:
        return self._masked(self.spectrum(signal, sample_rate_hz))

    def _masked(self, full: Spectrum) -> Spectrum:
        """``full`` at this featurizer's bins."""
        freqs, amp, noise = full.freq_hz, full.amplitude, full.noise_power
        mask = self.bins if self.bins is not None else np.ones(freqs.size, dtype=bool)
        return Spectrum(freqs[mask], amp[mask], noise)
