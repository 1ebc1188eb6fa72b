"""A record's report through its machine (``indicators --machine``): every shaft's TSA and,
against the machine's healthy baselines, every stage (:mod:`pydiag.gear.stage_judge`) and
every component (:mod:`pydiag.gear.component_judge`) judged."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pydiag.core.measurement import Measurement
from pydiag.gear.component_judge import ComponentVerdict, judge_components
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import MachineRecord, finite_or_none, machine_record
from pydiag.gear.speed import SpeedSettings
from pydiag.gear.stage_judge import StageVerdict, judge_stages


@dataclass(frozen=True)
class MachineReport:
    """What ``indicators --machine`` says of a record: the speed, every shaft's TSA, and
    (with baselines) every stage's verdict and the healthy spread it was judged by, and
    every component's (:mod:`pydiag.gear.component_judge`)."""

    machine: Machine
    record: MachineRecord
    baselines: tuple[str, ...]
    stages: tuple[StageVerdict, ...]
    spread_db: float | None
    swing_change_db: dict[str, float | None]
    components: tuple[ComponentVerdict, ...] = ()

    def to_dict(self) -> dict:
        """Plain data for JSON: ``speed_hz`` the input shaft's; ``shafts`` and ``stages`` in
        the machine's order; ``stages`` empty without a baseline."""
        return {
            "machine": self.machine.name, **self.record.speed.to_dict(),
            "shafts": [{"name": s.shaft, "speed_hz": s.speed_hz, "teeth": list(s.teeth),
                        "revolutions": s.revolutions,
                        "residual_energy": s.residual_energy,
                        "indicators": {c: {k: finite_or_none(v) for k, v in t.items()}
                                       for c, t in s.indicators.items()},
                        "swing_deg": s.swing_deg,
                        "swing_change_db": self.swing_change_db.get(s.shaft)}
                       for s in self.record.shafts],
            "baselines": list(self.baselines), "healthy_spread_db": self.spread_db,
            "stages": [v.to_dict() for v in self.stages],
            "components": [c.to_dict() for c in self.components],
            "severity_scale": ("change against the baselines" if self.baselines else
                               "none: without a baseline no stage is judged")}


def machine_report(measurement: Measurement, machine: Machine, speed: SpeedSettings,
                   input_hz: float, baselines: Sequence[MachineRecord] = ()) -> MachineReport:
    """Every shaft of ``measurement`` and, with ``baselines`` (healthy records as
    :func:`machine_record` sees them), every stage judged."""
    record = machine_record(measurement, machine, speed, input_hz)
    base = list(baselines)
    verdicts, spread = judge_stages(machine, record, base) if base else ([], None)
    judged = judge_components(machine, record, base, verdicts) if base else ()
    return MachineReport(machine, record, tuple(b.file for b in base), tuple(verdicts), spread,
                         swing_changes(record, base), judged)


def swing_changes(record: MachineRecord, baselines: Sequence[MachineRecord]
                  ) -> dict[str, float | None]:
    """Each shaft's swing in ``record`` against the mean of the ``baselines``' (dB); None
    where it or every baseline's is not measured."""
    out: dict[str, float | None] = {}
    for shaft in record.shafts:
        base = [s.swing_deg for b in baselines for s in b.shafts
                if s.shaft == shaft.shaft and s.swing_deg is not None]
        mean = float(np.mean(base)) if base else 0.0
        ok = shaft.swing_deg is not None and shaft.swing_deg > 0 and mean > 0
        out[shaft.shaft] = 20 * math.log10(shaft.swing_deg / mean) if ok else None
    return out
