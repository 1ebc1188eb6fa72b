"""Validation of compare's suggestions: each effect the residual points to is tried held
out (:mod:`pydiag.loop.held_out`), and at most one of those that claim the same lines is
confident (:mod:`pydiag.loop.competition`).

An effect is tried when its signature covers at least :data:`MIN_SCORE` of the
unexplained energy, or whatever its score when it is scored on an envelope (its score is
the spectrum's) or fitted affinely (one simulation more than it has parameters, less than
the base's own compare costs, so the test rather than the score decides). It is not tried
when the model has it already, when the machine's description does not place its lines
(another shaft's ratio, a bearing's geometry). An effect with a model of its own, tried
on a model that has other such effects already, is fitted on the model of them all
(:mod:`pydiag.loop.compose`) when ``composed`` can make it.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Mapping
from typing import Callable

from fmu_build import ModelicaBuildError as BuildError

from pydiag.core.errors import PydiagError
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import FitProblem
from pydiag.fmu.description import read_model_description
from pydiag.gear.effect import Effect
from pydiag.gear.effects import EFFECTS
from pydiag.loop.competition import mark_settled, settle
from pydiag.loop.effect_fit import in_model
from pydiag.loop.held_out import FALSE_ALARM_RATE, held_out, threshold
from pydiag.loop.results import Comparison, HeldOut, Status

#: Effects whose signature covers less of the unexplained energy than this are not tried
#: (but those scored on an envelope or fitted affinely: module docstring).
MIN_SCORE = 0.1
#: Parameters every model that extends GearDiag.GearPair has: what the effects build on.
GEARPAIR_PARAMETERS = {"a0", "a_f", "f_f", "f_ate", "f_dte", "k2", "phi2", "k4", "phi4", "Np",
                       "Ng", "f_pinion", "m", "K", "c", "T", "r_p", "xi_max", "gamma_max"}


def validate(problem: FitProblem, comparison: Comparison,
             effect_fmu: Callable[[Effect], str], estimator: FaultEstimator | None = None,
             min_score: float = MIN_SCORE,
             false_alarm_rate: float = FALSE_ALARM_RATE, present: tuple[str, ...] = (),
             progress: Callable[[str], None] | None = None,
             tried: dict[str, HeldOut] | None = None,
             composed: Callable[[tuple[str, ...]], str] | None = None,
             effects: Mapping[str, Effect] | None = None,
             every_synchronous: bool = False) -> Comparison:
    """The comparison with its suggestions tried held out (module docstring).

    ``effect_fmu``: the FMU of an effect, called only for an effect that is fitted (one
    without ``Effect.own_fmu`` is fitted on the base FMU); it raises a
    :class:`PydiagError` (or a build error) when there is none. ``present``: effect keys the model already has
    (compare of an effect's model); ``tried``: held-out verdicts already made on this
    comparison (by :func:`pydiag.loop.discover.discover`), used instead of fitting the
    effect again; ``composed``: the FMU of a model with several effects (their keys), for
    an effect tried beside those ``present`` (without it, such an effect is not
    validated). An FMU that is not a GearDiag.GearPair model gets every suggestion
    "not validated": the effects extend it. ``effects``: the catalogue as the model names
    it (a stage of a machine's model: :func:`pydiag.loop.stage_catalogue.stage_effect`; its
    FMU is then not checked to be a GearPair), default the catalogue itself;
    ``every_synchronous``: every synchronous effect that leaves the base as it is
    (``Effect.reshapes_base``) is tried whatever its score (the loop's: a fit over one
    period's simulations, and the loop must not stop for want of a try; an effect's
    signature says where its lines are, not how much of the error it moves, which a
    modulation deep enough to make sidebands past its first does), and each is held to
    ``false_alarm_rate`` over the number tried (Bonferroni: the tries together raise a
    false alarm no more often than one did). One that reshapes the base is fitted with
    every base parameter free as well, a freedom that can pass the test on a residual at
    the noise level: it is tried on its score alone (docs/loop.md, section 5)."""
    model = read_model_description(problem.spec.fmu_path)[0]
    catalogue = EFFECTS if effects is None else effects
    if effects is None and not GEARPAIR_PARAMETERS <= {v.name for v in model.modelVariables}:
        return not_validated(comparison, f"the catalogue's effects extend GearDiag.GearPair, "
                                         f"and {model.modelName} is not one of its models")
    suggestions = [dataclasses.replace(s) for s in comparison.suggested_effects]
    fits: dict[str, HeldOut] = {}
    memo: dict = {}  # what every effect's test shares (held_out.Halves)
    reasons = {s.effect: _not_fitted(problem, s, catalogue[s.effect], min_score, present,
                                     composed, every_synchronous) for s in suggestions}
    if every_synchronous:  # the family of tries keeps the false-alarm rate of one
        false_alarm_rate /= max(1, sum(why is None for why in reasons.values()))

    for s in suggestions:
        effect = catalogue[s.effect]
        why = reasons[s.effect]
        if why is not None:
            s.status, s.message = why
            continue
        beside = _beside(effect, present)
        h = (tried or {}).get(s.effect)
        if h is None:
            if progress:
                progress(s.effect)
            try:
                fmu = (functools.partial(composed, beside + (effect.key,)) if beside
                       else functools.partial(effect_fmu, effect) if effect.own_fmu
                       else problem.spec.fmu_path)  # built if it is fitted
                h = held_out(problem, comparison, effect, fmu, estimator, false_alarm_rate,
                             memo)
            except (PydiagError, BuildError) as err:
                s.status, s.message = _marked(Status.NOT_VALIDATED, str(err))
                continue
        if h.tried and h.threshold != threshold(false_alarm_rate):  # made elsewhere
            h = dataclasses.replace(h, threshold=threshold(false_alarm_rate))
        fits[s.effect] = h
        s.held_out = h if h.tried else None
        s.status, s.message, s.confident = h.status, h.message, h.confirmed
    mark_settled(suggestions, settle(fits, {s.effect: s.competing for s in suggestions},
                                     {key for key in fits if catalogue[key].reshapes_base},
                                     false_alarm_rate))
    return dataclasses.replace(comparison, suggested_effects=suggestions)


def effects_to_fit(problem: FitProblem, comparison: Comparison,
                   min_score: float = MIN_SCORE, present: tuple[str, ...] = (),
                   composed: Callable[[tuple[str, ...]], str] | None = None,
                   effects: Mapping[str, Effect] | None = None,
                   every_synchronous: bool = False) -> list[str]:
    """The suggestions of ``comparison`` that :func:`validate` (the same arguments)
    fits held out, in its order: to fit them elsewhere, side by side, and hand them to it
    as ``tried``."""
    catalogue = EFFECTS if effects is None else effects
    return [s.effect for s in comparison.suggested_effects
            if _not_fitted(problem, s, catalogue[s.effect], min_score, present, composed,
                           every_synchronous) is None]


def _beside(effect: Effect, present: tuple[str, ...]) -> tuple[str, ...]:
    """The effects with models of their own the model has, beside which ``effect``
    (with a model of its own too) is tried."""
    return tuple(k for k in present if effect.own_fmu and EFFECTS[k].own_fmu)


def _marked(status: Status, message: str) -> tuple[Status, str]:
    return status, f"{status.value}: {message}"


def _not_fitted(problem: FitProblem, s, effect: Effect, min_score: float,
                present: tuple[str, ...], composed, every_synchronous: bool = False
                ) -> tuple[Status, str] | None:
    """Why suggestion ``s`` is not fitted held out (its status and message), or None
    when it is (module docstring)."""
    if s.score < min_score and not (
            effect.envelope or effect.affine
            or (every_synchronous and effect.synchronous and not effect.reshapes_base)):
        return _marked(Status.NOT_TRIED, f"its lines hold {100 * s.score:.0f} % of the "
                                         "unexplained energy")
    if s.effect in present or in_model(problem, effect):
        return Status.IN_MODEL, Status.IN_MODEL.value
    unknown = effect.unknown_lines(problem.kinematics)
    if unknown:
        return _marked(Status.NOT_TRIED, unknown)
    beside = _beside(effect, present)
    if beside and composed is None:  # its model extends GearPair, not the model
        return _marked(Status.NOT_VALIDATED, f"the model has {', '.join(beside)}, which "
                                             f"{effect.model} lacks: trying {s.effect} too "
                                             "needs a Modelica model with both")
    return None


def not_validated(comparison: Comparison, why: str) -> Comparison:
    """The comparison with every suggestion marked as not validated, and why."""
    return dataclasses.replace(comparison, suggested_effects=[
        dataclasses.replace(s, status=Status.NOT_VALIDATED,
                            message=f"{Status.NOT_VALIDATED.value}: {why}")
        for s in comparison.suggested_effects])
