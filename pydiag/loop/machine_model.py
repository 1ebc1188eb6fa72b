"""A machine's model: every stage of a machine description in one Modelica model, each
sensor seeing every stage, written by pydiag and built once per content.

Each stage is a ``GearDiag.GearPair`` at its teeth, its pinion at the input speed times
the stage's speed ratio (``f_input``, the model's one speed). A sensor sees the stage it
is near (the machine file's ``near_stage``, else the first) as that pair's own output, and
every other stage through a level of its own relative to it, in dB
(``<output>_<stage>_dB``): a housing passes each mesh to a sensor differently. These
levels are fitted with the stages' fault parameters; the channel's overall level is the
fit's gain, as for a pair. A sensor's output adds the stages' signals as they are
simulated, so a line two stages share has the level their phases give: the stages start
with their faulty teeth in mesh together, and that relative phase is not fitted.

The stages are not coupled: each mesh turns at its constant speed, as the pair model's
does. What couples them in a gearbox (the shafts' torsion, one stage's transmission error
in the other's load) is not modelled.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from pydiag.core.errors import UsageError
from pydiag.core.measurement import Measurement
from pydiag.core.parameters import Parameter
from pydiag.fit.problem import FitProblem, build_problem
from pydiag.gear.conventions import GEAR_FAULT_PARAMETERS, HEALTHY_TOOTH
from pydiag.gear.machine import Machine
from pydiag.gear.speed import SpeedEstimate
from pydiag.gear.tracking import order_track
from pydiag.loop.compose import built_fmu
from pydiag.model.adapter import Adapter, Quantity, SensorMap
from pydiag.model.simulate import SIMULATED_SOURCE

#: The model's speed parameter: the input shaft's, Hz.
SPEED_PARAMETER = "f_input"
#: Range of a stage's level at a sensor relative to the stage the sensor is near, dB.
PATH_RANGE_DB = (-40.0, 40.0)
#: The model output a sensor maps to when the machine file describes no sensor.
DEFAULT_OUTPUT = "acc"
#: The outputs of a stage a sensor may measure.
STAGE_OUTPUTS = ("acc", "disp")
_UNITS = {"acc": "m/s2", "disp": "m"}


def _identifier(text: str, fallback: str, taken: set[str]) -> str:
    """``text`` as a Modelica identifier not in ``taken`` (``fallback`` when it makes none)."""
    name = re.sub(r"\W+", "_", text).strip("_")
    if not name or not name[0].isalpha():
        name = fallback
    while name in taken:
        name += "_"
    taken.add(name)
    return name


@dataclass(frozen=True)
class SensorOutput:
    """One output of the machine model: the channel it stands for (None: every channel of
    a record whose machine file names no sensor), what it measures, the index of the stage
    it sees as its own and the level parameter of each other stage (by stage index)."""

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

    def parameters(self, with_healthy_tooth: bool, outputs: set[str]
                   ) -> tuple[Parameter, ...]:
        """What a fit of ``outputs`` estimates: every stage's fault parameters (``a0`` too
        with ``with_healthy_tooth``, when the level is fitted) named ``<stage>.<name>``,
        then the stage levels of those outputs."""
        own = GEAR_FAULT_PARAMETERS + ((HEALTHY_TOOTH,) if with_healthy_tooth else ())
        out = [Parameter(f"{s}.{p.name}", p.low, p.high) for s in self.stages for p in own]
        out += [Parameter(level, *PATH_RANGE_DB) for o in self.outputs if o.name in outputs
                for level in o.levels.values()]
        return tuple(out)

    def adapter(self, channels: list[str]) -> Adapter:
        """The model described to a fit of ``channels``: each mapped to its sensor's output
        (every channel to the one output of a machine file without sensors), the first
        stage's kinematics with the speed in ``f_input``."""
        sensors = []
        for channel in channels:
            out = next((o for o in self.outputs if o.channel in (channel, None)), None)
            if out is None:
                raise UsageError(f"channel {channel} is none of the machine file's sensors "
                                 f"({', '.join(o.channel for o in self.outputs)})")
            sensors.append(SensorMap(channel, out.name))
        first = self.first_stage
        return Adapter(tuple(sensors), (),
                       {"n_pinion": Quantity(value=first[0]), "n_gear": Quantity(value=first[1]),
                        "f_pinion_hz": Quantity(parameter=SPEED_PARAMETER)},
                       source=f"the machine model {self.name}")


