"""A machine's model: every stage of a machine description in one Modelica model, each
sensor seeing every stage, written by pydiag from the library's components and built once
per content.

Each stage is a drive train (``GearDiag.Components``, connected through flanges): its mesh
(``GearMesh``: the pair's law at the stage's teeth, its pinion at the input speed times the
stage's speed ratio, ``f_input`` the model's one speed) between its pinion's shaft held at
its steady speed (``SteadySpeed``) and its gear's inertia under its load (``Inertia``,
``LoadTorque``): the pair model's assumption, which makes the mesh's acceleration
``GearDiag.GearPair``'s (``tests/fmu_build/test_components.py``). A sensor sees the
stage it is near (the machine file's ``near_stage``, else the first) as that mesh's own
acceleration, and every other stage through a level of its own relative to it, in dB
(``<output>_<stage>_dB``): a housing passes each mesh to a sensor differently. These
levels are fitted with the stages' fault parameters; the channel's overall level is the
fit's gain, as for a pair. A sensor's output adds the stages' signals as they are
simulated, so a line two stages share has the level their phases give: each stage after
the first meshes at a phase of its own relative to the first's (``<stage>_mesh_phase``, a
share of its mesh cycle by which its ``t_angle`` is ahead: ``GearMesh``'s ``t_phase``),
fitted too.

A stage carries the catalogue effects the machine file gives it (``[[effects]]``, which
``pydiag accept`` writes): those with models of their own make its mesh their composed
model (:func:`pydiag.loop.compose.compose` on :data:`~pydiag.loop.compose.MESH`, declared
inside the machine's), one of the base model's own parameters frees them; their parameters
are fitted as ``<stage>.<name>``, after the stages
(:func:`pydiag.loop.machine_fit.fit_machine`). A ripple's lines need not repeat with the
machine: a torque ripple is read from periods of the model's response without it, and so
is a speed ripple on a machine of one stage; on a stage among others a speed ripple's model
is simulated whole, not one period repeated (:func:`~pydiag.loop.stage_catalogue.stage_effect`,
:mod:`pydiag.signal.ripple`). A bearing's effect on a stage is the first bearing the
machine file places on the stage's pinion shaft (its geometry the file's), another shaft's
orders the next shaft's downstream of the stage's gear (else upstream of its pinion); a
stage with neither has nothing of theirs to fit. The housing (a sensor's path) is not a
stage's in this model yet. The catalogue as a stage has it (its parameters named for the
stage) is :mod:`pydiag.loop.stage_catalogue`'s.

The stages' shafts are not connected: each stage's pinion turns at its steady speed. A
shaft's torsion between two stages (``GearDiag.Components.Shaft``,
``GearDiag.Examples.TwoStageGearbox``) couples them, but without the machine's inertias and
shaft stiffnesses it puts torsional modes at made-up frequencies, and fitted no better
(measured in ``bench/RESULTS.md`` section 13, ``docs/gearbox.md``).

One concern: the machine's model, written and built. It is fitted by
:mod:`pydiag.loop.machine_fit`, its effects tried held out by
:mod:`pydiag.loop.machine_discover`, and pydiag's edits of the machine file (an effect
accepted, a fit to start from) are :mod:`pydiag.loop.machine_edits`'.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from pydiag.core.errors import UsageError
from pydiag.core.parameters import Parameter
from pydiag.gear.conventions import GEAR_FAULT_PARAMETERS, HEALTHY_TOOTH
from pydiag.gear.effect import Effect
from pydiag.gear.effects import EFFECTS
from pydiag.gear.machine import Machine
from pydiag.loop.compose import MESH, BuiltModel, built_fmu, compose
from pydiag.loop.stage_catalogue import (nothing_to_fit, not_on_a_stage, on_a_stage,
                                         stage_effect)
from pydiag.model.adapter import Adapter, Quantity, SensorMap
from pydiag.signal.ripple import Ripple

#: The model's speed parameter: the input shaft's, Hz.
SPEED_PARAMETER = "f_input"
#: Range of a stage's level at a sensor relative to the stage the sensor is near, dB.
PATH_RANGE_DB = (-40.0, 40.0)
#: The model output a channel is when the machine file describes no sensor (a channel
#: named as another of :data:`STAGE_OUTPUTS` is that one, as on a pair's FMU).
DEFAULT_OUTPUT = "acc"
#: The outputs of a stage a sensor may measure.
STAGE_OUTPUTS = ("acc", "disp")
_UNITS = {"acc": "m/s2", "disp": "m"}


def _identifier(text: str, fallback: str, taken: set[str]) -> str:
    """``text`` as a Modelica identifier not in ``taken`` (``fallback`` when it makes none):
    ASCII letters and digits joined by single underscores, which every tool on the way to
    an FMU takes; a second of the same name gets a number."""
    name = re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_")
    if not name or not name[0].isalpha():
        name = fallback
    unique, n = name, 1
    while unique in taken:
        n += 1
        unique = f"{name}_{n}"
    taken.add(unique)
    return unique


def _said(text: str) -> str:
    """``text`` (a name from the machine file) as it may stand in a Modelica string."""
    return text.replace("\\", "/").replace('"', "'")


@dataclass(frozen=True)
class SensorOutput:
    """One output of the machine model: the channel it stands for (None: every channel no
    other output names, of a record whose machine file describes no sensor), what it
    measures, the index of the stage it sees as its own and the level parameter of each
    other stage (by stage index)."""

    name: str
    channel: str | None
    quantity: str
    near: int
    levels: dict[int, str]


@dataclass(frozen=True)
class MachineModel:
    """The Modelica model of a machine: its name, its source, the instance name of each
    stage (in the machine's order), its outputs and the first stage's teeth."""

    name: str
    source: str
    stages: tuple[str, ...]
    outputs: tuple[SensorOutput, ...]
    first_stage: tuple[int, int]
    effect_parameters: tuple[Parameter, ...] = ()
    fixed_values: dict[str, float] = field(default_factory=dict)
    # those of the effect parameters the outputs are affine in (an affine effect's)
    affine_parameters: frozenset[str] = frozenset()
    # a ripple the model has, read from its periodic response (stage_effect)
    ripple: Ripple | None = None

    def parameters(self, with_healthy_tooth: bool, outputs: set[str]
                   ) -> tuple[Parameter, ...]:
        """What a fit of ``outputs`` estimates: every stage's fault parameters (``a0`` too
        with ``with_healthy_tooth``, when the level is fitted) named ``<stage>.<name>``,
        its effects' parameters, then the stage levels of those outputs."""
        own = GEAR_FAULT_PARAMETERS + ((HEALTHY_TOOTH,) if with_healthy_tooth else ())
        out = [Parameter(f"{s}.{p.name}", p.low, p.high) for s in self.stages for p in own]
        out += list(self.effect_parameters)
        out += [Parameter(level, *PATH_RANGE_DB) for o in self.outputs if o.name in outputs
                for level in o.levels.values()]
        return tuple(out)

    def stage_parameters(self, stage: int) -> frozenset[str]:
        """The names of stage ``stage``'s own parameters: its fault parameters and its
        effects' (``<stage>.<name>``), its mesh phase and its level at each sensor: what
        shapes its lines and nothing else's."""
        inst = self.stages[stage]
        own = {f"{inst}.{p.name}" for p in GEAR_FAULT_PARAMETERS + (HEALTHY_TOOTH,)}
        own |= {p.name for p in self.effect_parameters if p.name.startswith(f"{inst}.")}
        if stage > 0:  # the phases first, one a stage after the first (machine_model)
            own.add(self.effect_parameters[stage - 1].name)
        return frozenset(own | {o.levels[stage] for o in self.outputs if stage in o.levels})

    def unknown(self, names: Iterable[str]) -> list[str]:
        """Those of ``names`` (a ``[start]`` table's) that are no parameter of the model:
        an effect taken out of the machine file, a stage renamed, a name misspelt. A fit
        starts from the others; these it cannot use."""
        known = {p.name for p in self.parameters(True, {o.name for o in self.outputs})}
        return sorted(set(names) - known)

    @property
    def quantities(self) -> dict[str, str]:
        """Each output's name and the quantity it measures (``acc``, ``disp``)."""
        return {o.name: o.quantity for o in self.outputs}

    def stage_effects(self, stage: int) -> dict[str, Effect]:
        """The catalogue as stage ``stage`` has it: the effects a stage can have
        (:func:`~pydiag.loop.stage_catalogue.on_a_stage`), named for it
        (:func:`~pydiag.loop.stage_catalogue.stage_effect`)."""
        return {key: stage_effect(e, self.stages[stage], self.quantities, len(self.stages) == 1)
                for key, e in EFFECTS.items() if on_a_stage(e)}

    def adapter(self, channels: list[str]) -> Adapter:
        """The model described to a fit of ``channels``: each mapped to its sensor's output
        (of a machine file without sensors, a channel named ``disp`` to the deflection and
        every other to ``acc``), the first stage's kinematics with the speed in
        ``f_input``."""
        sensors = []
        for channel in channels:
            out = next((o for o in self.outputs if o.channel == channel),
                       next((o for o in self.outputs if o.channel is None), None))
            if out is None:
                raise UsageError(f"channel {channel} is none of the machine file's sensors "
                                 f"({', '.join(o.channel for o in self.outputs)})")
            sensors.append(SensorMap(channel, out.name))
        first = self.first_stage
        return Adapter(tuple(sensors), (),
                       {"n_pinion": Quantity(value=first[0]), "n_gear": Quantity(value=first[1]),
                        "f_pinion_hz": Quantity(parameter=SPEED_PARAMETER)},
                       source=f"the machine model {self.name}")


