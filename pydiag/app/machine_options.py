"""The machine file as the command-line options it stands for (``--machine FILE``)."""

from __future__ import annotations

from pydiag.core.errors import UsageError
from pydiag.gear.machine import Machine
from pydiag.gear.machine_file import load_machine, machine_from_dict
from pydiag.io.readers import parse_units

#: The commands that fit a pair model; of these, diagnose and batch fit every stage of a
#: machine, compare, discover and loop the one stage --stage names.
PAIR_COMMANDS = ("diagnose", "compare", "discover", "loop", "batch")
#: The commands for which --teeth NP,NG --rpm N without --fmu stand for a machine of one
#: stage, whose own model they fit (loop writes into a machine file: it takes one).
SHORTHAND_COMMANDS = ("diagnose", "compare", "discover")


def apply_machine(args) -> Machine | None:
    """The machine file's facts as the options they stand for, where the command line did
    not give them (it wins): channels and their units and sensitivities, the tacho, the
    nominal speed; for the commands that fit a pair, its teeth and its pinion bearing.
    Returns the machine (None without --machine). ``args.input_hz`` is then the nominal
    input speed in Hz (from --rpm, else the file's; None when neither says it): the one
    speed every command reads."""
    args.input_hz = args.rpm / 60.0 if getattr(args, "rpm", None) is not None else None
    if not getattr(args, "machine", None):
        if getattr(args, "pulses_per_rev", None) is None and hasattr(args, "pulses_per_rev"):
            args.pulses_per_rev = 1
        return _pair(args)
    if args.teeth is not None:
        raise UsageError("--teeth and --machine both give the gears' teeth: give one")
    machine = load_machine(args.machine)
    fits = args.command in PAIR_COMMANDS
    staged = len(machine.stages) > 1
    args.stage_index = _stage_of(args, machine) if fits else None
    if args.input_hz is None and machine.input_hz is not None:
        args.input_hz = machine.input_hz
    elif args.input_hz is None and getattr(args, "measurement", "") is not None:  # not --list
        raise UsageError(f"give the nominal input speed (--rpm): {args.machine} has no "
                         "input_rpm")
    tacho = machine.tacho
    if tacho is not None and args.tacho is None:  # never a sensor, even with --speed mesh
        if tacho.shaft != 0:
            raise UsageError(f"{args.machine}: a tacho on the {machine.shafts[tacho.shaft]} "
                             "shaft is not supported yet (only on the input shaft)")
        args.tacho = tacho.channel
        if args.pulses_per_rev is None:
            args.pulses_per_rev = tacho.pulses_per_rev
    if args.pulses_per_rev is None:
        args.pulses_per_rev = 1
    # a pair's FMU (--fmu) reads each sensor as the output it measures; the machine's own
    # model maps the file's channels itself, and a staged fit picks each stage's own
    as_output = fits and not staged and getattr(args, "fmu", None) is not None
    if not args.channel and machine.sensors:
        args.channel = [f"{s.channel}={s.output}" if as_output else s.channel
                        for s in machine.sensors]
    # the file's sensors the command line chose (every one when it chose none)
    chosen = {c.split("=", 1)[0] for c in args.channel or []}
    sensors = [s for s in machine.sensors if not chosen or s.channel in chosen]
    given_units = parse_units(args.unit)
    if None not in given_units:
        args.unit = list(args.unit or []) + [f"{s.channel}={s.unit}" for s in sensors
                                             if s.unit and s.channel not in given_units]
    given = dict(args.sensitivity or [])
    args.sensitivity = list(args.sensitivity or []) + [
        (s.channel, s.sensitivity) for s in sensors if s.sensitivity and s.channel not in given]
    if fits and not staged:
        stage = machine.stages[0]
        args.teeth = (stage.pinion_teeth, stage.gear_teeth)
        bearing = machine.pair_bearing(0)
        if bearing is not None and getattr(args, "bearing", "absent") is None:
            args.bearing = bearing
    return machine


def _pair(args) -> Machine | None:
    """``--teeth NP,NG --rpm N`` without ``--fmu`` (:data:`SHORTHAND_COMMANDS`): a machine of
    that one stage, its sensors the model's outputs (a channel named ``acc`` or ``disp``, or
    mapped to one with ``--channel NAME=acc``); None otherwise."""
    if (args.command not in SHORTHAND_COMMANDS or getattr(args, "fmu", None) is not None
            or args.teeth is None or args.input_hz is None):
        return None
    pinion, gear = args.teeth
    args.stage_index = 0
    return machine_from_dict({
        "name": f"pair {pinion}/{gear}", "input_rpm": 60 * args.input_hz,
        "stages": [{"name": "pair", "pinion_teeth": pinion, "gear_teeth": gear}],
        "sensors": [{"channel": output, "output": output} for output in ("acc", "disp")]},
        f"--teeth {pinion},{gear} --rpm {60 * args.input_hz:g}")


def _stage_of(args, machine: Machine) -> int | None:
    """The stage compare, discover and loop fit (``--stage``; the only one of a one-stage
    machine); None for the commands that fit every stage (diagnose and batch, stage by
    stage; compare, discover and loop without --fmu, the machine's own model)."""
    stage = getattr(args, "stage", None)
    if len(machine.stages) == 1:
        return 0 if stage is None else machine.stage_index(stage)
    if args.command in ("diagnose", "batch"):
        return None
    if args.command in ("compare", "discover", "loop") and not args.fmu:
        if stage is None:
            return None  # the machine's own model, every stage
        raise UsageError(f"--stage {stage}: {args.command} fits that stage's pair model: give "
                         "it with --fmu (without --stage and --fmu it fits the machine's own "
                         "model of every stage)")
    if stage is None:
        raise UsageError(f"{args.machine}: {len(machine.stages)} stages; {args.command} fits "
                         f"one stage's pair model: give --stage ({machine.stage_choices()}"
                         "); `pydiag diagnose --machine` fits every stage, `pydiag "
                         "compare --machine` without --fmu the machine's model of them all")
    if args.other_shaft is not None or args.bearing is not None:
        raise UsageError(f"--other-shaft and --bearing describe a pair's surroundings; "
                         f"{args.machine} describes the machine's: give them there")
    return machine.stage_index(stage)
