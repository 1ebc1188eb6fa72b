"""The commands of the model-improvement loop: compare, discover, loop, history."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Callable

from pydiag.app.commands import (check_outputs, estimator_settings, problem_of,
                                 problem_settings)
from pydiag.app.progress import progress_bar
from pydiag.app.formatting import (format_comparison, format_discovery, format_facts,
                                   format_history, format_loop_step)
from pydiag.app.models import effect_models, library, machine_fmus, machine_models
from pydiag.app.reading import read_input
from pydiag.core.errors import OutputError, UsageError
from pydiag.core.measurement import Measurement
from pydiag.fit.build import ProblemSettings
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.problem import FitProblem
from pydiag.fmu.description import read_model_description
from pydiag.gear.effects import EFFECTS
from pydiag.gear.machine import Machine
from pydiag.gear.speed import SpeedEstimate
from pydiag.io.outputs import check_output, write_text
from pydiag.loop import history, history_plot
from pydiag.loop.accumulate import accumulate
from pydiag.loop.compare import compare, refit_with_effect
from pydiag.diagnose.diagnosis import fit_warnings
from pydiag.loop.effect_fit import EFFECT_REFIT, check_transfer_base, with_effect
from pydiag.loop.compose import BuiltModel
from pydiag.loop.machine_discover import check_effects, discover_machine, validate_machine
from pydiag.loop.machine_loop import machine_loop
from pydiag.loop.machine_edits import accept
from pydiag.loop.machine_fit import compare_machine, machine_problem
from pydiag.loop.machine_model import MachineModel
from pydiag.diagnose.stages import machine_speed
from pydiag.loop.discover import (as_dict, discover)
from pydiag.loop.validate import validate
from pydiag.loop.report import write_report


def _effect_estimator(args) -> FaultEstimator:
    """The refit of an effect: EFFECT_REFIT's budget, overridden by the options given."""
    return FaultEstimator(**{**EFFECT_REFIT, **estimator_settings(args)})


def _machine(args) -> Machine:
    """The machine whose own model compare, discover or loop fit without --fmu
    (--machine)."""
    machine = getattr(args, "machine_description", None)
    if machine is None:
        raise UsageError(f"give --fmu, or --machine FILE to {args.command} the machine's own "
                         "model")
    return machine


def _machine_problem(args, m: Measurement, build: Callable[[Machine], tuple[MachineModel,
                                                                             BuiltModel]]
                     ) -> tuple[FitProblem, tuple[MachineModel, BuiltModel]]:
    """compare without --fmu: the fit problem of the machine's own model of every stage
    (:mod:`pydiag.loop.machine_model`), and that model, as written and as built."""
    machine = _machine(args)
    if getattr(args, "effect", None):
        raise UsageError(f"--effect fits a pair's effect: give --stage (the stages of "
                         f"{args.machine}: " + ", ".join(s.name for s in machine.stages)
                         + ") and --fmu")
    model, built = build(machine)
    found, settings = _machine_record(args, m)
    problem = machine_problem(built.fmu, model, m, machine, found, settings)
    return problem, (model, built)


def _start_warnings(machine: Machine, model: MachineModel) -> list[str]:
    """The warning that the machine file's [start] names parameters its model lacks."""
    unknown = model.unknown(dict(machine.start))
    return [f"{machine.source}: [start] names what its model does not fit, not used: "
            f"{', '.join(unknown)}"] if unknown else []


def _model_fact(args, built: BuiltModel) -> str:
    """The machine's own model, as the commands name it: its source, whose it is."""
    return (f"{built.source} (every stage of {args.machine_description.source}, "
            + ("your edit of what pydiag wrote" if built.edited else "written by pydiag")
            + ("; pydiag accept EFFECT --stage S gives a stage an effect)" if args.machine
               else "; a machine file takes effects: docs/machine-file.md)"))


def _machine_record(args, m: Measurement) -> tuple[SpeedEstimate, ProblemSettings]:
    """How the machine's own model sees the record ``m``: its input speed (from the tacho,
    else from every mesh), and the problem's settings."""
    settings = problem_settings(args)
    return machine_speed(m, args.machine_description, args.input_hz, settings.tracking), settings


def _stage_fact(args) -> dict:
    """The stage of a machine of several stages that was fitted: its name and teeth."""
    machine = getattr(args, "machine_description", None)
    if machine is None or len(machine.stages) == 1:
        return {}
    if args.stage_index is None:
        return {}
    s = machine.stages[args.stage_index]
    return {"stage": f"{s.name} ({s.pinion_teeth}/{s.gear_teeth} teeth) of {machine.name}; "
                     "the speed is its pinion shaft's"}