def _stage_class(machine: Machine, k: int, modelica_root: Path | None,
                 nested: dict[str, str]) -> str:
    """The Modelica class of stage ``k``'s mesh with its effects (a composed one declared
    in ``nested``, by name)."""
    keys = [e.key for e in machine.effects if e.stage == k]
    for key in keys:
        if not on_a_stage(EFFECTS[key]):
            raise UsageError(f"{machine.source}: effects: {not_on_a_stage(key)}")
    own = tuple(key for key in keys if EFFECTS[key].own_fmu)
    if not own:
        return MESH.model
    if modelica_root is None:
        raise UsageError("a stage with an effect of its own model needs the Modelica library "
                         "(--modelica)")
    composed = compose(own, modelica_root, MESH)
    body = composed.source.split("\n", 1)[1]  # without its `within`
    nested[composed.name] = "\n".join("  " + line if line else line
                                      for line in body.rstrip().splitlines())
    return composed.name


def _effect_parameters(machine: Machine, k: int, instance: str
                       ) -> tuple[list[Parameter], dict[str, float], set[str]]:
    """Stage ``k``'s effects' parameters as ``<instance>.<name>`` (ranges as the stage's
    teeth say: a tooth's index), the values of those not fitted (off, or the machine's),
    and the names of those fitted that an affine effect's outputs are affine in."""
    kin = machine.stage_kinematics(k, machine.input_hz or 1.0)
    fitted, fixed, affine = [], {}, set()
    for accepted in machine.effects:
        if accepted.stage != k:
            continue
        e = stage_effect(EFFECTS[accepted.key], instance, {})
        if why := nothing_to_fit(machine, k, e.key):
            raise UsageError(f"{machine.source}: effects: {why}")
        held = {f"{instance}.{name}" for name in accepted.off}
        chosen = [p for p in e.bounds([], 0.0, kin) if p.name not in held]
        names = {p.fmu_variable for p in chosen}
        fixed.update({name: value for name, value in e.neutral_values().items()
                      if name not in names})
        fixed.update(e.values_from(kin))
        fitted += chosen
        if e.affine and not any(p.periodic for p in e.parameters):
            # (one with a phase is fitted whole with the others: the machine's affine fit
            # takes no phase of several effects at once)
            affine.update(p.name for p in chosen)
    return fitted, fixed, affine


