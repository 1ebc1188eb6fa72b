"""A machine's healthy state on the command line: the --baseline records, read or found
among those kept in the history (``kept``), ``pydiag baseline``, which keeps, lists and
forgets them (:mod:`pydiag.loop.history`), and the machine's healthy model fitted to the
--baseline files, kept there so that it is fitted once."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import sys
from collections.abc import Callable, Collection, Mapping
from pathlib import Path

from pydiag import __version__
from pydiag.app.formatting import format_kept_baselines
from pydiag.app.models import library, machine_fmus
from pydiag.app.reading import read_input
from pydiag.core.errors import UsageError
from pydiag.core.measurement import Measurement
from pydiag.diagnose.stages import grown_healthy, healthy_model
from pydiag.fit.build import ProblemSettings
from pydiag.fit.estimator import FaultEstimator
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import MachineRecord, machine_record
from pydiag.gear.speed import SpeedSettings
from pydiag.gear.comparable import BASELINE_SPEED_SHARE, at_speed
from pydiag.loop import history
from pydiag.loop.compose import BuiltModel
from pydiag.loop.machine_discover import check_effects
from pydiag.loop.machine_model import MachineModel
from pydiag.loop.own_changes import HealthyModel
from pydiag.loop.stage_catalogue import FAULT_EFFECTS

#: The --baseline value that stands for the baselines kept in the history.
KEPT = "kept"


def baseline_records(args, machine: Machine, speed: SpeedSettings,
                     read: Mapping[str, Measurement] | None = None,
                     kept_in: str | None = None) -> list[MachineRecord]:
    """The --baseline records as the machine sees them (their speed and every shaft's TSA),
    read and made once; ``kept``: those kept for the machine in the history at the
    record's operating point (:func:`~pydiag.gear.comparable.at_speed`). Each baseline
    counts once, however often it is given or whether it is given and kept too (a second
    copy would narrow the healthy spread); the record among its own baselines is said.
    ``read``: files already read (:func:`healthy_measurements`), by the path given;
    ``kept_in``: a history where each file's record is kept, and found again under a
    fingerprint of all it is made from (:func:`record_fingerprint`), so that it is made
    once (a command that writes the history anyway gives it)."""
    record = _same_file(getattr(args, "measurement", None))
    asked = list(args.baseline or [])
    files = _files(args, warn=True)
    read = read or {}
    out = [_record_of(args, machine, speed, path, read, kept_in) for path in files.values()]
    if asked.count(KEPT) > 1:
        _warn(args, "--baseline kept is given twice; the kept baselines count once")
    if KEPT in asked:
        out += _kept(args, machine, set(files), record)
    return out


def _record_of(args, machine: Machine, speed: SpeedSettings, path: str,
               read: Mapping[str, Measurement], db: str | None) -> MachineRecord:
    """The record of the --baseline file ``path`` as the machine sees it: found in the
    history ``db`` (its file as read now), else made, and kept there."""
    key = record_fingerprint(args, path) if db is not None else None
    found = history.kept_baseline_record(db, machine, key) if key is not None else None
    if found is not None:
        return found if path not in read else dataclasses.replace(
            found, file=str(read[path].metadata.get("file", found.file)))
    made = machine_record(read[path] if path in read else read_input(args, path), machine,
                          speed, args.input_hz)
    if key is not None:
        history.keep_baseline_record(db, machine, key, path, made)
    return made


def records_kept_in(args, machine: Machine, healthy: Mapping[str, Measurement]) -> str | None:
    """The history where a command that keeps the machine's healthy model of the
    --baseline files ``healthy`` keeps their records too (:func:`baseline_records`),
    checked before any work; None when it keeps no healthy model."""
    if not healthy or not (machine.effects or lacking_effects(args)):
        return None
    db = str(history.resolve(args.history))
    history.check(db)
    return db


def healthy_measurements(args) -> dict[str, Measurement]:
    """The --baseline files' records themselves (not those kept: the history keeps what
    the indicators need, not the record), each once, by the path given, in the order
    given: what the machine's healthy model is fitted to (the first) and held to (the
    others)."""
    return {path: read_input(args, path) for path in _files(args, warn=False).values()}


#: Arguments that leave the healthy model as it is: the records judged, where outputs go,
#: what is said, how the work is spread, where models are built (the model built and its
#: library count instead), the machine file as parsed (its bytes count instead), and
#: --lacking (the effects a record may be asked about: the fit does not depend on them,
#: and each is tried on the healthy records when a record first asks for it).
NOT_FITTED_FROM = {"func", "command", "measurement", "measurements", "json", "out", "force",
                   "quiet", "history", "workers", "oversubscribe", "scheduler", "indicators",
                   "build_dir", "modelica", "baseline", "eval_timeout", "machine",
                   "machine_description", "lacking"}


def healthy_fingerprint(args, built: BuiltModel, files: list[str]) -> str:
    """What the healthy model of the --baseline ``files`` (in order) is made from, as a
    key: pydiag's version, the machine file's bytes, the model built and its Modelica
    library, each file's bytes, and every other argument but :data:`NOT_FITTED_FROM`."""
    root, _ = library(args)
    sources = sorted(root.rglob("*.mo"))
    return _fingerprint(args, {
        "model": history.sha256_of(built.fmu),
        "library": [[str(p.relative_to(root)), history.sha256_of(p)] for p in sources],
        "baselines": [history.sha256_of(f) for f in files]})


