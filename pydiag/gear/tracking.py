"""A record order-tracked to the shaft angle :mod:`pydiag.gear.speed` found.

:func:`order_track` resamples every channel at a whole number of samples per pinion
revolution (at least the original rate), so each fundamental period holds the same
samples; the result is a record at constant speed ``speed_hz``. :func:`track_revolutions`
does it for any shaft turning at a fixed ratio to the pinion (a TSA of that shaft). The
record's channels are upsampled for it (:func:`pydiag.signal.angle.upsample`); a record
tracked at several shafts (every shaft and stage of a machine) is upsampled once
(:func:`upsampled_record`), the same at every shaft.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pydiag.core.errors import MeasurementError
from pydiag.core.measurement import Measurement
from pydiag.gear.speed import SpeedEstimate, SpeedSource
from pydiag.signal.angle import angular_resample, upsample


@dataclass(frozen=True)
class Upsampled:
    """A record's channels where its angle was measured (``valid``, the speed estimate's),
    upsampled once (:func:`pydiag.signal.angle.upsample`) for tracking at several shafts."""

    valid: tuple[int, int]
    channels: dict[str, np.ndarray]


def upsampled_record(measurement: Measurement, estimate: SpeedEstimate,
                     drop: tuple[str, ...] = ()) -> Upsampled:
    """Every channel of ``measurement`` but ``drop``, where ``estimate`` measured the angle,
    upsampled: :func:`track_revolutions` and :func:`order_track` read it at any shaft whose
    estimate is ``estimate`` at a ratio (the same valid samples)."""
    a, b = estimate.valid
    return Upsampled(estimate.valid, {c: upsample(v[a:(b + 1) or None])
                                      for c, v in measurement.channels.items() if c not in drop})


def track_revolutions(measurement: Measurement, estimate: SpeedEstimate, samples_per_rev: int,
                      ratio: float = 1.0, drop: tuple[str, ...] = (), shaft: str = "pinion",
                      upsampled: Upsampled | None = None
                      ) -> tuple[list[str], list[np.ndarray], int]:
    """(channel names, signals, revolutions): every channel but ``drop`` resampled at
    ``samples_per_rev`` per revolution of a shaft that turns ``ratio`` times per pinion
    turn, over that shaft's whole revolutions where the angle was measured (not
    extrapolated); ``upsampled``: :func:`upsampled_record` of the record, when made once."""
    a, b = estimate.valid
    revs = estimate.revolutions[a:(b + 1) or None] * ratio
    first = math.ceil(revs[0])
    n_revs = int(math.floor(revs[-1] - first))
    if n_revs < 1:
        raise MeasurementError(f"record of {measurement.duration_s:.3g} s holds no whole {shaft} "
                               "revolution")
    names = [c for c in measurement.channels if c not in drop]
    if upsampled is not None and (upsampled.valid != estimate.valid
                                  or not set(names) <= set(upsampled.channels)):
        raise ValueError("the upsampled record is not this record's at this speed estimate")
    ups = None if upsampled is None else [upsampled.channels[c] for c in names]
    tracked = angular_resample([measurement.channels[c][a:(b + 1) or None] for c in names], revs,
                               samples_per_rev, first, n_revs, ups)
    return names, tracked, n_revs


def order_track(measurement: Measurement, estimate: SpeedEstimate,
                drop: tuple[str, ...] = (), upsampled: Upsampled | None = None) -> Measurement:
    """``measurement`` resampled at a whole number of samples per pinion revolution (at
    least the original rate), over its whole revolutions, without the ``drop`` channels
    (``upsampled``: :func:`track_revolutions`').

    The result is the record at constant speed ``estimate.speed_hz``: its sample rate is
    samples_per_rev x speed_hz. Metadata gain the speed estimate and ``order_tracking``.
    """
    if estimate.source is SpeedSource.NOMINAL:
        channels = {c: v for c, v in measurement.channels.items() if c not in drop}
        return Measurement(channels, measurement.sample_rate_hz,
                           {**measurement.metadata, **estimate.to_dict()})
    fs = measurement.sample_rate_hz
    samples_per_rev = int(math.ceil(fs / estimate.speed_hz))
    names, tracked, n_revs = track_revolutions(measurement, estimate, samples_per_rev, drop=drop,
                                               upsampled=upsampled)
    meta = {**measurement.metadata, **estimate.to_dict(),
            "order_tracking": {"samples_per_rev": samples_per_rev, "revolutions": n_revs,
                               "original_sample_rate_hz": fs}}
    return Measurement(dict(zip(names, tracked)), samples_per_rev * estimate.speed_hz, meta)