def _drive_train(machine: Machine, k: int, mesh: str, taken: set[str]
                 ) -> tuple[list[str], list[str]]:
    """The drive train of stage ``k``'s mesh (instance ``mesh``), as declarations and
    connect equations: its pinion's shaft at its steady speed, its gear's inertia under its
    load (module docstring)."""
    stage, pinion, gear = machine.stages[k], machine.shafts[k], machine.shafts[k + 1]
    drive = _identifier(f"{mesh}_drive", f"stage{k + 1}_drive", taken)
    wheel = _identifier(f"{mesh}_gear", f"stage{k + 1}_gear", taken)
    load = _identifier(f"{mesh}_load", f"stage{k + 1}_load", taken)
    declarations = [
        f"  GearDiag.Components.SteadySpeed {drive} \"The {_said(pinion)} shaft at its "
        "steady speed\";",
        f"  GearDiag.Components.Inertia {wheel}(J={mesh}.m_s*{mesh}.r_g^2) "
        f"\"{_said(stage.name)}'s gear, on the {_said(gear)} shaft\";",
        f"  GearDiag.Components.LoadTorque {load}(T={mesh}.T*{mesh}.r_g/{mesh}.r_p) \"The "
        f"{_said(gear)} shaft's load\";"]
    connects = [f"  connect({drive}.flange, {mesh}.flange_a);",
                f"  connect({mesh}.flange_b, {wheel}.flange_a);",
                f"  connect({wheel}.flange_b, {load}.flange);"]
    return declarations, connects


