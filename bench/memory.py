"""Does a worker leak? Resident memory of one plant after N evaluations.

Repeated FMU instantiation leaks in fmpy users' reports; pydiag keeps one instance per
worker and resets it. This runs --evaluations simulations (varying parameters) in one
process and prints its resident set size after 100 and after each 500. Usage:

    .venv/bin/python bench/memory.py [--evaluations 2000] [--engine native|fmpy]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import psutil

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.fmu.plant import FmuPlant  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu", default=str(ROOT / "build" / "GearPair.fmu"))
    ap.add_argument("--evaluations", type=int, default=2000)
    ap.add_argument("--engine", default="native", choices=("native", "fmpy"))
    args = ap.parse_args()
    proc = psutil.Process()
    rng = np.random.default_rng(0)
    marks = {}
    with FmuPlant(args.fmu, ("acc", "disp"), engine=args.engine) as plant:
        for i in range(1, args.evaluations + 1):
            x = rng.random(4)
            plant.simulate({"a_f": 0.1 + 0.8 * x[0], "f_f": 0.95 * x[1], "f_ate": x[2],
                            "f_dte": x[3]}, 0.12, 0.05)
            if i == 100 or i % 500 == 0:
                marks[i] = proc.memory_info().rss / 2 ** 20
                print(f"{args.engine}: after {i:5d} evaluations RSS {marks[i]:7.1f} MiB", flush=True)
    growth = marks[max(marks)] / marks[100] - 1
    print(f"{args.engine}: growth from 100 to {max(marks)} evaluations: {100 * growth:+.1f} %")
    return 0 if abs(growth) <= 0.10 else 1


if __name__ == "__main__":
    sys.exit(main())
