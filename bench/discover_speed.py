"""How long ``discover`` takes over the whole effect catalogue on a 4 s record.

The records: the independent simulator (tests/truth/gear_sim.py), 33 fundamental periods
(3.96 s) at 10 kHz, acc + disp at SNR 10, with hidden effects: a gear runout (its lines are
synchronous with the shafts: discover does not fit the effects none of whose lines are
among the scored ones), a torque ripple, and a ripple with both races of the pinion
bearing, and those with a misaligned motor shaft (lines that are not synchronous: the
effects that make such lines are fitted, each simulation over the whole record), and a
30 % torque ripple at 0.37x the pinion's speed driving a motor's rotor (the issue's slow
record; the bare pair's inertia would let it stall the pinion); the motor shaft's speed
ratio is given on every record. The base model: GearPair as ``pydiag discover``
fits it (the paper's parameters, default swarm), each effect fitted held out with the
refit budget ``compare.EFFECT_REFIT`` (the CLI's default). Effect FMUs are built before the clock starts (discover caches them in
build/effects). discover fits the effects side by side, one per core: each effect's row
is its own wall time while others ran beside it, so the rows add up to more than the
total. The base compare is timed again alone after each run. ``--repeat`` runs, medians
printed.

    .venv/bin/python bench/discover_speed.py [--repeat 3] [--workers N] [--records runout,ripple,ripple_and_races,ripple_races_motor,strong_ripple]
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

# the machine beyond the gear pair, known on every record: the motor shaft's speed ratio
from truth_fits import OPERATING_POINT  # noqa: E402
from truth.gear_sim import TruthGear, record  # noqa: E402

from pydiag.fit.estimator import FaultEstimator  # noqa: E402
from pydiag.fit.build import build_problem  # noqa: E402
from pydiag.gear.effects import EFFECTS  # noqa: E402
from pydiag.loop.compare import compare  # noqa: E402
from pydiag.loop.effect_fit import EFFECT_REFIT  # noqa: E402
from pydiag.loop.discover import discover, effect_fmu  # noqa: E402

PERIODS, RATE_HZ = 33, 10_000.0
#: The hidden effect of each record, as the simulator makes it (bench/independent_truth.py).
RECORDS = {"runout": dict(gear_runout_m=10e-6), "ripple": dict(torque_ripple=0.005),
           # the most effects to fit: a ripple and both races, ten times stronger than
           # bench/independent_truth.py's
           "ripple_and_races": dict(torque_ripple=0.005, outer_race_acc=600.0,
                                    inner_race_acc=600.0),
           # and a misaligned motor shaft (29/17 of the pinion's speed), whose lines are not
           # synchronous either; as much stronger as the races (at 3 m/s2 the races' noise
           # floor hid its lines: not tried)
           "ripple_races_motor": dict(torque_ripple=0.005, outer_race_acc=600.0,
                                      inner_race_acc=600.0, other_shaft_acc=30.0),
           # a 30 % torque ripple at 0.37 x the pinion's speed, driving a motor's rotor
           # (0.1 kg m2, behind a flexible coupling) whose inertia holds the speed's swing
           # to 1.6 %
           "strong_ripple": dict(torque_ripple=0.30, ripple_hz=0.37 * TruthGear().f_pinion_hz)}
#: The drive train of each record, where it is not the bare pair's.
GEARS = {"strong_ripple": TruthGear(rotor_inertia_kg_m2=0.1)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, help="worker processes (default: the cores)")
    ap.add_argument("--records", default=",".join(RECORDS))
    args = ap.parse_args()
    build = Path(tempfile.mkdtemp(prefix="discover_fmus_"))
    for key, effect in EFFECTS.items():
        if effect.own_fmu:
            effect_fmu(key, ROOT / "modelica", build)
    print(f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}; "
          f"records of {PERIODS} periods at {RATE_HZ:g} Hz, acc + disp; {args.repeat} runs")
    for name in args.records.split(","):
        m = record(GEARS.get(name, TruthGear()).with_effects(**RECORDS[name]), PERIODS, 5,
                   RATE_HZ)
        phases: dict[str, list[float]] = {}
        totals, ranking = [], []
        for _ in range(args.repeat):
            problem = build_problem(str(ROOT / "build/GearPair.fmu"), m,
                                    operating_point=OPERATING_POINT)
            t0 = time.perf_counter()
            _, found = discover(problem, FaultEstimator(n_workers=args.workers),
                                modelica_root=ROOT / "modelica", build_dir=build,
                                effect_estimator=FaultEstimator(**EFFECT_REFIT,
                                                                n_workers=args.workers))
            totals.append(time.perf_counter() - t0)
            t1 = time.perf_counter()
            compare(problem, FaultEstimator(n_workers=args.workers))  # the base alone
            phases.setdefault("base compare (timed alone)", []).append(time.perf_counter() - t1)
            for d in sorted(found, key=lambda d: list(EFFECTS).index(d.effect)):
                phases.setdefault(d.effect + ("" if d.held_out and d.held_out.tried
                                              else f" ({d.status.value})"),
                                  []).append(d.elapsed_s)
            ranking = [(d.effect, d.z, d.confident) for d in found]
        print(f"\nrecord with a hidden {name} ({m.duration_s:.2f} s)")
        print("| phase | median s | min s | max s |\n|---|---|---|---|")
        for phase, times in phases.items():
            print(f"| {phase} | {statistics.median(times):.1f} | {min(times):.1f} | "
                  f"{max(times):.1f} |")
        print(f"| **discover, whole catalogue** | **{statistics.median(totals):.1f}** | "
              f"{min(totals):.1f} | {max(totals):.1f} |")
        print("ranking (last run): " + ", ".join(f"{e} z {z:.1f}{' confident' if c else ''}"
                                                   for e, z, c in ranking))


if __name__ == "__main__":
    main()
