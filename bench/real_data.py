"""Benchmark: real records, and the throughput of reading, speed finding and order tracking.

1. For each record of a labelled set in the layout of ``../shared/data/gfd`` (a1..a4, no
   time column): the speed found and its variation, the periods analysed, the fit error
   with the model's level as it is, with the channel gain fitted, and with the housing
   sensor effect refitted on top (compare --effect housing_sensor), the fitted
   parameters and the wall time of a diagnosis.
2. Throughput: a synthetic 60 s, 4-channel, 51.2 kHz record with a drifting speed, written
   as CSV and as Parquet, read + speed + order tracking of every channel, each in a fresh
   process: wall time and peak memory (ru_maxrss of the child).

Usage:
    .venv/bin/python bench/real_data.py [--data ../shared/data/gfd] [--skip-throughput]
                                        [--markdown out.md]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.fit.estimator import FaultEstimator  # noqa: E402
from pydiag.fit.build import build_problem  # noqa: E402
from pydiag.gear.effects import EFFECTS  # noqa: E402
from pydiag.gear.speed import SpeedSettings, estimate_speed  # noqa: E402
from pydiag.gear.tracking import order_track  # noqa: E402
from pydiag.io.readers import read_measurement  # noqa: E402
from pydiag.loop.compare import compare, refit_with_effect  # noqa: E402
from pydiag.diagnose.diagnosis import diagnose  # noqa: E402

OPERATING_POINT = {"n_pinion": 32, "n_gear": 80, "f_pinion_hz": 30.0}  # README of gfd
SAMPLE_RATE_HZ = 12_900.0  # inferred in that README, not documented


def real_records(data: Path, fmu: str) -> list[tuple]:
    rows = []
    for path in sorted(data.glob("*.csv.gz")):
        m = read_measurement(path, SAMPLE_RATE_HZ, ["a1=acc"], ["g"])
        common = dict(operating_point=OPERATING_POINT, speed=SpeedSettings("auto"))
        t0 = time.perf_counter()
        problem = build_problem(fmu, m, fit_gain=True, **common)
        result = diagnose(problem, FaultEstimator(seed=0))
        wall = time.perf_counter() - t0
        fixed = FaultEstimator(seed=0).fit(build_problem(fmu, m, fit_gain=False, **common))
        effect = EFFECTS["housing_sensor"]
        base_problem = build_problem(fmu, m, fit_gain=True, **common)
        estimator = FaultEstimator(n_particles=8, iterations=6, polish_evaluations=60, seed=0)
        base = compare(base_problem, FaultEstimator(seed=0))
        housed = refit_with_effect(base_problem, base, effect, fmu, estimator)
        s = problem.speed
        p = result.parameters
        rows.append((path.name.split(".")[0], f"{s.speed_hz:.4f}", f"{s.variation_pct:.3f}",
                     str(problem.n_periods), f"{fixed.error:.3f}", f"{result.error:.3f}",
                     f"{base.error:.3f}", f"{housed.error:.3f}",
                     f"{housed.parameters['f_housing']:.0f}/{housed.parameters['zeta_housing']:.3f}",
                     f"{p['a_f']:.3f}/{p['f_f']:.3f}/{p['f_ate']:.3f}/{p['f_dte']:.3f}",
                     f"{result.fault_mode}/{result.severity}", f"{wall:.1f}"))
        print(" | ".join(rows[-1]), flush=True)
    return rows


def make_record(folder: Path) -> tuple[Path, Path]:
    import pandas as pd
    fs, duration, n_channels = 51_200.0, 60.0, 4
    n = int(fs * duration)
    t = np.arange(n) / fs
    revs = np.cumsum(29.9 * (1 + 0.004 * np.sin(2 * np.pi * t / duration))) / fs
    rng = np.random.default_rng(0)
    mesh = sum(np.cos(2 * np.pi * h * 32 * revs + h) / h for h in range(1, 5))
    frame = pd.DataFrame({"time_s": t, **{f"a{i + 1}": (mesh + rng.standard_normal(n)).astype(float)
                                          for i in range(n_channels)}})
    csv, parquet = folder / "long.csv", folder / "long.parquet"
    frame.to_csv(csv, index=False, float_format="%.9g")
    frame.to_parquet(parquet)
    return csv, parquet


def throughput_child(path: str) -> None:
    """Read + speed + order tracking of every channel; prints JSON (time, samples)."""
    from pydiag.gear.kinematics import GearKinematics
    t0 = time.perf_counter()
    m = read_measurement(path)
    t_read = time.perf_counter() - t0
    found = estimate_speed(m, GearKinematics(32, 80, 30.0), SpeedSettings("mesh", "a1"))
    t_speed = time.perf_counter() - t0 - t_read
    tracked = order_track(m, found)
    total = time.perf_counter() - t0
    print(json.dumps({"read_s": t_read, "speed_s": t_speed, "total_s": total,
                      "speed_hz": found.speed_hz, "samples": tracked.n_samples,
                      "channels": len(tracked.channels)}))


def throughput() -> list[tuple]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        files = make_record(Path(tmp))
        for path in files:
            out = subprocess.run([sys.executable, __file__, "--child", str(path)],
                                 capture_output=True, text=True, check=True)
            peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
            r = json.loads(out.stdout)
            rows.append((path.suffix, f"{path.stat().st_size / 1e6:.0f}", f"{r['read_s']:.2f}",
                         f"{r['speed_s']:.2f}", f"{r['total_s']:.2f}",
                         f"{peak_mb:.0f}", f"{r['speed_hz']:.5f}"))
            print(" | ".join(rows[-1]), flush=True)
    return rows


def table(header, rows) -> list[str]:
    return ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)] + \
           ["| " + " | ".join(r) + " |" for r in rows]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "gfd"))
    ap.add_argument("--fmu", default=str(ROOT / "build" / "GearPair.fmu"))
    ap.add_argument("--skip-throughput", action="store_true")
    ap.add_argument("--markdown")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        throughput_child(args.child)
        return 0
    machine = f"{platform.machine()}, {len(os.sched_getaffinity(0))} cores"
    lines = [f"Measured on {machine}."]
    h1 = ("record", "speed Hz", "variation %", "periods", "E level fixed", "E gain fitted",
          "E compare", "E + housing", "f_housing/zeta", "a_f/f_f/f_ate/f_dte",
          "mode/severity", "diagnose s")
    print(" | ".join(h1), flush=True)
    lines += [""] + table(h1, real_records(Path(args.data), args.fmu))
    if not args.skip_throughput:
        h2 = ("format", "MB", "read s", "speed s", "read+speed+tracking s", "peak MB",
              "speed Hz (true mean 29.9)")
        print(" | ".join(h2), flush=True)
        lines += ["", "60 s, 4 channels, 51.2 kHz:", ""] + table(h2, throughput())
    if args.markdown:
        Path(args.markdown).write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
