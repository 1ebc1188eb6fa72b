"""Command line: pydiag simulate | diagnose | compare | discover | history | batch | regress |
inspect | demo.

Library modules never print; this module does. Known failures end with one line on
stderr and exit status 2; a failed regression check exits 1.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from pydiag.adapter import Adapter, AdapterError, load_adapter
from pydiag.estimate import EstimationError, FaultEstimator
from pydiag.measurement import Measurement, MeasurementError, read_measurement, write_measurement
from pydiag.noise import add_white_noise
from pydiag.plant import FmuPlant, PlantError

#: Sensor channels of the GearDiag models: acceleration for mesh content, displacement
#: for the once-per-turn transmission error (see docs/method.md for the measurement).
DEFAULT_SENSORS = ("acc", "disp")
DEFAULT_WARMUP_S = 0.05
KNOWN_ERRORS = (PlantError, MeasurementError, EstimationError, AdapterError, ValueError, OSError)


class UsageError(Exception):
    pass


def _parse_set(items: list[str]) -> dict[str, float]:
    values = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise UsageError(f"--set takes NAME=VALUE, got '{item}'")
        try:
            values[name.strip()] = float(value)
        except ValueError:
            raise UsageError(f"--set {name}: '{value}' is not a number") from None
    return values


def _default_sensors(plant_outputs: list[str]) -> tuple[str, ...]:
    chosen = tuple(s for s in DEFAULT_SENSORS if s in plant_outputs)
    return chosen or tuple(plant_outputs)


def _warn_validation(fmu: str) -> None:
    """Print fmpy's schema complaints as warnings: many vendor FMUs fail it yet run."""
    from pydiag.plant import read_model_description
    if Path(fmu).is_file():
        _, warnings = read_model_description(Path(fmu))
        for w in warnings:
            print(f"pydiag: warning: {Path(fmu).name}: {w}", file=sys.stderr)


def _outputs_of(fmu: str) -> list[str]:
    from pydiag.plant import read_model_description
    if not Path(fmu).is_file():
        raise PlantError(f"no such FMU: {fmu}")
    md, _ = read_model_description(Path(fmu))
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    if not outputs:
        raise PlantError(f"{fmu} has no output variables to use as a sensor")
    return outputs


# ---------------------------------------------------------------------- simulate
def simulate_measurement(fmu: str, values: dict[str, float], duration_s: float | None,
                         sample_rate_hz: float, snr: float | None, seed: int,
                         sensors: tuple[str, ...] | None, warmup_s: float = DEFAULT_WARMUP_S,
                         adapter: Adapter | None = None) -> Measurement:
    """A (noisy) record of the FMU; channels named by the adapter, else by the outputs."""
    if adapter is not None:
        if sensors:
            raise UsageError("give the sensors in the adapter or with --sensor, not both")
        channels = [(s.channel, s.scale) for s in adapter.sensors]
        sensors = tuple(s.variable for s in adapter.sensors)
        warmup_s = adapter.warmup_s
    else:
        sensors = sensors or _default_sensors(_outputs_of(fmu))
        channels = [(s, 1.0) for s in sensors]
    with FmuPlant(fmu, sensors, sample_rate_hz,
                  adapter.relative_tolerance if adapter else None,
                  adapter.start_values if adapter else None,
                  adapter.engine if adapter else "auto") as plant:
        if adapter is not None:
            from pydiag.adapter import check_against_fmu
            check_against_fmu(adapter, plant.variables)
            kin = adapter.resolve_kinematics({**plant.parameters(), **values})
        else:
            try:
                kin = plant.kinematics()
            except PlantError:
                kin = None
        if duration_s is None:
            duration_s = (10 * kin.period_s if kin else
                          adapter.window_s if adapter and adapter.window_s else 1.0)
        if not duration_s > 0:
            raise UsageError(f"--duration must be positive, got {duration_s}")
        y = plant.simulate(values, duration_s, warmup_s)
        meta = {"source": "pydiag simulate", "fmu": plant.fmu_path.name, "set": values,
                "snr": snr, "seed": seed, "warmup_s": warmup_s}
        if kin:
            meta["kinematics"] = {"Np": kin.n_pinion, "Ng": kin.n_gear, "f_pinion": kin.f_pinion_hz}
    rng = np.random.default_rng(seed)
    signals = {}
    for i, (name, scale) in enumerate(channels):
        clean = scale * y[i]
        signals[name] = add_white_noise(clean, snr, rng) if snr else clean
    return Measurement(signals, sample_rate_hz, meta)


