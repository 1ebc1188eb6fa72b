"""A local record of every compare run (which model, which FMU, what error, which peaks),
of the baselines kept for each machine (records of it in a known healthy state), and of
each machine's healthy model fitted to them.

SQLite, four tables. ``pydiag history`` lists the runs and can plot the error across
model revisions (:mod:`pydiag.loop.history_plot`), so the effect of adding physics to
the Modelica model stays visible.
``pydiag baseline`` keeps a record as seen through its machine (the speed found, every
shaft's TSA facts: :class:`~pydiag.gear.machine_indicators.MachineRecord`), found again
by the machine's identity (:attr:`~pydiag.gear.machine.Machine.identity`); ``--baseline
kept`` judges a record against those of its operating point. ``diagnose --machine`` keeps
the healthy model it fits to its --baseline files (:class:`~pydiag.loop.own_changes.
HealthyModel`), found again by a fingerprint of all it was made from, so that it is
fitted once; and each --baseline file's record as its machine sees it, the same way, so
that it is made once.

The history is an input as much as an output: :func:`check` refuses, before any work, a
file that is not SQLite, an SQLite file of another application (a table that is not
ours) or of another version of pydiag (a ``runs`` table without our columns), and one that
cannot be written. :func:`recording` adds a run and commits it only when what was written
beside it (report, JSON) was written: a failed run is never recorded, and a history that
fails to take the run is the user's problem (:class:`OutputError`), after the outputs.
"""

from __future__ import annotations

import hashlib
import json
import os
import sqlite3
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from pydiag.core.errors import OutputError, UsageError
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import MachineRecord
from pydiag.io.outputs import check_output
from pydiag.loop.own_changes import HealthyModel


def default_path() -> Path:
    """The per-user history: ``$XDG_DATA_HOME/pydiag/history.sqlite`` (by default
    ``~/.local/share/pydiag/history.sqlite``); never the current folder."""
    base = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(base) / "pydiag" / "history.sqlite"


def resolve(path: str | Path | None) -> Path:
    """``path``, or the per-user history with its folder made on first use."""
    if path:
        return Path(path)
    default = default_path()
    default.parent.mkdir(parents=True, exist_ok=True)
    return default

#: Each table's definition: made when first written to.
SCHEMA = {"runs": """
CREATE TABLE IF NOT EXISTS runs (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    time_utc TEXT NOT NULL,
    measurement TEXT NOT NULL,
    fmu TEXT NOT NULL,
    fmu_sha256 TEXT NOT NULL,
    model_name TEXT,
    source_sha256 TEXT,
    parameters TEXT NOT NULL,
    error REAL NOT NULL,
    n_peaks INTEGER NOT NULL,
    peaks TEXT NOT NULL,
    suggested TEXT NOT NULL
)""", "baselines": """
CREATE TABLE IF NOT EXISTS baselines (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    time_utc TEXT NOT NULL,
    machine TEXT NOT NULL,
    machine_identity TEXT NOT NULL,
    measurement TEXT NOT NULL,
    speed_hz REAL NOT NULL,
    record TEXT NOT NULL
)""", "healthy_models": """
CREATE TABLE IF NOT EXISTS healthy_models (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    time_utc TEXT NOT NULL,
    machine TEXT NOT NULL,
    machine_identity TEXT NOT NULL,
    fingerprint TEXT NOT NULL,
    baselines TEXT NOT NULL,
    model TEXT NOT NULL
)""", "baseline_records": """
CREATE TABLE IF NOT EXISTS baseline_records (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    time_utc TEXT NOT NULL,
    machine TEXT NOT NULL,
    machine_identity TEXT NOT NULL,
    fingerprint TEXT NOT NULL,
    measurement TEXT NOT NULL,
    record TEXT NOT NULL
)"""}


