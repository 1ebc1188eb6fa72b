"""A measurement record: synchronously sampled sensor channels and facts about them."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pydiag.core.errors import MeasurementError


@dataclass
class Measurement:
    """Synchronously sampled sensor channels.

    Attributes:
        channels: channel name -> samples (signal units: SI, e.g. m/s2 or m)
        sample_rate_hz: samples per second, the same for every channel
        metadata: free-form facts about the record (operating point, source, SNR...)
    """

    channels: dict[str, np.ndarray]
    sample_rate_hz: float
    metadata: dict = field(default_factory=dict)

    @property
    def n_samples(self) -> int:
        return len(next(iter(self.channels.values())))

    @property
    def duration_s(self) -> float:
        return self.n_samples / self.sample_rate_hz

    def select(self, names: list[str]) -> "Measurement":
        missing = [n for n in names if n not in self.channels]
        if missing:
            raise MeasurementError(f"column(s) {', '.join(missing)} not in the measurement; it has: "
                                   f"{', '.join(self.channels)}")
        return Measurement({n: self.channels[n] for n in names}, self.sample_rate_hz,
                           dict(self.metadata))
