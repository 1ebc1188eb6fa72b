"""The commands that diagnose and check FMUs: simulate, diagnose, indicators, batch,
regress, inspect, demo. Each parses nothing and computes nothing itself: it calls the
library and prints."""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from pydiag.app import batch
from pydiag.app.baselines import (baseline_records, check_lacking, grower,
                                  healthy_measurements, kept_healthy_model, lacking_effects,
                                  records_kept_in)
from pydiag.app.models import library, machine_fmus, machine_models
from pydiag.app.progress import progress_bar, records_bar
from pydiag.app.formatting import (format_facts, format_healthy_model, format_indicators,
                                   format_machine_report,
                                   format_regression, format_result)
from pydiag.app.reading import channels_to_read, read_input
from pydiag.core.errors import UsageError
from pydiag.core.measurement import Measurement
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.build import ProblemSettings, build_problem
from pydiag.fit.problem import FitProblem
from pydiag.fmu.description import read_model_description
from pydiag.fmu.inspect import describe, format_info
from pydiag.gear.conventions import DEFAULT_SENSORS, kinematics_from
from pydiag.gear.indicators import condition_indicators
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.machine import Machine
from pydiag.gear.machine_file import load_machine
from pydiag.gear.paper_cases import case
from pydiag.gear.speed import SpeedEstimate, SpeedSettings
from pydiag.gear.machine_report import machine_report
from pydiag.io.measurements import write_measurement
from pydiag.io.readers import read_measurement
from pydiag.io.outputs import check_output, write_text
from pydiag.loop.compose import BuiltModel
from pydiag.loop.machine_model import SPEED_PARAMETER, MachineModel
from pydiag.model import regress
from pydiag.diagnose.diagnosis import Diagnosis, diagnose
from pydiag.diagnose.stages import (diagnose_machine, diagnose_machine_model, machine_speed,
                                    pair_json, stage_problem)
from pydiag.model.adapter import Adapter, load_adapter
from pydiag.model.simulate import simulate_measurement

#: Optimiser options of the command line -> FaultEstimator settings.
OPTIMISER_OPTIONS = {"particles": "n_particles", "iterations": "iterations",
                     "polish": "polish_evaluations", "seed": "seed", "workers": "n_workers"}


def warn_validation(fmu: str) -> None:
    """Print fmpy's schema complaints as warnings: many vendor FMUs fail it yet run."""
    if Path(fmu).is_file():
        _, warnings = read_model_description(fmu)
        for w in warnings:
            print(f"pydiag: warning: {Path(fmu).name}: {w}", file=sys.stderr)


def adapter_of(args) -> Adapter | None:
    return load_adapter(args.adapter) if getattr(args, "adapter", None) else None


def estimator_settings(args) -> dict:
    """The optimiser options the user gave (the library's defaults fill the rest)."""
    given = {key: getattr(args, opt) for opt, key in OPTIMISER_OPTIONS.items()
             if getattr(args, opt, None) is not None}
    if getattr(args, "eval_timeout", None) is not None:
        given["eval_timeout_s"] = args.eval_timeout
    return given


def check_outputs(args, *names: str) -> None:
    """Before any work: every output option can be written, none is an input, and no two
    name the same file."""
    given = [getattr(args, name, None) for name in ("measurement", "fmu", "adapter",
                                                     "history", "machine")]
    given += list(getattr(args, "baseline", None) or [])
    inputs = [Path(p).resolve() for p in given if isinstance(p, str)]
    seen: dict[Path, str] = {}
    for name in names:
        out = getattr(args, name, None)
        if out is None:
            continue
        option = f"--{name.replace('_', '-')}"
        path = Path(out).resolve()
        if path in inputs:
            raise UsageError(f"{option} {out} would overwrite an input file")
        if path in seen:
            raise UsageError(f"{option} and {seen[path]} name the same file {out}")
        seen[path] = option
        check_output(out, getattr(args, "force", False))