def sha256_of(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


#: The columns of our ``runs`` table.
COLUMNS = ("id", "time_utc", "measurement", "fmu", "fmu_sha256", "model_name",
           "source_sha256", "parameters", "error", "n_peaks", "peaks", "suggested")
#: Our tables and their columns.
TABLES = {"runs": COLUMNS,
          "baselines": ("id", "time_utc", "machine", "machine_identity", "measurement",
                        "speed_hz", "record"),
          "healthy_models": ("id", "time_utc", "machine", "machine_identity", "fingerprint",
                             "baselines", "model"),
          "baseline_records": ("id", "time_utc", "machine", "machine_identity", "fingerprint",
                               "measurement", "record")}


def _tables(con: sqlite3.Connection) -> set[str]:
    """The database's tables, SQLite's own left out."""
    return {r[0] for r in con.execute(
        "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'")}


def _check_schema(con: sqlite3.Connection, db: str | Path) -> None:
    """OutputError unless the database holds nothing but our tables (:data:`TABLES`),
    each with our columns."""
    tables = sorted(_tables(con))
    foreign = [t for t in tables if t not in TABLES]
    if foreign:
        raise OutputError(f"{db} is not a pydiag run history (it holds table(s) "
                          f"{', '.join(foreign)}); give --history another file")
    for table in tables:
        columns = {r[1] for r in con.execute(f"PRAGMA table_info({table})")}
        missing = [c for c in TABLES[table] if c not in columns]
        if missing:
            raise OutputError(f"{db} is a run history of another pydiag version (its {table} "
                              f"have no column {missing[0]}); give --history another file")


def _connect(db: str | Path, table: str | None = None) -> sqlite3.Connection:
    """A connection to the history ``db`` (checked: :func:`_check_schema`), with ``table``
    made if it is not there yet."""
    if Path(db).is_dir():
        raise OutputError(f"history {db} is a folder, not an SQLite file")
    try:
        con = sqlite3.connect(str(db))
        _check_schema(con, db)
        if table is not None:
            con.execute(SCHEMA[table])
    except sqlite3.Error as err:
        raise OutputError(f"cannot use {db} as the run history: {err}") from err
    return con


def check(db: str | Path) -> None:
    """Raise OutputError unless ``db`` is a run history (ours, and writable) or can be
    created as one; call it before the work whose result it will record (nothing is
    created here, nor changed in an existing history)."""
    if not (Path(db).exists() or Path(db).is_symlink()):
        check_output(db)
        return
    con = _connect(db)
    try:
        con.execute("BEGIN IMMEDIATE")  # a write lock: fails on a read-only database
        con.rollback()
    except sqlite3.Error as err:
        raise OutputError(f"cannot write the run history {db}: {err}") from err
    finally:
        con.close()


@contextmanager
def recording(db: str | Path, comparison, measurement_path: str, model_name: str | None,
              source_path: str | None = None) -> Iterator[tuple[int, list[dict]]]:
    """Add one compare run; yields (its id, every run with it) and commits when the block
    ends without an error (module docstring)."""
    peaks = [{"channel": p.channel, "freq_hz": p.freq_hz, "family": p.family,
              "energy_fraction": p.energy_fraction} for p in comparison.peaks]
    suggested = [{"effect": s.effect, "score": s.score, "confident": s.confident}
                 for s in comparison.suggested_effects if s.shown]
    con = _connect(db, "runs")
    try:
        try:
            cur = con.execute(
                "INSERT INTO runs (time_utc, measurement, fmu, fmu_sha256, model_name, "
                "source_sha256, parameters, error, n_peaks, peaks, suggested) "
                "VALUES (?,?,?,?,?,?,?,?,?,?,?)",
                (time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), str(measurement_path),
                 str(comparison.fmu), sha256_of(comparison.fmu), model_name,
                 sha256_of(source_path) if source_path else None,
                 json.dumps(comparison.parameters), comparison.error, len(comparison.peaks),
                 json.dumps(peaks), json.dumps(suggested)))
            con.row_factory = sqlite3.Row
            rows = [dict(r) for r in con.execute("SELECT * FROM runs ORDER BY id")]
        except sqlite3.Error as err:
            raise OutputError(f"cannot record the run in {db}: {err}") from err
        yield int(cur.lastrowid), rows
        try:
            con.commit()
        except sqlite3.Error as err:
            raise OutputError(f"the outputs are written, but the run could not be recorded in "
                              f"{db}: {err}") from err
    except BaseException:
        con.rollback()
        raise
    finally:
        con.close()


