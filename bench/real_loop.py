"""The loop on real records: compare, validate held out, accept the confident effect,
compare again; until no effect is confident.

For each record of a labelled set in the layout of ``../shared/data/gfd`` (channel a1 in g,
no time column): GearPair with the channel gain fitted (the healthy teeth's ``a0`` with
it), the speed found and the record order-tracked; compare (every line of the whole
record), then every suggestion tried held out (:func:`pydiag.loop.validate.validate`; the loop is :mod:`pydiag.loop.accumulate`).
The confident one with the largest held-out z is accepted: its parameters join the base
model's (bounds as the residual narrowed them), its FMU becomes the base model's (an
``in_base`` effect keeps the FMU; a second effect with a model of its own makes the model
of both, :mod:`pydiag.loop.compose`), they are fitted on the whole record from the fit
before (``refit_with_effect``, as ``pydiag compare --effect`` does), and the loop
validates that comparison's suggestions, trying each effect with a model of its own on
the model with every accepted one. It stops when nothing is confident.

Printed per record and step: the residual by family, every suggestion's held-out status,
and the held-out error (noise-corrected Eq. 12 on the second half of the periods, on bins
the first half chose) of the base model and of the accepted effect.

Usage:
    .venv/bin/python bench/real_loop.py [--data ../shared/data/gfd] [--records b30hz90,...]
                                        [--steps 3] [--gain curve]
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.fit.estimator import FaultEstimator  # noqa: E402
from pydiag.fit.build import build_problem  # noqa: E402
from pydiag.gear.effects import EFFECTS  # noqa: E402
from pydiag.gear.speed import SpeedSettings  # noqa: E402
from pydiag.io.readers import read_measurement  # noqa: E402
from pydiag.loop.accumulate import LoopStep, accumulate  # noqa: E402
from pydiag.loop.residual import RESIDUAL_GROUPS  # noqa: E402
from pydiag.loop.compose import composed_fmu  # noqa: E402
from pydiag.loop.discover import effect_fmu  # noqa: E402

OPERATING_POINT = {"n_pinion": 32, "n_gear": 80, "f_pinion_hz": 30.0}  # README of gfd
SAMPLE_RATE_HZ = 12_900.0  # inferred in that README, not documented
BASE_FMU = str(ROOT / "build" / "GearPair.fmu")


def loop(path: Path, steps: int, build: Path, gain_curve: bool = False) -> list[str]:
    """The markdown rows of one record's sequence (:func:`pydiag.loop.accumulate.accumulate`);
    prints each step as it is made."""
    m = read_measurement(path, SAMPLE_RATE_HZ, ["a1=acc"], ["g"])
    name = path.name.split(".")[0]
    problem = build_problem(BASE_FMU, m, operating_point=OPERATING_POINT,
                            speed=SpeedSettings("auto"), fit_gain=True, gain_curve=gain_curve)
    rows, clock = [], [time.perf_counter()]

    def report(step: LoopStep) -> None:
        wall = time.perf_counter() - clock[-1]
        clock.append(time.perf_counter())
        c = step.comparison
        model = "GearPair" + "".join(f" + {a}" for a in step.effects)
        print(f"\n{name}, step {len(rows)}: {model}: error {c.error:.3f} on {c.n_error_bins} "
              f"bins, {wall:.0f} s", flush=True)
        shares = c.residual_by_family["acc"]
        print("  by family (measured / residual): " + ", ".join(
            f"{g} {100 * shares[g]['measured']:.0f}/{100 * shares[g]['residual']:.0f} %"
            for g in RESIDUAL_GROUPS), flush=True)
        for s in c.suggested_effects:
            print(f"  {s.effect}: {s.message}", flush=True)
        tried = [s for s in c.suggested_effects if s.held_out]
        # the base an effect is scored against: the fit held, or for one that reshapes the
        # base that fit polished free on half A; the held one unless an effect is accepted
        held = [s for s in tried if not EFFECTS[s.effect].reshapes_base
                and math.isfinite(s.held_out.error_base)]
        base_held = f"{held[0].held_out.error_base:.3f}" if held else "-"
        verdicts = "; ".join(f"{s.effect}: {s.status.value}" for s in tried) or "nothing tried"
        if step.accepted is None:
            rows.append(f"| {name} | {len(rows)} | {model} | {c.error:.3f} | {base_held} | - | "
                        f"- | {verdicts} | {wall:.0f} |")
            return
        s = next(s for s in c.suggested_effects if s.effect == step.accepted)
        base_held = f"{s.held_out.error_base:.3f}"
        values = ", ".join(f"{k} {v:.3g}" for k, v in s.held_out.parameters.items())
        rows.append(f"| {name} | {len(rows)} | {model} | {c.error:.3f} | {base_held} | "
                    f"**{s.effect}** ({values}, z {s.held_out.z:.0f}) | "
                    f"{s.held_out.error_effect:.3f} | {verdicts} | {wall:.0f} |")

    accumulate(problem, lambda e: str(effect_fmu(e.key, ROOT / "modelica", build)),
               lambda keys: str(composed_fmu(keys, ROOT / "modelica", build)), steps,
               FaultEstimator(seed=0), progress=report)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "gfd"))
    ap.add_argument("--records", help="comma-separated record names (default: every *.csv.gz)")
    ap.add_argument("--steps", type=int, default=3, help="at most this many compares per record")
    ap.add_argument("--gain", choices=("fit", "curve"), default="fit",
                    help="a gain a channel, or a gain curve with a node at every mesh harmonic")
    args = ap.parse_args()
    paths = sorted(Path(args.data).glob("*.csv.gz"))
    if args.records:
        paths = [p for p in paths if p.name.split(".")[0] in args.records.split(",")]
    if not paths:
        sys.exit(f"real_loop.py: no records (*.csv.gz{', ' + args.records if args.records else ''})"
                 f" in {args.data}")
    build = Path(tempfile.mkdtemp(prefix="real_loop_fmus_"))
    print(f"{platform.machine()}, {platform.python_version()}; records: "
          f"{', '.join(p.name for p in paths)}")
    rows = []
    for p in paths:
        rows += loop(p, args.steps, build, args.gain == "curve")
    print("\n| record | step | model | error | held-out error, base | accepted | held-out "
          "error, with it | held-out verdicts | s |\n|---|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
