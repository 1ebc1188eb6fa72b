"""The pinion speed of a real record, and the record order-tracked to that speed.

A real machine turns at a speed that is only nominal (motor slip moves it with the load)
and drifts within the record, so a synchronous cut at the nominal speed smears the mesh
harmonics. :func:`estimate_speed` finds the shaft angle over the record:

- ``"tacho"``: from a pulse channel (:func:`pydiag.signal.angle.tacho_revolutions`);
- ``"mesh"``: from the mesh harmonics. A harmonic-product search over the Hann spectrum
  finds the speed at which the mesh harmonics line up, within the nominal speed
  +- ``SPEED_SEARCH`` and +- 0.45/Np: beyond half a pinion order at the mesh, the comb of
  sidebands h f_mesh - h f_pinion of a faulty tooth lines up as well as the mesh and can
  pass for it (seen on a simulated tooth fault, Np = 14). The nominal speed must be that
  close (1.4 % for a 32-tooth pinion); otherwise use a tacho. The harmonic that stands
  highest above its band's median is then phase-demodulated in a band of +- half the
  slower shaft's speed (Tukey taper, flat over the inner half), which excludes the
  shaft-order sidebands, so the phase is the shaft angle times h Np. The mean speed is the slope of that phase (far below one FFT bin);
- ``"nominal"``: the nominal speed, constant.

The mesh line must stand above the noise: its amplitude over its band's median must
exceed what the largest of the band's bins reaches by chance with probability 1e-3
(Rayleigh noise: ``r^2 ln 2 > ln(bins / 1e-3)``); otherwise the estimate is refused.

``speed_variation_pct`` is 100 (max - min) / mean of the speed averaged over blocks of
``BLOCK_REVS`` pinion revolutions (or over quarters of a shorter record).

:func:`order_track` resamples every channel at a whole number of samples per pinion
revolution (at least the original rate), so each fundamental period holds the same
samples; the result is a record at constant speed ``speed_hz``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from pydiag.core.errors import MeasurementError, UsageError
from pydiag.core.measurement import Measurement
from pydiag.gear.kinematics import GearKinematics
from pydiag.signal.angle import (EDGE_BANDWIDTHS, angular_resample, extend_linearly,
                                 tacho_revolutions, tone_phase)
from pydiag.signal.spectra import amplitude_spectrum

SPEED_METHODS = ("auto", "mesh", "tacho", "nominal")
#: The mesh search spans the nominal speed +- this fraction (induction-motor slip is a
#: few per cent; the nominal speed may be the synchronous one).
SPEED_SEARCH = 0.08
#: ... and within this many pinion orders at the mesh (module docstring).
SIDEBAND_FRACTION = 0.45
#: Mesh harmonics used by the search (fewer when the sample rate cannot hold them).
SEARCH_HARMONICS = 4
BLOCK_REVS = 10
#: "auto" follows the mesh phase only in a record longer than the two ends the
#: demodulation loses (EDGE_BANDWIDTHS / bandwidth each, :func:`tone_phase`) plus this
#: many fundamental periods; a shorter one is taken at the nominal speed, and says so.
MIN_TRACKED_PERIODS = 4
FALSE_ALARM = 1e-3


@dataclass(frozen=True)
class SpeedSettings:
    """How to find the speed: ``method`` (see :data:`SPEED_METHODS`), the ``channel``
    searched for mesh lines (default: the first), the ``tacho`` channel and its
    ``pulses_per_rev``."""

    method: str = "auto"
    channel: str | None = None
    tacho: str | None = None
    pulses_per_rev: int = 1

    def __post_init__(self) -> None:
        if self.method not in SPEED_METHODS:
            raise UsageError(f"speed method must be one of {SPEED_METHODS}, got {self.method!r}")
        if self.pulses_per_rev < 1:
            raise UsageError(f"pulses per revolution must be >= 1, got {self.pulses_per_rev}")


class SpeedSource(str, Enum):
    """Where a speed estimate comes from."""

    TACHO = "tacho"
    MESH = "mesh"
    NOMINAL = "nominal"  # not measured: the record is taken at the nominal speed


@dataclass(frozen=True)
class SpeedEstimate:
    """Attributes:
        speed_hz: mean pinion speed over the record
        variation_pct: speed range over the record, % of the mean (see module docstring)
        method: how, in words: "tacho", "mesh harmonic <h>" or "nominal" (and why)
        nominal_hz: the nominal speed the estimate started from
        revolutions: pinion revolutions at every sample (not serialised)
        valid: (first, last) sample where the angle is measured, not extrapolated
        source: where it comes from (:class:`SpeedSource`)
    """

    speed_hz: float
    variation_pct: float
    method: str
    nominal_hz: float
    revolutions: np.ndarray = dataclasses.field(repr=False, compare=False)
    valid: tuple[int, int] = (0, -1)
    source: SpeedSource = SpeedSource.MESH

    def to_dict(self) -> dict:
        return {"speed_hz": self.speed_hz, "speed_variation_pct": self.variation_pct,
                "speed_method": self.method, "nominal_speed_hz": self.nominal_hz}


def _variation_pct(revs: np.ndarray, sample_rate_hz: float, mean_hz: float) -> float:
    total = revs[-1] - revs[0]
    n_blocks = max(int(total // BLOCK_REVS), 4) if total >= 4 else 1
    if n_blocks < 2:
        return 0.0
    edges = np.searchsorted(revs, revs[0] + total * np.arange(n_blocks + 1) / n_blocks)
    edges = np.clip(edges, 0, revs.size - 1)
    speeds = [(revs[b] - revs[a]) / ((b - a) / sample_rate_hz)
              for a, b in zip(edges[:-1], edges[1:]) if b > a]
    return float(100 * (max(speeds) - min(speeds)) / mean_hz)


def _mean_speed(revs: np.ndarray, sample_rate_hz: float) -> float:
    n = np.arange(revs.size)
    return float(np.polyfit(n, revs, 1)[0] * sample_rate_hz)


def _demodulation_band_hz(kinematics: GearKinematics) -> float:
    """Half-width of the band around a mesh harmonic: half the slower shaft's speed, so no
    shaft-order sideband enters it (module docstring)."""
    return 0.5 * min(kinematics.f_pinion_hz, kinematics.f_gear_hz)


def mesh_speed(signal: np.ndarray, sample_rate_hz: float, kinematics: GearKinematics,
               search: float = SPEED_SEARCH) -> SpeedEstimate:
    """Pinion speed from the mesh harmonics of ``signal`` around the nominal
    ``kinematics.f_pinion_hz`` (see the module docstring)."""
    x = np.asarray(signal, dtype=float)
    n_pinion, nominal_hz = kinematics.n_pinion, kinematics.f_pinion_hz
    freqs, amp = amplitude_spectrum(x, sample_rate_hz, "hann")
    bin_hz = freqs[1]
    search = min(search, SIDEBAND_FRACTION / n_pinion)
    low, high = nominal_hz * (1 - search), nominal_hz * (1 + search)
    n_harm = min(SEARCH_HARMONICS, int(0.45 * sample_rate_hz // (n_pinion * high)))
    if n_harm < 1:
        raise MeasurementError(f"the mesh frequency near {n_pinion * nominal_hz:.1f} Hz is above "
                               f"the record's Nyquist frequency ({sample_rate_hz / 2:.1f} Hz): "
                               "check --rpm, --teeth and the sample rate")
    grid = np.arange(low, high, bin_hz / (4 * n_harm * n_pinion))
    score = np.zeros(grid.size)
    floors = []
    for h in range(1, n_harm + 1):
        band = (freqs >= h * n_pinion * low) & (freqs <= h * n_pinion * high)
        floor = float(np.median(amp[band]))
        floors.append((floor, int(np.count_nonzero(band))))
        score += np.log(np.interp(h * n_pinion * grid, freqs, amp) / max(floor, 1e-300) + 1e-12)
    coarse = float(grid[np.argmax(score)])
    ratios = [np.interp(h * n_pinion * coarse, freqs, amp) / max(f, 1e-300)
              for h, (f, _) in zip(range(1, n_harm + 1), floors)]
    best = int(np.argmax(ratios))
    h, ratio, n_bins = best + 1, float(ratios[best]), floors[best][1]
    needed = math.sqrt(math.log(max(n_bins, 2) / FALSE_ALARM) / math.log(2))
    if ratio < needed:
        raise MeasurementError(
            f"no mesh line stands out near {n_pinion * nominal_hz:.1f} Hz (+-{100 * search:g} %): "
            f"the best is {ratio:.1f}x its band's median, chance reaches {needed:.1f}x; check "
            "--rpm and --teeth, or give a tacho channel (--tacho)")
    band = _demodulation_band_hz(dataclasses.replace(kinematics, f_pinion_hz=coarse))
    index, cycles = tone_phase(x, sample_rate_hz, h * n_pinion * coarse, band)
    revs = extend_linearly(index, cycles / (h * n_pinion), x.size)
    inner = (np.arange(x.size) >= index[0]) & (np.arange(x.size) <= index[-1])
    mean = _mean_speed(revs[inner], sample_rate_hz)
    return SpeedEstimate(mean, _variation_pct(revs[inner], sample_rate_hz, mean),
                         f"mesh harmonic {h}", nominal_hz, revs,
                         (int(np.ceil(index[0])), int(np.floor(index[-1]))))


def estimate_speed(measurement: Measurement, kinematics: GearKinematics,
                   settings: SpeedSettings = SpeedSettings(),
                   tracked_s: float | None = None) -> SpeedEstimate:
    """The pinion speed of ``measurement`` around ``kinematics.f_pinion_hz`` (nominal).

    ``settings.method``: "auto" (the tacho when one is named, else the mesh), "mesh",
    "tacho" or "nominal"; see :class:`SpeedSettings`. ``tracked_s``: under "auto", the
    shortest stretch worth following beyond the demodulation's edges (default
    :data:`MIN_TRACKED_PERIODS` fundamental periods: what a fit needs).
    """
    method, channel, tacho = settings.method, settings.channel, settings.tacho
    pulses_per_rev = settings.pulses_per_rev
    if tracked_s is None:
        tracked_s = MIN_TRACKED_PERIODS * kinematics.period_s
    short = measurement.duration_s < (2 * EDGE_BANDWIDTHS / _demodulation_band_hz(kinematics)
                                      + tracked_s)
    if method == "auto":
        method = "tacho" if tacho else "nominal" if short else "mesh"
    fs, nominal = measurement.sample_rate_hz, kinematics.f_pinion_hz
    if method == "tacho":
        if not tacho:
            raise UsageError("the tacho method needs a tacho channel (--tacho NAME)")
        if tacho not in measurement.channels:
            raise MeasurementError(f"tacho channel '{tacho}' not in the measurement; it has: "
                                   f"{', '.join(measurement.channels)}")
        revs = tacho_revolutions(measurement.channels[tacho], pulses_per_rev)
        mean = _mean_speed(revs, fs)
        return SpeedEstimate(mean, _variation_pct(revs, fs, mean), "tacho", nominal, revs,
                             source=SpeedSource.TACHO)
    if method == "nominal":
        revs = np.arange(measurement.n_samples) * (nominal / fs)
        why = (f" (auto: a record of {measurement.duration_s:.3g} s is too short to follow the "
               "mesh phase)" if settings.method == "auto" else "")
        return SpeedEstimate(nominal, 0.0, "nominal" + why, nominal, revs,
                             source=SpeedSource.NOMINAL)
    names = [c for c in measurement.channels if c != tacho]
    channel = channel or names[0]
    if channel not in measurement.channels:
        raise MeasurementError(f"channel '{channel}' not in the measurement")
    return mesh_speed(measurement.channels[channel], fs, kinematics)


def track_revolutions(measurement: Measurement, estimate: SpeedEstimate, samples_per_rev: int,
                      ratio: float = 1.0, drop: tuple[str, ...] = (), shaft: str = "pinion"
                      ) -> tuple[list[str], list[np.ndarray], int]:
    """(channel names, signals, revolutions): every channel but ``drop`` resampled at
    ``samples_per_rev`` per revolution of a shaft that turns ``ratio`` times per pinion
    turn, over that shaft's whole revolutions where the angle was measured (not
    extrapolated)."""
    a, b = estimate.valid
    revs = estimate.revolutions[a:(b + 1) or None] * ratio
    first = math.ceil(revs[0])
    n_revs = int(math.floor(revs[-1] - first))
    if n_revs < 1:
        raise MeasurementError(f"record of {measurement.duration_s:.3g} s holds no whole {shaft} "
                               "revolution")
    names = [c for c in measurement.channels if c not in drop]
    tracked = angular_resample([measurement.channels[c][a:(b + 1) or None] for c in names], revs,
                               samples_per_rev, first, n_revs)
    return names, tracked, n_revs


def order_track(measurement: Measurement, estimate: SpeedEstimate,
                drop: tuple[str, ...] = ()) -> Measurement:
    """``measurement`` resampled at a whole number of samples per pinion revolution (at
    least the original rate), over its whole revolutions, without the ``drop`` channels.

    The result is the record at constant speed ``estimate.speed_hz``: its sample rate is
    samples_per_rev x speed_hz. Metadata gain the speed estimate and ``order_tracking``.
    """
    if estimate.source is SpeedSource.NOMINAL:
        channels = {c: v for c, v in measurement.channels.items() if c not in drop}
        return Measurement(channels, measurement.sample_rate_hz,
                           {**measurement.metadata, **estimate.to_dict()})
    fs = measurement.sample_rate_hz
    samples_per_rev = int(math.ceil(fs / estimate.speed_hz))
    names, tracked, n_revs = track_revolutions(measurement, estimate, samples_per_rev, drop=drop)
    meta = {**measurement.metadata, **estimate.to_dict(),
            "order_tracking": {"samples_per_rev": samples_per_rev, "revolutions": n_revs,
                               "original_sample_rate_hz": fs}}
    return Measurement(dict(zip(names, tracked)), samples_per_rev * estimate.speed_hz, meta)