def runs(db: str | Path) -> list[dict]:
    """Every compare run of the history ``db``, oldest first (none when it has none)."""
    if not Path(db).exists():
        return []
    con = _connect(db)
    try:
        if "runs" not in _tables(con):
            return []
        con.row_factory = sqlite3.Row
        return [dict(r) for r in con.execute("SELECT * FROM runs ORDER BY id")]
    except sqlite3.Error as err:
        raise OutputError(f"cannot read the run history {db}: {err}") from err
    finally:
        con.close()


@dataclass(frozen=True)
class KeptBaseline:
    """A baseline kept in the history: its id there, when it was kept (UTC), its machine's
    name, the file it was read from, and the record as the machine sees it."""

    id: int
    time_utc: str
    machine: str
    measurement: str
    record: MachineRecord


def keep_baseline(db: str | Path, machine: Machine, record: MachineRecord,
                  measurement_path: str) -> KeptBaseline:
    """Keep ``record`` (of ``machine``, read from ``measurement_path``) as one of the
    machine's baselines in the history ``db``."""
    i, when = _kept_row(db, "baselines", machine, "the baseline", {
        "measurement": str(measurement_path), "speed_hz": record.speed.speed_hz,
        "record": json.dumps(record.to_dict())})
    return KeptBaseline(i, when, machine.name, str(measurement_path), record)


def _kept_row(db: str | Path, table: str, machine: Machine, what: str, values: dict
              ) -> tuple[int, str]:
    """(its id, when, UTC): a row of ``values`` kept for ``machine`` in ``table`` of the
    history ``db``, with the time and the machine's name and identity; ``what`` it is,
    for the error that says it could not be kept."""
    when = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    row = {"time_utc": when, "machine": machine.name, "machine_identity": machine.identity,
           **values}
    con = _connect(db, table)
    try:
        with con:
            cur = con.execute(f"INSERT INTO {table} ({', '.join(row)}) VALUES "
                              f"({','.join('?' * len(row))})", tuple(row.values()))
    except sqlite3.Error as err:
        raise OutputError(f"cannot keep {what} in {db}: {err}") from err
    finally:
        con.close()
    return int(cur.lastrowid), when


def kept_baselines(db: str | Path, machine: Machine) -> list[KeptBaseline]:
    """The baselines of ``machine`` kept in the history ``db``, oldest first."""
    if not Path(db).exists():
        return []
    con = _connect(db)
    try:
        if "baselines" not in _tables(con):
            return []
        rows = con.execute("SELECT id, time_utc, machine, measurement, record FROM baselines "
                           "WHERE machine_identity = ? ORDER BY id", (machine.identity,))
        return [KeptBaseline(i, when, name, path, MachineRecord.from_dict(json.loads(record)))
                for i, when, name, path, record in rows]
    except (sqlite3.Error, ValueError, KeyError, TypeError) as err:
        raise OutputError(f"cannot read the baselines kept in {db}: {err}") from err
    finally:
        con.close()


