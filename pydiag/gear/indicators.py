"""Gear condition indicators of a record: the speed found, the record order-tracked to one
shaft, its time-synchronous average, and the indicators of :mod:`pydiag.signal.condition`.

NA4 and NB4 are trend indicators: they divide by the variance of a reference record (a
``baseline``, healthy or first of a trend). Without one, the record is its own reference
and they reduce to the kurtosis of the residual and of the envelope; the report says
which reference was used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pydiag.core.errors import MeasurementError, UsageError
from pydiag.core.measurement import Measurement
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.speed import SpeedEstimate, SpeedSettings, estimate_speed
from pydiag.gear.tracking import track_revolutions
from pydiag.signal.condition import (TrendReference, TsaSignals, raw_indicators,
                                     synchronous_average, tsa_indicators, tsa_signals)

#: The shafts a TSA can follow.
SHAFTS = ("pinion", "gear")
#: Under speed "auto", a record is order-tracked when it holds this many shaft revolutions
#: beyond the ends the demodulation loses; a shorter one is taken at the nominal speed.
MIN_TRACKED_REVOLUTIONS = 20
#: Names of the indicators, in report order.
INDICATORS = ("rms", "peak", "crest_factor", "kurtosis", "fm0", "fm4", "na4", "nb4", "m6a",
              "m8a", "er", "ser")


@dataclass(frozen=True)
class IndicatorReport:
    """Plain-data result of :func:`condition_indicators`.

    Attributes:
        indicators: channel -> indicator name -> value (nan where undefined)
        shaft: the shaft the TSA follows; mesh_order: its teeth
        samples_per_rev: TSA length; revolutions: revolutions averaged
        speed: the pinion speed estimate
        reference: what NA4 and NB4 divide by ("baseline FILE" or "this record")
    """

    indicators: dict[str, dict[str, float]]
    shaft: str
    mesh_order: int
    samples_per_rev: int
    revolutions: int
    speed: SpeedEstimate
    reference: str

    def to_dict(self) -> dict:
        """``{"indicators": {name: value}}`` for one channel, ``{"indicators": {channel:
        {name: value}}}`` for several, and what the TSA was made of."""
        clean = {c: {k: finite_or_none(v) for k, v in t.items()}
                 for c, t in self.indicators.items()}
        table = next(iter(clean.values())) if len(clean) == 1 else clean
        return {"indicators": table, "shaft": self.shaft, "mesh_order": self.mesh_order,
                "samples_per_rev": self.samples_per_rev, "revolutions": self.revolutions,
                "trend_reference": self.reference, **self.speed.to_dict()}

    def columns(self) -> dict[str, float]:
        """Flat columns for a table: ``name`` for one channel, ``channel:name`` for several."""
        if len(self.indicators) == 1:
            return dict(next(iter(self.indicators.values())))
        return {f"{c}:{k}": v for c, table in self.indicators.items() for k, v in table.items()}


def _shaft_geometry(kinematics: GearKinematics, shaft: str) -> tuple[int, float]:
    """(teeth on the shaft, shaft revolutions per pinion revolution)."""
    if shaft not in SHAFTS:
        raise UsageError(f"shaft must be one of {', '.join(SHAFTS)}, got {shaft!r}")
    if shaft == "pinion":
        return kinematics.n_pinion, 1.0
    return kinematics.n_gear, kinematics.n_pinion / kinematics.n_gear


def synchronous_signals(measurement: Measurement, kinematics: GearKinematics,
                        estimate: SpeedEstimate, shaft: str = "pinion",
                        drop: tuple[str, ...] = ()) -> tuple[dict[str, TsaSignals], int, int]:
    """Channel -> TSA signals of ``shaft``, with (samples per revolution, revolutions)."""
    teeth, ratio = _shaft_geometry(kinematics, shaft)
    fs = measurement.sample_rate_hz
    shaft_hz = estimate.speed_hz * ratio
    samples_per_rev = int(math.ceil(fs / shaft_hz))
    if teeth * 1.5 >= samples_per_rev / 2:
        raise MeasurementError(f"the {shaft} mesh (order {teeth}) and its sidebands need a sample "
                               f"rate above {3 * teeth * shaft_hz:.5g} Hz; the record has {fs:g}")
    names, tracked, n_revs = track_revolutions(measurement, estimate, samples_per_rev, ratio,
                                               drop, shaft)
    signals = {c: tsa_signals(synchronous_average(x, samples_per_rev), teeth)
               for c, x in zip(names, tracked)}
    return signals, samples_per_rev, n_revs


def condition_indicators(measurement: Measurement, kinematics: GearKinematics,
                         speed: SpeedSettings = SpeedSettings(), shaft: str = "pinion",
                         baseline: Measurement | None = None) -> IndicatorReport:
    """The indicators of every channel of ``measurement`` (the tacho excluded) on the TSA
    of ``shaft``, NA4/NB4 against ``baseline`` (same channels) or the record itself.

    ``kinematics`` gives the teeth and the nominal speed the speed search starts from.
    """
    drop = (speed.tacho,) if speed.tacho else ()
    _, ratio = _shaft_geometry(kinematics, shaft)
    tracked_s = MIN_TRACKED_REVOLUTIONS / (kinematics.f_pinion_hz * ratio)
    estimate = estimate_speed(measurement, kinematics, speed, tracked_s)
    signals, samples_per_rev, n_revs = synchronous_signals(measurement, kinematics, estimate,
                                                           shaft, drop)
    references = {c: TrendReference() for c in signals}
    described = "this record (NA4 and NB4 are the kurtosis of the residual and the envelope)"
    if baseline is not None:
        missing = [c for c in signals if c not in baseline.channels]
        if missing:
            raise MeasurementError(f"the baseline has no channel {', '.join(missing)}; it has: "
                                   f"{', '.join(baseline.channels)}")
        base_estimate = estimate_speed(baseline, kinematics, speed, tracked_s)
        base, _, _ = synchronous_signals(baseline, kinematics, base_estimate, shaft,
                                         tuple(c for c in baseline.channels if c not in signals))
        references = {c: TrendReference.of(base[c]) for c in signals}
        described = f"baseline {baseline.metadata.get('file', '(in memory)')}"
    table = {}
    for c, s in signals.items():
        values = {**raw_indicators(measurement.channels[c]), **tsa_indicators(s, references[c])}
        table[c] = {name: float(values[name]) for name in INDICATORS}
    return IndicatorReport(table, shaft, _shaft_geometry(kinematics, shaft)[0], samples_per_rev,
                           n_revs, estimate, described)


def finite_or_none(value: float) -> float | None:
    """JSON has no NaN: an undefined indicator is null."""
    return float(value) if np.isfinite(value) else None
