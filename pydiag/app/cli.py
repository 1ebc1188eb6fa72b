"""Command line: pydiag simulate | diagnose | indicators | compare | discover | loop | history |
accept | baseline | batch | regress | inspect | demo.

This module parses arguments (every number is checked here, before any work), calls the
command, and maps errors to exit codes: a :class:`~pydiag.core.errors.PydiagError` is the
user's to fix (one line on stderr, status 2); anything else is an internal error (one
line, status 3; ``PYDIAG_DEBUG=1`` shows the traceback). A failed regression exits 1,
and so does a diagnosis the model cannot make (it explains none of the record).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading

from pydiag.app.arguments import (bearing, effect_list, number, parameter_value, positive,
                                  rate, sensitivity, speed_ratio, teeth)
from pydiag.app.baselines import cmd_baseline
from pydiag.app.commands import (cmd_batch, cmd_demo, cmd_diagnose, cmd_indicators,
                                 cmd_inspect, cmd_regress, cmd_simulate, warn_validation)
from pydiag.app.loop_commands import (cmd_accept, cmd_compare, cmd_discover, cmd_history,
                                      cmd_loop)
from pydiag.app.machine_options import apply_machine
from pydiag.core.errors import PydiagError
from pydiag.core.termination import raise_once
from pydiag.gear.effects import EFFECTS
from pydiag.gear.features import FEATURE_MODES
from pydiag.gear.indicators import SHAFTS
from pydiag.gear.paper_cases import TABLE1
from pydiag.gear.speed import SPEED_METHODS
from pydiag.gear.comparable import BASELINE_SPEED_SHARE
from pydiag.model.regress import DEFAULT_RTOL


# ---------------------------------------------------------------------- parser
class Parser(argparse.ArgumentParser):
    """Bad arguments end with one line on stderr (and a pointer to --help), status 2."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _optimiser_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--particles", type=number(int, 2), help="swarm size (default 16; an "
                   "effect's refit: 8)")
    p.add_argument("--iterations", type=number(int, 1), help="swarm iterations (default 20; "
                   "an effect's refit: 6)")
    p.add_argument("--polish", type=number(int, 0), help="least-squares polish evaluations "
                   "per start, 0 to skip (default 150; an effect's refit: 60)")
    p.add_argument("--seed", type=number(int, 0), help="random seed (default 0)")
    p.add_argument("--workers", type=number(int, 1),
                   help="worker processes (default: cores; at most the cores unless "
                   "--oversubscribe); batch: measurements in parallel")
    p.add_argument("--oversubscribe", action="store_true",
                   help="allow more workers than cores (they only share the cores)")
    p.add_argument("--eval-timeout", type=positive, help="seconds one simulation may take "
                   "before it is killed and penalised (default 60)")
    p.add_argument("--features", choices=FEATURE_MODES, default="lines",
                   help="every synchronous line in the bands, or the paper's band maxima")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def _reading_args(p: argparse.ArgumentParser) -> None:
    """How to read a record: channels, units, rate."""
    p.add_argument("--channel", "--column", dest="channel", action="append",
                   metavar="NAME[=OUTPUT]", help="channel to use, mapped to a model output "
                   "(repeat; e.g. a1=acc; default: every column)")
    p.add_argument("--unit", action="append", metavar="[NAME=]UNIT",
                   help="unit of the channels (or of one), converted to SI: g, m/s2, mm/s, um")
    p.add_argument("--sample-rate", type=positive, help="Hz, if the file has no time column "
                   "or rate")
    p.add_argument("--sensitivity", action="append", type=sensitivity, metavar="NAME=VALUE",
                   help="a sensor's sensitivity (e.g. ch1=100mV/g): its channel, in volts, "
                   "becomes an acceleration (velocity, displacement); without one a channel "
                   "in volts keeps its level unknown, and a fit takes it as a gain")


