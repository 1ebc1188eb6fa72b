"""The loop that accumulates: compare, accept the one confident effect, compare the model
with it, and again, until nothing is confident.

Each step validates the comparison's suggestions held out (:mod:`pydiag.loop.validate`),
every synchronous one whose fit keeps the base whatever its score while the model leaves
anything above the noise (an error of 0, less its noise part, has nothing left to explain);
the confident one with the largest held-out z is accepted: its parameters join the
model's (bounds as the residual narrowed them) and are fitted on the whole record from the
fit before (:func:`~pydiag.loop.compare.refit_with_effect`, as ``compare --effect``
does). The model with it is the effect's own FMU, or for a second effect with a model of
its own the model of all of them (:mod:`pydiag.loop.compose`); an effect of the base's
own parameters keeps the FMU, a transfer path is applied to its output. The next step
validates the rest on that model.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import FitProblem
from pydiag.gear.effect import Effect
from pydiag.gear.effects import EFFECTS
from pydiag.loop.compare import compare, refit_with_effect
from pydiag.loop.effect_fit import EFFECT_REFIT, with_effect
from pydiag.loop.results import Comparison
from pydiag.loop.validate import validate


@dataclass
class LoopStep:
    """One comparison of the loop: the effects its model has, its error (noise-corrected
    Eq. 12 on the whole record), and the effect accepted after it with its held-out errors
    (base and with it, on the second half's bins) and z, or None: nothing confident."""

    effects: tuple[str, ...]
    error: float
    accepted: str | None
    held_out_error_base: float | None
    held_out_error_with: float | None
    z: float | None
    comparison: Comparison

    def to_dict(self) -> dict:
        return {"effects": list(self.effects), "error": self.error, "effect": self.accepted,
                "held_out_error_base": self.held_out_error_base,
                "held_out_error_with": self.held_out_error_with, "z": self.z,
                "suggested_effects": [s.to_dict() for s in self.comparison.suggested_effects]}


def accumulate(problem: FitProblem, effect_fmu: Callable[[Effect], str],
               composed: Callable[[tuple[str, ...]], str], max_steps: int = 4,
               estimator: FaultEstimator | None = None,
               refit: FaultEstimator | None = None,
               progress: Callable[[LoopStep], None] | None = None
               ) -> tuple[list[LoopStep], FitProblem]:
    """The loop on ``problem`` (module docstring): its steps, the last one the comparison
    nothing more was accepted after (or the ``max_steps``-th), and the problem of the
    final model. ``effect_fmu``/``composed``: an effect's FMU, the FMU of several;
    ``estimator``: the base fit's; ``refit``: every effect's (default EFFECT_REFIT's)."""
    refit = refit or FaultEstimator(**EFFECT_REFIT)
    c = compare(problem, estimator)
    c = validate(problem, c, effect_fmu, refit, composed=composed, every_synchronous=c.error > 0)
    accepted: tuple[str, ...] = ()
    steps: list[LoopStep] = []
    while True:
        confident = sorted((s for s in c.suggested_effects if s.confident),
                           key=lambda s: -s.held_out.z)
        if not confident or len(steps) + 1 >= max_steps:
            steps.append(LoopStep(accepted, c.error, None, None, None, None, c))
            if progress:
                progress(steps[-1])
            return steps, problem
        best = confident[0]
        h = best.held_out
        steps.append(LoopStep(accepted, c.error, best.effect, h.error_base, h.error_effect,
                              h.z, c))
        if progress:
            progress(steps[-1])
        effect = EFFECTS[best.effect]
        beside = tuple(k for k in accepted if EFFECTS[k].own_fmu)
        fmu = (problem.spec.fmu_path if not effect.own_fmu
               else composed(beside + (effect.key,)) if beside else effect_fmu(effect))
        fitted = refit_with_effect(problem, c, effect, fmu, refit)
        problem = with_effect(problem, c, effect, fmu)
        accepted += (effect.key,)
        c = validate(problem, fitted, effect_fmu, refit, present=accepted, composed=composed,
                     every_synchronous=fitted.error > 0)