def forget_baseline(db: str | Path, machine: Machine, baseline_id: int) -> KeptBaseline:
    """Remove baseline ``baseline_id`` of ``machine`` from the history ``db``; returns it.
    UsageError when the machine has no baseline of that id there."""
    kept = {b.id: b for b in kept_baselines(db, machine)}
    if baseline_id not in kept:
        ids = ", ".join(str(i) for i in kept) or "none"
        raise UsageError(f"no baseline {baseline_id} of machine '{machine.name}' is kept in "
                         f"{db} (its baselines: {ids})")
    con = _connect(db)
    try:
        with con:
            con.execute("DELETE FROM baselines WHERE id = ?", (baseline_id,))
    except sqlite3.Error as err:
        raise OutputError(f"cannot remove the baseline from {db}: {err}") from err
    finally:
        con.close()
    return kept[baseline_id]


@dataclass(frozen=True)
class KeptHealthyModel:
    """A machine's healthy model kept in the history: its id there, when it was kept
    (UTC), the baseline files it was fitted to and held to, and the model."""

    id: int
    time_utc: str
    baselines: tuple[str, ...]
    model: HealthyModel


def keep_healthy_model(db: str | Path, machine: Machine, fingerprint: str,
                       baselines: list[str], model: HealthyModel) -> KeptHealthyModel:
    """Keep ``model`` (of ``machine``, fitted to the first of ``baselines`` and held to
    the others) in the history ``db`` under ``fingerprint``: what it is found again by
    (everything it was made from, the caller's to say)."""
    i, when = _kept_row(db, "healthy_models", machine, "the healthy model", {
        "fingerprint": fingerprint, "baselines": json.dumps(baselines),
        "model": json.dumps(model.to_dict())})
    return KeptHealthyModel(i, when, tuple(baselines), model)


def kept_healthy_model(db: str | Path, machine: Machine, fingerprint: str
                       ) -> KeptHealthyModel | None:
    """The healthy model of ``machine`` last kept in the history ``db`` under
    ``fingerprint``, or None."""
    return _last_kept(db, "healthy_models", ("id", "time_utc", "baselines", "model"),
                      machine, fingerprint, "the healthy models",
                      lambda i, when, files, model: KeptHealthyModel(
                          i, when, tuple(json.loads(files)),
                          HealthyModel.from_dict(json.loads(model))))


def _last_kept(db: str | Path, table: str, columns: tuple[str, ...], machine: Machine,
               fingerprint: str, what: str, made: Callable):
    """``made(*columns)`` of the row of ``machine`` last kept in ``table`` of the history
    ``db`` under ``fingerprint``, or None; ``what`` the table holds, for the error that
    says it could not be read."""
    if not Path(db).exists():
        return None
    con = _connect(db)
    try:
        if table not in _tables(con):
            return None
        row = con.execute(f"SELECT {', '.join(columns)} FROM {table} WHERE "
                          "machine_identity = ? AND fingerprint = ? ORDER BY id DESC LIMIT 1",
                          (machine.identity, fingerprint)).fetchone()
        return None if row is None else made(*row)
    except (sqlite3.Error, ValueError, KeyError, TypeError) as err:
        raise OutputError(f"cannot read {what} kept in {db}: {err}") from err
    finally:
        con.close()


def keep_baseline_record(db: str | Path, machine: Machine, fingerprint: str,
                         measurement_path: str, record: MachineRecord) -> None:
    """Keep ``record`` (a --baseline file of ``machine``, read from ``measurement_path``)
    in the history ``db`` under ``fingerprint`` (everything it was made from, the
    caller's to say), so that it is made once."""
    _kept_row(db, "baseline_records", machine, "the baseline's record", {
        "fingerprint": fingerprint, "measurement": str(measurement_path),
        "record": json.dumps(record.to_dict())})


def kept_baseline_record(db: str | Path, machine: Machine, fingerprint: str
                         ) -> MachineRecord | None:
    """The record of a --baseline file of ``machine`` last kept in the history ``db``
    under ``fingerprint``, or None."""
    return _last_kept(db, "baseline_records", ("record",), machine, fingerprint,
                      "the baseline records",
                      lambda record: MachineRecord.from_dict(json.loads(record)))