def record_fingerprint(args, path: str) -> str:
    """What a --baseline file's record is made from, as a key: pydiag's version, the
    machine file's bytes, the file's bytes, and every argument but
    :data:`NOT_FITTED_FROM` (how it is read, its speed; those that cannot change it only
    make the key narrower)."""
    return _fingerprint(args, {"baseline": history.sha256_of(path)})


def _fingerprint(args, facts: dict) -> str:
    """``facts`` with pydiag's version, the machine file's bytes and every argument but
    :data:`NOT_FITTED_FROM`, hashed."""
    facts = {"pydiag": __version__, "machine": history.sha256_of(args.machine), **facts,
             "arguments": {k: v for k, v in sorted(vars(args).items())
                           if k not in NOT_FITTED_FROM}}
    return hashlib.sha256(json.dumps(facts, sort_keys=True, default=str).encode()).hexdigest()


def lacking_effects(args) -> tuple[str, ...]:
    """The effects the machine's healthy model lacks that a record is asked about: --lacking,
    else every component fault of the catalogue
    (:data:`~pydiag.loop.stage_catalogue.FAULT_EFFECTS`); none for a command without the
    option."""
    if not hasattr(args, "lacking"):
        return ()
    return FAULT_EFFECTS if args.lacking is None else tuple(args.lacking)


def check_lacking(args) -> None:
    """--lacking is asked of the machine's healthy model: refused with --fmu or fewer than
    two --baseline files; its keys checked."""
    if args.lacking is not None and (args.fmu or len(_files(args, warn=False)) < 2):
        raise UsageError("--lacking tries effects against the machine's healthy model: give "
                         "--machine FILE (no --fmu) and two --baseline files")
    check_effects(args.lacking)


def kept_healthy_model(args, machine: Machine, model: MachineModel, built: BuiltModel,
                       read: Mapping[str, Measurement], settings: ProblemSettings,
                       estimator: FaultEstimator
                       ) -> tuple[history.KeptHealthyModel, bool, str]:
    """(the machine's healthy model of the --baseline files ``read``, whether it was fitted
    now, the history): the one kept in the history under the same fingerprint
    (:func:`healthy_fingerprint`), else fitted
    (:func:`~pydiag.diagnose.stages.healthy_model`) and kept there. Of one file, it judges
    nothing (no repeat) and lacks nothing a record is asked about: its fit is where each
    record's own starts, found once."""
    db = str(history.resolve(args.history))
    history.check(db)
    key = healthy_fingerprint(args, built, list(read))
    kept = history.kept_healthy_model(db, machine, key)
    # asked about this call's lacking effects; none without a repeat, which would judge them
    lacking = lacking_effects(args) if len(read) > 1 else ()
    if kept is not None:
        return dataclasses.replace(kept, model=dataclasses.replace(
            kept.model, lacking=lacking)), False, db
    fitted = healthy_model(str(built.fmu), model, machine, list(read.values()), args.input_hz,
                           settings, estimator, lacking)
    return history.keep_healthy_model(db, machine, key, _resolved(read), fitted), True, db


def keeper(args, machine: Machine, built: BuiltModel, read: Mapping[str, Measurement],
           kept: list[history.KeptHealthyModel]) -> Callable[[HealthyModel], None]:
    """What keeps the healthy model of the --baseline files ``read`` again, grown (the
    rows of the lacking effects a record first asked for), under the same fingerprint
    (found after the one before), and appends it to ``kept``."""
    def keep(grown: HealthyModel) -> None:
        kept.append(history.keep_healthy_model(
            str(history.resolve(args.history)), machine,
            healthy_fingerprint(args, built, list(read)), _resolved(read), grown))
    return keep


def grower(args, machine: Machine, model: MachineModel, built: BuiltModel,
           read: Mapping[str, Measurement], settings: ProblemSettings,
           kept: list[history.KeptHealthyModel]
           ) -> Callable[[HealthyModel, Collection[tuple[str, str]]], HealthyModel]:
    """What grows the healthy model of the --baseline files ``read`` by lacking tries on
    those records (:func:`~pydiag.diagnose.stages.grown_healthy`, the effect models built
    as --build-dir says) and keeps it again (:func:`keeper`)."""
    effects = machine_fmus(args)
    keep = keeper(args, machine, built, read, kept)

    def grow(healthy: HealthyModel, tries: Collection[tuple[str, str]]) -> HealthyModel:
        grown = grown_healthy(healthy, str(built.fmu), model, machine, list(read.values()),
                              args.input_hz, settings, tries, effects)
        if grown is not healthy:
            keep(grown)
        return grown
    return grow