def machine_model(machine: Machine, modelica_root: Path | None = None) -> MachineModel:
    """The model of ``machine`` (module docstring); ``modelica_root``: the library whose
    effects a stage with several is composed of."""
    # the outputs of a machine without sensors are named as a pair's (acc, disp)
    taken: set[str] = {SPEED_PARAMETER} | (set() if machine.sensors else set(STAGE_OUTPUTS))
    stages = tuple(_identifier(s.name, f"stage{k + 1}", taken)
                   for k, s in enumerate(machine.stages))
    lines = [f"  parameter Real {SPEED_PARAMETER}(unit=\"Hz\") = "
             f"{machine.input_hz or 25.0:.12g} \"Input shaft speed\";"]
    nested: dict[str, str] = {}
    phases: list[Parameter] = []
    effect_parameters: list[Parameter] = []
    affine: set[str] = set()
    fixed: dict[str, float] = {}
    connects: list[str] = []
    for k, (s, inst) in enumerate(zip(machine.stages, stages)):
        ratio = machine.shaft_ratio(k)
        speed = SPEED_PARAMETER if ratio == 1 else \
            f"{SPEED_PARAMETER}*{ratio.numerator}/{ratio.denominator}"
        params, values, linear = _effect_parameters(machine, k, inst)
        affine |= linear
        cls = _stage_class(machine, k, modelica_root, nested)
        effect_parameters += params
        fixed.update(values)
        phase = ""
        if k > 0:  # its meshing relative to the first stage's: a fraction of its mesh cycle
            name = _identifier(f"{inst}_mesh_phase", f"stage{k + 1}_mesh_phase", taken)
            lines.append(f"  parameter Real {name} = 0 \"{_said(s.name)}'s mesh relative to "
                         f"{_said(machine.stages[0].name)}'s, a share of its mesh cycle\";")
            phase = f", t_phase={name}/({s.pinion_teeth}*{speed})"
            phases.append(Parameter(name, 0.0, 1.0, periodic=True))
        lines.append(f"  {cls} {inst}(Np={s.pinion_teeth}, Ng={s.gear_teeth}, "
                     f"f_pinion={speed}{phase}) \"{_said(s.name)}: {s.pinion_teeth}/"
                     f"{s.gear_teeth} teeth, shafts {_said(machine.shafts[k])} and "
                     f"{_said(machine.shafts[k + 1])}\";")
        declarations, equations = _drive_train(machine, k, inst, taken)
        lines += declarations
        connects += equations
    described = bool(machine.sensors)
    sensors = [(s.channel, s.output, s.near_stage or 0) for s in machine.sensors] or \
        [(None, DEFAULT_OUTPUT, 0)] + [(q, q, 0) for q in STAGE_OUTPUTS if q != DEFAULT_OUTPUT]
    outputs = []
    for channel, quantity, near in sensors:
        if quantity not in STAGE_OUTPUTS:
            raise UsageError(f"{machine.source}: sensor {channel} measures {quantity}; a "
                             f"machine model has {', '.join(STAGE_OUTPUTS)}")
        name = quantity if not described else \
            _identifier(f"{quantity}_{channel}", f"{quantity}_{len(outputs) + 1}", taken)
        levels = {k: _identifier(f"{name}_{inst}_dB", f"{name}_{k + 1}_dB", taken)
                  for k, inst in enumerate(stages) if k != near}
        for k, level in levels.items():
            lines.append(f"  parameter Real {level}(unit=\"dB\") = 0 \"Level of "
                         f"{_said(machine.stages[k].name)} at {_said(channel or 'the sensor')} relative "
                         f"to {_said(machine.stages[near].name)}'s\";")
        terms = [f"{stages[near]}.{quantity}"] + [
            f"exp({level}*log(10)/20)*{stages[k]}.{quantity}" for k, level in levels.items()]
        lines.append(f"  output Real {name}(unit=\"{_UNITS[quantity]}\") = "
                     + " + ".join(terms) + f" \"{_said(channel or 'the sensor')}: every stage, "
                     f"{_said(machine.stages[near].name)} its own\";")
        outputs.append(SensorOutput(name, channel, quantity, near, levels))
    body = ("".join(f"{text}\n" for text in nested.values())
            + "\n".join(lines) + "\nequation\n" + "\n".join(connects))
    # the name carries a hash of what the model is, so that each model has a source file of
    # its own (two machine files of one name, a machine and itself with an effect more),
    # and not the file's name: a copy of the file (the loop's) is the same model, built once
    name = _identifier(f"Machine_{machine.name}", "Machine", set()) + \
        "_" + hashlib.sha256(body.encode()).hexdigest()[:8]
    source = ("within GearDiag;\n"
              f"model {name} \"{_said(machine.name)}: every stage, as each sensor sees them\"\n"
              "  // Written by pydiag from a machine file (pydiag/loop/machine_model.py).\n"
              + body + f"\nend {name};\n")
    first = machine.stages[0]
    quantities = {o.name: o.quantity for o in outputs}
    ripples = [stage_effect(EFFECTS[e.key], stages[e.stage], quantities,
                            len(stages) == 1).ripple for e in machine.effects]
    return MachineModel(name, source, stages, tuple(outputs),
                        (first.pinion_teeth, first.gear_teeth),
                        tuple(phases) + tuple(effect_parameters), fixed, frozenset(affine),
                        next((r for r in ripples if r is not None), None))


def machine_fmu(machine: Machine, modelica_root: Path, build_dir: Path
                ) -> tuple[MachineModel, BuiltModel]:
    """The model of ``machine`` and its FMU, built unless one of the same source exists;
    the source is ``<build_dir>/machines/<name>.mo`` (an edit of it wins:
    :func:`~pydiag.loop.compose.built_fmu`)."""
    model = machine_model(machine, modelica_root)
    return model, built_fmu(model.name, model.source, modelica_root,
                            Path(build_dir) / "machines")
