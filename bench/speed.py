"""Speed of one plant evaluation: fmpy per call, fmpy with a reused instance, the native
engine, and CasADi's compiled CVODES on the same ODE (the near-physical limit).

One evaluation = what diagnosis does per particle: 0.05 s start-up plus one fundamental
period (0.12 s) of acc and disp at 10 kHz, Table 1 case 8. Prints medians over
--repeat runs, evaluations per second, ratios, and each path's deviation from a tight
reference (fmpy, rtol 1e-11) in % of the peak.

Equal tolerances are not equal accuracy (fmpy's CVode uses atol = rtol x nominal and the
acceleration is a small difference of large forces), so naive fmpy and the native engine
are each run over a range of tolerances and compared twice: at the same rtol, and at
equal accuracy (for each accuracy bar, the fastest run of each path that meets it).
Usage:

    .venv/bin/python bench/speed.py [--repeat 20]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import casadi as ca
import fmpy
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from fmu_build.build import ode_system  # noqa: E402
from pydiag.fmu.native_engine import NativeMeRunner  # noqa: E402
from pydiag.gear.paper_cases import case  # noqa: E402
from pydiag.fmu.plant import FmuPlant  # noqa: E402
sys.path.insert(0, str(ROOT / "bench"))
from timing import median_time  # noqa: E402

FS = 10_000.0
WARMUP_S, PERIOD_S = 0.05, 0.12
SENSORS = ("acc", "disp")



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


def deviation_pct(y: np.ndarray, reference: np.ndarray) -> list[float]:
    """max |y - reference| / max |reference| per output, in %."""
    return [100 * float(np.max(np.abs(y[i] - reference[i])) / np.max(np.abs(reference[i])))
            for i in range(len(reference))]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu", default=str(ROOT / "build" / "GearPair.fmu"))
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--rtol", type=float, default=1e-6, help="the native engine's default")
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
    rows = []  # (path, rtol, median s, deviations %)

    def record(path, rtol, fn):
        t, y = median_time(fn, args.repeat)
        rows.append((path, rtol, t, deviation_pct(y, reference)))
        return t

    for rtol in (1e-6, 1e-7, 1e-8, 1e-9):
        record("fmpy simulate_fmu (naive)", rtol, naive(rtol))
    with FmuPlant(args.fmu, SENSORS, FS, args.rtol, engine="fmpy") as plant:
        record("fmpy, instance reused", args.rtol,
               lambda: plant.simulate(params, PERIOD_S, WARMUP_S))
    calls = {}
    for rtol in (1e-4, 1e-5, 1e-6, 1e-7):
        with FmuPlant(args.fmu, SENSORS, FS, rtol, engine="native") as plant:
            t = record("native DOP853", rtol, lambda: plant.simulate(params, PERIOD_S, WARMUP_S))
            calls[rtol] = (plant._native.n_rhs / args.repeat, plant._native.n_steps / args.repeat,
                           t)
    with FmuPlant(args.fmu, SENSORS, FS, args.rtol, engine="native") as plant:
        plant._native = NativeMeRunner(plant._instance, plant.model_description,
                                       list(plant._native.refs), args.rtol, "dopri5")
        record("native Dormand-Prince 5(4)", args.rtol,
               lambda: plant.simulate(params, PERIOD_S, WARMUP_S))
    t_ref = record("CasADi CVODES (reference)", args.rtol, casadi_reference(params, args.rtol))

    def time_of(path, rtol):
        return next(t for p, r, t, _ in rows if p == path and r == rtol)

    t_naive = time_of("fmpy simulate_fmu (naive)", args.rtol)
    t_native = time_of("native DOP853", args.rtol)
    print(f"one evaluation: {WARMUP_S + PERIOD_S:.2f} s simulated, {len(SENSORS)} outputs at "
          f"{FS:g} Hz, Table 1 case 8; medians of {args.repeat} runs; "
          f"{platform.machine()}, {os.cpu_count()} cores\n")
    print(f"{'path':<28} {'rtol':>6} {'median s':>9} {'evals/s':>8} {'vs naive':>9}"
          f" {'dev acc %':>10} {'dev disp %':>10}")
    for path, rtol, t, devs in rows:
        print(f"{path:<28} {rtol:6.0e} {t:9.4f} {1 / t:8.1f} {t_naive / t:8.1f}x"
              f" {devs[0]:10.4f} {devs[1]:10.5f}")
    print("\nnative DOP853 per evaluation: " + "; ".join(
        f"rtol {r:g}: {n:.0f} right-hand sides, {st:.0f} steps, {1e6 * t / n:.2f} us per call"
        for r, (n, st, t) in calls.items()))
    print(f"same rtol ({args.rtol:g}): native / naive speed {t_naive / t_native:.1f}x; "
          f"native / CasADi CVODES time {t_native / t_ref:.2f}x")
    matched = {}
    for bar in (1.0, 0.1, 0.01):
        best = {}
        for kind in ("fmpy simulate_fmu (naive)", "native DOP853"):
            ok = [(t, r) for p, r, t, d in rows if p == kind and max(d) <= bar]
            best[kind] = min(ok) if ok else None
        a, b = best["fmpy simulate_fmu (naive)"], best["native DOP853"]
        if a and b:
            matched[bar] = a[0]
            print(f"equal accuracy (every output within {bar:g} % of its peak): naive needs rtol "
                  f"{a[1]:g} ({a[0]:.4f} s), native {b[1]:g} ({b[0]:.4f} s): "
                  f"{a[0] / b[0]:.1f}x")
        else:
            print(f"equal accuracy ({bar:g} %): not reached by "
                  f"{'naive fmpy' if not a else 'native'} in the tolerances run")
    # The diagnosis path: native engine in isolated worker processes (one instance each).
    from pydiag.fmu.isolation import IsolatedPool

    class Evaluate:
        def __init__(self):
            self.plant = None

        def residuals(self, x):
            if self.plant is None:
                self.plant = FmuPlant(args.fmu, SENSORS, FS, args.rtol)
            return self.plant.simulate(dict(zip(("a_f", "f_f", "f_ate", "f_dte"), x)),
                                       PERIOD_S, WARMUP_S)[0]

    xs = np.tile([params[k] for k in ("a_f", "f_f", "f_ate", "f_dte")], (200, 1))
    print()
    for workers in (1, 2):
        with IsolatedPool(Evaluate(), workers) as pool:
            pool.map(xs[:4])  # start-up: fork, open the FMU
            t0 = time.perf_counter()
            pool.map(xs)
            rate = len(xs) / (time.perf_counter() - t0)
        extra = "".join(f", {rate * t:.1f}x at {bar:g} % accuracy" for bar, t in matched.items())
        print(f"diagnosis path, {workers} isolated worker(s): {rate:.1f} evals/s = "
              f"{rate * t_naive:.1f}x naive at the same rtol{extra}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