def _operating_args(p: argparse.ArgumentParser) -> None:
    """The record's operating point and how to find its speed."""
    p.add_argument("--machine", metavar="FILE", help="machine description (TOML: stages, "
                   "shafts, bearings, sensors, tacho; see examples/); --rpm then sets the "
                   "input shaft's nominal speed")
    p.add_argument("--rpm", type=positive, help="nominal pinion speed, rev/min (sets f_pinion)")
    p.add_argument("--teeth", type=teeth, metavar="NP,NG", help="pinion and gear teeth "
                   "(set Np, Ng)")
    p.add_argument("--speed", choices=SPEED_METHODS, default="auto",
                   help="how to find the speed in the record: auto (tacho if given, else the "
                   "mesh lines), mesh, tacho, or nominal (take it as constant; default auto)")
    p.add_argument("--tacho", metavar="NAME", help="tacho channel (pulses), not a sensor")
    p.add_argument("--pulses-per-rev", type=number(int, 1),
                   help="tacho pulses per pinion (input shaft) revolution (default: the "
                   "machine file's, else 1)")


def _loop_args(p: argparse.ArgumentParser) -> None:
    """compare's, discover's and loop's: the pair's surroundings, the stage, the effect
    models."""
    p.add_argument("--bearing", type=bearing, help="pinion bearing N_BALLS,BALL_MM,PITCH_MM"
                   "[,ANGLE_DEG] for BPFO/BPFI/BSF/FTF")
    p.add_argument("--other-shaft", type=speed_ratio, metavar="RATIO",
                   help="speed of another shaft over the pinion's (a motor shaft whose Z1 "
                   "teeth drive Z2 on the pinion's: Z2/Z1; a second stage on the gear's "
                   "shaft, Z3 driving Z4: NP/NG*Z3/Z4): its orders are kinematic lines")
    p.add_argument("--stage", metavar="NAME|N", help="with a --machine of several stages: "
                   "the stage whose pair model is fitted (its name, or its number from 1 at "
                   "the input); every stage's lines are named. compare without it and "
                   "without --fmu fits the machine's own model of every stage")
    _library_args(p)


def _library_args(p: argparse.ArgumentParser) -> None:
    """Where the models pydiag writes come from and are built."""
    p.add_argument("--modelica", help="Modelica library root holding GearDiag/Effects")
    p.add_argument("--build-dir", help="where the models pydiag writes (a machine's, an "
                   "effect's) are built (default: a per-user cache, ~/.cache/pydiag/effects, "
                   "or under $XDG_CACHE_HOME)")


def _record_args(p: argparse.ArgumentParser) -> None:
    """How to read a record and find its operating point (diagnose, compare, discover, batch)."""
    _reading_args(p)
    p.add_argument("--adapter", help="adapter TOML describing the FMU")
    _operating_args(p)
    p.add_argument("--gain", choices=("auto", "fit", "curve", "fixed"), default="auto",
                   help="fit a gain per channel in closed form, or take the model's level as "
                   "it is; curve: fit a gain curve over frequency, a node at every mesh "
                   "harmonic (a housing between the gears and the sensor: the model is "
                   "judged on the lines around each harmonic, not on the spectrum's shape); "
                   "auto (default): the model's level on records pydiag simulate made; on "
                   "others curve with --machine and no --fmu when the machine file places "
                   "its sensors ([[sensors]]: on its housing), else fit")


def _measurement_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--measurement", required=True, help="record file: CSV/TSV (.gz), Parquet, "
                   "MAT, WAV, TDMS")
    _record_args(p)


#: --baseline's word for the kept baselines, in its help.
KEPT_HELP = ("; the word kept: those kept for the machine (pydiag baseline) within "
             f"{100 * BASELINE_SPEED_SHARE:g} %% of its nominal speed")


