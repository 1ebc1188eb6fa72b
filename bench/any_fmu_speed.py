"""Speed of one evaluation of any FMU: naive ``fmpy.simulate_fmu`` per call vs pydiag's plant.

For FMUs that are not ours (other exporters, FMI 2.0): the plant picks its engine
(``auto``: the compiled engine for Model-Exchange FMUs without event indicators, fmpy
otherwise) and reuses one instance. Both paths run at the same rtol; deviation is
against fmpy at rtol 1e-10, in % of each output's peak. Usage:

    .venv/bin/python bench/any_fmu_speed.py FMU --outputs x1,x2 [--duration 5] [--rate 100]

The OpenModelica FMUs the tests use come from the gemseo-fmu wheel on PyPI
(``pip download --no-deps gemseo-fmu==3.1.1``, then unzip ``gemseo_fmu/problems/fmu_files``).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
from pathlib import Path

import fmpy
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.fmu.plant import FmuPlant  # noqa: E402
sys.path.insert(0, str(ROOT / "bench"))
from timing import median_time  # noqa: E402



def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("fmu")
    ap.add_argument("--outputs", required=True, help="comma-separated output names")
    ap.add_argument("--duration", type=float, default=5.0, help="simulated seconds")
    ap.add_argument("--rate", type=float, default=100.0, help="output samples per second")
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--repeat", type=int, default=20)
    args = ap.parse_args()
    outputs = args.outputs.split(",")
    n = int(round(args.duration * args.rate))

    md = fmpy.read_model_description(args.fmu, validate=False)
    # fmpy picks Co-Simulation when an FMU has both; the plant prefers Model Exchange.
    # Compare like with like (OpenModelica's CS solver with the output step as its step
    # was 5 % off on MassSpringSystem and diverged on Mass_Damper).
    fmi_type = "ModelExchange" if md.modelExchange is not None else "CoSimulation"

    def naive():
        r = fmpy.simulate_fmu(args.fmu, stop_time=n / args.rate, output_interval=1 / args.rate,
                              output=outputs, relative_tolerance=args.rtol, fmi_type=fmi_type)
        return np.array([r[o][:n] for o in outputs])

    with FmuPlant(args.fmu, tuple(outputs), args.rate, 1e-10, engine="fmpy") as ref:
        reference = ref.simulate({}, args.duration)
    rows = []
    t_naive, y = median_time(naive, args.repeat)
    rows.append(("fmpy simulate_fmu (naive)", t_naive, y))
    with FmuPlant(args.fmu, tuple(outputs), args.rate, args.rtol) as plant:
        t_plant, y = median_time(lambda: plant.simulate({}, args.duration), args.repeat)
        rows.append((f"pydiag plant, engine {plant.engine}", t_plant, y))
    print(f"{Path(args.fmu).name}: FMI {md.fmiVersion} ({md.generationTool}), "
          f"{fmi_type}, {args.duration:g} s of {', '.join(outputs)} at {args.rate:g} Hz, rtol {args.rtol:g}; "
          f"medians of {args.repeat} runs; {platform.machine()}, {os.cpu_count()} cores")
    print(f"{'path':<30} {'median s':>9} {'evals/s':>8} {'vs naive':>9} {'max dev %':>10}")
    for name, t, y in rows:
        dev = max(100 * np.max(np.abs(y[i] - reference[i])) / np.max(np.abs(reference[i]))
                  for i in range(len(outputs)))
        print(f"{name:<30} {t:9.4f} {1 / t:8.1f} {t_naive / t:8.1f}x {dev:10.5f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
