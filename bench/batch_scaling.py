"""Batch throughput: the same measurements diagnosed with 1 and with 2 local workers.

Makes --count noisy measurements (Table 1 cases in turn, SNR 10, 10 periods) in a
temporary folder, runs ``pydiag.app.batch.run_batch`` with 1 and 2 workers (--repeat times
each, alternating), and prints the median wall time, measurements per minute and the
speed-up; rows must be identical. Usage:

    .venv/bin/python bench/batch_scaling.py [--count 16] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.app import batch  # noqa: E402
from pydiag.core.measurement import Measurement  # noqa: E402
from pydiag.io.measurements import write_measurement  # noqa: E402
from pydiag.signal.noise import add_white_noise  # noqa: E402
from pydiag.gear.conventions import kinematics_from  # noqa: E402
from pydiag.gear.paper_cases import TABLE1  # noqa: E402
from pydiag.fmu.plant import FmuPlant  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu", default=str(ROOT / "build" / "GearPair.fmu"))
    ap.add_argument("--count", type=int, default=16)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    estimator = dict(n_particles=16, iterations=20, polish_evaluations=150, seed=0)
    with tempfile.TemporaryDirectory() as tmp:
        with FmuPlant(args.fmu, ("acc", "disp")) as plant:
            kin = kinematics_from(plant.parameters())
            for i in range(args.count):
                c = TABLE1[i % len(TABLE1)]
                y = plant.simulate(c.parameters, 10 * kin.period_s, 0.05)
                rng = np.random.default_rng(i)
                write_measurement(Path(tmp) / f"m{i:03d}.csv", Measurement(
                    {s: add_white_noise(y[j], 10.0, rng) for j, s in enumerate(("acc", "disp"))},
                    plant.sample_rate_hz))
        tasks = [batch.BatchTask(p, args.fmu, estimator) for p in batch.find_measurements(tmp)]
        walls: dict[int, list[float]] = {1: [], 2: []}
        rows_of: dict[int, list] = {}
        for _ in range(args.repeat):  # alternate, so slow drift of the machine hits both
            for workers in (1, 2):
                t0 = time.perf_counter()
                rows_of[workers] = batch.run_batch(tasks, "local", n_workers=workers)
                walls[workers].append(time.perf_counter() - t0)
        print(f"{args.count} measurements, 16 particles x 20 iterations + polish each; "
              f"median of {args.repeat} runs")
        print(f"{'workers':>7} {'wall s':>8} {'meas/min':>9} {'speed-up':>9}  runs s")
        median = {w: statistics.median(v) for w, v in walls.items()}
        for workers in (1, 2):
            print(f"{workers:7d} {median[workers]:8.1f} {60 * args.count / median[workers]:9.2f} "
                  f"{median[1] / median[workers]:8.2f}x  "
                  + " ".join(f"{w:.1f}" for w in walls[workers]))
        results = {w: (median[w], rows_of[w]) for w in (1, 2)}
        def strip(rows):
            return [{k: v for k, v in r.items() if k != "elapsed_s"} for r in rows]
        same = strip(results[1][1]) == strip(results[2][1])
        ok = sum(r["status"] == "ok" for r in results[2][1])
        print(f"identical rows with 1 and 2 workers: {same}; diagnosed {ok}/{len(tasks)}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
