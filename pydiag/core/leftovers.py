"""Temporary files and folders that name their owner, and the reclaiming of those whose
owner is gone.

A process killed with SIGKILL (alone, or with its whole process group, as a batch
scheduler or systemd does) runs no cleanup of its own. Every temporary entry pydiag makes
outside its run's lifetime therefore carries its owner in its name (``<pid>-<start>``:
the process id and its start time, so that a reused process id is not taken for the
owner), and the next run that makes one of the same kind removes those whose owner no
longer runs. An entry of another user, or one whose owner cannot be told, is left alone.
"""

from __future__ import annotations

import glob
import os
import shutil
from pathlib import Path


def _start_time(pid: int) -> str | None:
    """The start time of process ``pid`` in clock ticks since boot (Linux), or None."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return stat.rsplit(")", 1)[-1].split()[19]  # field 22 of the whole line


def owner_tag(pid: int | None = None) -> str:
    """``<pid>-<start>`` of this process (or ``pid``): the owner part of an entry's name."""
    pid = os.getpid() if pid is None else pid
    return f"{pid}-{_start_time(pid) or 0}"


def _owner_gone(tag: str) -> bool:
    pid_text, _, start = tag.partition("-")
    if not pid_text.isdigit() or not start.isdigit():
        return False  # not ours to judge
    pid = int(pid_text)
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False  # alive, another user's
    now = _start_time(pid)
    return now is not None and start != "0" and now != start  # the id was reused


def reclaim(folder: str | Path, prefix: str, suffix: str = "") -> list[Path]:
    """Remove the entries ``<folder>/<prefix><pid>-<start>.*<suffix>`` of this user whose
    owner no longer runs; returns what was removed."""
    removed = []
    for name in glob.glob(os.path.join(glob.escape(str(folder)), glob.escape(prefix) + "*"
                                       + glob.escape(suffix))):
        entry = Path(name)
        tag = entry.name[len(prefix):].split(".", 1)[0].split("_", 1)[0]
        try:
            if entry.lstat().st_uid != os.getuid() or not _owner_gone(tag):
                continue
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry)
            else:
                entry.unlink()
            removed.append(entry)
        except OSError:
            continue  # gone meanwhile, or not ours to remove
    return removed
