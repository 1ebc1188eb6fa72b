"""Speed of one plant evaluation: fmpy per call, fmpy with a reused instance, the native
engine, and CasADi's compiled CVODES on the same ODE (the near-physical limit).

One evaluation = what diagnosis does per particle: 0.05 s start-up plus one fundamental
period (0.12 s) of acc and disp at 10 kHz, Table 1 case 8. Prints medians over
--repeat runs, evaluations per second, ratios, and each path's deviation from a tight
reference (fmpy, rtol 1e-10) in % of the peak. Usage:

    .venv/bin/python bench/speed.py [--repeat 20]
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
from pathlib import Path

import casadi as ca
import fmpy
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from fmu_build.build import ode_system  # noqa: E402
from pydiag.paper_cases import case  # noqa: E402
from pydiag.plant import FmuPlant  # noqa: E402

FS = 10_000.0
WARMUP_S, PERIOD_S = 0.05, 0.12
SENSORS = ("acc", "disp")


def median_time(fn, repeat: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def casadi_reference(params: dict, rtol: float):
    """CVODES on the CasADi ODE built from the same Modelica source, outputs on the grid."""
    system = ode_system(ROOT / "modelica/GearDiag/GearPair.mo", "GearDiag.GearPair")
    rhs, out, x0 = system.functions()
    values = {**system.parameter_values(), **params}
    p = ca.DM([values[q.name] for q in system.parameters])
    t, x = ca.SX.sym("t"), ca.SX.sym("x", len(system.states))
    psym = ca.SX.sym("p", p.numel())
    grid = WARMUP_S + np.arange(int(round(PERIOD_S * FS))) / FS
    f = ca.integrator("ref", "cvodes", {"t": t, "x": x, "p": psym, "ode": rhs(t, x, psym)}, 0.0,
                      list(grid), {"reltol": rtol, "abstol": rtol * 1e-5})
    outputs = [o.name for o in system.outputs]
    idx = [outputs.index(s) for s in SENSORS]

    def run():
        xs = f(x0=x0(p), p=p)["xf"]
        ys = np.column_stack([np.asarray(out(grid[k], xs[:, k], p)).ravel() for k in range(grid.size)])
        return ys[idx]
    return run


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu", default=str(ROOT / "build" / "GearPair.fmu"))
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--rtol", type=float, default=1e-6)
    args = ap.parse_args()
    params = case(8).parameters
    n_first, n = int(round(WARMUP_S * FS)), int(round(PERIOD_S * FS))

    def naive():
        r = fmpy.simulate_fmu(args.fmu, stop_time=(n_first + n) / FS, output_interval=1 / FS,
                              start_values=params, output=list(SENSORS),
                              relative_tolerance=args.rtol)
        return np.array([r[s][n_first:n_first + n] for s in SENSORS])

    with FmuPlant(args.fmu, SENSORS, FS, 1e-10, engine="fmpy") as ref_plant:
        reference = ref_plant.simulate(params, PERIOD_S, WARMUP_S)
    rows = []
    t_naive, y = median_time(naive, max(3, args.repeat // 4))
    rows.append(("fmpy simulate_fmu per call", t_naive, y))
    with FmuPlant(args.fmu, SENSORS, FS, args.rtol, engine="fmpy") as plant:
        t, y = median_time(lambda: plant.simulate(params, PERIOD_S, WARMUP_S), args.repeat)
        rows.append(("fmpy, instance reused", t, y))
    with FmuPlant(args.fmu, SENSORS, FS, args.rtol, engine="native") as plant:
        t_native, y = median_time(lambda: plant.simulate(params, PERIOD_S, WARMUP_S), args.repeat)
        rows.append(("native engine (pydiag)", t_native, y))
    t_ref, y = median_time(casadi_reference(params, args.rtol), args.repeat)
    rows.append(("CasADi CVODES, compiled ODE", t_ref, y))

    print(f"one evaluation: {WARMUP_S + PERIOD_S:.2f} s simulated, {len(SENSORS)} outputs at "
          f"{FS:g} Hz, rtol {args.rtol:g}; medians of {args.repeat} runs; "
          f"{platform.machine()}, 2 cores\n")
    print(f"{'path':<30} {'median s':>9} {'evals/s':>8} {'vs naive':>9} {'vs CasADi':>9}"
          f" {'dev acc %':>9} {'dev disp %':>10}")
    for name, t, y in rows:
        devs = [100 * np.max(np.abs(y[i] - reference[i])) / np.max(np.abs(reference[i]))
                for i in range(len(SENSORS))]
        print(f"{name:<30} {t:9.4f} {1 / t:8.1f} {t_naive / t:8.1f}x {t / t_ref:8.2f}x"
              f" {devs[0]:9.3f} {devs[1]:10.4f}")
    print(f"\nnative vs naive: {t_naive / t_native:.1f}x faster; native / CasADi reference: "
          f"{t_native / t_ref:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