def _adapter(args) -> Adapter | None:
    return load_adapter(args.adapter) if getattr(args, "adapter", None) else None


def cmd_simulate(args) -> int:
    values = _parse_set(args.set)
    m = simulate_measurement(args.fmu, values, args.duration, args.sample_rate, args.snr, args.seed,
                             tuple(args.sensor) if args.sensor else None, adapter=_adapter(args))
    write_measurement(args.out, m, overwrite=args.force)
    if not args.quiet:
        print(f"wrote {args.out}: {m.n_samples} samples at {m.sample_rate_hz:g} Hz, "
              f"channels {', '.join(m.channels)}")
    return 0


# ---------------------------------------------------------------------- diagnose
def _progress_bar(quiet: bool):
    if quiet:
        return None, lambda: None
    from tqdm import tqdm
    bar = tqdm(total=1, desc="diagnose", unit="sim", file=sys.stderr, leave=False)

    def update(done: int, total: int, best: float) -> None:
        bar.total = total
        bar.n = done
        bar.set_postfix(best_error=f"{best:.4g}", refresh=False)
        bar.refresh()

    return update, bar.close


def format_result(result, truth: dict | None = None) -> str:
    head = f"{'parameter':<10} {'estimate':>9}" + (f" {'true':>7} {'abs.err':>8}" if truth else "")
    lines = [head, "-" * len(head)]
    for name, value in result.parameters.items():
        row = f"{name:<10} {value:9.4f}"
        if truth and name in truth:
            row += f" {truth[name]:7.3f} {abs(value - truth[name]):8.4f}"
        lines.append(row)
    lines += ["",
              f"fault mode : {result.fault_mode}",
              f"severity   : {result.severity} (tooth: {result.tooth_severity}, "
              f"transmission error: {result.te_severity})",
              f"error      : {result.error:.5f} (Eq. 12, relative, summed over channels)",
              f"evaluations: {result.evaluations} in {result.elapsed_s:.1f} s"]
    if result.failed_evaluations:
        lines.append(f"failed     : {result.failed_evaluations} simulations, penalised: " + "; ".join(
            f"{n} x {reason}" for reason, n in result.failure_reasons.items()))
    return "\n".join(lines)


def run_diagnosis(fmu: str, measurement: Measurement, args):
    update, close = _progress_bar(args.quiet)
    est = FaultEstimator(fmu, adapter=_adapter(args), n_particles=args.particles,
                         iterations=args.iterations,
                         seed=args.seed, polish_evaluations=args.polish,
                         feature_mode=args.features, n_workers=args.workers, progress=update)
    try:
        return est.fit(measurement)
    finally:
        close()


def cmd_diagnose(args) -> int:
    if args.json and Path(args.json).resolve() == Path(args.measurement).resolve():
        raise UsageError("--json would overwrite the measurement file")
    m = read_measurement(args.measurement, args.sample_rate, args.column)
    result = run_diagnosis(args.fmu, m, args)
    print(format_result(result))
    if args.json:
        out = {"parameters": result.parameters, "fault_mode": result.fault_mode,
               "severity": result.severity, "tooth_severity": result.tooth_severity,
               "te_severity": result.te_severity, "error": result.error,
               "evaluations": result.evaluations, "elapsed_s": result.elapsed_s,
               "failed_evaluations": result.failed_evaluations,
               "failure_reasons": result.failure_reasons,
               "channels": list(m.channels), "measurement": str(args.measurement)}
        Path(args.json).write_text(json.dumps(out, indent=2) + "\n")
    return 0


