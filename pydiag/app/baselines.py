"""A machine's healthy state on the command line: the --baseline records, read or found
among those kept in the history (``kept``), and ``pydiag baseline``, which keeps, lists
and forgets them (:mod:`pydiag.loop.history`)."""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Mapping
from pathlib import Path

from pydiag.app.formatting import format_kept_baselines
from pydiag.app.reading import read_input
from pydiag.core.errors import UsageError
from pydiag.core.measurement import Measurement
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import MachineRecord, machine_record
from pydiag.gear.speed import SpeedSettings
from pydiag.gear.comparable import BASELINE_SPEED_SHARE, at_speed
from pydiag.loop import history

#: The --baseline value that stands for the baselines kept in the history.
KEPT = "kept"


def baseline_records(args, machine: Machine, speed: SpeedSettings,
                     read: Mapping[str, Measurement] | None = None) -> list[MachineRecord]:
    """The --baseline records as the machine sees them (their speed and every shaft's TSA),
    read and made once; ``kept``: those kept for the machine in the history at the
    record's operating point (:func:`~pydiag.gear.comparable.at_speed`). Each baseline
    counts once, however often it is given or whether it is given and kept too (a second
    copy would narrow the healthy spread); the record among its own baselines is said.
    ``read``: files already read (:func:`healthy_measurements`), by the path given."""
    record = _same_file(getattr(args, "measurement", None))
    asked = list(args.baseline or [])
    files = _files(args, warn=True)
    read = read or {}
    out = [machine_record(read[path] if path in read else read_input(args, path), machine,
                          speed, args.input_hz) for path in files.values()]
    if asked.count(KEPT) > 1:
        _warn(args, "--baseline kept is given twice; the kept baselines count once")
    if KEPT in asked:
        out += _kept(args, machine, set(files), record)
    return out


def healthy_measurements(args) -> dict[str, Measurement]:
    """The --baseline files' records themselves (not those kept: the history keeps what
    the indicators need, not the record), each once, by the path given, in the order
    given: what the machine's healthy model is fitted to (the first) and held to (the
    others)."""
    return {path: read_input(args, path) for path in _files(args, warn=False).values()}


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
