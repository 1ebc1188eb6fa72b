"""What is said of a record through its machine, one type for ``indicators --machine``,
``diagnose --machine`` and ``batch --machine``: the input speed, every shaft's TSA, each
stage (judged against the machine's healthy baselines, :mod:`pydiag.gear.stage_judge`,
and fitted by a model where one was), and every component
(:mod:`pydiag.gear.component_judge`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from pydiag.core.measurement import Measurement
from pydiag.gear.component import ComponentVerdict, ModelChange
from pydiag.gear.component_judge import judge_components
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import MachineRecord, finite_or_none, machine_record
from pydiag.gear.speed import SpeedEstimate, SpeedSettings
from pydiag.gear.stage_judge import StageVerdict, judge_stages

#: What a stage's severity is judged on (the JSON's ``severity_scale``), by whether the
#: stages were judged against baselines and fitted by a model.
SCALE_BASELINES = "change against the baselines, classified on the paper's simulated scale"
SCALE_PAPER = "the paper's simulated scale (no baseline)"
SCALE_INDICATORS = "change against the baselines"
SCALE_NONE = "none: without a baseline no stage is judged"


class StageFit(Protocol):
    """What a stage's report takes of a model's fit of the stage
    (:class:`pydiag.diagnose.diagnosis.Diagnosis` is one)."""

    fault_mode: str
    severity: str
    tooth_contrast: float | None
    warnings: list[str]

    @property
    def parameters(self) -> dict[str, float]: ...

    @property
    def error(self) -> float: ...

    @property
    def explained(self) -> bool: ...

    def to_dict(self) -> dict: ...


@dataclass(frozen=True)
class StageReport:
    """One stage of a record: what the baselines say of it (``verdict``, None without
    baselines), a model's fit of it (``fit``, None where none was fitted), and the two
    read together (:func:`stage_report`): ``fault_mode``, ``severity``, ``suspect``."""

    name: str
    pinion_teeth: int
    gear_teeth: int
    pinion_shaft_hz: float
    gear_shaft_hz: float
    mesh_hz: float
    verdict: StageVerdict | None
    fit: StageFit | None
    fault_mode: str
    severity: str
    suspect: str | None
    #: what the names of the stage's fault parameters begin with in ``fit`` (a machine's
    #: model: ``"<stage>."``; a pair's: none)
    prefix: str = ""

    def to_dict(self) -> dict:
        params = self.fit.parameters if self.fit is not None else {}
        return {"name": self.name, "pinion_teeth": self.pinion_teeth,
                "gear_teeth": self.gear_teeth, "pinion_shaft_hz": self.pinion_shaft_hz,
                "gear_shaft_hz": self.gear_shaft_hz, "mesh_hz": self.mesh_hz,
                "fault_mode": self.fault_mode, "severity": self.severity,
                "suspect": self.suspect,
                "tooth_contrast": None if self.fit is None else self.fit.tooth_contrast,
                "transmission_error": {k: params[self.prefix + k] for k in ("f_ate", "f_dte")
                                       if self.prefix + k in params},
                "model": None if self.fit is None else self.fit.to_dict(),
                "baseline": None if self.verdict is None else self.verdict.to_dict()}


def stage_report(name: str, pinion_teeth: int, gear_teeth: int, pinion_shaft_hz: float,
                 verdict: StageVerdict | None, fit: StageFit | None = None,
                 suspect: str | None = None, prefix: str = "") -> StageReport:
    """Stage ``name`` read from the baselines' ``verdict`` and the model's ``fit``: a stage
    that did not change is healthy whatever the model says of it; one that changed keeps
    the model's fault mode and severity ("changed" where the model finds nothing it can
    classify, or no model was fitted), and the verdict's suspect. Without a verdict the
    model's classes stand, with ``suspect`` (the caller's reading of the record)."""
    fault_mode, severity = (fit.fault_mode, fit.severity) if fit is not None else (
        "healthy", "none")
    if verdict is not None:
        suspect = verdict.suspect
        if not verdict.changed:
            fault_mode, severity = "healthy", "none"
        elif fault_mode == "healthy":
            fault_mode, severity = "changed", "unknown"
    return StageReport(name, pinion_teeth, gear_teeth, pinion_shaft_hz,
                       pinion_shaft_hz * pinion_teeth / gear_teeth,
                       pinion_shaft_hz * pinion_teeth, verdict, fit, fault_mode, severity,
                       suspect, prefix)


@dataclass(frozen=True)
class MachineReport:
    """A record through its machine: the input ``speed``; with baselines, every shaft's TSA
    (``record``), the healthy spread, every shaft's swing against theirs and every
    component judged (:mod:`pydiag.gear.component_judge`); ``stages``, each judged or
    fitted (none: neither); ``model_changes``: the model's verdict on each effect of the
    machine's healthy model, fitted to the first baseline and held to the others
    (:mod:`pydiag.loop.own_changes`), the largest first."""

    machine: Machine
    speed: SpeedEstimate
    stages: tuple[StageReport, ...]
    baselines: tuple[str, ...] = ()
    spread_db: float | None = None
    components: tuple[ComponentVerdict, ...] = ()
    record: MachineRecord | None = None
    swing_change_db: dict[str, float | None] = field(default_factory=dict)
    model_changes: tuple[ModelChange, ...] = ()

    @property
    def fitted(self) -> bool:
        """Whether a model fitted the stages."""
        return any(s.fit is not None for s in self.stages)

    @property
    def severity_scale(self) -> str:
        if self.baselines:
            return SCALE_BASELINES if self.fitted else SCALE_INDICATORS
        return SCALE_PAPER if self.fitted else SCALE_NONE

    @property
    def warnings(self) -> list[str]:
        """The speed's warning, at the input shaft, then each stage's fit's (which leave the
        speed to the machine)."""
        speed = self.speed.warning()
        return ([speed] if speed else []) + [f"{stage.name}: {w}" for stage in self.stages
                                             if stage.fit is not None
                                             for w in stage.fit.warnings]

    def to_dict(self) -> dict:
        """Plain data for JSON: ``speed_hz`` the input shaft's; ``shafts`` (where the TSA
        was taken) and ``stages`` in the machine's order."""
        shafts = [] if self.record is None else [
            {"name": s.shaft, "speed_hz": s.speed_hz, "teeth": list(s.teeth),
             "revolutions": s.revolutions, "residual_energy": s.residual_energy,
             "indicators": {c: {k: finite_or_none(v) for k, v in t.items()}
                            for c, t in s.indicators.items()},
             "swing_deg": s.swing_deg, "swing_change_db": self.swing_change_db.get(s.shaft)}
            for s in self.record.shafts]
        return {"machine": self.machine.name, **self.speed.to_dict(), "shafts": shafts,
                "stages": [s.to_dict() for s in self.stages],
                "components": [c.to_dict() for c in self.components],
                "model_changes": [c.to_dict() for c in self.model_changes],
                "baselines": list(self.baselines), "healthy_spread_db": self.spread_db,
                "severity_scale": self.severity_scale}


