"""A peak of the residual spectrum (measurement over model), named by the kinematic map:
what compare finds and what an effect's hint narrows its bounds by."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class Peak:
    """An unexplained line: its channel, frequency, amplitudes (measured, model and the
    excess R - S), the kinematic line it falls on (``family`` "unexplained" when none)
    and its share of the unexplained energy."""

    channel: str
    freq_hz: float
    amplitude: float  # excess over the model, R - S
    measured: float
    model: float
    family: str  # "unexplained" when no kinematic line matches
    order: int | None
    label: str
    energy_fraction: float
