"""The machine's own model (every stage in one Modelica model) on records in the PHM 2009
challenge's naming: the error of the first stage alone (the model with the other stages
silenced, on the same bins), of every stage, and of every stage with the effects given,
a row a record. Usage:

    .venv/bin/python bench/machine_model.py [DIR] [--records "spur 1_30hz_High_1,..."]
                                            [--effects KEY@STAGE,...] [--channel ch1]

DIR defaults to ../shared/data/phm09; the 45 Hz records take the machine file's speed
times 1.5. ``--effects`` names catalogue effects on stages (numbered from 1), fitted
after the stages (:func:`pydiag.loop.machine_model.fit_machine`). Errors are compare's
(Eq. 12 less its noise part, on every synchronous line of the machine's period and the
record's peaks). Cite the PHM Society 2009 Data Challenge where you report results.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import re
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.fit.estimator import FaultEstimator  # noqa: E402
from pydiag.fit.build import ProblemSettings  # noqa: E402
from pydiag.gear.machine import StageEffect  # noqa: E402
from pydiag.gear.machine_file import load_machine  # noqa: E402
from pydiag.gear.speed import SpeedSettings  # noqa: E402
from pydiag.io.readers import read_measurement  # noqa: E402
from pydiag.loop.compare import compare  # noqa: E402
from pydiag.loop.machine_fit import fit_machine, machine_problem  # noqa: E402
from pydiag.loop.machine_model import machine_fmu  # noqa: E402
from pydiag.diagnose.stages import machine_speed  # noqa: E402

NAME = re.compile(r"spur \d+_(\d+)hz_(High|Low)_\d+")
RATE_HZ = 200_000 / 3
SILENT_DB = -60.0  # a stage this far below the one a sensor is near is not there


def errors(path: Path, channel: str, effects: tuple[StageEffect, ...], build: Path
           ) -> tuple[float, float, float | None, float]:
    """(first stage alone, every stage, every stage with ``effects`` or None, seconds)."""
    started = time.perf_counter()
    base = load_machine(ROOT / "examples" / "phm09_spur.toml")
    input_hz = base.input_hz * int(NAME.search(path.name).group(1)) / 30
    m = read_measurement(path, RATE_HZ, [channel, base.tacho.channel], [f"{channel}=V"], {})
    speed = machine_speed(m, base, input_hz, SpeedSettings(
        "auto", tacho=base.tacho.channel, pulses_per_rev=base.tacho.pulses_per_rev))
    out = []
    for machine in (base, dataclasses.replace(base, effects=effects)):
        if machine is not base and not effects:
            out.append(None)
            continue
        model, built = machine_fmu(machine, ROOT / "modelica", build)
        problem = machine_problem(built.fmu, model, m, machine, speed, ProblemSettings(
            speed=SpeedSettings(tacho=base.tacho.channel)))
        if machine is base:  # the other stages silenced: the first stage's model alone
            output = next(o for o in model.outputs if o.channel == channel)
            alone = problem.derive(
                parameters=tuple(p for p in problem.parameters
                                 if p.name.startswith(model.stages[output.near] + ".")),
                fixed_values={level: SILENT_DB for level in output.levels.values()})
            out.append(compare(alone, FaultEstimator()).error)
        fit = fit_machine(problem, model, FaultEstimator())
        out.append(compare(problem, None, parameters=fit.parameters).error)
    return out[0], out[1], out[2], time.perf_counter() - started


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default=str(ROOT.parent / "shared" / "data" / "phm09"))
    ap.add_argument("--records", help="comma-separated record names (default: every one)")
    ap.add_argument("--effects", default="", help="KEY@STAGE,... (stages from 1)")
    ap.add_argument("--channel", default="ch1")
    args = ap.parse_args()
    effects = tuple(StageEffect(key, int(stage) - 1) for key, stage in
                    (item.split("@") for item in args.effects.split(",") if item))
    files = sorted(p for p in Path(args.folder).iterdir() if NAME.search(p.name))
    if args.records:
        wanted = set(args.records.split(","))
        files = [p for p in files if p.name.split(".")[0] in wanted]
    if not files:
        print(f"no record of that name in {args.folder}", file=sys.stderr)
        return 2
    print(f"# {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; channel {args.channel}; effects: "
          + (", ".join(f"{e.key} on stage {e.stage + 1}" for e in effects) or "none"))
    print("| record | first stage alone | every stage | with the effects | s |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="bench_machine_") as build:
        for path in files:
            alone, both, extended, seconds = errors(path, args.channel, effects, Path(build))
            print(f"| {path.name.split('.')[0]} | {alone:.3f} | {both:.3f} | "
                  f"{'-' if extended is None else f'{extended:.3f}'} | {seconds:.0f} |",
                  flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