def _baseline_args(p: argparse.ArgumentParser) -> None:
    """diagnose's and batch's: the machine's healthy records, and its healthy model's."""
    p.add_argument("--baseline", metavar="FILE|kept", action="append",
                   help="with --machine: a record of the machine in a known healthy state, "
                   "every stage judged against it (repeat for more; without --fmu, the "
                   "first file is the healthy model's record, the others its repeats)"
                   + KEPT_HELP)
    p.add_argument("--lacking", type=effect_list, help="with that healthy model: the effects "
                   "it lacks that a record is asked for, held out, where they could name a "
                   "component the indicators find changed (comma-separated keys, or none; "
                   "default: every fault of a gear, bearing or shaft the catalogue has)")


def _history_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--history", help="SQLite history of runs and kept baselines (default: the "
                   "per-user ~/.local/share/pydiag/history.sqlite, or under $XDG_DATA_HOME)")


def _force(p: argparse.ArgumentParser) -> None:
    p.add_argument("--force", action="store_true", help="replace existing output files")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="pydiag", description="FMU-based gear diagnosis")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("simulate", help="simulate a measurement CSV from an FMU")
    p.add_argument("--fmu", required=True)
    p.add_argument("--set", action="append", type=parameter_value, metavar="NAME=VALUE",
                   help="parameter value (repeat)")
    p.add_argument("--duration", type=positive, help="seconds of signal (default: 10 "
                   "fundamental periods)")
    p.add_argument("--sample-rate", type=positive, default=10_000.0, help="Hz (default 10000)")
    p.add_argument("--snr", type=positive, help="signal/noise power ratio per channel "
                   "(default: no noise)")
    p.add_argument("--seed", type=number(int, 0), default=0)
    p.add_argument("--sensor", action="append", help="output to record (repeat; default acc, disp)")
    p.add_argument("--adapter", help="adapter TOML describing the FMU (sensors, start values)")
    p.add_argument("--out", required=True, help="CSV file to write")
    _force(p)
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("diagnose", help="estimate fault parameters from a measurement")
    p.add_argument("--fmu", help="a model of your own (or a vendor's, with --adapter); "
                   "without it, --machine's own model is written and built")
    _measurement_args(p)
    _library_args(p)
    _baseline_args(p)
    _history_arg(p)
    p.add_argument("--json", help="write the result as JSON here")
    _force(p)
    _optimiser_args(p)
    p.set_defaults(func=cmd_diagnose)

    p = sub.add_parser("indicators", help="gear condition indicators on the synchronous average "
                       "(no FMU)")
    p.add_argument("--measurement", required=True, help="record file: CSV/TSV (.gz), Parquet, "
                   "MAT, WAV, TDMS")
    _reading_args(p)
    _operating_args(p)
    p.add_argument("--shaft", choices=SHAFTS, default="pinion",
                   help="the shaft the synchronous average follows (default pinion)")
    p.add_argument("--baseline", metavar="FILE|kept", action="append",
                   help="reference record of the machine in a known healthy state (or the "
                   "first of a trend): NA4 and NB4 against it; with --machine every stage is "
                   "judged against it (repeat for more baselines)" + KEPT_HELP)
    _history_arg(p)
    p.add_argument("--json", help="write the indicators as JSON here")
    _force(p)
    p.set_defaults(func=cmd_indicators)

    p = sub.add_parser("batch", help="diagnose many measurements (locally or on Dask)")
    p.add_argument("--fmu", help="a model of your own (or a vendor's, with --adapter); "
                   "without it, --machine's own model is written and built, once")
    p.add_argument("--measurements", required=True,
                   help="folder of record files (any format pydiag reads), or a glob")
    p.add_argument("--out", required=True, help="results table (.parquet, or .csv)")
    p.add_argument("--scheduler", default="local", help="'local' or a Dask tcp://HOST:PORT")
    p.add_argument("--indicators", nargs="?", const="pinion", choices=SHAFTS,
                   help="add the condition indicators of this shaft as columns (default pinion)")
    _baseline_args(p)
    _history_arg(p)
    _record_args(p)
    _library_args(p)
    _force(p)
    _optimiser_args(p)
    p.set_defaults(func=cmd_batch)

    p = sub.add_parser("baseline", help="keep a record of a machine in a known healthy "
                       "state as its baseline (--baseline kept judges against it); --list, "
                       "--forget")
    p.add_argument("--measurement", help="the record to keep: CSV/TSV (.gz), Parquet, MAT, "
                   "WAV, TDMS, or a zip of one")
    p.add_argument("--list", action="store_true", help="list the machine's kept baselines")
    p.add_argument("--forget", type=number(int, 1), metavar="ID",
                   help="remove the machine's baseline of this id (--list shows them)")
    _reading_args(p)
    _operating_args(p)
    _history_arg(p)
    p.set_defaults(func=cmd_baseline)

    p = sub.add_parser("regress", help="check an FMU, or a machine's own model, against "
                       "golden spectra")
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--fmu", help="the FMU to check")
    which.add_argument("--machine", help="machine TOML file: its own model, written and built "
                       "(checked on the machine's period at the file's input speed)")
    _library_args(p)
    p.add_argument("--golden", required=True, help="golden JSON file")
    p.add_argument("--bless", action="store_true", help="write the golden file from this FMU "
                   "(replace an existing one with --force)")
    p.add_argument("--rtol", type=number(float, 0), default=DEFAULT_RTOL,
                   help=f"tolerance, fraction of the largest line (default {DEFAULT_RTOL:g})")
    p.add_argument("--sensor", action="append", help="output to check when blessing (repeat; "
                   "default the GearDiag sensors, or every output of a machine's model)")
    p.add_argument("--sample-rate", type=positive, default=10_000.0, help="Hz when blessing")
    p.add_argument("--adapter", help="adapter TOML (sensors, start values, kinematics) for --bless")
    _force(p)
    p.set_defaults(func=cmd_regress)

    p = sub.add_parser("compare", help="fit, then show where the model fails and which effect is missing")
    p.add_argument("--fmu", help="the model FMU; with --machine of several stages and no "
                   "--stage, none: the machine's own model (every stage) is written and built")
    _measurement_args(p)
    _loop_args(p)
    p.add_argument("--false-alarm-rate", type=rate, default=0.01,
                   help="chance of any false peak on a perfect model among the kinematic "
                   "lines, and again among the other bins, in (0, 1) (default 0.01)")
    p.add_argument("--json", help="write error, peaks, suggested_effects as JSON here")
    p.add_argument("--report", help="write a self-contained HTML report here")
    _history_arg(p)
    p.add_argument("--source", help="the Modelica source of the FMU, hashed into the history")
    p.add_argument("--effect", choices=list(EFFECTS), help="also fit this catalogue effect: "
                   "the FMU is its model (or the base, for housing_sensor's transfer path)")
    p.add_argument("--no-validate", action="store_true", help="do not try the suggested "
                   "effects held out (then none is confident)")
    _force(p)
    _optimiser_args(p)
    p.set_defaults(func=cmd_compare)

    p = sub.add_parser("discover", help="try every catalogue effect held out, rank them")
    p.add_argument("--fmu", help="the base model FMU; with --machine of several stages and no "
                   "--stage, none: every effect the machine's own model lacks, on every stage")
    _measurement_args(p)
    _loop_args(p)
    p.add_argument("--effects", type=effect_list, help="comma-separated effect keys (default: "
                   "the whole catalogue)")
    p.add_argument("--json", help="write the ranking as JSON here")
    _force(p)
    _optimiser_args(p)
    p.set_defaults(func=cmd_discover)

    p = sub.add_parser("loop", help="compare, accept the one confident effect, compare the "
                       "model with it, and again until nothing is confident")
    p.add_argument("--fmu", help="the base model FMU; with --machine of several stages and no "
                   "--stage, none: the machine's own model, its accepted effects written "
                   "into a copy of the machine file (<name>.loop.toml)")
    _measurement_args(p)
    _loop_args(p)
    p.add_argument("--max-steps", type=number(int, 1), default=4,
                   help="comparisons at most (default 4)")
    p.add_argument("--out", metavar="FILE", help="with --machine and no --fmu: the copy of "
                   "the machine file that gets the accepted effects (default <name>.loop.toml "
                   "beside it)")
    p.add_argument("--json", help="write the steps as JSON here")
    _history_arg(p)
    _force(p)
    _optimiser_args(p)
    p.set_defaults(func=cmd_loop)

    p = sub.add_parser("accept", help="give a stage of a machine file a catalogue effect: "
                       "compare --machine then fits the machine's model with it")
    p.add_argument("effect", choices=list(EFFECTS), metavar="EFFECT",
                   help="the catalogue effect (pydiag compare names them)")
    p.add_argument("--machine", required=True, metavar="FILE",
                   help="the machine file (TOML) to add it to; edited in place")
    p.add_argument("--stage", metavar="NAME|N", help="the stage it is on (its name, or its "
                   "number from 1 at the input; not needed for a machine of one stage)")
    p.set_defaults(func=cmd_accept)

    p = sub.add_parser("history", help="list compare runs; --plot the error across model revisions")
    p.add_argument("--history", help="SQLite run history (default: as for compare)")
    p.add_argument("--plot", help="PNG (or .svg, .pdf) file for the error history")
    _force(p)
    p.set_defaults(func=cmd_history)

    p = sub.add_parser("inspect", help="describe an FMU: version, interfaces, settable variables")
    p.add_argument("fmu", nargs="+")
    p.add_argument("--all", action="store_true", help="list every variable, not only the interface")
    p.set_defaults(func=cmd_inspect)

    p = sub.add_parser("demo", help="simulate a Table 1 case at SNR 10 and diagnose it")
    p.add_argument("--fmu", required=True)
    p.add_argument("--case", type=int, choices=[c.number for c in TABLE1], default=8,
                   help="Table 1 case number (default 8)")
    p.add_argument("--snr", type=positive, default=10.0)
    _optimiser_args(p)
    p.set_defaults(func=cmd_demo)
    return parser


