"""A local record of every compare run: which model, which FMU, what error, which peaks.

SQLite, one table. ``pydiag history`` lists the runs and can plot the error across
model revisions, so the effect of adding physics to the Modelica model stays visible.
"""

from __future__ import annotations

import hashlib
import os
import json
import sqlite3
import time
from pathlib import Path

from pydiag.core.errors import OutputError
from pydiag.io.outputs import atomic_output, check_output



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

SCHEMA = """
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
)
"""


def sha256_of(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _connect(db: str | Path) -> sqlite3.Connection:
    if Path(db).is_dir():
        raise OutputError(f"history {db} is a folder, not an SQLite file")
    try:
        con = sqlite3.connect(str(db))
        con.execute(SCHEMA)
    except sqlite3.Error as err:
        raise OutputError(f"cannot use {db} as the run history: {err}") from err
    return con


def check(db: str | Path) -> None:
    """Raise OutputError unless ``db`` is a run history or can be created as one; call it
    before the work whose result it will record (nothing is created here)."""
    if Path(db).exists() or Path(db).is_symlink():
        _connect(db).close()
    else:
        check_output(db)


def record(db: str | Path, comparison, measurement_path: str, model_name: str | None,
           source_path: str | None = None) -> int:
    """Append one compare run; returns its id."""
    peaks = [{"channel": p.channel, "freq_hz": p.freq_hz, "family": p.family,
              "energy_fraction": p.energy_fraction} for p in comparison.peaks]
    suggested = [{"effect": s.effect, "score": s.score, "confident": s.confident}
                 for s in comparison.suggested_effects if s.shown]
    with _connect(db) as con:
        cur = con.execute(
            "INSERT INTO runs (time_utc, measurement, fmu, fmu_sha256, model_name, source_sha256,"
            " parameters, error, n_peaks, peaks, suggested) VALUES (?,?,?,?,?,?,?,?,?,?,?)",
            (time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), str(measurement_path),
             str(comparison.fmu), sha256_of(comparison.fmu), model_name,
             sha256_of(source_path) if source_path else None, json.dumps(comparison.parameters),
             comparison.error, len(comparison.peaks), json.dumps(peaks), json.dumps(suggested)))
        return int(cur.lastrowid)


def runs(db: str | Path) -> list[dict]:
    if not Path(db).exists():
        return []
    with _connect(db) as con:
        con.row_factory = sqlite3.Row
        return [dict(r) for r in con.execute("SELECT * FROM runs ORDER BY id")]


def plot(rows: list[dict], out: str | Path, force: bool = False) -> Path:
    """Error per run, labelled with the model name: the error falling as physics is added.
    Written under the output policy (:mod:`pydiag.io.outputs`); the format follows the
    name's suffix (.png, .svg, .pdf)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, ax = plt.subplots(figsize=(7, 3.5), dpi=110)
    ax.plot([r["id"] for r in rows], [r["error"] for r in rows], "o-", color="#1f5fa8")
    for r in rows:
        ax.annotate(r["model_name"] or Path(r["fmu"]).stem, (r["id"], r["error"]),
                    textcoords="offset points", xytext=(4, 6), fontsize=8)
    ax.set_xlabel("compare run")
    ax.set_ylabel("spectral error (Eq. 12, relative)")
    ax.set_ylim(bottom=0)
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.grid(alpha=0.3)
    fig.tight_layout()
    try:
        with atomic_output(out, force) as tmp:
            fig.savefig(tmp, format=Path(out).suffix.lstrip(".") or "png")
    finally:
        plt.close(fig)
    return Path(out)
