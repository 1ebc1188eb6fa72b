"""A machine's components a fault is named on (its gears, bearings and shafts), and what
a judge says of one (:mod:`pydiag.gear.component_judge`, :mod:`pydiag.gear.bearing_judge`)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pydiag.gear.faults import CHANGED, GOOD, NOT_JUDGED
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import finite_or_none
from pydiag.gear.stage_judge import MIN_SPREAD_DB

#: Who said a component's state (``ComponentVerdict.judge``): the indicators, the healthy
#: model, or both, agreeing that it is faulty or that it is good (:func:`judged_by_model`).
BY_INDICATORS, BY_MODEL, BY_BOTH = "indicators", "model", "both"


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
    to (dB), and how sure: the largest change over that threshold (None: not judged);
    ``judge``: who said the state, the record's "indicators" against the baselines', the
    machine's healthy "model", or "both" (:func:`judged_by_model`)."""

    component: Component
    state: str
    evidence: dict[str, float] = field(default_factory=dict)
    threshold_db: float | None = None
    margin: float | None = None
    reason: str = ""
    judge: str = BY_INDICATORS

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
                "reason": self.reason, "judge": self.judge}


@dataclass(frozen=True)
class ModelChange:
    """The model's verdict on one effect of a stage of the machine's healthy model: what a
    record asks of it, held out (:mod:`pydiag.loop.own_changes`).

    ``z``: its held-out z on the record, ``baseline_z`` on the baseline, against the
    healthy fit; ``repeat_rise``: the RMS of the healthy repeats' rises of it over the
    baseline's (None: no repeat); ``margin``: the record's rise over what it is held to
    (``K_SPREAD`` times ``repeat_rise``, never below a z of 1; nan without a repeat);
    ``values``: each sizing parameter's healthy value and the record's fitted one, named as
    the model names them; ``part``: the part of the stage its largest growth sizes,
    ``components``: the machine's components that part is (a mesh: both gears);
    ``fault``: the state it names them in when changed (``Effect.fault``); ``covers``:
    every component a change of the effect could name (any of its parts); ``beaten_by``:
    the larger change that claims its lines too, which names them instead (its
    :attr:`label`; "" for none);
    ``explained``: the share of the residual on its lines of the held-out half its fit
    removes (:attr:`pydiag.loop.results.HeldOut.explained`)."""

    stage: str
    effect: str
    z: float
    baseline_z: float
    repeat_rise: float | None
    margin: float
    values: dict[str, tuple[float, float]]
    part: str | None
    components: tuple[str, ...]
    fault: str = CHANGED
    covers: tuple[str, ...] = ()
    beaten_by: str = ""
    explained: float = math.nan

    @property
    def label(self) -> str:
        """The change as another's ``beaten_by`` names it: its effect on its stage."""
        return f"{self.effect} on {self.stage}"

    @property
    def changed(self) -> bool:
        """Whether the record asks for other values beyond the healthy repeats' spread,
        no larger change claims its lines (``beaten_by``), and the record's own lines are
        better predicted with them: a fit that leaves more residual on its lines of the
        held-out half than the healthy values (``explained`` at most 0; nan: not known)
        took its z from other lines, which are another effect's."""
        return self.margin > 1.0 and not self.beaten_by and not self.explained <= 0

    def to_dict(self) -> dict:
        return {"stage": self.stage, "effect": self.effect, "changed": self.changed,
                "margin": finite_or_none(self.margin), "z": finite_or_none(self.z),
                "baseline_z": finite_or_none(self.baseline_z),
                "repeat_rise": finite_or_none(self.repeat_rise),
                "values": {k: [finite_or_none(a), finite_or_none(b)]
                           for k, (a, b) in self.values.items()},
                "part": self.part, "components": list(self.components), "fault": self.fault,
                "covers": list(self.covers), "beaten_by": self.beaten_by or None,
                "explained": finite_or_none(self.explained)}


#: A component the indicators call good with a change of at least this share of its
#: threshold is asked of the model too (:func:`asked_of_model`): a fault the model's
#: held-out fit may see before the indicators' thresholds do.
ASK_MODEL = 0.5


def asked_of_model(verdicts: Sequence[ComponentVerdict]) -> set[str]:
    """The names of the components whose verdict the model is asked for: those the
    indicators find faulty, or good with a margin of at least :data:`ASK_MODEL`."""
    return {v.component.name for v in verdicts
            if v.faulty or (v.margin is not None and v.margin >= ASK_MODEL)}