def machine_model(machine: Machine) -> MachineModel:
    """The model of ``machine`` (module docstring)."""
    taken: set[str] = {SPEED_PARAMETER}
    stages = tuple(_identifier(s.name, f"stage{k + 1}", taken)
                   for k, s in enumerate(machine.stages))
    lines = [f"  parameter Real {SPEED_PARAMETER}(unit=\"Hz\") = "
             f"{machine.input_hz or 25.0:.12g} \"Input shaft speed\";"]
    for k, (s, inst) in enumerate(zip(machine.stages, stages)):
        ratio = machine.shaft_ratio(k)
        speed = SPEED_PARAMETER if ratio == 1 else \
            f"{SPEED_PARAMETER}*{ratio.numerator}/{ratio.denominator}"
        lines.append(f"  GearDiag.GearPair {inst}(Np={s.pinion_teeth}, Ng={s.gear_teeth}, "
                     f"f_pinion={speed}) \"{s.name}: {s.pinion_teeth}/{s.gear_teeth} teeth, "
                     f"shafts {machine.shafts[k]} and {machine.shafts[k + 1]}\";")
    sensors = [(s.channel, s.output, s.near_stage or 0) for s in machine.sensors] or \
        [(None, DEFAULT_OUTPUT, 0)]
    outputs = []
    for channel, quantity, near in sensors:
        if quantity not in STAGE_OUTPUTS:
            raise UsageError(f"{machine.source}: sensor {channel} measures {quantity}; a "
                             f"machine model has {', '.join(STAGE_OUTPUTS)}")
        name = quantity if channel is None else \
            _identifier(f"{quantity}_{channel}", f"{quantity}_{len(outputs) + 1}", taken)
        levels = {k: _identifier(f"{name}_{inst}_dB", f"{name}_{k + 1}_dB", taken)
                  for k, inst in enumerate(stages) if k != near}
        for k, level in levels.items():
            lines.append(f"  parameter Real {level}(unit=\"dB\") = 0 \"Level of "
                         f"{machine.stages[k].name} at {channel or 'the sensor'} relative "
                         f"to {machine.stages[near].name}'s\";")
        terms = [f"{stages[near]}.{quantity}"] + [
            f"exp({level}*log(10)/20)*{stages[k]}.{quantity}" for k, level in levels.items()]
        lines.append(f"  output Real {name}(unit=\"{_UNITS[quantity]}\") = "
                     + " + ".join(terms) + f" \"{channel or 'the sensor'}: every stage, "
                     f"{machine.stages[near].name} its own\";")
        outputs.append(SensorOutput(name, channel, quantity, near, levels))
    name = _identifier(f"Machine_{machine.name}", "Machine", set())
    source = ("within GearDiag;\n"
              f"model {name} \"{machine.name}: every stage, as each sensor sees them\"\n"
              f"  // Written by pydiag from {Path(machine.source).name} "
              "(pydiag/loop/machine_model.py).\n"
              + "\n".join(lines) + f"\nend {name};\n")
    first = machine.stages[0]
    return MachineModel(name, source, stages, tuple(outputs),
                        (first.pinion_teeth, first.gear_teeth))


def machine_problem(fmu_path: str | Path, model: MachineModel, measurement: Measurement,
                    machine: Machine, speed: SpeedEstimate, fit_gain: bool | None = None,
                    feature_mode: str = "lines", drop: tuple[str, ...] = ()) -> FitProblem:
    """The fit problem of ``measurement`` on the machine model ``model`` (its FMU at
    ``fmu_path``): the record order-tracked at the input shaft (``speed``, found from every
    mesh or the tacho; the channels ``drop`` left out), every stage's lines analysed over
    the machine's fundamental period
    (:meth:`~pydiag.gear.machine.Machine.model_kinematics`)."""
    tracked = order_track(measurement, speed, drop=drop)
    channels = [c for c in tracked.channels if c not in drop]
    adapter = model.adapter(channels)
    if fit_gain is None:
        fit_gain = tracked.metadata.get("source") != SIMULATED_SOURCE
    parameters = model.parameters(fit_gain, {s.variable for s in adapter.sensors})
    return build_problem(str(fmu_path), tracked, adapter, parameters=parameters,
                         kinematics=machine.model_kinematics(speed.speed_hz),
                         feature_mode=feature_mode, fit_gain=fit_gain, speed_estimate=speed)


def machine_fmu(machine: Machine, modelica_root: Path, build_dir: Path) -> tuple[MachineModel, Path]:
    """The model of ``machine`` and its FMU, built unless one of the same source exists;
    the source is ``<build_dir>/machines/<name>.mo``."""
    model = machine_model(machine)
    return model, built_fmu(model.name, model.source, modelica_root,
                            Path(build_dir) / "machines")
