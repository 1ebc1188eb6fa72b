"""Which baselines can judge a record of a machine: taken at its operating point (a
residual's energy grows with the speed: another operating point is a change by itself),
its channels read at the same levels (volts at a sensitivity against volts without one
differ by the sensitivity)."""

from __future__ import annotations

from collections.abc import Sequence

from pydiag.core.errors import MeasurementError
from pydiag.gear.machine_indicators import MachineRecord

#: A baseline is at a record's operating point when its input speed lies within this share
#: of the record's nominal input speed (:func:`at_speed`): a motor slips a few percent
#: under load, and a machine's operating speeds lie further apart. The load is not told
#: by a record: which baselines share it is the user's to say.
BASELINE_SPEED_SHARE = 0.05


def at_speed(baselines: Sequence[MachineRecord], nominal_hz: float) -> list[MachineRecord]:
    """The ``baselines`` whose input speed is within :data:`BASELINE_SPEED_SHARE` of the
    nominal input speed ``nominal_hz``."""
    return [b for b in baselines
            if abs(b.speed.speed_hz / nominal_hz - 1) <= BASELINE_SPEED_SHARE]


def check_comparable(record: MachineRecord, baselines: Sequence[MachineRecord]) -> None:
    """MeasurementError unless each baseline can judge ``record``: its input speed within
    :data:`BASELINE_SPEED_SHARE` of the record's (a residual's energy grows with the
    speed: another operating point is a change by itself), its channels read at the same
    levels (volts at a sensitivity against volts without one differ by the sensitivity)."""
    for b in baselines:
        share = abs(b.speed.speed_hz / record.speed.speed_hz - 1)
        if share > BASELINE_SPEED_SHARE:
            raise MeasurementError(
                f"the baseline {b.file} runs at {b.speed.speed_hz:.4g} Hz, {100 * share:.0f} % "
                f"from the record's {record.speed.speed_hz:.4g} Hz: a baseline judges records "
                f"within {100 * BASELINE_SPEED_SHARE:g} % of its speed (give one of the "
                "record's operating point)")
        if record.units is None:
            continue
        if b.units is None:
            raise MeasurementError(f"the baseline {b.file} was kept without its channels' "
                                   "units: keep it again (pydiag baseline)")
        for channel, level in record.units.items():
            if channel in b.units and b.units[channel] != level:
                raise MeasurementError(
                    f"channel {channel} is read as {level} in the record and as "
                    f"{b.units[channel]} in the baseline {b.file}: give both the same unit "
                    "and sensitivity")