def judged_stages(machine: Machine, record: MachineRecord,
                  verdicts: Sequence[StageVerdict]) -> tuple[StageReport, ...]:
    """Each stage of ``record`` as its baselines' ``verdicts`` say (no model)."""
    return tuple(stage_report(stage.name, stage.pinion_teeth, stage.gear_teeth,
                              record.speed.speed_hz * float(machine.shaft_ratio(k)), v)
                 for k, (stage, v) in enumerate(zip(machine.stages, verdicts)))


def machine_report(measurement: Measurement, machine: Machine, speed: SpeedSettings,
                   input_hz: float, baselines: Sequence[MachineRecord] = ()) -> MachineReport:
    """Every shaft of ``measurement`` and, with ``baselines`` (healthy records as
    :func:`machine_record` sees them), every stage and component judged."""
    record = machine_record(measurement, machine, speed, input_hz)
    return judged_report(machine, record, baselines)


def judged_report(machine: Machine, record: MachineRecord,
                  baselines: Sequence[MachineRecord]) -> MachineReport:
    """``record`` (every shaft's TSA) judged against ``baselines``: its stages and
    components (none without baselines), the shafts' swings."""
    base = list(baselines)
    verdicts, spread = judge_stages(machine, record, base) if base else ([], None)
    judged = judge_components(machine, record, base, verdicts) if base else ()
    return MachineReport(machine, record.speed, judged_stages(machine, record, verdicts),
                         tuple(b.file for b in base), spread, judged, record,
                         swing_changes(record, base))


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