# ---------------------------------------------------------------------- batch
def cmd_batch(args) -> int:
    from pydiag import batch

    if Path(args.out).exists():
        raise UsageError(f"{args.out} exists; choose another name")
    paths = batch.find_measurements(args.measurements)
    estimator = dict(n_particles=args.particles, iterations=args.iterations, seed=args.seed,
                     polish_evaluations=args.polish, feature_mode=args.features)
    if args.adapter:
        load_adapter(args.adapter)  # fail early, once, on a bad adapter
    tasks = [batch.BatchTask(p, args.fmu, estimator, tuple(args.column) if args.column else None,
                             args.sample_rate, args.adapter) for p in paths]
    bar = None
    if not args.quiet:
        from tqdm import tqdm
        bar = tqdm(total=len(tasks), desc="batch", unit="meas", file=sys.stderr, leave=False)
    try:
        rows = batch.run_batch(tasks, args.scheduler, args.workers,
                               (lambda done, total: bar.update(done - bar.n)) if bar else None)
    finally:
        if bar:
            bar.close()
    batch.write_results(rows, args.out)
    failed = [r for r in rows if r["status"] != "ok"]
    print(f"wrote {args.out}: {len(rows)} measurements, {len(rows) - len(failed)} diagnosed, "
          f"{len(failed)} failed")
    for r in failed:
        print(f"  {r['measurement']}: {r['message']}")
    return 0


# ---------------------------------------------------------------------- regress
def cmd_regress(args) -> int:
    from pydiag import regress
    adapter = _adapter(args)
    if args.bless:
        if adapter is not None:
            sensors = tuple(s.variable for s in adapter.sensors)
        else:
            sensors = tuple(args.sensor) if args.sensor else _default_sensors(_outputs_of(args.fmu))
        with FmuPlant(args.fmu, sensors, args.sample_rate,
                      adapter.relative_tolerance if adapter else None,
                      adapter.start_values if adapter else None,
                      adapter.engine if adapter else "auto") as plant:
            path = regress.bless(plant, args.golden, adapter=adapter)
        print(f"blessed {path}")
        return 0
    report = regress.check(args.fmu, args.golden, args.rtol)
    for mm in report.mismatches:
        print(f"FAIL {mm.case} {mm.sensor} at {mm.freq_hz:.2f} Hz: golden {mm.golden:.6g}, "
              f"now {mm.actual:.6g} (allowed +-{mm.allowed:.3g})")
    status = "PASS" if report.passed else "FAIL"
    print(f"{status}: {report.cases} cases x {len(report.sensors)} sensors, worst deviation "
          f"{report.worst_relative:.2e} of the largest line (tolerance {report.rtol:.1e})")
    return 0 if report.passed else 1


# ---------------------------------------------------------------------- compare, history
def _bearing(text: str | None):
    from pydiag.kinematic_map import Bearing
    if not text:
        return None
    try:
        parts = [float(v) for v in text.split(",")]
        n, d_mm, pitch_mm = parts[:3]
        angle = parts[3] if len(parts) > 3 else 0.0
    except ValueError:
        raise UsageError(f"--bearing takes N_BALLS,BALL_MM,PITCH_MM[,ANGLE_DEG], got '{text}'") from None
    return Bearing(int(n), d_mm * 1e-3, pitch_mm * 1e-3, np.radians(angle))


