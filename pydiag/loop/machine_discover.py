"""Effects tried held out on a machine's own model, stage by stage: discover (every effect
a stage can have and does not have yet, ranked) and compare's validation (the effects
each stage's residual points to).

For each stage, the model's problem is seen from that stage's shafts, its own parameters
free and the other stages' held at the machine's fit
(:func:`~pydiag.loop.machine_fit.stage_view`), with the catalogue named for it
(:meth:`~pydiag.loop.machine_model.MachineModel.stage_effects`); each effect the stage
lacks is fitted on half of the periods on the model with it on that stage and scored on
the other half (:func:`pydiag.loop.held_out.held_out`), whatever its score on the
residual (compare tries only those its residual points to). The models are built here,
one after the other; the fits run side by side, one per core, as
:func:`pydiag.loop.discover.discover` runs a pair's, the longest first. Competitors are
settled stage by stage: two effects on one stage claim the same lines, the same effect on
two stages does not.

Validation (:func:`validate_machine`) tries on each stage what
:func:`pydiag.loop.validate.validate` would try there, the fits of every stage side by
side in the same way, then lets it judge each stage with them.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from typing import Callable

from fmu_build import ModelicaBuildError as BuildError

from pydiag.core.errors import PydiagError, UsageError
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import FitProblem
from pydiag.gear.effect import Effect
from pydiag.gear.effects import EFFECTS
from pydiag.gear.machine import Machine, StageEffect
from pydiag.loop.builds import each_built
from pydiag.loop.compare import compare
from pydiag.loop.competition import mark_settled, settle
from pydiag.loop.discover import (discovery_cost, failed_row, held_out_row, shared_halves,
                                  side_by_side)
from pydiag.loop.effect_fit import EFFECT_REFIT, in_model
from pydiag.loop.machine_fit import stage_view
from pydiag.loop.machine_model import MachineModel
from pydiag.loop.stage_catalogue import nothing_to_fit, on_a_stage
from pydiag.loop.results import Comparison, Status, Suggestion
from pydiag.loop.validate import effects_to_fit, validate


@dataclasses.dataclass(frozen=True)
class _Stage:
    """What every effect tried on one stage shares: its view of the problem, the
    comparison seen from it, the held-out halves."""

    view: FitProblem
    seen: Comparison
    memo: dict


def _try_on_stage(stage: _Stage, model: MachineModel, index: int, name: str, key: str,
                  fmu: str, estimator: FaultEstimator) -> Suggestion:
    """:func:`~pydiag.loop.discover.held_out_row` of the effect ``key`` on stage ``index``
    (called ``name``). Takes the key, not the effect (whose hints are closures): it runs in
    a worker process."""
    return held_out_row(stage.view, stage.seen, model.stage_effects(index)[key], fmu,
                        estimator, stage.memo, name)


def lacking(machine: Machine, model: MachineModel, stage: int) -> dict[str, Effect]:
    """The catalogue as stage ``stage`` of ``model`` has it
    (:meth:`~pydiag.loop.machine_model.MachineModel.stage_effects`) but the effects the
    machine file already gives it, whatever parameters of theirs it holds off."""
    has = machine.effect_keys(stage)
    return {key: e for key, e in model.stage_effects(stage).items() if key not in has}


def check_effects(effects: list[str] | None) -> None:
    """A UsageError naming those of ``effects`` no stage of a machine's model can have
    (:func:`~pydiag.loop.stage_catalogue.on_a_stage`), before any work."""
    allowed = [key for key, effect in EFFECTS.items() if on_a_stage(effect)]
    unknown = [key for key in effects or () if key not in allowed]
    if unknown:
        raise UsageError(f"not an effect a stage of a machine's model can have: "
                         f"{', '.join(unknown)} ({', '.join(allowed)})")


def discover_machine(problem: FitProblem, machine: Machine, model: MachineModel,
                     base: Comparison, effect_model: Callable[[Machine], str],
                     estimator: FaultEstimator | None = None, effects: list[str] | None = None,
                     progress: Callable[[Suggestion], None] | None = None,
                     where: Callable[[int, str], bool] | None = None) -> list[Suggestion]:
    """Every effect of ``effects`` (default: the catalogue) that a stage can have and lacks,
    tried on every stage of ``machine``'s model (``problem``, fitted as ``base``), ranked by
    held-out z (module docstring). ``effect_model``: the FMU of a machine (the machine with
    one more effect); ``estimator``: each effect's fit (default
    :data:`~pydiag.loop.effect_fit.EFFECT_REFIT`), its ``n_workers`` the cores the fits
    share; ``progress`` gets each row as it is done; ``where(stage, key)``: whether to try
    the effect ``key`` on that stage (default: every one; one left out has no row)."""
    check_effects(effects)
    estimator = estimator or FaultEstimator(**EFFECT_REFIT)
    catalogues = [lacking(machine, model, k) for k in range(len(machine.stages))]
    views = [stage_view(problem, machine, model, k, base.parameters)
             for k in range(len(machine.stages))]
    tasks = [(k, key) for k, catalogue in enumerate(catalogues) for key, effect in
             catalogue.items() if (not effects or key in effects)
             and (where is None or where(k, key)) and not in_model(views[k], effect)]
    tasks.sort(key=lambda task: -discovery_cost(catalogues[task[0]][task[1]]))
    found: list[Suggestion] = []
    buildable = []
    for k, key in tasks:
        if why := nothing_to_fit(machine, k, key):
            found.append(Suggestion(key, status=Status.NOT_TRIED,
                                    message=f"{Status.NOT_TRIED.value}: {why}",
                                    n_parameters=len(EFFECTS[key].parameters),
                                    stage=machine.stages[k].name))
            if progress:
                progress(found[-1])
        else:
            buildable.append((k, key))
    fmus: dict[tuple[int, str], str] = {}
    # built here, side by side, before any fit: two workers must not build one model
    for task, built in zip(buildable, each_built(functools.partial(
            _effect_fmu, machine, effect_model), buildable, estimator.n_workers)):
        if isinstance(built, Suggestion):
            found.append(built)
            if progress:
                progress(built)
        else:
            fmus[task] = built
    tasks = [task for task in tasks if task in fmus]
    stages = {}
    for k in sorted({k for k, _ in tasks}):
        seen = compare(views[k], None, base.false_alarm_rate, base.n_periods,
                       parameters=base.parameters, effects=catalogues[k])
        keys = [key for j, key in tasks if j == k]
        stages[k] = _Stage(views[k], seen, shared_halves(views[k], seen, keys, estimator,
                                                         catalogues[k]))
    name = [s.name for s in machine.stages]
    found += side_by_side(lambda task, one: (_try_on_stage, (
        stages[task[0]], model, task[0], name[task[0]], task[1], fmus[task], one)), tasks,
        estimator, progress)
    for k, stage in stages.items():
        mine = [d for d in found if d.stage == name[k]]
        mark_settled(mine, settle(
            {d.effect: d.held_out for d in mine if d.held_out is not None},
            {s.effect: s.competing for s in stage.seen.suggested_effects},
            {d.effect for d in mine if catalogues[k][d.effect].reshapes_base}))
    found.sort(key=lambda d: math.inf if math.isnan(d.z) else -d.z)  # those not tried last
    return found


def validate_machine(problem: FitProblem, machine: Machine, model: MachineModel,
                     comparison: Comparison, effect_model: Callable[[Machine], str],
                     estimator: FaultEstimator | None = None,
                     progress: Callable[[str], None] | None = None,
                     every_synchronous: bool = False) -> Comparison:
    """``comparison`` (of ``problem``, the machine's model at its fit) with the effects
    its residual points to on each stage tried held out (:func:`pydiag.loop.validate.
    validate`, on :func:`~pydiag.loop.machine_fit.stage_view`), every stage's
    suggestions in one list, each with its stage; ``effect_model``: the FMU of a machine
    (the machine with one more effect). The fits of every stage run side by side, one a
    core (module docstring); ``progress`` gets each as it starts, as "effect on stage";
    ``every_synchronous``: :func:`~pydiag.loop.validate.validate`'s."""
    estimator = estimator or FaultEstimator(**EFFECT_REFIT)
    catalogues = [lacking(machine, model, k) for k in range(len(machine.stages))]
    views, seens, wanted = {}, {}, []
    for k, catalogue in enumerate(catalogues):
        views[k] = stage_view(problem, machine, model, k, comparison.parameters)
        seens[k] = compare(views[k], None, comparison.false_alarm_rate, comparison.n_periods,
                           parameters=comparison.parameters, effects=catalogue)
        wanted += [(k, key) for key in effects_to_fit(views[k], seens[k], effects=catalogue,
                                                      every_synchronous=every_synchronous)]
    # built here, side by side, before any fit: two workers must not build one model; one
    # that fails is built again by validate, which says why
    fmus = {task: built for task, built in zip(wanted, each_built(functools.partial(
        _effect_fmu, machine, effect_model), wanted, estimator.n_workers))
        if not isinstance(built, Suggestion)}
    stages, tasks = {}, []
    for k in range(len(machine.stages)):
        keys = [key for j, key in wanted if j == k and (j, key) in fmus]
        stages[k] = _Stage(views[k], seens[k], shared_halves(
            views[k], seens[k], keys, estimator, catalogues[k]))
        tasks += [(k, key) for key in keys]
    tasks.sort(key=lambda task: -discovery_cost(model.stage_effects(task[0])[task[1]]))
    name = [s.name for s in machine.stages]
    for k, key in tasks:
        if progress:
            progress(f"{key} on {name[k]}")
    rows = side_by_side(lambda task, one: (_try_on_stage, (
        stages[task[0]], model, task[0], name[task[0]], task[1], fmus[task], one)), tasks,
        estimator, None)
    tried = {task: row.held_out for task, row in zip(tasks, rows) if row.held_out is not None}
    found = []
    for k, stage in stages.items():
        def fmu(effect: Effect, k: int = k) -> str:
            return effect_model(_with_effect(machine, effect.key, k))
        checked = validate(stage.view, stage.seen, fmu, estimator,
                           effects=catalogues[k],
                           tried={key: h for (j, key), h in tried.items() if j == k},
                           every_synchronous=every_synchronous,
                           progress=None if progress is None else
                           functools.partial(_said, progress, name[k]))
        found += [dataclasses.replace(s, stage=name[k]) for s in checked.suggested_effects]
    found.sort(key=lambda s: (not s.confident, -(s.held_out.z if s.held_out else -math.inf),
                              -s.score))
    return dataclasses.replace(comparison, suggested_effects=found)


def refit_own_effects(problem: FitProblem, machine: Machine, model: MachineModel,
                      base: Comparison, estimator: FaultEstimator | None = None
                      ) -> list[Suggestion]:
    """Every effect the machine file gives a stage, its parameters polished on half the
    periods from ``base``'s values and scored on the other half against them
    (:func:`~pydiag.loop.held_out.held_out`, ``own``), on the stage's view of ``problem``
    (the machine's model, ``base`` a fit of it: a healthy baseline's, seen on another
    record): whether the record asks for other values of what the model has (a gear's
    deeper modulation), where :func:`discover_machine` asks what it lacks. The fits run
    side by side, one a core, as :func:`discover_machine`'s do. Rows stage by stage, a
    stage's by key."""
    estimator = estimator or FaultEstimator(**EFFECT_REFIT)
    stages, tasks = {}, []
    for k in range(len(machine.stages)):
        keys = sorted(machine.effect_keys(k))
        if not keys:
            continue
        view = stage_view(problem, machine, model, k, base.parameters)
        seen = compare(view, None, base.false_alarm_rate, base.n_periods,
                       parameters=base.parameters)
        stages[k] = _Stage(view, seen, shared_halves(view, seen, keys, estimator,
                                                     model.stage_effects(k)))
        tasks += [(k, key) for key in keys]
    name = [s.name for s in machine.stages]
    return side_by_side(lambda task, one: (_refit_on_stage, (
        stages[task[0]], model, task[0], name[task[0]], task[1], one)), tasks, estimator, None)


def _refit_on_stage(stage: _Stage, model: MachineModel, index: int, name: str, key: str,
                    estimator: FaultEstimator) -> Suggestion:
    """:func:`~pydiag.loop.discover.held_out_row` of the effect ``key`` stage ``index``
    (called ``name``) has, its values asked for again (``own``): a worker's task."""
    return held_out_row(stage.view, stage.seen, model.stage_effects(index)[key],
                        stage.view.spec.fmu_path, estimator, stage.memo, name, own=True)


def _effect_fmu(machine: Machine, effect_model: Callable[[Machine], str],
                task: tuple[int, str]) -> str | Suggestion:
    """The FMU ``effect_model`` builds of ``machine`` with the effect of ``task`` (stage,
    key), or the row saying why it cannot be built."""
    k, key = task
    started = time.perf_counter()
    try:
        return effect_model(_with_effect(machine, key, k))
    except (PydiagError, BuildError) as err:
        return failed_row(key, err, started, machine.stages[k].name)


def _with_effect(machine: Machine, key: str, stage: int) -> Machine:
    """``machine`` with the effect ``key`` on stage ``stage`` too: the model it is tried on."""
    return dataclasses.replace(machine, effects=machine.effects + (StageEffect(key, stage),))


def _said(progress: Callable[[str], None], stage: str, key: str) -> None:
    progress(f"{key} on {stage}")