def problem_settings(args) -> ProblemSettings:
    """How the command line makes a record a fit problem (feature mode, operating point,
    speed, gain); commands without record options (demo) take the record as it is, its
    level the model's."""
    feature_mode = getattr(args, "features", "lines")
    if not hasattr(args, "speed"):
        return ProblemSettings(feature_mode, fit_gain=False, gain_curve=False)
    op = {}
    if args.input_hz is not None:
        op["f_pinion_hz"] = args.input_hz
    if args.teeth is not None:
        op["n_pinion"], op["n_gear"] = args.teeth
    if getattr(args, "other_shaft", None) is not None:  # compare and discover
        op["other_shaft_ratio"] = args.other_shaft
    if getattr(args, "bearing", None) is not None:  # compare and discover
        op["bearing"] = args.bearing
    return ProblemSettings(
        feature_mode, fit_gain={"auto": None, "fit": True, "curve": True, "fixed": False}[args.gain],
        gain_curve={"auto": None, "curve": True}.get(args.gain, False),
        speed=SpeedSettings(args.speed, tacho=args.tacho, pulses_per_rev=args.pulses_per_rev),
        operating_point=op or None)


def problem_of(args, measurement: Measurement,
               fixed_values: dict[str, float] | None = None) -> FitProblem:
    """The fit problem of the command line: its pair's, or a machine's stage's (--stage)."""
    machine, settings = getattr(args, "machine_description", None), problem_settings(args)
    if machine is None or len(machine.stages) == 1:
        return build_problem(args.fmu, measurement, adapter_of(args), **settings.keywords(),
                             fixed_values=fixed_values)
    return stage_problem(args.fmu, measurement, machine, args.stage_index,
                         machine_speed(measurement, machine, args.input_hz, settings.tracking),
                         settings, adapter_of(args), fixed_values)


def fit(args, problem: FitProblem) -> Diagnosis:
    update, close = progress_bar(args.quiet)
    try:
        return diagnose(problem, FaultEstimator(**estimator_settings(args), progress=update))
    finally:
        close()


# ---------------------------------------------------------------------- commands
def cmd_simulate(args) -> int:
    check_outputs(args, "out")
    values = dict(args.set or [])
    m = simulate_measurement(args.fmu, values, args.duration, args.sample_rate, args.snr,
                             args.seed, tuple(args.sensor) if args.sensor else None,
                             adapter=adapter_of(args))
    write_measurement(args.out, m, overwrite=args.force)
    if not args.quiet:
        print(f"wrote {args.out}: {m.n_samples} samples at {m.sample_rate_hz:g} Hz, "
              f"channels {', '.join(m.channels)}")
    return 0


def cmd_diagnose(args) -> int:
    check_outputs(args, "json")
    machine = args.machine_description
    if args.fmu is None and machine is None:
        raise UsageError("give --machine FILE, or --teeth NP,NG --rpm N for a gear pair (its "
                         "own model is written and built), or --fmu FILE (a model of your own)")
    if args.fmu is None and args.adapter:
        raise UsageError("--adapter describes an FMU of your own: give it with --fmu (the "
                         "machine's own model needs none)")
    check_lacking(args)
    m = read_input(args)
    if _staged(args):
        return _diagnose_stages(args, machine, m)
    problem = problem_of(args, m)
    result = fit(args, problem)
    print(format_result(result))
    print(format_facts(result.facts))
    for warning in result.warnings:
        print(f"pydiag diagnose: warning: {warning}", file=sys.stderr)
    if args.json:
        name = machine.stages[0].name if machine is not None else "stage 1"
        out = {**result.to_dict(), **pair_json(name, problem, result),
               "channels": list(problem.channels), "measurement": str(args.measurement)}
        write_text(args.json, json.dumps(out, indent=2) + "\n", args.force)
    return 0 if result.explained else 1


def _staged(args) -> bool:
    """Whether the record is diagnosed stage by stage (diagnose and batch): a --machine of
    several stages, or of one judged against --baseline; --baseline without a machine file
    is refused."""
    machine = args.machine_description
    if args.baseline and machine is None:
        raise UsageError("--baseline judges the stages of a machine against it: give "
                         "--machine FILE (a machine of one stage will do)")
    return machine is not None and (len(machine.stages) > 1 or bool(args.baseline)
                                    or args.fmu is None)