def cmd_compare(args) -> int:
    from pydiag import history
    from pydiag.compare import compare
    from pydiag.plant import read_model_description

    for out in (args.json, args.report):
        if out and Path(out).resolve() == Path(args.measurement).resolve():
            raise UsageError("--json/--report would overwrite the measurement file")
    from pydiag.compare import refit_with_effect
    from pydiag.effects import EFFECTS

    effect = None
    if args.effect:
        if args.effect not in EFFECTS:
            raise UsageError(f"unknown effect '{args.effect}'; known: {', '.join(EFFECTS)}")
        effect = EFFECTS[args.effect]
    m = read_measurement(args.measurement, args.sample_rate, args.column)
    bearing = _bearing(args.bearing)
    update, close = _progress_bar(args.quiet)
    # with an effect model, the base fit runs with the effect switched off (lower bounds)
    neutral = {n: lo for n, lo, _ in effect.parameters} if effect else None
    est = FaultEstimator(args.fmu, adapter=_adapter(args), fixed_values=neutral,
                         n_particles=args.particles, iterations=args.iterations, seed=args.seed,
                         polish_evaluations=args.polish, n_workers=args.workers, progress=update)
    try:
        c = compare(args.fmu, m, est, bearing, args.false_alarm_rate)
        if effect is not None:
            c = refit_with_effect(args.fmu, m, c, effect, bearing, args.seed, args.workers)
    finally:
        close()
    md, _ = read_model_description(Path(args.fmu))
    run_id = history.record(args.history, c, args.measurement, md.modelName, args.source)
    print(f"error      : {c.error:.5f} (Eq. 12 less its noise part, {c.error_raw:.5f} raw, on "
          f"{c.n_error_bins} bins: synchronous lines and the measurement's peaks; "
          f"{c.n_periods} periods, {c.bin_hz:.3g} Hz bins)")
    print("parameters : " + ", ".join(f"{k}={v:.4g}" for k, v in c.parameters.items()))
    print(f"peaks      : {len(c.peaks)} unexplained above the noise floor "
          f"(false-alarm rate {c.false_alarm_rate:g})")
    for i, p in enumerate(c.peaks[:10], 1):
        print(f"  {i:2d}. {p.channel:<5} {p.freq_hz:9.2f} Hz  {p.family:<15} {p.label:<24} "
              f"{100 * p.energy_fraction:5.1f} % of residual energy")
    shown = [s for s in c.suggested_effects if s.score > 0]
    print("suggested  : " + ("none" if not shown else ""))
    for s in shown:
        flag = "confident" if s.confidence >= 0.5 else "weak"
        print(f"  {s.effect:<26} confidence {s.confidence:.2f} ({flag}); " + "; ".join(s.evidence[:1]))
    print(f"recorded as run {run_id} in {args.history}")
    if args.report:
        from pydiag.report import write_report
        write_report(c, args.report, args.measurement, history.runs(args.history))
        print(f"report     : {args.report}")
    if args.json:
        Path(args.json).write_text(json.dumps(c.to_dict(), indent=2) + "\n")
    return 0


def cmd_discover(args) -> int:
    from pydiag.discover import MODELICA_ROOT, as_dict, discover

    m = read_measurement(args.measurement, args.sample_rate, args.column)
    est = FaultEstimator(args.fmu, adapter=_adapter(args), n_particles=args.particles,
                         iterations=args.iterations, seed=args.seed,
                         polish_evaluations=args.polish, n_workers=args.workers)
    progress = None if args.quiet else (lambda key: print(f"trying {key} ...", file=sys.stderr))
    base, found = discover(args.fmu, m, est, _bearing(args.bearing),
                           args.effects.split(",") if args.effects else None,
                           Path(args.modelica) if args.modelica else MODELICA_ROOT,
                           Path(args.build_dir), progress)
    print(f"base model error {base.error:.5f}; effects ranked by BIC (dBIC < 0: worth its "
          "parameters)")
    print(f"{'rank':>4} {'effect':<26} {'dBIC':>10} {'error':>8} {'reduction':>9}  parameters")
    for i, d in enumerate(found, 1):
        if d.status != "ok":
            print(f"{i:4d} {d.effect:<26} {'-':>10} {'-':>8} {'-':>9}  failed: {d.status}")
            continue
        params = ", ".join(f"{k}={v:.4g}" for k, v in d.parameters.items())
        print(f"{i:4d} {d.effect:<26} {d.delta_bic:10.1f} {d.error:8.4f} "
              f"{100 * d.error_reduction:8.0f}%  {params}")
    if args.json:
        Path(args.json).write_text(json.dumps(as_dict(base, found), indent=2) + "\n")
    return 0


def cmd_history(args) -> int:
    from pydiag import history

    rows = history.runs(args.history)
    if not rows:
        raise UsageError(f"no compare runs recorded in {args.history}")
    print(f"{'run':>4} {'time (UTC)':<20} {'model':<28} {'fmu sha256':<12} {'error':>8} {'peaks':>5}")
    for r in rows:
        print(f"{r['id']:4d} {r['time_utc']:<20} {(r['model_name'] or '')[:28]:<28} "
              f"{r['fmu_sha256'][:12]:<12} {r['error']:8.4f} {r['n_peaks']:5d}")
    if args.plot:
        print(f"wrote {history.plot(rows, args.plot)}")
    return 0


# ---------------------------------------------------------------------- inspect
def cmd_inspect(args) -> int:
    from pydiag.inspect_fmu import describe, format_info

    for i, fmu in enumerate(args.fmu):
        if i:
            print()
        print(format_info(describe(fmu), args.all))
    return 0


