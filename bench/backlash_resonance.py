"""The independent simulator's backlash where its teeth do separate: the mesh at the mesh
resonance. Prints, for a record without and with a gap, the strongest line change the gap
makes, what compare + held-out validation make confident, and what discover says of
``backlash`` (its held-out z and verdict). RESULTS.md section 9.

    .venv/bin/python bench/backlash_resonance.py [--seeds 5,6,7] [--gap-um 5]   (2-7 min a record)
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.append(str(ROOT / "tests"))

from truth_fits import (RESONANCE_RATE_HZ, RESONANCE_TOP_HZ, line_margin_db,  # noqa: E402
                        resonance_clean, resonance_problem)

from pydiag.fit.estimator import FaultEstimator  # noqa: E402
from pydiag.loop.compare import compare  # noqa: E402
from pydiag.loop.discover import discover, effect_fmu  # noqa: E402
from pydiag.loop.validate import validate  # noqa: E402

FAST = dict(n_particles=10, iterations=8, polish_evaluations=100, polish_starts=2)
#: discover's candidates: backlash and those that could take its lines.
EFFECTS = ["backlash", "gear_eccentricity", "gear_tooth_fault", "second_pinion_tooth_fault",
           "housing_sensor", "load_fluctuation"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="5,6,7")
    ap.add_argument("--gap-um", type=float, default=5.0)
    args = ap.parse_args()
    build = Path(tempfile.mkdtemp(prefix="backlash_fmus_"))
    clean = {0.0: resonance_clean(), args.gap_um: resonance_clean(args.gap_um * 1e-6)}
    for channel in ("acc", "disp"):
        freq, margin = line_margin_db(clean[args.gap_um][channel], clean[0.0][channel], 10.0,
                                      RESONANCE_RATE_HZ, RESONANCE_TOP_HZ)
        print(f"gap {args.gap_um:g} um, {channel}: strongest change at {freq:.1f} Hz, "
              f"{margin:.1f} dB over the noise")
    print("| gap um | seed | error | confident (compare) | backlash in discover | s |\n"
          "|---|---|---|---|---|---|")
    for gap, channels in clean.items():
        for seed in (int(s) for s in args.seeds.split(",")):
            t0 = time.perf_counter()
            problem = resonance_problem(ROOT / "build/GearPair.fmu", channels, seed)
            c = validate(problem, compare(problem, FaultEstimator(**FAST)),
                         lambda e: str(effect_fmu(e.key, ROOT / "modelica", build)))
            confident = [s.effect for s in c.suggested_effects if s.confident] or ["-"]
            _, found = discover(problem, FaultEstimator(**FAST), effects=EFFECTS,
                                modelica_root=ROOT / "modelica", build_dir=build)
            row = next(d for d in found if d.effect == "backlash")
            others = [d.effect for d in found if d.confident]
            print(f"| {gap:g} | {seed} | {c.error:.3f} | {', '.join(confident)} | z {row.z:.1f}: "
                  f"{row.status.value}; confident: {', '.join(others) or '-'} | "
                  f"{time.perf_counter() - t0:.0f} |", flush=True)


if __name__ == "__main__":
    main()
