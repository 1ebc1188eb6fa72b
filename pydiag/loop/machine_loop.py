"""The loop on a machine's own model: compare (its stages fitted, then its effects), try
what the residual points to on each stage held out, accept the one confident effect on
its stage, and again with the model that has it, until nothing is confident.

Each step's fit also starts from the step before's, with the accepted effect at its
held-out fit (:func:`pydiag.loop.machine_fit.fit_machine`), so the error it fits does
not rise from step to step; the parameters its try did not fit (a shaft's orders whose
lines did not stand out of another shaft's) are held off in the accepted model
(:func:`held_off`). Every accepted effect is written into a copy of the machine file
(:func:`pydiag.loop.machine_edits.accept`), and each step's fit, to start the next one
from, as its ``[start]`` table (:func:`pydiag.loop.machine_edits.record_start`), so the
loop ends with a machine file the user can read, compare with another record, edit, and
loop on again from where it stopped (a fit of the model's many parameters from nothing
lands elsewhere); each step's model is built from that file
(:func:`pydiag.loop.machine_model.machine_fmu`). The steps are the
pair loop's (:class:`pydiag.loop.accumulate.LoopStep`), an effect named with its stage.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from pydiag.core.measurement import Measurement
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.build import ProblemSettings
from pydiag.gear.machine import Machine
from pydiag.gear.machine_file import load_machine
from pydiag.gear.speed import SpeedEstimate
from pydiag.loop.accumulate import LoopStep
from pydiag.loop.compose import BuiltModel
from pydiag.loop.effect_fit import EFFECT_REFIT
from pydiag.loop.machine_discover import validate_machine
from pydiag.loop.machine_edits import accept, record_start
from pydiag.loop.machine_fit import compare_machine, machine_problem
from pydiag.loop.machine_model import MachineModel
from pydiag.loop.stage_catalogue import possible_parameters


def machine_loop(path: str | Path, measurement: Measurement, speed: SpeedEstimate,
                 build: Callable[[Machine], tuple[MachineModel, BuiltModel]],
                 settings: ProblemSettings = ProblemSettings(), max_steps: int = 4,
                 estimator: FaultEstimator | None = None,
                 refit: FaultEstimator | None = None,
                 progress: Callable[[LoopStep], None] | None = None) -> list[LoopStep]:
    """The loop (module docstring) on the machine file ``path``, which gets every accepted
    effect: its steps, the last the comparison nothing more was accepted after (or the
    ``max_steps``-th). ``speed``: the input shaft's in ``measurement``; ``build``: a
    machine's model and its FMU; ``estimator``: the stages' fit; ``refit``: the effects'
    (default EFFECT_REFIT's); ``settings``: how the record becomes a fit problem
    (:func:`~pydiag.loop.machine_fit.machine_problem`)."""
    estimator = estimator or FaultEstimator()
    refit = refit or FaultEstimator(**EFFECT_REFIT)
    steps: list[LoopStep] = []
    while True:
        machine = load_machine(path)  # its start: the fit before, and the accepted effect's
        model, built = build(machine)
        problem = machine_problem(built.fmu, model, measurement, machine, speed, settings)
        c = compare_machine(problem, model, estimator, refit,
                            start=machine.fit_start())
        c = validate_machine(problem, machine, model, c,
                             lambda other: str(build(other)[1].fmu), refit,
                             every_synchronous=c.error > 0)
        effects = tuple(f"{e.key} on {machine.stages[e.stage].name}" for e in machine.effects)
        confident = sorted((s for s in c.suggested_effects if s.confident),
                           key=lambda s: -s.held_out.z)
        if not confident or len(steps) + 1 >= max_steps:
            steps.append(LoopStep(effects, c.error, None, None, None, None, c))
        else:
            best = confident[0]
            h = best.held_out
            steps.append(LoopStep(effects, c.error, best.label, h.error_base,
                                  h.error_effect, h.z, c))
        if progress:
            progress(steps[-1])
        if steps[-1].accepted is None:
            record_start(path, c.parameters)
            return steps
        accept(path, best.effect, best.stage, held_off(machine, best.effect, best.stage,
                                                         h.parameters))
        record_start(path, {**c.parameters, **h.parameters})


def held_off(machine: Machine, key: str, stage: str, fitted: dict[str, float]
             ) -> tuple[str, ...]:
    """The parameters of the effect ``key`` that stage ``stage`` of ``machine`` could have
    and its try did not fit (``fitted``, named ``<instance>.<name>``): a shaft's orders
    whose lines did not stand out of another shaft's orders around them. The accepted
    model holds them off, so that it fits what the try was confirmed with."""
    own = {name.split(".", 1)[-1] for name in fitted}
    return tuple(p.name for p in possible_parameters(machine, machine.stage_index(stage), key)
                 if p.name not in own)
