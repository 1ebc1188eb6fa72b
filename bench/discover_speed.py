"""How long ``discover`` takes over the whole effect catalogue on a 4 s record.

The record: the independent simulator (tests/truth/gear_sim.py) with a hidden gear
runout, 33 fundamental periods (3.96 s) at 10 kHz, acc + disp at SNR 10. The base model:
GearPair as ``pydiag discover`` fits it (the paper's parameters, default swarm), each
effect fitted held out with the refit budget ``compare.EFFECT_REFIT`` (the CLI's
default). Effect FMUs are built before the clock starts (discover caches them in
build/effects). discover fits the effects side by side, one per core: each effect's row
is its own wall time while others ran beside it, so the rows add up to more than the
total. The base compare is timed again alone after each run. ``--repeat`` runs, medians
printed.

    .venv/bin/python bench/discover_speed.py [--repeat 3] [--workers N]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.append(str(ROOT / "tests"))

from truth.gear_sim import TruthGear, record  # noqa: E402

from pydiag.fit.estimator import FaultEstimator  # noqa: E402
from pydiag.fit.problem import build_problem  # noqa: E402
from pydiag.gear.effects import EFFECTS  # noqa: E402
from pydiag.loop.compare import EFFECT_REFIT, compare  # noqa: E402
from pydiag.loop.discover import discover, effect_fmu  # noqa: E402

PERIODS, RATE_HZ = 33, 10_000.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, help="worker processes (default: the cores)")
    args = ap.parse_args()
    g = TruthGear().with_effects(gear_runout_m=10e-6)
    m = record(g, PERIODS, 5, RATE_HZ)
    build = Path(tempfile.mkdtemp(prefix="discover_fmus_"))
    for key, effect in EFFECTS.items():
        if not effect.in_base:
            effect_fmu(key, ROOT / "modelica", build)
    phases: dict[str, list[float]] = {}
    totals, ranking = [], []
    for _ in range(args.repeat):
        problem = build_problem(str(ROOT / "build/GearPair.fmu"), m)
        t0 = time.perf_counter()
        _, found = discover(problem, FaultEstimator(n_workers=args.workers), None,
                            modelica_root=ROOT / "modelica", build_dir=build,
                            effect_estimator=FaultEstimator(**EFFECT_REFIT,
                                                            n_workers=args.workers))
        totals.append(time.perf_counter() - t0)
        t1 = time.perf_counter()
        compare(problem, FaultEstimator(n_workers=args.workers))  # the base phase, alone
        phases.setdefault("base compare (timed alone)", []).append(time.perf_counter() - t1)
        for d in sorted(found, key=lambda d: list(EFFECTS).index(d.effect)):
            phases.setdefault(d.effect, []).append(d.elapsed_s)
        ranking = [(d.effect, d.z, d.confident) for d in found]
    print(f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}; "
          f"record {PERIODS} periods ({m.duration_s:.2f} s) at {RATE_HZ:g} Hz, acc + disp; "
          f"{args.repeat} runs")
    print("| phase | median s | min s | max s |\n|---|---|---|---|")
    for name, times in phases.items():
        print(f"| {name} | {statistics.median(times):.1f} | {min(times):.1f} | {max(times):.1f} |")
    print(f"| **discover, whole catalogue** | **{statistics.median(totals):.1f}** | "
          f"{min(totals):.1f} | {max(totals):.1f} |")
    print("ranking (last run): " + ", ".join(f"{e} z {z:.1f}{' confident' if c else ''}"
                                               for e, z, c in ranking))


if __name__ == "__main__":
    main()
