"""A machine's own model fitted to a record: the problem (the record order-tracked at the
input shaft, every stage's lines over the machine's period), the fit in steps (the stages,
then their effects, never above the stages' fit), the comparison at that fit, and the
problem seen from one stage's shafts.

What the residual points to on each stage is tried held out as on a pair
(:func:`pydiag.loop.machine_discover.validate_machine`): the model's problem seen from
that stage's shafts (:func:`stage_view`: its kinematics name the lines), the catalogue
named for it (:func:`pydiag.loop.stage_catalogue.stage_effect`), the model with the effect
on the stage built for it.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from pydiag.core.measurement import Measurement
from pydiag.core.parameters import fmu_values
from pydiag.fit.affine import fit_affine
from pydiag.fit.estimator import FaultEstimator, FitResult
from pydiag.fit.build import ProblemSettings, build_problem
from pydiag.fit.problem import FitProblem, ProblemObjective
from pydiag.gear.machine import Machine
from pydiag.gear.speed import SpeedEstimate
from pydiag.gear.tracking import order_track
from pydiag.loop.compare import compare
from pydiag.loop.machine_model import MachineModel
from pydiag.loop.residual import measured_spectra
from pydiag.loop.results import Comparison
from pydiag.model.simulate import SIMULATED_SOURCE


def machine_problem(fmu_path: str | Path, model: MachineModel, measurement: Measurement,
                    machine: Machine, speed: SpeedEstimate,
                    settings: ProblemSettings = ProblemSettings()) -> FitProblem:
    """The fit problem of ``measurement`` on the machine model ``model`` (its FMU at
    ``fmu_path``): the record order-tracked at the input shaft (``speed``, found from every
    mesh or the tacho; the tacho's channel left out), every stage's lines analysed over
    the machine's fundamental period
    (:meth:`~pydiag.gear.machine.Machine.model_kinematics`); ``settings.gain_curve``: the
    fitted gains are curves with a node at every stage's mesh harmonics
    (:mod:`pydiag.fit.gain`); None (the default): curves where the gain is fitted on the
    accelerometers the machine file places (``[[sensors]]``, output ``acc``): they sit on
    its housing, which passes each band of the meshes differently; one gain a channel for
    a record whose sensors the file does not place (a simulator's mesh acceleration) and
    for a sensor of the mesh's deflection (``disp``: no housing between), and none for a
    record ``pydiag simulate`` made (its level is the model's)."""
    drop = settings.dropped
    tracked = order_track(measurement, speed, drop=drop)
    channels = [c for c in tracked.channels if c not in drop]
    adapter = model.adapter(channels)
    fit_gain, gain_curve = settings.fit_gain, settings.gain_curve
    if fit_gain is None:
        fit_gain = tracked.metadata.get("source") != SIMULATED_SOURCE
    if gain_curve is None and machine.sensors:
        housing = {o.name for o in model.outputs if o.quantity == "acc"}
        gain_curve = [s.channel for s in adapter.sensors if s.variable in housing]
    parameters = model.parameters(fit_gain, {s.variable for s in adapter.sensors})
    problem = build_problem(str(fmu_path), tracked, adapter, parameters=parameters,
                            fixed_values=model.fixed_values,
                            kinematics=machine.model_kinematics(speed.speed_hz),
                            feature_mode=settings.feature_mode, fit_gain=fit_gain,
                            speed_estimate=speed, gain_curve=gain_curve)
    return problem.derive(ripple=model.ripple) if model.ripple is not None else problem


def fit_machine(problem: FitProblem, model: MachineModel, estimator: FaultEstimator,
                effect_estimator: FaultEstimator | None = None,
                start: dict[str, float] | None = None,
                false_alarm_rate: float = 0.01) -> FitResult:
    """The fit of a machine's model with its effects, in steps: the stages alone (every
    effect off) on ``problem``'s features; the effects' parameters with the stages held
    there (``effect_estimator``, default ``estimator``; the parameters of an effect whose
    outputs are affine in them after the others, by :func:`~pydiag.fit.affine.fit_affine`)
    on the bins a comparison scores (:func:`~pydiag.loop.residual.measured_spectra` at
    ``false_alarm_rate``), as a pair's accepted effect is
    (:func:`~pydiag.loop.compare.refit_with_effect`); then every parameter polished on
    those bins from the better of the two. An effect's lines need not lie in the stages'
    bands (a gear's runout is its turn's line in the displacement, below every band; a
    ripple's sidebands are no line of the machine's period): fitted on the bands, its
    parameters would go wherever nothing holds them, and the stages, polished on the bands
    with an effect that reshapes their lines held, stay as the effect's absence bent them
    (bench/CHANGELOG.md, c985a6c). The error is never above the stages' fit on those bins, which one swarm over
    every parameter at once does not promise (more parameters, the same budget).

    ``start``: values (by name) of a fit before, e.g. the model's before it accepted an
    effect and the effect's held-out fit; every parameter is polished from there as well
    (one missing starts off), and the better fit is kept. An affine parameter the scored
    bins do not see (a shaft's order above them:
    :attr:`~pydiag.fit.affine.AffineFit.unseen`) stays off through the polishes, which
    would otherwise leave it wherever their steps wander."""
    added = _effect_parameters(problem, model)
    later = effect_estimator or estimator
    if not added:
        best = estimator.fit(problem)
        if start is not None:
            again = later.refine(problem, {p.name: start.get(p.name, p.off)
                                           for p in problem.parameters})
            best = again if again.error < best.error else best
        return best
    off = {p.name: p.off for p in added}
    scored = _scored(problem, false_alarm_rate)
    base = estimator.fit(_held(problem, off))
    at_base = {**base.parameters, **off}
    with ProblemObjective(scored) as objective:
        base_error = objective(np.array([at_base[p.name] for p in scored.parameters]))
    effects, pinned, error = _effects_fit(scored, model, added, later, base.parameters)
    free = _held(scored, pinned)
    fits = [dataclasses.replace(base, parameters=at_base, error=base_error),
            later.refine(free, {**base.parameters,
                                **(effects if error < base_error else off)})]
    if start is not None:
        fits.append(later.refine(free, {p.name: start.get(p.name, p.off)
                                        for p in free.parameters}))
    best = min(fits, key=lambda f: f.error)
    return dataclasses.replace(best, parameters={**at_base, **best.parameters, **pinned},
                               evaluations=sum(f.evaluations for f in fits))


def refit_machine(problem: FitProblem, model: MachineModel, estimator: FaultEstimator,
                  start: dict[str, float], false_alarm_rate: float = 0.01) -> FitResult:
    """The machine's model polished on ``problem`` from ``start`` (the values, by name, of
    a fit of the same machine before: its healthy model's), no swarm: on the bins
    :func:`fit_machine` polishes on, an affine effect parameter those bins do not see held
    off. A record of a machine whose healthy fit is known is that fit moved by what
    changed: a search from nothing costs many times the simulations and may settle in
    another basin than the healthy fit's, so that the record's values and the healthy
    ones would differ by the search, not by the machine."""
    added = _effect_parameters(problem, model)
    at = {p.name: start.get(p.name, p.off) for p in problem.parameters}
    if not added:
        return estimator.refine(problem, at)
    scored = _scored(problem, false_alarm_rate)
    affine = {p.name for p in added if p.name in model.affine_parameters}
    pinned: dict[str, float] = {}
    if affine:  # n + 1 simulations: which of them the bins see
        seen = fit_affine(_held(scored, {n: v for n, v in at.items() if n not in affine}))
        pinned = {p.name: p.off for p in added if p.name in seen.unseen}
    free = _held(scored, pinned)
    fit = estimator.refine(free, {p.name: at[p.name] for p in free.parameters})
    return dataclasses.replace(fit, parameters={**fit.parameters, **pinned})


def _effect_parameters(problem: FitProblem, model: MachineModel) -> tuple:
    """The parameters of ``problem`` that are its machine's effects' (not its stages')."""
    names = {p.name for p in model.effect_parameters}
    return tuple(p for p in problem.parameters if p.name in names)


def _scored(problem: FitProblem, false_alarm_rate: float) -> FitProblem:
    """``problem`` on the bins a comparison scores
    (:func:`~pydiag.loop.residual.measured_spectra` at ``false_alarm_rate``)."""
    return problem.derive(featurizer=measured_spectra(problem, false_alarm_rate).featurizer)


def _effects_fit(scored: FitProblem, model: MachineModel, added: tuple,
                 estimator: FaultEstimator, stages: dict[str, float]
                 ) -> tuple[dict[str, float], dict[str, float], float]:
    """The effects' parameters (``added``) fitted on ``scored`` with the stages held at
    ``stages``, those held off (an affine one the bins do not see), and the error."""
    off = {p.name: p.off for p in added}
    affine = tuple(p for p in added if p.name in model.affine_parameters)
    other = tuple(p for p in added if p.name not in model.affine_parameters)
    values: dict[str, float] = {}
    pinned: dict[str, float] = {}
    error = float("inf")
    if other:
        fitted = estimator.fit(_held(scored, {**stages, **{p.name: off[p.name]
                                                           for p in affine}}))
        values, error = dict(fitted.parameters), fitted.error
    if affine:  # n + 1 simulations, however many parameters
        linear = fit_affine(_held(scored, {**stages, **{p.name: values[p.name]
                                                        for p in other}}))
        values.update(linear.values)
        error = linear.error
        pinned = {name: off[name] for name in linear.unseen}
    return {**values, **pinned}, pinned, error


def _held(problem: FitProblem, values: dict[str, float]) -> FitProblem:
    """``problem`` with the parameters named in ``values`` held there."""
    if not values:
        return problem
    held = [p for p in problem.parameters if p.name in values]
    return problem.derive(parameters=tuple(p for p in problem.parameters
                                           if p.name not in values),
                          fixed_values=fmu_values(held, values))


def compare_machine(problem: FitProblem, model: MachineModel, estimator: FaultEstimator,
                    effect_estimator: FaultEstimator | None = None,
                    false_alarm_rate: float = 0.01,
                    start: dict[str, float] | None = None) -> Comparison:
    """compare (:func:`pydiag.loop.compare.compare`) of the machine's model at its fit
    (:func:`fit_machine`), whose error the comparison reports as its fit error."""
    fit = fit_machine(problem, model, estimator, effect_estimator, start, false_alarm_rate)
    return dataclasses.replace(compare(problem, None, false_alarm_rate,
                                       parameters=fit.parameters), fit_error=fit.error)


def stage_view(problem: FitProblem, machine: Machine, model: MachineModel, stage: int,
               values: dict[str, float]) -> FitProblem:
    """The machine model's ``problem`` seen from stage ``stage``: the same record, model and
    features, the kinematics (which name the lines, and say which are an effect's) the
    stage's, over the machine's period; its parameters the stage's own
    (:meth:`MachineModel.stage_parameters`), every other held at ``values`` (the machine's
    fit). An effect tried on the stage that frees the base (``Effect.reshapes_base``) then
    frees only the stage's: the other stages' lines are not its, and what they fit is the
    machine's fit, not the try's."""
    input_hz = problem.kinematics.f_pinion_hz  # the first stage's pinion: the input shaft
    own = model.stage_parameters(stage)
    held = tuple(p for p in problem.parameters if p.name not in own)
    return dataclasses.replace(
        problem.derive(parameters=tuple(p for p in problem.parameters if p.name in own),
                       fixed_values=fmu_values(held, values)),
        kinematics=machine.model_kinematics(input_hz, stage))