def cmd_compare(args) -> int:
    check_outputs(args, "json", "report")
    args.history = str(history.resolve(args.history))
    history.check(args.history)
    effect = EFFECTS[args.effect] if args.effect else None
    if effect is not None and effect.transfer is not None and args.fmu:
        check_transfer_base(args.fmu, effect)
    m = read_input(args)
    machine_model = None  # (as written, as built) when compare fits the machine's own
    if args.fmu:
        models = None if args.no_validate else effect_models(args)
        # with an effect model, the base fit runs with the effect switched off (lower bounds)
        problem = problem_of(args, m, fixed_values=effect.neutral_values() if effect else None)
    else:  # the machine's own model, its effects tried stage by stage (below)
        machines = machine_models(args)
        (problem, machine_model), models = _machine_problem(args, m, machines), None
    update, close = progress_bar(args.quiet, "compare")
    try:
        estimator = FaultEstimator(**estimator_settings(args), progress=update)
        if machine_model is None:
            c = compare(problem, estimator, args.false_alarm_rate)
        else:  # the machine's model: its effects fitted after its stages
            c = compare_machine(problem, machine_model[0], estimator,
                                _effect_estimator(args).replace(progress=update),
                                args.false_alarm_rate,
                                start=args.machine_description.fit_start())
        if effect is not None:
            base, c = c, refit_with_effect(problem, c, effect, args.fmu, _effect_estimator(args))
            problem = with_effect(problem, base, effect, args.fmu)  # validated with its lines
    finally:
        close()
    if machine_model is not None and not args.no_validate:
        c = validate_machine(problem, args.machine_description, machine_model[0], c,
                             machine_fmus(args),
                             _effect_estimator(args), None if args.quiet else
                             (lambda key: print(f"validating {key} held out ...",
                                                file=sys.stderr)))
    if models is not None:
        c = validate(problem, c, models[0], _effect_estimator(args),
                     present=(args.effect,) if args.effect else (), composed=models[1],
                     progress=None if args.quiet else
                     (lambda key: print(f"validating {key} held out ...", file=sys.stderr)))
    md, _ = read_model_description(problem.spec.fmu_path)
    facts = {k: v for k, v in problem.record_facts().items()
             if k not in ("n_periods", "duration_s")}  # the comparison's own are in c
    facts.update(_stage_fact(args))
    if machine_model is not None:
        facts["model"] = _model_fact(args, machine_model[1])
    warnings = (fit_warnings(problem, c.fit_error, c.gains, c.parameters)
                if c.fit_error is not None else [])
    if machine_model is not None:
        warnings += _start_warnings(args.machine_description, machine_model[0])
    # the run is recorded when its outputs are written (history.recording)
    with history.recording(args.history, c, args.measurement, md.modelName,
                           args.source) as (run_id, runs):
        print(format_comparison(c))
        print(format_facts({**facts, "gains": c.gains}))
        for warning in warnings:
            print(f"pydiag compare: warning: {warning}", file=sys.stderr)
        if args.report:
            write_report(c, args.report, args.measurement, runs, args.force)
            print(f"report     : {args.report}")
        if args.json:
            write_text(args.json, json.dumps({**c.to_dict(), **facts, "warnings": warnings},
                                             indent=2) + "\n", args.force)
    print(f"recorded as run {run_id} in {args.history}")
    return 0


def cmd_discover(args) -> int:
    check_outputs(args, "json")
    root, build = library(args)  # checked before any work
    if not args.fmu:
        check_effects(args.effects)
    m = read_input(args)
    progress = None if args.quiet else (lambda d: print(f"{d.label}: tried in {d.elapsed_s:.1f} s",
                                                        file=sys.stderr))
    facts = _stage_fact(args)
    if args.fmu:
        base, found = discover(problem_of(args, m), FaultEstimator(**estimator_settings(args)),
                               args.effects,
                               root, build, progress,
                               _effect_estimator(args))
    else:  # the machine's own model: every effect its stages lack, on every stage
        machines = machine_models(args)
        problem, (model, built) = _machine_problem(args, m, machines)
        update, close = progress_bar(args.quiet, "compare")
        try:
            base = compare_machine(problem, model,
                                   FaultEstimator(**estimator_settings(args), progress=update),
                                   _effect_estimator(args).replace(progress=update),
                                   start=args.machine_description.fit_start())
        finally:
            close()
        found = discover_machine(problem, args.machine_description, model, base,
                                 machine_fmus(args),
                                 _effect_estimator(args), args.effects, progress)
        facts["model"] = _model_fact(args, built)
        for warning in _start_warnings(args.machine_description, model):
            print(f"pydiag discover: warning: {warning}", file=sys.stderr)
    print("\n".join(filter(None, [format_facts(facts), format_discovery(base, found)])))
    if args.json:
        write_text(args.json, json.dumps(as_dict(base, found), indent=2) + "\n", args.force)
    return 0