def _resolved(read: Mapping[str, Measurement]) -> list[str]:
    return [str(Path(p).resolve()) for p in read]


def _files(args, warn: bool) -> dict[str, str]:
    """The --baseline files but ``kept``, each once (by the file it is), in the order
    given; ``warn``: say a file given twice, or the record itself."""
    record = _same_file(getattr(args, "measurement", None))
    files: dict[str, str] = {}  # one file, one baseline
    for path in args.baseline or []:
        if path == KEPT:
            continue
        if _same_file(path) in files:
            if warn:
                _warn(args, f"--baseline {path} is given twice; it counts once")
            continue
        if _same_file(path) == record and warn:
            _warn(args, f"--baseline {path} is the record itself: it is judged against "
                  "itself there")
        files[_same_file(path)] = path
    return files


def _kept(args, machine: Machine, files: set[str], record: str | None) -> list[MachineRecord]:
    """The baselines kept for ``machine`` at the record's operating point, but those of
    ``files`` (given on the command line too)."""
    db = str(args.history or history.default_path())
    if args.history and not Path(db).exists():
        raise UsageError(f"--baseline kept: no history {db} (nothing is kept there)")
    nominal_hz = args.input_hz  # the machine file's when --rpm is not given
    found = history.kept_baselines(db, machine)
    kept = [dataclasses.replace(b.record, file=f"kept {b.id}: {b.record.file}") for b in found]
    chosen = {id(r) for r in at_speed(kept, nominal_hz)}  # the records it was given
    if not chosen:
        speeds = ", ".join(f"{b.speed.speed_hz:.4g} Hz ({b.file.partition(':')[0]})"
                           for b in kept)
        raise UsageError(f"--baseline kept: no baseline of machine '{machine.name}' kept in "
                         f"{db} within {100 * BASELINE_SPEED_SHARE:g} % of "
                         f"{nominal_hz:.4g} Hz (kept: {speeds or 'none'}); keep one with "
                         "pydiag baseline")
    near = [(_same_file(b.measurement), r) for b, r in zip(found, kept) if id(r) in chosen]
    if any(name in files for name, _ in near):
        _warn(args, "a --baseline given is kept too; it counts once")
    if any(name == record for name, _ in near):
        _warn(args, "a kept baseline is the record itself: it is judged against itself there")
    return [r for name, r in near if name not in files]


def _same_file(path: str | None) -> str | None:
    """``path`` as one name for one file (a baseline given twice, a record that is its own
    baseline), or None for no path."""
    return None if path is None else str(Path(path).resolve())


def _warn(args, text: str) -> None:
    print(f"pydiag {args.command}: warning: {text}", file=sys.stderr)


def cmd_baseline(args) -> int:
    """Keep a record as a baseline of its machine (--measurement), list the machine's
    (--list), or forget one (--forget ID)."""
    machine = args.machine_description
    if machine is None:
        raise UsageError("baseline keeps a record of a machine: give --machine FILE")
    chosen = [o for o, v in (("--measurement", args.measurement), ("--list", args.list),
                             ("--forget", args.forget)) if v not in (None, False)]
    if len(chosen) != 1:
        raise UsageError("give one of --measurement (keep it), --list or --forget ID")
    db = str(history.resolve(args.history))
    if (args.list or args.forget is not None) and not Path(db).exists():
        if args.history:  # the one the user named: a typo is not "none kept"
            raise UsageError(f"--history {db}: no such file (nothing is kept there)")
    if args.list:
        print(format_kept_baselines(machine.name, history.kept_baselines(db, machine), db))
        return 0
    if args.forget is not None:
        gone = history.forget_baseline(db, machine, args.forget)
        print(f"forgot baseline {gone.id} of {machine.name} ({gone.measurement}) in {db}")
        return 0
    history.check(db)
    speed = SpeedSettings(args.speed, tacho=args.tacho, pulses_per_rev=args.pulses_per_rev)
    record = machine_record(read_input(args), machine, speed, args.input_hz)
    kept = history.keep_baseline(db, machine, record, str(Path(args.measurement).resolve()))
    warning = record.speed.warning()
    if warning:
        print(f"pydiag baseline: warning: {warning}", file=sys.stderr)
    print(f"kept       : baseline {kept.id} of {machine.name}, input "
          f"{record.speed.speed_hz:.5f} Hz ({record.speed.method})")
    print(format_kept_baselines(machine.name, history.kept_baselines(db, machine), db))
    return 0