def judged_by_model(verdicts: Sequence[ComponentVerdict], changes: Sequence[ModelChange]
                    ) -> tuple[ComponentVerdict, ...]:
    """``verdicts`` (the indicators') with the healthy model's verdict where it has one.

    A component an effect of the model could name (``ModelChange.covers``; the effect
    held to healthy repeats) and a change names (the largest margin's) is in that change's
    fault, or, where the model's word is only "changed", in the indicators' if they name
    one (an eccentric gear by its shaft's swing). A covered component no change names
    keeps the indicators' state: an effect of the healthy model covers a part without
    sizing every fault of it (a shaft's orders with its 1x held off see no imbalance). The
    judge is "both" where the two agree that it is faulty or that it is good. Where the
    indicators name a bearing's fault (its race or ball, read from its defect lines in the
    envelope, which another bearing's comb may share) and the covering effect of that very
    fault, tried held out on the record, has its lines claimed by another bearing's
    change, the model's "good" stands: the lines are that bearing's. Where the try is only
    within the repeats, or its lines a gear's or a shaft's change, the indicators' word
    stands: the envelope of what does not repeat with the machine, which no synchronous
    change makes, is the more sensitive reading of a bearing. A component no effect
    covers keeps the indicators' verdict: what the model lacks, it cannot judge.
    A gear the model alone names whose shaft's gear of the other stage the indicators find
    faulty keeps the indicators' "good": the model's stages are not coupled, so a fault of
    one gear of a shaft, which moves the shaft and with it the other stage's mesh, is
    fitted as well by a change of the other gear; the indicators tell the two apart by each
    mesh's own sidebands (:mod:`pydiag.gear.gear_sidebands`).
    The indicators' measures stay in the evidence, their word in the reason."""
    out = _joined(verdicts, changes)
    mates = {v.component.name: v for v in verdicts}
    for i, v in enumerate(out):
        mate = _shaft_mate(v, verdicts)
        if v.judge == BY_MODEL and v.faulty and mate is not None and mates[mate].faulty:
            out[i] = dataclasses.replace(
                mates[v.component.name], evidence=v.evidence,
                reason=f"{v.reason}; but the indicators find {mate} on its shaft faulty and "
                "not it, and the model's uncoupled stages do not tell a change of one gear "
                "of a shaft from one of the other: the indicators' word stands")
    return tuple(sorted(out, key=lambda v: not v.faulty))


def _shaft_mate(v: ComponentVerdict, verdicts: Sequence[ComponentVerdict]) -> str | None:
    """The name of the gear of another stage on ``v``'s gear's shaft (None: none, or
    ``v`` is no gear)."""
    c = v.component
    if c.kind != "gear":
        return None
    return next((o.component.name for o in verdicts if o.component.kind == "gear"
                 and o.component.shaft == c.shaft and o.component.stage != c.stage), None)


def _joined(verdicts: Sequence[ComponentVerdict], changes: Sequence[ModelChange]
            ) -> list[ComponentVerdict]:
    """Each of ``verdicts`` with the model's word (:func:`judged_by_model`), in order."""
    held = [c for c in changes if math.isfinite(c.margin)]
    bearings = {v.component.name for v in verdicts if v.component.kind == "bearing"}
    out = []
    for v in verdicts:
        name = v.component.name
        covering = [c for c in held if name in c.covers]
        if not covering:
            out.append(v)
            continue
        named = [c for c in covering if c.changed and name in c.components]
        said = max(named or covering, key=lambda c: c.margin)
        evidence = {**v.evidence, f"model {said.stage} {said.effect}": said.margin}
        indicators = (f"the indicators: {v.state}" + (f" ({v.reason})" if v.reason else "")
                      if v.state != GOOD else "")
        if named:
            sizes = ", ".join(f"{k.rsplit('.', 1)[-1]} {a:.3g} -> {b:.3g}"
                              for k, (a, b) in said.values.items())
            model = (f"the healthy model's {said.effect} on {said.stage} asks for other "
                     f"values ({sizes}), {said.margin:.2f} x what the healthy repeats allow")
            state = (v.state if said.fault == CHANGED and v.faulty and v.state != CHANGED
                     else said.fault)
            out.append(ComponentVerdict(v.component, state, evidence, v.threshold_db,
                                        said.margin, "; ".join(filter(None, (model, indicators))),
                                        BY_BOTH if v.faulty else BY_MODEL))
            continue
        tested = [c for c in covering if v.component.kind == "bearing" and v.faulty
                  and c.fault == v.state]
        if tested:  # the indicators' very fault, tried by the model: its word is that try's
            said = max(tested, key=lambda c: c.margin)
            evidence = {**v.evidence, f"model {said.stage} {said.effect}": said.margin}
        if tested and _claimed_by_a_bearing(said, held, name, bearings):
            model = (f"the healthy model's {said.effect} on {said.stage}, the fault the "
                     f"indicators name, " + (f"names {', '.join(said.components)}"
                                             if said.changed else _not_named(said)))
            out.append(ComponentVerdict(v.component, GOOD, evidence, v.threshold_db,
                                        None if said.changed else said.margin,
                                        f"{model}; the indicators: {v.state}"
                                        + (f" ({v.reason})" if v.reason else ""), BY_MODEL))
            continue
        model = (f"the healthy model's {said.effect} on {said.stage} "
                 + ((f"names {', '.join(said.components)}" if said.components else
                     "names no part: no parameter that sizes a fault grew more than another fell")
                    if said.changed else _not_named(said)))
        if v.faulty:
            out.append(dataclasses.replace(v, evidence=evidence,
                                           reason=f"{v.reason}; {model}" if v.reason else model))
        else:
            out.append(ComponentVerdict(
                v.component, GOOD, evidence, v.threshold_db,
                None if said.changed else said.margin, model,
                BY_BOTH if v.state == GOOD else BY_MODEL))
    return out


def _claimed_by_a_bearing(change: ModelChange, changes: Sequence[ModelChange], name: str,
                          bearings: set[str]) -> bool:
    """Whether the lines of ``change`` (a try of the fault the indicators name on the
    bearing ``name``) are claimed by a larger change that names other bearings only
    (``bearings``: the machine's bearings' names)."""
    winner = next((c for c in changes if c.label == change.beaten_by), None)
    return (winner is not None and bool(winner.components) and name not in winner.components
            and set(winner.components) <= bearings)


def _not_named(change: ModelChange) -> str:
    """Why a change that is not a fault (:attr:`ModelChange.changed`) names nothing."""
    if change.beaten_by:
        return f"has its lines claimed by {change.beaten_by} ({change.margin:.2f} x)"
    if change.margin > 1:
        return (f"does not predict its own lines better on the held-out half "
                f"({change.margin:.2f} x)")
    return f"is within the healthy repeats ({change.margin:.2f} x)"


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
