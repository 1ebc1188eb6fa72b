"""A machine's components a fault is named on (its gears, bearings and shafts), and what
a judge says of one (:mod:`pydiag.gear.component_judge`, :mod:`pydiag.gear.bearing_judge`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import finite_or_none
from pydiag.gear.stage_judge import MIN_SPREAD_DB

GOOD, CHANGED, NOT_JUDGED = "good", "changed", "not judged"


@dataclass(frozen=True)
class Component:
    """A part of a machine a fault is named on: a gear (on its shaft, with its teeth, in
    its stage, as the stage's "pinion" or "gear"), a bearing (by its name, on its shaft)
    or a shaft (by its name)."""

    kind: str
    name: str
    shaft: str
    teeth: int | None = None
    stage: str | None = None
    role: str | None = None


@dataclass(frozen=True)
class ComponentVerdict:
    """One component judged: its ``state`` ("good", the fault, "changed" where something
    changed and the fault is not told, "not judged" and why), the changes it was judged by
    (``evidence``, dB, or FM4 for a gear's impulsiveness, and a size where one is read:
    ``swing_1x_deg``, the input's angle once a turn of a swinging gear's shaft, degrees of
    the input's turn), the threshold they were held
    to (dB), and how sure: the largest change over that threshold (None: not judged)."""

    component: Component
    state: str
    evidence: dict[str, float] = field(default_factory=dict)
    threshold_db: float | None = None
    margin: float | None = None
    reason: str = ""

    @property
    def faulty(self) -> bool:
        return self.state not in (GOOD, NOT_JUDGED)

    def to_dict(self) -> dict:
        c = self.component
        out = {"kind": c.kind, "name": c.name, "shaft": c.shaft}
        if c.kind == "gear":
            out.update(teeth=c.teeth, stage=c.stage, role=c.role)
        return {**out, "state": self.state,
                "evidence": {k: finite_or_none(v) for k, v in self.evidence.items()},
                "threshold_db": self.threshold_db, "margin": finite_or_none(self.margin),
                "reason": self.reason}


@dataclass(frozen=True)
class ModelChange:
    """The model's verdict on one effect of a stage of the machine's healthy model: what a
    record asks of it, held out (:mod:`pydiag.loop.own_changes`).

    ``z``: its held-out z on the record, ``baseline_z`` on the baseline, against the
    healthy fit; ``repeat_rise``: the RMS of the healthy repeats' rises of it over the
    baseline's (None: no repeat); ``margin``: the record's rise over what it is held to
    (``K_SPREAD`` times ``repeat_rise``, never below a z of 1; nan without a repeat);
    ``values``: each sizing parameter's healthy value and the record's fitted one, named as
    the model names them; ``part``: the part of the stage its largest change sizes,
    ``components``: the machine's components that part is (a mesh: both gears)."""

    stage: str
    effect: str
    z: float
    baseline_z: float
    repeat_rise: float | None
    margin: float
    values: dict[str, tuple[float, float]]
    part: str | None
    components: tuple[str, ...]

    @property
    def changed(self) -> bool:
        """Whether the record asks for other values beyond the healthy repeats' spread."""
        return self.margin > 1.0

    def to_dict(self) -> dict:
        return {"stage": self.stage, "effect": self.effect, "changed": self.changed,
                "margin": finite_or_none(self.margin), "z": finite_or_none(self.z),
                "baseline_z": finite_or_none(self.baseline_z),
                "repeat_rise": finite_or_none(self.repeat_rise),
                "values": {k: [finite_or_none(a), finite_or_none(b)]
                           for k, (a, b) in self.values.items()},
                "part": self.part, "components": list(self.components)}


def components(machine: Machine) -> tuple[Component, ...]:
    """Every gear (stage by stage, pinion then gear), bearing and shaft of ``machine``."""
    gears = []
    for k, s in enumerate(machine.stages):
        gears += [Component("gear", f"{s.pinion_teeth}T pinion of {s.name}", machine.shafts[k],
                            s.pinion_teeth, s.name, "pinion"),
                  Component("gear", f"{s.gear_teeth}T gear of {s.name}", machine.shafts[k + 1],
                            s.gear_teeth, s.name, "gear")]
    bearings = [Component("bearing", b.name, b.shaft) for b in machine.bearings]
    return tuple(gears + bearings + [Component("shaft", name, name) for name in machine.shafts])


def finite_rms(diffs: list[float], floor: float = MIN_SPREAD_DB) -> float:
    """The RMS of the finite ``diffs``, never below ``floor`` (``floor`` when none is)."""
    finite = [d for d in diffs if math.isfinite(d)]
    return max(float(np.sqrt(np.mean(np.square(finite)))) if finite else 0.0, floor)


def finite_mean(values: list[float]) -> float:
    """The mean of the finite ``values`` (nan when none is)."""
    finite = [v for v in values if math.isfinite(v)]
    return float(np.mean(finite)) if finite else math.nan
