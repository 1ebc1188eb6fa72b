"""Benchmark: the paper's Table 1 cases at SNR 10, several noise seeds, full diagnosis.

For every case and seed: simulate the FMU at the case's parameters, add white noise at
the given SNR (a power ratio, per channel), diagnose, and print true vs estimated
parameters, absolute errors, mode/severity, the objective at the estimate and at the
truth (an optimiser whose answer scores worse than the truth has not converged),
evaluations and wall time. Usage:

    .venv/bin/python bench/paper_cases.py [--cases 1,2,...] [--seeds 3] [--markdown out.md]
                                          [--json estimates.json]

``--machine`` diagnoses the same records through a machine file of one stage (the pair's
teeth and speed, a sensor for each output): the machine's own model, written and built by
pydiag, as ``pydiag diagnose --machine FILE`` fits it (the speed found from the meshes);
E(true) is then not computed.

``--json`` keeps every run's estimates at full precision (parameters, error, evaluations,
best-error history), so two versions of the code can be compared exactly with
``bench/same_estimates.py``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.fit.estimator import FaultEstimator  # noqa: E402
from pydiag.fit.build import ProblemSettings, build_problem  # noqa: E402
from pydiag.fit.problem import ProblemObjective  # noqa: E402
from pydiag.gear.conventions import kinematics_from  # noqa: E402
from pydiag.core.measurement import Measurement  # noqa: E402
from pydiag.signal.noise import add_white_noise  # noqa: E402
from pydiag.gear.paper_cases import TABLE1, case  # noqa: E402
from pydiag.gear.speed import SpeedSettings  # noqa: E402
from pydiag.diagnose.diagnosis import classified  # noqa: E402
from pydiag.fmu.plant import FmuPlant  # noqa: E402
from pydiag.gear.machine_file import machine_from_dict  # noqa: E402
from pydiag.loop.discover import default_build_dir  # noqa: E402
from pydiag.loop.machine_model import machine_fmu  # noqa: E402
from pydiag.diagnose.stages import diagnose_machine_model  # noqa: E402
from pydiag.diagnose.support import unprefixed  # noqa: E402

NAMES = ("a_f", "f_f", "f_ate", "f_dte")


def _through_machine(m: Measurement, kin, sensors: tuple[str, ...], est: FaultEstimator,
                     features: str, fit_gain: bool) -> SimpleNamespace:
    """The diagnosis of ``m`` by the machine's own model of one stage (``--machine``), as
    the pair's: its parameters without the stage's prefix, its stage's mode and severity."""
    machine = machine_from_dict({
        "name": "Table 1 pair", "input_rpm": 60 * kin.f_pinion_hz,
        "stages": [{"name": "pair", "pinion_teeth": kin.n_pinion, "gear_teeth": kin.n_gear}],
        "sensors": [{"channel": s, "output": s} for s in sensors]}, "Table 1")
    root = ROOT / "modelica"
    model, built = machine_fmu(machine, root, default_build_dir(root))
    result = diagnose_machine_model(str(built.fmu), model, m, machine, kin.f_pinion_hz,
                                    ProblemSettings(features, fit_gain,
                                                    speed=SpeedSettings("mesh")), est)
    stage = result.stages[0]
    return SimpleNamespace(parameters=unprefixed(stage.fit.parameters, stage.prefix),
                           fault_mode=stage.fault_mode, severity=stage.severity,
                           error=stage.fit.error, fit=stage.fit.fit)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu", default=str(ROOT / "build" / "GearPair.fmu"))
    ap.add_argument("--cases", default=",".join(str(c.number) for c in TABLE1))
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--snr", type=float, default=10.0)
    ap.add_argument("--periods", type=int, default=10, help="record length in fundamental periods")
    ap.add_argument("--sensors", default="acc,disp")
    ap.add_argument("--features", default="lines", choices=("lines", "paper"))
    ap.add_argument("--particles", type=int, default=16)
    ap.add_argument("--iterations", type=int, default=20)
    ap.add_argument("--polish", type=int, default=150)
    ap.add_argument("--starts", type=int, default=3)
    ap.add_argument("--fit-gain", action="store_true", help="fit a gain per channel")
    ap.add_argument("--speed", choices=("mesh", "nominal"), help="find the speed in the record "
                    "and order-track it (default: take the record as it is)")
    ap.add_argument("--machine", action="store_true", help="through a machine file of one "
                    "stage: the machine's own model (module docstring)")
    ap.add_argument("--markdown", help="also write the table as Markdown here")
    ap.add_argument("--json", help="also write every run's full-precision estimates here")
    args = ap.parse_args()

    sensors = tuple(args.sensors.split(","))
    rows, worst, correct, walls, evals, exact = [], 0.0, 0, [], [], {}
    header = ("case", "seed", *[f"{n} true/est" for n in NAMES], "max abs err", "mode/severity",
              "ok", "E(est)", "E(true)", "evals", "wall s")
    print(" | ".join(header), flush=True)
    with FmuPlant(args.fmu, sensors) as plant:
        kin = kinematics_from(plant.parameters())
        for number in map(int, args.cases.split(",")):
            c = case(number)
            clean = plant.simulate(c.parameters, args.periods * kin.period_s, 0.05)
            for seed in range(args.seeds):
                rng = np.random.default_rng(1000 * number + seed)
                m = Measurement({s: add_white_noise(clean[i], args.snr, rng)
                                 for i, s in enumerate(sensors)}, plant.sample_rate_hz)
                est = FaultEstimator(n_particles=args.particles, iterations=args.iterations,
                                     seed=seed, polish_evaluations=args.polish,
                                     polish_starts=args.starts)
                t0 = time.perf_counter()
                if args.machine:
                    r = _through_machine(m, kin, sensors, est, args.features, args.fit_gain)
                    e_true = float("nan")
                else:
                    problem = build_problem(args.fmu, m, feature_mode=args.features,
                                            fit_gain=args.fit_gain, speed=SpeedSettings(
                                                args.speed) if args.speed else None)
                    r = classified(problem, est.fit(problem))
                    with ProblemObjective(problem) as objective:
                        e_true = objective(np.array([c.parameters[n] for n in NAMES]))
                wall = time.perf_counter() - t0
                err = max(abs(r.parameters[n] - c.parameters[n]) for n in NAMES)
                ok = (r.fault_mode, r.severity) == (c.fault_mode, c.severity)
                worst, correct = max(worst, err), correct + ok
                walls.append(wall)
                exact[f"{number}/{seed}"] = {"parameters": r.parameters, "error": r.error,
                                             "evaluations": r.fit.evaluations,
                                             "history": r.fit.best_error_history}
                evals.append(r.fit.evaluations)
                row = (str(number), str(seed),
                       *[f"{c.parameters[n]:.2f}/{r.parameters[n]:.4f}" for n in NAMES],
                       f"{err:.4f}", f"{r.fault_mode}/{r.severity}", "yes" if ok else "NO",
                       f"{r.error:.4f}", f"{e_true:.4f}", str(r.fit.evaluations), f"{wall:.1f}")
                rows.append(row)
                print(" | ".join(row), flush=True)
    summary = (f"{len(rows)} runs: worst absolute error {worst:.4f}, mode and severity correct in "
               f"{correct}/{len(rows)}, median wall time {statistics.median(walls):.1f} s, median "
               f"evaluations {statistics.median(evals):.0f} ({platform.processor() or platform.machine()},"
               f" {len(__import__('os').sched_getaffinity(0))} cores)")
    print(summary)
    if args.markdown:
        lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
        Path(args.markdown).write_text("\n".join(lines) + "\n\n" + summary + "\n")
    if args.json:
        Path(args.json).write_text(json.dumps(exact, indent=1) + "\n")
    return 0 if worst <= 0.03 and correct == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
