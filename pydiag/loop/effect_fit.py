"""Fitting a catalogue effect on top of a fitted base model: which channels are its
evidence, its parameters' bounds from the residual's peaks, and its fit with the base held
(or freed as well, for an effect that reshapes the base's own lines)."""

from __future__ import annotations

from pydiag.core.errors import UsageError
from pydiag.core.parameters import Parameter
from pydiag.fit.affine import fit_affine
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import FitProblem
from pydiag.fmu.description import read_model_description
from pydiag.gear.effect import Effect
from pydiag.gear.features import FullSpectrumFeaturizer
from pydiag.gear.peaks import Peak
from pydiag.loop.results import Comparison
from pydiag.signal.transfer import HousingMode

#: The refit of an effect's few parameters: a smaller swarm than a full diagnosis, which
#: stops when its best cost stood still (by 1e-3 of 1 + the cost) for 2 iterations, and
#: one polish, from the swarm's best, which stops at steps under 1e-3 of the ranges (its
#: own difference step; a diagnosis's, 1e-4) or when a step lowers the squared error by
#: under 1e-6 of it: changes worth well under 1 in the held-out z (bench/RESULTS.md,
#: section 11).
EFFECT_REFIT = dict(n_particles=8, iterations=6, polish_evaluations=60, polish_starts=1,
                    polish_xtol=1e-3, polish_ftol=1e-6, swarm_ftol=1e-3, swarm_ftol_iter=2)
#: Swarm positions an effect that reshapes the base's lines is polished from, base held
#: (sharing half of one start's polish budget).
RESHAPE_STARTS = 2
#: A polish with the base parameters free (:func:`free_polish`) gets at least this many
#: least-squares iterations (each a difference Jacobian of n + 1 simulations), whatever
#: the estimator's budget, so that it converges: a verdict taken on a polish stopped
#: half-way depends on where it started (bench/RESULTS.md, changelog).
FREE_POLISH_ITERATIONS = 16
#: ... and tighter stops than :data:`EFFECT_REFIT`'s, which stopped such a polish at its
#: start: it goes on while a step lowers the squared error by 1e-4 of it (1e-5 and 1e-8
#: gave the same verdicts at up to twice the cost: bench/RESULTS.md, changelog).
FREE_POLISH = dict(polish_xtol=1e-6, polish_ftol=1e-4)


def free_polish(estimator: FaultEstimator, n_parameters: int) -> FaultEstimator:
    """``estimator`` for a polish with the base parameters free, ``n_parameters`` in all:
    :data:`FREE_POLISH`'s stops, at least :data:`FREE_POLISH_ITERATIONS` iterations."""
    return estimator.replace(**FREE_POLISH, polish_evaluations=max(
        estimator.polish_evaluations, FREE_POLISH_ITERATIONS * (n_parameters + 1)))


def changed_channels(problem: FitProblem, effect: Effect) -> set[str]:
    """The channels of ``problem`` whose model output ``effect`` changes."""
    return {c for c, output in zip(problem.channels, problem.spec.sensors)
            if effect.changes(output)}


def evidence_channels(problem: FitProblem, effect: Effect) -> set[str]:
    """The channels whose residual is evidence for ``effect``: those it changes, or every
    channel for an effect that reshapes the base (``Effect.reshapes_base``), whose absence
    bent the base parameters every channel shares (a housing mode on acc: the base fit
    made acc's lines right and the displacement's wrong)."""
    return set(problem.channels) if effect.reshapes_base else changed_channels(problem, effect)


def effect_peaks(problem: FitProblem, effect: Effect, peaks: list[Peak]) -> list[Peak]:
    """The ``peaks`` on channels whose model output ``effect`` changes: where to look for
    its parameters (whose residual is evidence for it: :func:`evidence_channels`)."""
    changed = changed_channels(problem, effect)
    return [pk for pk in peaks if pk.channel in changed]


def effect_parameters(problem: FitProblem, base: Comparison, effect: Effect
                      ) -> tuple[Parameter, ...]:
    """The effect's parameters, bounds narrowed by ``base``'s peaks on the channels it
    changes: what its refit searches, and what a model that accepts it fits."""
    return effect.bounds(effect_peaks(problem, effect, base.peaks), base.bin_hz,
                         problem.kinematics)


def with_effect(problem: FitProblem, base: Comparison, effect: Effect,
                effect_fmu: str) -> FitProblem:
    """The problem of the model that has ``effect``: the base problem's parameters and
    the effect's (bounds narrowed by ``base``'s peaks, as its refit searched them), on the
    effect's FMU, with the values its model takes from the kinematics. What a comparison
    after :func:`refit_with_effect` is validated on, so that the base every other effect
    is held against has the effect's lines."""
    names = {p.name for p in problem.parameters}
    own = tuple(p for p in effect_parameters(problem, base, effect) if p.name not in names)
    return problem.derive(fmu_path=effect_fmu, parameters=problem.parameters + own,
                          fixed_values=effect.values_from(problem.kinematics),
                          transfer=_transfer(problem, effect), ripple=effect.ripple)


