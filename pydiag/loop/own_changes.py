"""The model's verdict on a record against the machine's healthy model: which of its
effects the record asks for at other values, and which effects it lacks the record needs
(those asked of), held out, beside healthy repeats of the baseline, and the part of the
machine each change sizes. :func:`fit_healthy` makes the healthy model once (plain data,
:class:`HealthyModel`, kept by the caller); :func:`record_changes` tries a record against
it.

The healthy model is the machine's own model fitted to a healthy baseline (with the
effects the loop gave it there, if any). Each effect a stage of it has is polished on half of a
record's periods from the healthy values and scored on the other half
(:func:`~pydiag.loop.machine_discover.refit_own_effects`): its held-out z says whether the
record asks for other values. On a real machine two healthy records differ by more than a
record's halves do (a z of a healthy repeat is not standard normal: bench/CHANGELOG.md), so
a record's rise of z over the baseline's own is held, as a component's change is
(:mod:`pydiag.gear.component_judge`), to ``K_SPREAD`` times the healthy repeats' rise of
the same effect on the same stage (their RMS), never below a z of 1. The effect's sizing
parameter that grew most, unless another fell by more, names the part
(:attr:`pydiag.gear.effect.Effect.parts`): a deeper pinion modulation is its pinion,
larger orders of the pinion shaft are that shaft; the effect names the fault where it
can (``Effect.fault``: a softer tooth chipped or broken, a shaft's risen orders an
imbalance or a bend), else "changed". An effect the healthy model lacks is tried the same
way, from off (:func:`~pydiag.loop.machine_discover.discover_machine`), where it could
name a component a record is asked about (:func:`lacking_tries`), on the baseline and the
repeats the first time a record asks for it (:func:`with_lacking`). Of two changes whose
held-out fits claim one line, the larger names it (:func:`_settled`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass

from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import FitProblem
from pydiag.gear.component import ModelChange, components
from pydiag.gear.effect import (GEAR, GEAR_BEARING, GEAR_SHAFT, MESH, OTHER_SHAFT, PINION,
                               PINION_BEARING, PINION_SHAFT, Effect)
from pydiag.gear.machine import Machine
from pydiag.gear.stage_judge import K_SPREAD
from pydiag.loop.compare import compare
from pydiag.loop.effect_fit import EFFECT_REFIT
from pydiag.loop.machine_discover import discover_machine, refit_own_effects
from pydiag.loop.machine_discover import lacking as stage_lacking
from pydiag.loop.machine_fit import compare_machine
from pydiag.loop.machine_model import MachineModel
from pydiag.loop.results import Suggestion

#: A rise of held-out z is never held to less than this times ``K_SPREAD``: a z of noise
#: alone is about 1.
MIN_RISE = 1.0


@dataclass(frozen=True)
class HealthyModel:
    """The machine's healthy model as its verdict uses it: its fit to the baseline
    (``parameters``, ``false_alarm_rate``), and the held-out z of each (stage, effect) on
    the baseline (``baseline_z``) and on each healthy repeat (``repeat_z``), seen through
    that fit, what a record's are held to; ``lacking``: the effects it lacks that a record
    may be asked about; ``held``: the (stage, effect) of those already tried on the
    baseline and every repeat (a record's try is held to those rows; the others are tried
    there when a record first asks for them: :func:`with_lacking`). Plain data, so that it
    is fitted once and kept (the run history)."""

    parameters: dict[str, float]
    false_alarm_rate: float
    baseline_z: dict[tuple[str, str], float]
    repeat_z: tuple[dict[tuple[str, str], float], ...]
    lacking: tuple[str, ...] = ()
    held: tuple[tuple[str, str], ...] = ()

    def to_dict(self) -> dict:
        def rows(z: dict[tuple[str, str], float]) -> list:
            return [[stage, effect, value] for (stage, effect), value in z.items()]
        return {"parameters": self.parameters, "false_alarm_rate": self.false_alarm_rate,
                "baseline_z": rows(self.baseline_z),
                "repeat_z": [rows(z) for z in self.repeat_z], "lacking": list(self.lacking),
                "held": [list(pair) for pair in self.held]}

    @classmethod
    def from_dict(cls, data: dict) -> "HealthyModel":
        def z(rows: list) -> dict[tuple[str, str], float]:
            return {(str(stage), str(effect)): float(value) for stage, effect, value in rows}
        return cls({str(k): float(v) for k, v in data["parameters"].items()},
                   float(data["false_alarm_rate"]), z(data["baseline_z"]),
                   tuple(z(rows) for rows in data["repeat_z"]),
                   tuple(str(k) for k in data["lacking"]),
                   tuple((str(stage), str(effect)) for stage, effect in data.get("held", [])))


def fit_healthy(machine: Machine, model: MachineModel, baseline: FitProblem,
                repeats: Sequence[FitProblem], estimator: FaultEstimator,
                effect_estimator: FaultEstimator | None = None, lacking: Sequence[str] = ()
                ) -> HealthyModel:
    """The machine's model with the effects its file gives (the healthy model) fitted once
    to the ``baseline`` problem (:func:`~pydiag.loop.machine_fit.compare_machine`, from the
    file's ``[start]``), and the rows a record's are held to: each of its effects refitted
    held out (``effect_estimator``, default :data:`~pydiag.loop.effect_fit.EFFECT_REFIT`'s)
    on the baseline and on each healthy repeat, seen through that fit (none without a
    repeat: the model then judges nothing, its fit a record's start). Every problem is of
    the same model (:func:`~pydiag.loop.machine_fit.machine_problem`).

    ``lacking``: catalogue effects the healthy model does not have that a record may be
    asked about (the first question: a bearing's strikes, a tooth fault where the model has
    none); each is tried on the baseline and the repeats when a record first asks for it
    (:func:`with_lacking`), not here: a record asks about the components the indicators
    see change, a few of the machine's, and a healthy one about none."""
    refit = effect_estimator or FaultEstimator(**EFFECT_REFIT)
    fitted = compare_machine(baseline, model, estimator, refit, start=machine.fit_start())
    healthy = HealthyModel(dict(fitted.parameters), fitted.false_alarm_rate, {}, (),
                           tuple(lacking))
    # the rows a record's are held to; of no repeat, none (nothing to hold them to)
    own = _rows(healthy, machine, model, baseline, refit, None, set()) if repeats else []
    again = [_rows(healthy, machine, model, problem, refit, None, set())
             for problem in repeats]
    return dataclasses.replace(healthy, baseline_z=_z_of(own),
                               repeat_z=tuple(_z_of(rows) for rows in again))


def lacking_tries(healthy: HealthyModel, machine: Machine, model: MachineModel,
                  asked: Collection[str] | None) -> set[tuple[str, str]]:
    """The (stage, effect) of ``healthy.lacking`` a record is asked for: on every stage
    that can have the effect, where it could name one of the components ``asked`` (their
    names; None: wherever it can be)."""
    wanted = None if asked is None else set(asked)
    out = set()
    for k, stage in enumerate(machine.stages):
        catalogue = stage_lacking(machine, model, k)
        for key in healthy.lacking:
            if key in catalogue and (wanted is None or wanted & set(
                    effect_covers(machine, k, catalogue[key]))):
                out.add((stage.name, key))
    return out


def with_lacking(healthy: HealthyModel, machine: Machine, model: MachineModel,
                 baseline: FitProblem, repeats: Sequence[FitProblem],
                 tries: Collection[tuple[str, str]], effect_model: Callable[[Machine], str],
                 effect_estimator: FaultEstimator | None = None) -> HealthyModel:
    """``healthy`` with the rows a record's ``tries`` (:func:`lacking_tries`) are held to:
    each (stage, effect) not yet in ``healthy.held`` tried held out on the ``baseline``
    and each of the ``repeats`` problems (of the records it was fitted to and held to),
    as a record's is (:func:`~pydiag.loop.machine_discover.discover_machine`, on the models
    ``effect_model`` builds); ``healthy`` itself when every one is there. A try's rows do
    not depend on which others are tried with it, so a model grown record by record holds
    the same rows as one that tried them all at once."""
    missing = set(tries) - set(healthy.held)
    if not missing:
        return healthy
    refit = effect_estimator or FaultEstimator(**EFFECT_REFIT)
    rows = [_rows(healthy, machine, model, problem, refit, effect_model, missing, own=False)
            for problem in (baseline, *repeats)]
    return dataclasses.replace(
        healthy, baseline_z={**healthy.baseline_z, **_z_of(rows[0])},
        repeat_z=tuple({**z, **_z_of(r)} for z, r in zip(healthy.repeat_z, rows[1:])),
        held=tuple(sorted(set(healthy.held) | missing)))


def record_changes(healthy: HealthyModel, machine: Machine, model: MachineModel,
                   problem: FitProblem, effect_estimator: FaultEstimator | None = None,
                   effect_model: Callable[[Machine], str] | None = None,
                   asked: Collection[str] | None = None) -> list[ModelChange]:
    """The model's verdict on the record of ``problem`` (:func:`own_changes`): each effect
    of the ``healthy`` model, and each it lacks (:func:`lacking_tries`) whose rows on its
    baseline and repeats it holds (:func:`with_lacking`), tried held out on the record as
    there. ``asked``: the names of the components the model is asked about (those the
    indicators found changed, or near it); an effect it lacks is tried only on a stage
    where it could name one of them (None: everywhere). A lacking effect's try is the
    costly part of a record's verdict, and one that could name only components whose every
    measure stayed well within the healthy spread would, held to the same repeats, name
    none of them either but by chance."""
    tries = lacking_tries(healthy, machine, model, asked) & set(healthy.held)
    rows = _rows(healthy, machine, model, problem,
                 effect_estimator or FaultEstimator(**EFFECT_REFIT), effect_model, tries)
    return _changes(machine, model, healthy.parameters, rows, healthy.baseline_z,
                    list(healthy.repeat_z))


def _rows(healthy: HealthyModel, machine: Machine, model: MachineModel, problem: FitProblem,
          refit: FaultEstimator, effect_model: Callable[[Machine], str] | None,
          tries: set[tuple[str, str]], own: bool = True) -> list[Suggestion]:
    """Every effect of the healthy model (``own``), and those of ``healthy.lacking`` named
    in ``tries`` (stage, effect), tried held out on ``problem`` seen through the healthy
    fit."""
    if tries and effect_model is None:
        raise ValueError("trying lacking effects needs effect_model")
    seen = compare(problem, None, healthy.false_alarm_rate, parameters=healthy.parameters)
    seen = dataclasses.replace(seen, fit_error=seen.error)
    name = [s.name for s in machine.stages]
    new = discover_machine(problem, machine, model, seen, effect_model, refit,
                           sorted({key for _, key in tries}),
                           where=lambda k, key: (name[k], key) in tries) if tries else []
    return (refit_own_effects(problem, machine, model, seen, refit) if own else []) + new


def _z_of(rows: Sequence[Suggestion]) -> dict[tuple[str, str], float]:
    """Each tried row's held-out z, by (stage, effect)."""
    return {(r.stage, r.effect): r.held_out.z for r in rows
            if r.held_out is not None and r.held_out.tried}


def own_changes(machine: Machine, model: MachineModel, healthy: Mapping[str, float],
                record: Sequence[Suggestion], baseline: Sequence[Suggestion],
                repeats: Sequence[Sequence[Suggestion]] = (),
                k_spread: float = K_SPREAD) -> list[ModelChange]:
    """Every effect tried on ``record`` (rows of
    :func:`~pydiag.loop.machine_discover.refit_own_effects` against the ``healthy`` fit's
    values) as a :class:`~pydiag.gear.component.ModelChange`, beside the same rows of the
    ``baseline`` the healthy model was fitted to and of each healthy repeat of it
    (``repeats``); the largest margin first. A row not tried on the record (nothing of it
    to fit) is left out; one not tried on the baseline or a repeat (no line of it stood
    out there) counts as a z of 0 there: an output bearing's strikes, which no healthy
    record shows."""
    return _changes(machine, model, healthy, record, _z_of(baseline),
                    [_z_of(rows) for rows in repeats], k_spread)


def _changes(machine: Machine, model: MachineModel, healthy: Mapping[str, float],
             record: Sequence[Suggestion], own: Mapping[tuple[str, str], float],
             again: Sequence[Mapping[tuple[str, str], float]], k_spread: float = K_SPREAD
             ) -> list[ModelChange]:
    """:func:`own_changes` with the baseline's and the repeats' rows as their z."""
    stages = [s.name for s in machine.stages]
    catalogue: dict[int, dict] = {}  # each stage's effects as the model names them
    out = []
    claimed: dict[tuple[str, str], set[str]] = {}
    for row in record:
        h = row.held_out
        if h is None or not h.tried or row.stage not in stages:
            continue
        key = (row.stage, row.effect)
        k = stages.index(row.stage)
        if k not in catalogue:
            catalogue[k] = model.stage_effects(k)
        effect = catalogue[k][row.effect]
        base_z = own.get(key, 0.0)
        rises = [z.get(key, 0.0) - base_z for z in again]  # not tried there: nothing stood out
        repeat_rise = math.sqrt(sum(r * r for r in rises) / len(rises)) if rises else None
        held_to = k_spread * max(repeat_rise, MIN_RISE) if repeat_rise is not None \
            else math.nan
        off = {p.name: p.off for p in effect.parameters}  # an effect the model lacks
        values = {name: (healthy.get(name, off.get(name, math.nan)), h.parameters[name])
                  for name, _ in effect.parts if name in h.parameters}
        part = effect.part_of({name: after - before for name, (before, after) in values.items()})
        covers = effect_covers(machine, k, effect)
        out.append(ModelChange(row.stage, row.effect, h.z, base_z, repeat_rise,
                               (h.z - base_z) / held_to, values, part,
                               part_components(machine, k, part), effect.fault_of(values),
                               covers, explained=h.explained))
        claimed[key] = set(h.claimed)
    out.sort(key=lambda c: -c.margin if math.isfinite(c.margin) else math.inf)
    return _settled(out, claimed)


def _settled(changes: list[ModelChange], claimed: dict[tuple[str, str], set[str]]
             ) -> list[ModelChange]:
    """``changes`` (the largest margin first), each change that claims a line a larger
    change claims too (``claimed``: the non-synchronous lines each held-out fit claimed,
    :attr:`~pydiag.loop.results.HeldOut.claimed`) beaten by it: the record's lines are one
    component's, the one that explains them most (an input bearing's outer race, whose
    strikes' lines are every other line of the intermediate bearing's at half its
    speed), as competing effects are settled by their z in the loop
    (:mod:`pydiag.loop.competition`)."""
    out: list[ModelChange] = []
    for c in changes:
        lines = claimed.get((c.stage, c.effect), set())
        winner = next((w for w in out if w.changed and lines
                       & claimed.get((w.stage, w.effect), set())), None)
        out.append(c if winner is None or not c.changed else dataclasses.replace(
            c, beaten_by=winner.label))
    return out


def effect_covers(machine: Machine, stage: int, effect: Effect) -> tuple[str, ...]:
    """The names of ``machine``'s components a change of ``effect`` on stage ``stage``
    could name: those of any of its parts (:attr:`~pydiag.gear.effect.Effect.parts`)."""
    return tuple(dict.fromkeys(name for _, part in effect.parts
                               for name in part_components(machine, stage, part)))


def part_components(machine: Machine, stage: int, part: str | None) -> tuple[str, ...]:
    """The names of ``machine``'s components that ``part`` of stage ``stage`` is: its
    pinion, its gear, both (the mesh), the shaft of either or the other shaft its
    other-shaft effect models, the bearings of the pinion's or the gear's shaft; none for
    no part."""
    name = machine.stages[stage].name
    roles = {PINION: ("pinion",), GEAR: ("gear",), MESH: ("pinion", "gear")}.get(part, ())
    other = machine.other_shaft(stage)
    shaft = {PINION_SHAFT: machine.shafts[stage], GEAR_SHAFT: machine.shafts[stage + 1],
             OTHER_SHAFT: None if other is None else machine.shafts[other]}.get(part)
    bearing_shaft = {PINION_BEARING: machine.shafts[stage],
                     GEAR_BEARING: machine.shafts[stage + 1]}.get(part)
    every = components(machine)
    return tuple(c.name for c in every
                 if (c.kind == "gear" and c.stage == name and c.role in roles)
                 or (c.kind == "shaft" and c.name == shaft)
                 or (c.kind == "bearing" and c.shaft == bearing_shaft))