class Terminated(BaseException):
    """SIGTERM, raised in the main thread so that every ``finally`` runs (workers stopped,
    temporary files removed) before the process ends."""


#: A second TERM waits for the first one's cleanup (:mod:`pydiag.core.termination`).
_raise_terminated = raise_once(Terminated)


def _check_workers(parser: Parser, args: argparse.Namespace) -> None:
    cores = os.cpu_count() or 1
    if getattr(args, "workers", None) and args.workers > cores and not args.oversubscribe:
        parser.error(f"--workers: {args.workers} is more than the {cores} cores of this machine; "
                     "more workers than cores make a fit slower (--oversubscribe to insist)")


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    _check_workers(parser, args)
    if threading.current_thread() is not threading.main_thread():
        return _run(args)
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        return _run(args)
    finally:
        signal.signal(signal.SIGTERM, previous)


def _run(args: argparse.Namespace) -> int:
    try:
        if isinstance(getattr(args, "fmu", None), str):
            warn_validation(args.fmu)
        # the machine file as the options it stands for, on the commands that read records
        args.machine_description = apply_machine(args) if hasattr(args, "rpm") else None
        return args.func(args)
    except PydiagError as err:
        print(f"pydiag {args.command}: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("pydiag: interrupted", file=sys.stderr)
        return 130
    except Terminated:
        print("pydiag: terminated", file=sys.stderr)
        return 143
    except Exception as err:  # a bug: one line for the user; PYDIAG_DEBUG=1 shows the traceback
        if os.environ.get("PYDIAG_DEBUG"):
            raise
        print(f"pydiag {args.command}: internal error: {type(err).__name__}: {err} "
              "(a bug in pydiag; set PYDIAG_DEBUG=1 for the traceback)", file=sys.stderr)
        return 3