def _diagnose_stages(args, machine: Machine, m: Measurement) -> int:
    """diagnose --machine stage by stage (:func:`_staged`): every stage fitted, judged
    against the baselines when there are some."""
    settings = problem_settings(args)
    # the healthy model's records, read once for it and for the baselines' indicators
    healthy = healthy_measurements(args) if not args.fmu else {}
    baselines = baseline_records(args, machine, settings.tracking, healthy,
                                 records_kept_in(args, machine, healthy))
    machines = None if args.fmu else machine_models(args)
    model = None if machines is None else machines(machine)
    update, close = progress_bar(args.quiet)
    kept, grown = None, []
    try:
        estimator = FaultEstimator(**estimator_settings(args), progress=update)
        if model is None:
            result = diagnose_machine(args.fmu, m, machine, args.input_hz, settings,
                                      estimator, baselines, adapter_of(args))
        else:  # the machine's own model, every stage at once
            if healthy and (machine.effects or lacking_effects(args)):
                kept = kept_healthy_model(args, machine, model[0], model[1], healthy,
                                          settings, estimator)
            result = diagnose_machine_model(
                str(model[1].fmu), model[0], m, machine, args.input_hz, settings, estimator,
                baselines, None if kept is None else kept[0].model, machine_fmus(args),
                grower(args, machine, *model, healthy, settings, grown))
    finally:
        close()
    print(format_machine_report(result))
    if kept is not None:
        print(format_healthy_model(*kept, grown[-1] if grown else None))
    for warning in result.warnings:
        print(f"pydiag diagnose: warning: {warning}", file=sys.stderr)
    if model is not None:
        _warn_one_healthy(args, len(healthy))
    if args.json:
        out = {**result.to_dict(), "measurement": str(args.measurement)}
        write_text(args.json, json.dumps(out, indent=2) + "\n", args.force)
    return 0 if all(s.fit.explained for s in result.stages) else 1


def _warn_one_healthy(args, files: int) -> None:
    """Say that the machine's model judges no component with baselines of fewer than two
    files (``files``)."""
    if args.baseline and files < 2:
        print(f"pydiag {args.command}: warning: the model's verdict on the components needs "
              "two --baseline files (the healthy model's record, then a healthy repeat; kept "
              f"baselines hold no record): {files} given", file=sys.stderr)


def record_kinematics(args, measurement: Measurement) -> GearKinematics:
    """Teeth and nominal speed from --teeth/--rpm, else from the record's metadata."""
    meta = measurement.metadata.get("kinematics")
    known = kinematics_from(meta) if isinstance(meta, dict) else None
    if args.teeth is None and known is None:
        raise UsageError("give the teeth (--teeth NP,NG): the record does not say them")
    if args.input_hz is None and known is None:
        raise UsageError("give the nominal pinion speed (--rpm): the record does not say it")
    n_pinion, n_gear = args.teeth if args.teeth is not None else (known.n_pinion, known.n_gear)
    return GearKinematics(n_pinion, n_gear,
                          args.input_hz if args.input_hz is not None else known.f_pinion_hz)


def cmd_indicators(args) -> int:
    check_outputs(args, "json")
    m = read_input(args)
    speed = SpeedSettings(args.speed, tacho=args.tacho, pulses_per_rev=args.pulses_per_rev)
    machine = args.machine_description
    if machine is not None:
        report = machine_report(m, machine, speed, args.input_hz,
                                baseline_records(args, machine, speed))
        return _said_indicators(args, format_machine_report(report), report.record.speed,
                                report.to_dict())
    if args.baseline and len(args.baseline) > 1:
        raise UsageError("NA4 and NB4 of one pair take one --baseline (with --machine, "
                         "several judge every stage)")
    baseline = read_input(args, args.baseline[0]) if args.baseline else None
    report = condition_indicators(m, record_kinematics(args, m), speed, args.shaft, baseline)
    return _said_indicators(args, format_indicators(report), report.speed, report.to_dict())


def _said_indicators(args, text: str, speed: SpeedEstimate, data: dict) -> int:
    """An indicators report printed (``text``), the speed's warning, the JSON (``data``)."""
    print(text)
    warning = speed.warning()
    if warning:
        print(f"pydiag indicators: warning: {warning}", file=sys.stderr)
    if args.json:
        out = {**data, "measurement": str(args.measurement)}
        write_text(args.json, json.dumps(out, indent=2) + "\n", args.force)
    return 0


