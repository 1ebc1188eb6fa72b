"""The effect catalogue as a stage of a machine's model has it: which effects a stage can
carry (:func:`on_a_stage`), which of their parameters its kinematics leave to fit
(:func:`possible_parameters`), and each effect with its parameters, hint, values and
outputs named for the stage (:func:`stage_effect`). The model itself is
:mod:`pydiag.loop.machine_model`'s.
"""

from __future__ import annotations

import dataclasses
import functools

from pydiag.core.parameters import Parameter
from pydiag.gear.effect import Effect
from pydiag.gear.effects import EFFECTS
from pydiag.gear.faults import CHANGED
from pydiag.gear.machine import Machine


def on_a_stage(effect: Effect) -> bool:
    """Whether a machine's model can give ``effect`` to a stage
    (:mod:`pydiag.loop.machine_model`'s docstring): an effect of the mesh, of its shafts or
    of a component the machine file describes on them (a bearing on the stage's pinion
    shaft, another shaft of the machine), not a sensor's path (the housing)."""
    return effect.transfer is None


def names_a_fault(effect: Effect) -> bool:
    """Whether ``effect`` is a component's fault (:attr:`~pydiag.gear.effect.Effect.fault`
    a fault word or a rule, not "changed": a gear's tooth or runout, a bearing's race or
    ball, a shaft's orders) that a stage can have, of a model of its own: not a refinement
    of the pair's own pinion tooth (``in_base``: its softening over its contact, a second
    tooth), which each stage's fit already has and classifies, and not one that reshapes
    the base's own lines (docs/gearbox.md says why the pinion tooth's softening is not
    asked by default)."""
    return (on_a_stage(effect) and effect.fault != CHANGED and not effect.in_base
            and not effect.reshapes_base)


#: The keys of the effects :func:`names_a_fault`: what a record is asked about against a
#: machine's healthy model by default (``diagnose --machine`` with two baselines).
FAULT_EFFECTS = tuple(key for key, effect in EFFECTS.items() if names_a_fault(effect))


def not_on_a_stage(key: str) -> str:
    """Why the effect ``key`` cannot be a stage's (one that :func:`on_a_stage` refuses)."""
    return (f"{key} is not a stage's in a machine's model yet (the housing is a sensor's "
            "path)")


def possible_parameters(machine: Machine, k: int, key: str) -> tuple[Parameter, ...]:
    """The parameters of the effect ``key`` that stage ``k`` of ``machine`` may fit, as the
    stage's kinematics alone say (no record's spectrum), named as the catalogue names them."""
    return EFFECTS[key].bounds([], 0.0, machine.stage_kinematics(k, machine.input_hz or 1.0))


def nothing_to_fit(machine: Machine, k: int, key: str) -> str:
    """Why the effect ``key`` has nothing to fit on stage ``k`` of ``machine``, or "" when
    it has: the machine file does not say where its lines are (no bearing on the stage's
    pinion shaft, no other shaft), or every line it would fit is another's of the stage
    (each of the first ten orders of a 6-tooth pinion is a mesh harmonic or one of its
    sidebands)."""
    effect = EFFECTS[key]
    name = machine.stages[k].name
    if why := effect.unknown_lines(machine.stage_kinematics(k, machine.input_hz or 1.0)):
        return f"{key} has nothing to fit on {name}: {why}"
    if effect.parameters and not possible_parameters(machine, k, key):
        return f"{key} has nothing to fit on {name} (its lines are all another's of the stage's)"
    return ""


def _prefixed(instance: str, values: dict) -> dict:
    return {f"{instance}.{name}": value for name, value in values.items()}


def _hint(effect: Effect, instance: str, peaks, bin_hz, kinematics) -> dict:
    return _prefixed(instance, effect.hint(peaks, bin_hz, kinematics))


def _machine_values(effect: Effect, instance: str, kinematics) -> dict:
    return _prefixed(instance, effect.machine_values(kinematics))


def _free_start(effect: Effect, instance: str, top_hz: float) -> dict:
    return _prefixed(instance, effect.free_start(top_hz))


def stage_effect(effect: Effect, instance: str, outputs: dict[str, str],
                 alone: bool = False) -> Effect:
    """``effect`` as the stage ``instance`` of a machine's model has it: its parameters (and
    the parts they size), and the values its hint, the kinematics and its free start give,
    named ``<instance>.<name>``; the outputs it changes, those of the model's ``outputs`` (each
    output's name and the quantity it measures: ``acc``, ``disp``) that measure them. A speed
    ripple (``Effect.ripple``) is read from the model's periodic response only on a stage
    ``alone`` in its machine, where it is the whole model's; on a stage among others its
    model ripples that stage alone, and is simulated whole. A torque ripple is read so on
    any stage: the stages' meshes are not coupled, so the response to its torque is its
    mesh's."""
    def renamed(p: Parameter) -> Parameter:
        return dataclasses.replace(p, name=f"{instance}.{p.name}",
                                   variable=f"{instance}.{p.fmu_variable}")
    ripple = None
    if effect.ripple is not None and (alone or not effect.ripple.whole_model):
        ripple = effect.ripple.renamed(instance, tuple(name for name, quantity
                                                       in outputs.items() if quantity == "acc"))
    return dataclasses.replace(
        effect, parameters=tuple(renamed(p) for p in effect.parameters), ripple=ripple,
        parts=tuple((f"{instance}.{name}", part) for name, part in effect.parts),
        hint=None if effect.hint is None else functools.partial(_hint, effect, instance),
        machine_values=None if effect.machine_values is None else
        functools.partial(_machine_values, effect, instance),
        free_start=None if effect.free_start is None else
        functools.partial(_free_start, effect, instance),
        outputs=None if effect.outputs is None else
        tuple(name for name, quantity in outputs.items() if quantity in effect.outputs))