# ---------------------------------------------------------------------- demo
def cmd_demo(args) -> int:
    from pydiag.paper_cases import case
    c = case(args.case)
    print(f"Table 1 case {c.number} ({c.name}): simulating {', '.join(DEFAULT_SENSORS)} "
          f"at SNR {args.snr:g} ...")
    m = simulate_measurement(args.fmu, c.parameters, None, 10_000.0, args.snr, args.seed, None)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "measurement.csv"
        write_measurement(path, m)
        m = read_measurement(path)
    print(f"measurement: {m.duration_s:.2f} s at {m.sample_rate_hz:g} Hz; diagnosing ...")
    result = run_diagnosis(args.fmu, m, args)
    print(format_result(result, c.parameters))
    ok = result.fault_mode == c.fault_mode and result.severity == c.severity
    print(f"\nexpected   : {c.fault_mode}, {c.severity} -> {'correct' if ok else 'WRONG'}")
    return 0 if ok else 1


# ---------------------------------------------------------------------- parser
def _add_optimiser_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--particles", type=int, default=16, help="swarm size (default 16)")
    p.add_argument("--iterations", type=int, default=20, help="swarm iterations (default 20)")
    p.add_argument("--polish", type=int, default=150,
                   help="Nelder-Mead polish evaluations, 0 to skip (default 150)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--workers", type=int, default=None,
                   help="worker processes (default: cores); batch: measurements in parallel")
    p.add_argument("--features", choices=("lines", "paper"), default="lines",
                   help="every synchronous line in the bands, or the paper's band maxima")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="pydiag", description="FMU-based gear diagnosis")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("simulate", help="simulate a measurement CSV from an FMU")
    p.add_argument("--fmu", required=True)
    p.add_argument("--set", action="append", metavar="NAME=VALUE", help="parameter value (repeat)")
    p.add_argument("--duration", type=float, default=None,
                   help="seconds of signal (default: 10 fundamental periods)")
    p.add_argument("--sample-rate", type=float, default=10_000.0, help="Hz (default 10000)")
    p.add_argument("--snr", type=float, default=None, help="signal/noise power ratio per channel")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--sensor", action="append", help="output to record (repeat; default acc, disp)")
    p.add_argument("--adapter", help="adapter TOML describing the FMU (sensors, start values)")
    p.add_argument("--out", required=True, help="CSV file to write")
    p.add_argument("--force", action="store_true", help="replace an existing --out file")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("diagnose", help="estimate fault parameters from a measurement")
    p.add_argument("--fmu", required=True)
    p.add_argument("--measurement", required=True, help="CSV with time_s and sensor columns")
    p.add_argument("--column", action="append", help="channel to use (repeat; default: all)")
    p.add_argument("--sample-rate", type=float, default=None, help="Hz, if the CSV has no time_s")
    p.add_argument("--json", help="write the result as JSON here")
    p.add_argument("--adapter", help="adapter TOML describing the FMU")
    _add_optimiser_args(p)
    p.set_defaults(func=cmd_diagnose)

    p = sub.add_parser("batch", help="diagnose many measurements (locally or on Dask)")
    p.add_argument("--fmu", required=True)
    p.add_argument("--measurements", required=True, help="folder of CSV files, or a glob")
    p.add_argument("--out", required=True, help="results table (.parquet, or .csv)")
    p.add_argument("--scheduler", default="local", help="'local' or a Dask tcp://HOST:PORT")
    p.add_argument("--adapter", help="adapter TOML describing the FMU")
    p.add_argument("--column", action="append", help="channel to use (repeat; default: all)")
    p.add_argument("--sample-rate", type=float, default=None, help="Hz, if CSVs have no time_s")
    _add_optimiser_args(p)
    p.set_defaults(func=cmd_batch)

    p = sub.add_parser("regress", help="check an FMU against golden spectra")
    p.add_argument("--fmu", required=True)
    p.add_argument("--golden", required=True, help="golden JSON file")
    p.add_argument("--bless", action="store_true", help="write the golden file from this FMU")
    p.add_argument("--rtol", type=float, default=None,
                   help="tolerance, fraction of the largest line (default 2e-3)")
    p.add_argument("--sensor", action="append", help="output to check when blessing (repeat)")
    p.add_argument("--sample-rate", type=float, default=10_000.0, help="Hz when blessing")
    p.add_argument("--adapter", help="adapter TOML (sensors, start values, kinematics) for --bless")
    p.set_defaults(func=cmd_regress)

    p = sub.add_parser("compare", help="fit, then show where the model fails and which effect is missing")
    p.add_argument("--fmu", required=True)
    p.add_argument("--measurement", required=True)
    p.add_argument("--column", action="append", help="channel to use (repeat; default: all)")
    p.add_argument("--sample-rate", type=float, default=None, help="Hz, if the CSV has no time_s")
    p.add_argument("--adapter", help="adapter TOML describing the FMU")
    p.add_argument("--bearing", help="pinion bearing N_BALLS,BALL_MM,PITCH_MM[,ANGLE_DEG] "
                                     "for BPFO/BPFI/BSF/FTF")
    p.add_argument("--false-alarm-rate", type=float, default=0.01,
                   help="chance of any false peak on a perfect model (default 0.01)")
    p.add_argument("--json", help="write error, peaks, suggested_effects as JSON here")
    p.add_argument("--report", help="write a self-contained HTML report here")
    p.add_argument("--history", default="pydiag_history.sqlite", help="SQLite run history")
    p.add_argument("--source", help="the Modelica source of the FMU, hashed into the history")
    p.add_argument("--effect", help="the FMU is this catalogue effect's model (e.g. "
                                    "bearing_outer_race): also fit the effect's parameters")
    _add_optimiser_args(p)
    p.set_defaults(func=cmd_compare)

    p = sub.add_parser("discover", help="try every catalogue effect, rank them by BIC")
    p.add_argument("--fmu", required=True, help="the base model FMU")
    p.add_argument("--measurement", required=True)
    p.add_argument("--column", action="append", help="channel to use (repeat; default: all)")
    p.add_argument("--sample-rate", type=float, default=None, help="Hz, if the CSV has no time_s")
    p.add_argument("--adapter", help="adapter TOML describing the FMU")
    p.add_argument("--bearing", help="pinion bearing N_BALLS,BALL_MM,PITCH_MM[,ANGLE_DEG]")
    p.add_argument("--effects", help="comma-separated effect keys (default: the whole catalogue)")
    p.add_argument("--modelica", help="Modelica library root holding GearDiag/Effects")
    p.add_argument("--build-dir", default="build/effects", help="where effect FMUs are built")
    p.add_argument("--json", help="write the ranking as JSON here")
    _add_optimiser_args(p)
    p.set_defaults(func=cmd_discover)

    p = sub.add_parser("history", help="list compare runs; --plot the error across model revisions")
    p.add_argument("--history", default="pydiag_history.sqlite")
    p.add_argument("--plot", help="PNG file for the error history")
    p.set_defaults(func=cmd_history)

    p = sub.add_parser("inspect", help="describe an FMU: version, interfaces, settable variables")
    p.add_argument("fmu", nargs="+")
    p.add_argument("--all", action="store_true", help="list every variable, not only the interface")
    p.set_defaults(func=cmd_inspect)

    p = sub.add_parser("demo", help="simulate a Table 1 case at SNR 10 and diagnose it")
    p.add_argument("--fmu", required=True)
    p.add_argument("--case", type=int, default=8, help="Table 1 case number (default 8)")
    p.add_argument("--snr", type=float, default=10.0)
    _add_optimiser_args(p)
    p.set_defaults(func=cmd_demo)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if getattr(args, "rtol", 0) is None:
        from pydiag.regress import DEFAULT_RTOL
        args.rtol = DEFAULT_RTOL
    try:
        if args.command in ("simulate", "diagnose", "batch", "regress", "demo", "compare",
                            "discover"):
            _warn_validation(args.fmu)
        return args.func(args)
    except (UsageError, *KNOWN_ERRORS) as err:
        print(f"pydiag {args.command}: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("pydiag: interrupted", file=sys.stderr)
        return 130
    except Exception as err:  # never a traceback dump for the user; PYDIAG_DEBUG=1 shows it
        if os.environ.get("PYDIAG_DEBUG"):
            raise
        print(f"pydiag {args.command}: internal error: {type(err).__name__}: {err} "
              "(set PYDIAG_DEBUG=1 for the traceback)", file=sys.stderr)
        return 3
