"""Where the first two-file ``diagnose --machine`` of a record spends its time: each part's
wall seconds, the CPU-seconds the whole machine was busy meanwhile and the cores that
makes, beside the total and the floor (the CPU-seconds over the cores). Run on an idle
machine (Linux: the busy time is read from /proc/stat, the machine's, not the process's).

The command is the README's, run in this process with a fresh build folder and history:
the machine's model built, fitted to the first --baseline file and held to the second
(the healthy model), the component faults the record asks for tried on both healthy runs
(the model grown), then the record's fit and its tries. Parts inside another are
indented under it. Usage:

    .venv/bin/python bench/first_record.py [FOLDER] [--record "spur 2_30hz_High_1"]

FOLDER: PHM 2009 records (default ../shared/data/phm09); the baselines are the healthy
runs of the record's box, speed and load (run 2, then run 1). Cite the PHM Society 2009
Data Challenge where you report results.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import io
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "bench")]

from components import NAME, healthy_runs  # noqa: E402

import pydiag.app.commands as commands  # noqa: E402
import pydiag.diagnose.stages as stages  # noqa: E402
import pydiag.loop.machine_discover as machine_discover  # noqa: E402
from pydiag.app.cli import main as pydiag_main  # noqa: E402

BUILT = "the machine's model built"
#: (module, function, label, depth): the parts timed, where the command calls them.
PARTS = [
    (commands, "read_input", "the record read", 0),
    (commands, "baseline_records", "the baseline files read (their indicators' records)", 0),
    (stages, "fit_healthy", "the healthy model fitted to run 2, held to run 1", 0),
    (stages, "with_lacking", "the record's asked faults tried on both healthy runs", 0),
    (machine_discover, "each_built", "their models built, side by side", 1),
    (stages, "refit_machine", "the record's fit (the healthy fit polished)", 0),
    (stages, "record_changes", "the record's tries", 0),
]


def busy_s() -> float:
    """CPU-seconds the machine has been busy (every core; /proc/stat's user, nice, system,
    irq and softirq ticks)."""
    with open("/proc/stat") as f:
        ticks = [int(x) for x in f.readline().split()[1:8]]
    return (sum(ticks) - ticks[3] - ticks[4]) / os.sysconf("SC_CLK_TCK")


def timed(function, label: str, depth: int, rows: list):
    """``function`` that adds a row (label, depth, wall s, busy s) each call."""
    @functools.wraps(function)
    def run(*args, **kwargs):
        wall, busy = time.perf_counter(), busy_s()
        try:
            return function(*args, **kwargs)
        finally:
            rows.append((label, depth, time.perf_counter() - wall, busy_s() - busy))
    return run


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default=str(ROOT.parent / "shared" / "data" / "phm09"))
    ap.add_argument("--record", default="spur 2_30hz_High_1")
    args = ap.parse_args()
    files = sorted(p for p in Path(args.folder).iterdir() if NAME.search(p.name))
    record = next((p for p in files if p.stem == args.record), None)
    if record is None:
        raise SystemExit(f"no record {args.record!r} in {args.folder}")
    healthy = healthy_runs(record, files)
    if len(healthy) < 2:
        raise SystemExit(f"{args.record}: fewer than two healthy runs of its operating point")
    box, _, hz, _, _ = NAME.search(record.name).groups()
    rows: list = []
    for module, name, label, depth in PARTS:
        setattr(module, name, timed(getattr(module, name), label, depth, rows))
    models = commands.machine_models  # the machine's model is built when its maker is called
    commands.machine_models = lambda a: timed(models(a), BUILT, 0, rows)
    with tempfile.TemporaryDirectory() as scratch:
        argv = ["diagnose", "--machine", str(ROOT / "examples" / f"phm09_{box}.toml"),
                "--sample-rate", "66666.67", "--rpm", str(60 * int(hz)),
                "--measurement", str(record), "--build-dir", f"{scratch}/build",
                "--history", f"{scratch}/history.sqlite", "--quiet",
                *(a for h in healthy[:2] for a in ("--baseline", str(h)))]
        wall, busy = time.perf_counter(), busy_s()
        with contextlib.redirect_stdout(io.StringIO()):
            code = pydiag_main(argv)
        wall, busy = time.perf_counter() - wall, busy_s() - busy
    cores = os.cpu_count() or 1
    print(f"# {platform.machine()}, {cores} cores, Python {platform.python_version()}; "
          f"{record.stem} against {healthy[0].stem} and {healthy[1].stem} (exit {code})")
    print(f"{'part':<58}{'calls':>6}{'wall s':>9}{'CPU s':>9}{'cores':>7}")
    top = 0.0
    for label, depth in [(BUILT, 0)] + [(label, depth) for _, _, label, depth in PARTS]:
        mine = [r for r in rows if r[0] == label]
        if not mine:
            continue
        w, b = sum(r[2] for r in mine), sum(r[3] for r in mine)
        top += w if depth == 0 else 0.0
        print(f"{'  ' * depth + label:<58}{len(mine):>6}{w:>9.1f}{b:>9.1f}{b / w:>7.2f}")
    print(f"{'the rest (the stages judged, the kinematics, start-up)':<58}{'':>6}"
          f"{wall - top:>9.1f}")
    print(f"{'all':<58}{'':>6}{wall:>9.1f}{busy:>9.1f}{busy / wall:>7.2f}")
    print(f"floor on {cores} cores (CPU s / cores): {busy / cores:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