def _transfer(problem: FitProblem, effect: Effect) -> tuple[HousingMode, ...]:
    """The transfer paths of ``problem``'s model with ``effect``."""
    return problem.transfer + ((effect.transfer,) if effect.transfer is not None else ())


def fit_effect(problem: FitProblem, base: Comparison, effect: Effect, effect_fmu: str,
               featurizer: FullSpectrumFeaturizer, estimator: FaultEstimator | None = None
               ) -> tuple[FitProblem, dict[str, float]]:
    """(the effect's problem, its fitted parameters): the effect's parameters, bounds
    narrowed by ``base``'s peaks, fitted on ``featurizer``'s bins with the base parameters
    held at ``base``'s values; ``estimator`` defaults to ``FaultEstimator(**EFFECT_REFIT)``
    (an ``Effect.affine`` one needs none: :func:`pydiag.fit.affine.fit_affine`).

    An effect that takes energy from the base model's own lines (``Effect.reshapes_base``)
    found a base fit bent to make up for it, which its own parameters alone cannot undo:
    its swarm (base held) is polished from its two best distinct positions, base still
    held, sharing half of one start's budget (the swarm alone can stop outside the narrow
    basin of a ripple's frequency), and the best is polished once more, with the base parameters free as well
    (:func:`free_polish`), and, for an effect with a ``free_start``, once more from there,
    the better kept. Its problem then fits both, and the parameters returned are both."""
    estimator = estimator or FaultEstimator(**EFFECT_REFIT)
    own = effect_parameters(problem, base, effect)
    machine = effect.values_from(problem.kinematics)
    transfer = _transfer(problem, effect)
    held = problem.derive(fmu_path=effect_fmu, parameters=own, featurizer=featurizer,
                          fixed_values={**problem.fmu_values(base.parameters), **machine},
                          transfer=transfer, ripple=effect.ripple)
    if not effect.reshapes_base:
        return held, (fit_affine(held).values if effect.affine else estimator.fit(held).parameters)
    fitted = estimator.replace(polish_starts=RESHAPE_STARTS, polish_evaluations=max(
        1, estimator.polish_evaluations // (2 * RESHAPE_STARTS))).fit(held).parameters
    names = {p.name for p in own}
    free = problem.derive(fmu_path=effect_fmu, featurizer=featurizer, fixed_values=machine,
                          transfer=transfer, ripple=effect.ripple,
                          parameters=tuple(p for p in problem.parameters
                                           if p.name not in names) + own)
    polish = free_polish(estimator, len(free.parameters))
    best = polish.refine(free, {**base.parameters, **fitted})
    if effect.free_start is not None:  # a start its held fit cannot find (Effect.free_start)
        far = polish.refine(free, {**base.parameters, **fitted,
                                   **effect.free_start(featurizer.max_freq_hz)})
        best = far if far.error < best.error else best
    return free, best.parameters


def refit_own(problem: FitProblem, base: Comparison, effect: Effect,
              featurizer: FullSpectrumFeaturizer, estimator: FaultEstimator
              ) -> tuple[FitProblem, dict[str, float]]:
    """(the problem, its fit) of ``effect``, one the model has: those of its parameters
    ``problem`` fits, polished on ``featurizer``'s bins from ``base``'s values within the
    ranges ``problem`` gives them, everything else held at ``base``'s. Whether a record
    asks for other values of an effect the model has (a deeper modulation of a gear a
    healthy model has already), where :func:`fit_effect`'s swarm within bounds read from
    the peaks looks for one it lacks and may not find the base's values again."""
    variables = {p.fmu_variable for p in effect.parameters}
    own = tuple(p for p in problem.parameters if p.fmu_variable in variables)
    if not own:
        raise ValueError(f"{effect.key} is not in the model: it has none of its parameters")
    held = problem.derive(parameters=own, featurizer=featurizer,
                          fixed_values=problem.fmu_values(base.parameters))
    return held, estimator.refine(held, {p.name: base.parameters[p.name] for p in own}
                                  ).parameters


def check_transfer_base(fmu_path: str, effect: Effect) -> None:
    """UsageError when ``fmu_path`` already has the transfer path ``effect`` is (a
    HousingSensor FMU given for housing_sensor): pydiag applies it to the base model's
    outputs, and would pass the signal through the mode twice."""
    md, _ = read_model_description(fmu_path)
    has = sorted({v.name for v in md.modelVariables} & set(effect.transfer.variables))
    if has:
        raise UsageError(f"{effect.key} is a transfer path pydiag applies to the base model's "
                         f"outputs, and {md.modelName} has it already ({', '.join(has)}): "
                         "give --fmu the base model (GearPair.fmu)")


def in_model(problem: FitProblem, effect: Effect) -> bool:
    """The base problem fits some of ``effect``'s parameters, and every one the effect
    fits on this gear pair whatever the record (its hint leaves out some: the pinion
    shaft's orders a gear line falls on are never fitted, so a model that has the shaft's
    lines lacks them; another shaft's orders are fitted only where the record has a line)."""
    fitted = {p.fmu_variable for p in problem.parameters}
    own = effect.bounds([], 0.0, problem.kinematics)  # no peaks: only what the pair says
    return (any(p.fmu_variable in fitted for p in effect.parameters)
            and all(p.fmu_variable in fitted for p in own))
