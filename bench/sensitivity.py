"""Which sensor sees which fault parameter? Objective change for a +-0.03 parameter step.

For each Table 1 case: a noisy record (SNR 10, one seed) of one sensor channel, then the
noise-aware Eq. (12) error at the truth and its change when one parameter moves by
+-0.03 (the accuracy target). A change well above zero means the channel pins that
parameter; a change near zero (or negative) means noise hides it. Usage:

    .venv/bin/python bench/sensitivity.py [--sensor acc] [--periods 10]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.fit.build import build_problem  # noqa: E402
from pydiag.fit.problem import ProblemObjective  # noqa: E402
from pydiag.gear.conventions import kinematics_from  # noqa: E402
from pydiag.core.measurement import Measurement  # noqa: E402
from pydiag.signal.noise import add_white_noise  # noqa: E402
from pydiag.gear.paper_cases import TABLE1  # noqa: E402
from pydiag.fmu.plant import FmuPlant  # noqa: E402

NAMES = ("a_f", "f_f", "f_ate", "f_dte")
STEP = 0.03


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu", default=str(ROOT / "build" / "GearPair.fmu"))
    ap.add_argument("--sensor", action="append", help="channel(s) (default: acc, then disp)")
    ap.add_argument("--periods", type=int, default=10)
    args = ap.parse_args()
    for sensor in args.sensor or ["acc", "disp"]:
        print(f"\nsensor {sensor}, {args.periods} periods, SNR 10: "
              f"min over +-{STEP} of E(step) - E(truth)")
        print(f"{'case':>4} {'E(truth)':>9} {'plain':>7} " + " ".join(f"{n:>8}" for n in NAMES)
              + "   (plain: E(truth) without the noise correction)")
        with FmuPlant(args.fmu, (sensor,)) as plant:
            kin = kinematics_from(plant.parameters())
            for c in TABLE1:
                clean = plant.simulate(c.parameters, args.periods * kin.period_s, 0.05)[0]
                m = Measurement({sensor: add_white_noise(clean, 10.0, np.random.default_rng(1))},
                                plant.sample_rate_hz)
                problem = build_problem(args.fmu, m)
                objective = ProblemObjective(problem)
                truth = np.array([c.parameters[n] for n in NAMES])
                e0 = objective(truth)
                plain = dataclasses.replace(problem, reference={
                    k: dataclasses.replace(v, noise_power=0.0) for k, v in problem.reference.items()})
                with ProblemObjective(plain) as plain_objective:
                    e_plain = plain_objective(truth)
                deltas = []
                for i in range(len(NAMES)):
                    changes = []
                    for step in (-STEP, STEP):
                        x = truth.copy()
                        x[i] += step
                        if x[i] >= 0:
                            changes.append(objective(x) - e0)
                    deltas.append(min(changes))
                objective.close()
                print(f"{c.number:>4} {e0:9.4f} {e_plain:7.4f} "
                      + " ".join(f"{d:+8.4f}" for d in deltas))
    return 0


if __name__ == "__main__":
    sys.exit(main())
