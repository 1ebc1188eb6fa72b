"""Speed of one plant evaluation: fmpy per call, fmpy with a reused instance, the native
engine, and CasADi's compiled CVODES on the same ODE (the near-physical limit).

One evaluation = what diagnosis does per particle: 0.05 s start-up plus one fundamental
period (0.12 s) of acc and disp at 10 kHz, Table 1 case 8. Prints medians over
--repeat runs, evaluations per second, ratios, and each path's deviation from a tight
reference (fmpy, rtol 1e-11) in % of the peak. fmpy is timed at the same rtol as the
others and at the rtol where it reaches the native engine's accuracy (--fmpy-rtol):
equal tolerances are not equal accuracy (fmpy's CVode uses atol = rtol x nominal).
Usage:

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
from pydiag.native_me import NativeMeRunner  # noqa: E402
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

    outs = out.map(grid.size)
    tgrid = ca.DM(grid).T
    pgrid = ca.repmat(p, 1, grid.size)

    def run():
        xs = f(x0=x0(p), p=p)["xf"]
        return np.asarray(outs(tgrid, xs, pgrid))[idx]
    return run


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu", default=str(ROOT / "build" / "GearPair.fmu"))
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--fmpy-rtol", type=float, default=1e-9,
                    help="fmpy tolerance that matches the native engine's accuracy")
    args = ap.parse_args()
    params = case(8).parameters
    n_first, n = int(round(WARMUP_S * FS)), int(round(PERIOD_S * FS))

    def naive(rtol):
        def run():
            r = fmpy.simulate_fmu(args.fmu, stop_time=(n_first + n) / FS, output_interval=1 / FS,
                                  start_values=params, output=list(SENSORS),
                                  relative_tolerance=rtol)
            return np.array([r[s][n_first:n_first + n] for s in SENSORS])
        return run

    with FmuPlant(args.fmu, SENSORS, FS, 1e-11, engine="fmpy") as ref_plant:
        reference = ref_plant.simulate(params, PERIOD_S, WARMUP_S)
    rows = []
    t_naive, y = median_time(naive(args.rtol), args.repeat)
    rows.append((f"fmpy simulate_fmu, rtol {args.rtol:g}", t_naive, y))
    t_naive_acc, y = median_time(naive(args.fmpy_rtol), args.repeat)
    rows.append((f"fmpy simulate_fmu, rtol {args.fmpy_rtol:g}", t_naive_acc, y))
    with FmuPlant(args.fmu, SENSORS, FS, args.rtol, engine="fmpy") as plant:
        t, y = median_time(lambda: plant.simulate(params, PERIOD_S, WARMUP_S), args.repeat)
        rows.append((f"fmpy, instance reused, {args.rtol:g}", t, y))
    with FmuPlant(args.fmu, SENSORS, FS, args.rtol, engine="native") as plant:
        refs = list(plant._native.refs)
        plant._native = NativeMeRunner(plant._instance, plant.model_description, refs, args.rtol,
                                       "dopri5")
        t, y = median_time(lambda: plant.simulate(params, PERIOD_S, WARMUP_S), args.repeat)
        rows.append(("native, Dormand-Prince 5(4)", t, y))
    with FmuPlant(args.fmu, SENSORS, FS, args.rtol, engine="native") as plant:
        t_native, y = median_time(lambda: plant.simulate(params, PERIOD_S, WARMUP_S), args.repeat)
        rows.append(("native, DOP853 (default)", t_native, y))
    t_ref, y = median_time(casadi_reference(params, args.rtol), args.repeat)
    rows.append((f"CasADi CVODES, rtol {args.rtol:g}", t_ref, y))

    print(f"one evaluation: {WARMUP_S + PERIOD_S:.2f} s simulated, {len(SENSORS)} outputs at "
          f"{FS:g} Hz, rtol {args.rtol:g}; medians of {args.repeat} runs; "
          f"{platform.machine()}, 2 cores\n")
    print(f"{'path':<34} {'median s':>9} {'evals/s':>8} {'vs first':>9} {'vs CasADi':>9}"
          f" {'dev acc %':>9} {'dev disp %':>10}")
    for name, t, y in rows:
        devs = [100 * np.max(np.abs(y[i] - reference[i])) / np.max(np.abs(reference[i]))
                for i in range(len(SENSORS))]
        print(f"{name:<34} {t:9.4f} {1 / t:8.1f} {t_naive / t:8.1f}x {t / t_ref:8.2f}x"
              f" {devs[0]:9.3f} {devs[1]:10.4f}")
    print(f"\none process: native vs naive at the same rtol: {t_naive / t_native:.1f}x; at equal "
          f"accuracy (fmpy rtol {args.fmpy_rtol:g}): {t_naive_acc / t_native:.1f}x; native / "
          f"CasADi reference: {t_native / t_ref:.2f}x")
    # The diagnosis path: native engine in isolated worker processes (one instance each).
    from pydiag.isolation import IsolatedPool

    class Evaluate:
        def __init__(self):
            self.plant = None

        def residuals(self, x):
            if self.plant is None:
                self.plant = FmuPlant(args.fmu, SENSORS, FS, args.rtol)
            return self.plant.simulate(dict(zip(("a_f", "f_f", "f_ate", "f_dte"), x)),
                                       PERIOD_S, WARMUP_S)[0]

    xs = np.tile([params[k] for k in ("a_f", "f_f", "f_ate", "f_dte")], (200, 1))
    for workers in (1, 2):
        with IsolatedPool(Evaluate(), workers) as pool:
            pool.map(xs[:4])  # start-up: fork, open the FMU
            t0 = time.perf_counter()
            pool.map(xs)
            rate = len(xs) / (time.perf_counter() - t0)
        print(f"diagnosis path, {workers} isolated worker(s): {rate:.1f} evals/s = "
              f"{rate * t_naive:.1f}x naive at the same rtol, {rate * t_naive_acc:.1f}x at equal "
              "accuracy")
    return 0


if __name__ == "__main__":
    sys.exit(main())
