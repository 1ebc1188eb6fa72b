"""Every component of the gearbox simulator's short box judged by the machine's healthy
model (``diagnose --machine`` with the loop's healthy model, tests/golden/short_box.loop.toml,
its effects refitted held out and the effects of every component it lacks tried, held to
healthy repeats) beside the indicators alone (``indicators --machine``, the same
baselines), on the independent simulator's records (tests/truth/gearbox.py: faults written
from the shafts' angles and the bearings' own geometry, not the catalogue's equations).
Prints a row a record (seconds of each command; the first diagnose also fits the healthy
model and builds the models with one effect more) and a row a labelled or said component:
the truth, the indicators' state, the joined state and its judge, the model's margin and
the size it fitted. Usage:

    .venv/bin/python bench/model_components.py [--seeds 2,5]

Baselines: healthy seeds 1 (the healthy model's record), 3 and 4 (its repeats); each case's
record on each seed of ``--seeds``. The commands run as a user runs them, with their
defaults, a history and build folder of their own (a temporary folder).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from components import SIMULATED, _right  # noqa: E402

from pydiag.io.measurements import write_measurement  # noqa: E402

HEALTHY_MODEL = ROOT / "tests" / "golden" / "short_box.loop.toml"
#: The catalogue effects of the short box's components that its healthy model lacks:
#: each bearing's races and ball (the pinion's and, on the output shaft, the gear's), the
#: shafts' orders, a gear's tooth.
LACKING = ("bearing_outer_race", "bearing_inner_race", "bearing_ball",
           "gear_bearing_outer_race", "gear_bearing_inner_race", "gear_bearing_ball",
           "pinion_shaft_orders", "other_shaft_orders", "gear_tooth_fault")
#: The kind of each gear fault the simulator writes (bench/components.py labels a gear
#: "changed": its judge does not tell the kind; the model's tooth effect may).
GEAR_FAULTS = {"broken tooth, short box's output gear": "broken",
               "chipped idler gear (short box)": "chipped",
               "input outer race + broken tooth": "broken"}
#: The short box's cases of bench/components.py, and the output bearing (the last stage's
#: gear bearing), which no pinion's shaft carries.
CASES = [(name, box, faults, {c: GEAR_FAULTS[name] if state == "changed" else state
                              for c, state in labels.items()})
         for name, box, faults, labels in SIMULATED if box == "SHORT_BOX"] + [
    ("output outer race", "SHORT_BOX", dict(bearing=((2, "outer", 6.0),)),
     {"output bearing": "outer"})]


def _run(*argv: str) -> tuple[dict, float]:
    """A pydiag command's JSON (its --json) and its wall seconds."""
    out = Path(argv[argv.index("--json") + 1])
    started = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "pydiag", *argv], capture_output=True,
                       text=True, cwd=ROOT)
    seconds = time.perf_counter() - started
    if not out.exists():
        raise SystemExit(f"pydiag {argv[0]} failed ({r.returncode}): {r.stderr.strip()[-800:]}")
    return json.loads(out.read_text()), seconds


def _fitted(component: dict, changes: list[dict]) -> str:
    """The size the model fitted for a component it names: the largest change's sizing
    parameters, healthy -> record."""
    named = [c for c in changes if c["changed"] and component["name"] in c["components"]]
    if not named:
        return "-"
    said = max(named, key=lambda c: c["margin"])
    return ", ".join(f"{k.rsplit('.', 1)[-1]} {a:.3g}->{b:.3g}"
                     for k, (a, b) in said["values"].items())


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="2,5", help="the records' seeds (default 2,5)")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    from truth import gearbox as sim
    print(f"# {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, the gearbox simulator's short box, seeds {seeds}")
    with tempfile.TemporaryDirectory() as scratch:
        tmp = Path(scratch)
        healthy = []
        for seed in (1, 3, 4):
            healthy.append(tmp / f"healthy_{seed}.csv")
            write_measurement(healthy[-1], sim.gearbox_record(seed, box=sim.SHORT_BOX))
        baselines = [a for h in healthy for a in ("--baseline", str(h))]
        common = ["--machine", str(HEALTHY_MODEL), *baselines, "--force"]
        records, rows = [], []
        print(f"{'case':<40}{'seed':>5}{'indicators s':>14}{'diagnose s':>12}")
        for i, (case, _, faults, labels) in enumerate(CASES):
            for seed in seeds:
                rec = tmp / f"case{i}_seed{seed}.csv"
                write_measurement(rec, sim.gearbox_record(seed, box=sim.SHORT_BOX, **faults))
                alone, s_ind = _run("indicators", *common, "--measurement", str(rec),
                                    "--json", str(tmp / "ind.json"))
                joined, s_diag = _run("diagnose", *common, "--measurement", str(rec),
                                      "--build-dir", str(tmp / "build"), "--quiet",
                                      "--history", str(tmp / "history.sqlite"),
                                      "--lacking", ",".join(LACKING),
                                      "--json", str(tmp / "diag.json"))
                print(f"{case:<40}{seed:>5}{s_ind:>14.1f}{s_diag:>12.1f}", flush=True)
                records.append((case, seed, s_ind, s_diag))
                ind = {c["name"]: c for c in alone["components"]}
                for c in joined["components"]:
                    truth = labels.get(c["name"], "good")
                    faulty = c["state"] != "good" or ind[c["name"]]["state"] != "good"
                    if truth != "good" or faulty:
                        rows.append((case, seed, c["name"], truth, ind[c["name"]]["state"],
                                     c["state"], c["judge"], c["margin"],
                                     _fitted(c, joined["model_changes"])))
    print()
    print(f"{'case':<40}{'seed':>5}  {'component':<22}{'truth':<10}{'indicators':<11}"
          f"{'joined':<11}{'judge':<11}{'x thr':>7}  model's size")
    for case, seed, name, truth, ind, said, judge, margin, fitted in rows:
        shown = "-" if margin is None else f"{margin:.2f}"
        print(f"{case:<40}{seed:>5}  {name:<22}{truth:<10}{ind:<11}{said:<11}{judge:<11}"
              f"{shown:>7}  {fitted}")
    labelled = [r for r in rows if r[3] != "good"]
    for title, k in (("indicators alone", 4), ("joined with the model", 5)):
        right = sum(_right(r[k], r[3]) for r in labelled)
        wrong = sum(r[3] == "good" and r[k] != "good" for r in rows)
        clean = sum(not any(r[0] == case and r[1] == seed and r[3] == "good" and r[k] != "good"
                            for r in rows)
                    for case, seed, *_ in records if case.startswith("healthy"))
        print(f"{title}: faults named on their component {right} of {len(labelled)}; "
              f"components called faulty that are not {wrong}; healthy records all good "
              f"{clean} of {sum(case.startswith('healthy') for case, *_ in records)}")
    diag = sorted(s for *_, s in records[1:])
    if diag:
        print(f"diagnose with the healthy model kept: median {diag[len(diag) // 2]:.1f} s, "
              f"first (fitting it, building the models) {records[0][3]:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