def cmd_loop(args) -> int:
    """compare, accept the one confident effect, compare again, until nothing is
    confident (:mod:`pydiag.loop.accumulate`), printing each step as it is made."""
    check_outputs(args, "json", "out")
    args.history = str(history.resolve(args.history))
    history.check(args.history)
    if args.out and args.fmu:
        raise UsageError("--out names the machine file the loop writes: it goes with "
                         "--machine and no --fmu")
    if not args.fmu:
        steps, model = _machine_loop(args)
    else:
        effect_model, composed_model = effect_models(args)
        problem = problem_of(args, read_input(args))
        facts = format_facts(_stage_fact(args))
        if facts:
            print(facts)
        steps, final = accumulate(
            problem, effect_model, composed_model, args.max_steps,
            FaultEstimator(**estimator_settings(args)), _effect_estimator(args),
            lambda step: print(format_loop_step(step), flush=True))
        model = str(final.spec.fmu_path)
    print(f"model      : {model}")
    ids = []
    for step in steps:  # every step a run of the history, its model named by its FMU
        name = read_model_description(step.comparison.fmu)[0].modelName
        with history.recording(args.history, step.comparison, args.measurement, name) as (i, _):
            ids.append(i)
    print(f"recorded as run {ids[0]} in {args.history}" if len(ids) == 1 else
          f"recorded as runs {ids[0]}-{ids[-1]} in {args.history}")
    if args.json:
        write_text(args.json, json.dumps({"steps": [s.to_dict() for s in steps],
                                          "model_fmu": model if args.fmu
                                          else steps[-1].comparison.fmu,
                                          "machine": None if args.fmu else model},
                                         indent=2) + "\n", args.force)
    return 0


def cmd_accept(args) -> int:
    """Give a stage of the machine file an effect (:func:`pydiag.loop.machine_edits.accept`)."""
    machine = accept(args.machine, args.effect, args.stage)
    stage = machine.stages[machine.effects[-1].stage].name
    print(f"{args.machine}: {args.effect} on {stage}; `pydiag compare --machine "
          f"{args.machine} --measurement RECORD` fits the machine's model with it")
    return 0


def _machine_loop(args) -> tuple[list, str]:
    """pydiag loop --machine FILE without --fmu: the loop on the machine's own model
    (:mod:`pydiag.loop.machine_loop`), on a copy of FILE (--out, default ``<stem>.loop.toml``
    beside it; refused if it exists, unless --force) that gets every accepted effect. Returns the
    steps and the copy's path."""
    _machine(args)
    source = Path(args.machine)
    copy = Path(args.out) if args.out else source.with_name(f"{source.stem}.loop.toml")
    try:
        check_output(str(copy), args.force)
    except OutputError as err:
        raise OutputError(f"{err} (--out names another)") from err
    m = read_input(args)
    machines = machine_models(args)
    found, settings = _machine_record(args, m)
    write_text(str(copy), source.read_text(encoding="utf-8"), True)
    print(f"machine    : {copy} (a copy of {source}; every effect accepted goes into it)")
    for warning in _start_warnings(args.machine_description,
                                   machines(args.machine_description)[0]):
        print(f"pydiag loop: warning: {warning}", file=sys.stderr)
    steps = machine_loop(copy, m, found, machines, settings, args.max_steps,
                         FaultEstimator(**estimator_settings(args)), _effect_estimator(args),
                         progress=lambda step: print(format_loop_step(step), flush=True))
    return steps, str(copy)


def cmd_history(args) -> int:
    check_outputs(args, "plot")
    if args.plot:
        history_plot.check_plot(args.plot)
    args.history = str(args.history or history.default_path())
    rows = history.runs(args.history)
    if not rows:
        raise UsageError(f"no compare runs recorded in {args.history}")
    print(format_history(rows))
    if args.plot:
        print(f"wrote {history_plot.plot(rows, args.plot, args.force)}")
    return 0
