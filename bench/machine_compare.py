"""How long a two-stage compare takes on the machine's own model: ``pydiag compare
--machine FILE`` (no ``--fmu``) on records in the PHM 2009 challenge's naming, once with
``--no-validate`` (the stages' fit) and once with the held-out tries of every stage, each
the median of ``--repeat`` runs. The models are built before the first timed run (one
untimed compare), so the times are those of a warm build cache. Usage:

    .venv/bin/python bench/machine_compare.py [DIR] [--records "spur 1_30hz_High_1"]
                                              [--repeat 3] [--channel ch1]

DIR defaults to ../shared/data/phm09; the machine file is examples/phm09_spur.toml (the
45 Hz records are given --rpm 2700). Cite the PHM Society 2009 Data Challenge where you
report results.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
NAME = re.compile(r"spur \d+_(\d+)hz_(High|Low)_\d+")
PYDIAG = [sys.executable, "-m", "pydiag"]


def compare(record: Path, folder: Path, channel: str, validate: bool, run: int
            ) -> tuple[float, dict]:
    """Seconds of one compare and its JSON."""
    out = folder / f"c{run}_{int(validate)}.json"
    hz = int(NAME.search(record.name).group(1))
    command = PYDIAG + ["compare", "--machine", str(folder / "box.toml"), "--channel", channel,
                        "--sample-rate", str(200_000 / 3), "--measurement", str(record),
                        "--rpm", str(60 * hz), "--json", str(out), "--quiet",
                        "--history", str(folder / "history.sqlite")]
    started = time.perf_counter()
    res = subprocess.run(command + ([] if validate else ["--no-validate"]), cwd=ROOT,
                         capture_output=True, text=True)
    took = time.perf_counter() - started
    if res.returncode != 0:
        raise SystemExit(f"compare failed on {record.name}: {res.stderr.strip()[-500:]}")
    return took, json.loads(out.read_text())


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default=str(ROOT.parent / "shared" / "data" / "phm09"))
    ap.add_argument("--records", default="spur 1_30hz_High_1",
                    help="comma-separated record names")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--channel", default="ch1")
    args = ap.parse_args()
    wanted = args.records.split(",")
    files = [p for p in sorted(Path(args.folder).iterdir()) if p.name.split(".")[0] in wanted]
    if not files:
        print(f"no record named {args.records} in {args.folder}", file=sys.stderr)
        return 2
    print(f"# {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; channel {args.channel}; median of {args.repeat}")
    print("| record | stages' fit s | with validation s | held-out tries s | tried | confident |")
    print("|---|---|---|---|---|---|")
    for record in files:
        with tempfile.TemporaryDirectory(prefix="bench_compare_") as tmp:
            folder = Path(tmp)
            shutil.copy(ROOT / "examples" / "phm09_spur.toml", folder / "box.toml")
            compare(record, folder, args.channel, True, -1)  # builds what it needs
            fits, totals, data = [], [], {}
            for run in range(args.repeat):
                fits.append(compare(record, folder, args.channel, False, run)[0])
                took, data = compare(record, folder, args.channel, True, run)
                totals.append(took)
            rows = data["suggested_effects"]
            tried = sum(1 for s in rows if s.get("held_out"))
            confident = ", ".join(f"{s['effect']} on {s['stage']}" for s in rows
                                  if s.get("confident")) or "none"
            fit, total = statistics.median(fits), statistics.median(totals)
            print(f"| {record.name.split('.')[0]} | {fit:.0f} | {total:.0f} | "
                  f"{total - fit:.0f} | {tried} | {confident} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