def cmd_batch(args) -> int:
    check_outputs(args, "out")
    batch.check_results_name(args.out)
    check_lacking(args)
    paths = batch.find_measurements(args.measurements)
    if args.adapter:
        load_adapter(args.adapter)  # fail early, once, on a bad adapter
    settings = {k: v for k, v in estimator_settings(args).items() if k != "n_workers"}
    channels = channels_to_read(args)
    machine = args.machine_description
    if not args.fmu and machine is None:
        raise UsageError("give --fmu, or --machine FILE to diagnose by the machine's own model")
    staged = _staged(args)
    problem = problem_settings(args)
    # the healthy model's records, read once for it and for the baselines' indicators
    healthy = healthy_measurements(args) if not args.fmu else {}
    baselines = tuple(baseline_records(args, machine, problem.tracking, healthy,
                                       records_kept_in(args, machine, healthy)))
    # the machine's own model, built once here for every record (a worker only runs it)
    machines = None if args.fmu else machine_models(args)
    built = None if machines is None else machines(machine)
    model, fmu = (None, args.fmu) if built is None else _built(built)
    kept, grown = None, []
    if healthy and (machine.effects or lacking_effects(args)):
        kept = kept_healthy_model(args, machine, model, built[1], healthy,
                                  problem, FaultEstimator(**settings))  # once, here
    if built is not None:
        _warn_one_healthy(args, len(healthy))
    tasks = [batch.BatchTask(p, fmu, settings, tuple(channels) if channels else None,
                             args.sample_rate, args.adapter, problem,
                             tuple(args.unit) if args.unit else None, args.indicators,
                             tuple(args.sensitivity or ()), args.machine if staged else None,
                             baselines, args.input_hz if staged else None, model,
                             None if kept is None else kept[0].model,
                             None if kept is None else tuple(map(str, library(args))))
             for p in paths]
    if kept is not None:  # grown once by what any record asks, before any is judged
        grow = grower(args, machine, *built, healthy, problem, grown)
        with records_bar(args.quiet, len(tasks), "asking") as update:
            tasks = batch.grown_first(tasks, lambda tries: grow(kept[0].model, tries),
                                      args.scheduler, args.workers, update)
        print(format_healthy_model(*kept, grown[-1] if grown else None))
    with records_bar(args.quiet, len(tasks), "batch") as update:
        rows = batch.run_batch(tasks, args.scheduler, args.workers, update)
    batch.write_results(rows, args.out, args.force)
    failed = [r for r in rows if r["status"] != "ok"]
    print(f"wrote {args.out}: {len(rows)} measurements, {len(rows) - len(failed)} diagnosed, "
          f"{len(failed)} failed")
    for r in rows:
        if r["message"]:
            print(f"  {r['measurement']}: {'' if r['status'] != 'ok' else 'warning: '}"
                  f"{r['message']}")
    return 0


def _built(model: tuple[MachineModel, BuiltModel]) -> tuple[MachineModel, str]:
    return model[0], str(model[1].fmu)


def cmd_regress(args) -> int:
    fmu, machine, sensors = args.fmu, None, tuple(args.sensor) if args.sensor else None
    if args.machine:
        if args.adapter:
            raise UsageError("--adapter describes an FMU of one's own: a machine's model "
                             "(--machine) describes itself")
        machine = load_machine(args.machine)
        model, fmu = _built(machine_models(args)(machine))
        sensors = sensors or tuple(o.name for o in model.outputs)
    if args.bless:
        check_outputs(args, "golden")  # an accepted behaviour is replaced only with --force
        path = regress.bless_fmu(fmu, args.golden, adapter_of(args), sensors, args.sample_rate,
                                 machine, SPEED_PARAMETER)
        print(f"blessed {path}")
        return 0
    report = regress.check(fmu, args.golden, args.rtol)
    print(format_regression(report))
    return 0 if report.passed else 1


def cmd_inspect(args) -> int:
    print("\n\n".join(format_info(describe(fmu), args.all) for fmu in args.fmu))
    return 0


def cmd_demo(args) -> int:
    c = case(args.case)
    print(f"Table 1 case {c.number} ({c.name}): simulating {', '.join(DEFAULT_SENSORS)} "
          f"at SNR {args.snr:g} ...")
    m = simulate_measurement(args.fmu, c.parameters, None, 10_000.0, args.snr, args.seed or 0)
    with tempfile.TemporaryDirectory() as tmp:  # the record goes through its file format too
        path = Path(tmp) / "measurement.csv"
        write_measurement(path, m)
        m = read_measurement(path)
    print(f"measurement: {m.duration_s:.2f} s at {m.sample_rate_hz:g} Hz; diagnosing ...")
    result = fit(args, problem_of(args, m))
    print(format_result(result, c.parameters))
    ok = result.fault_mode == c.fault_mode and result.severity == c.severity
    print(f"\nexpected   : {c.fault_mode}, {c.severity} -> {'correct' if ok else 'WRONG'}")
    return 0 if ok else 1
