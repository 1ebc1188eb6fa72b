"""Every gear, bearing and shaft of the PHM 2009 gearboxes judged against a healthy record of
the same box, speed and load (``indicators --machine --baseline``: the stage judge and
the component judge, no model fit), beside the data set's labels. Prints a row a faulty
component (what the label says, what was said, how far over its threshold and its size:
:func:`size`) and a row a record (how many of its
components were called faulty, and the seconds it took), then the counts. Usage:

    .venv/bin/python bench/components.py [DIR]     # default ../shared/data/phm09
    .venv/bin/python bench/components.py --simulator
    .venv/bin/python bench/components.py --every-baseline [DIR]

``--simulator``: the same on the independent gearbox simulator's records
(tests/truth/gearbox.py: faults written from the shafts' angles and the bearing's own
geometry), each fault alone and two at once, seeds 2-4 (``--seeds``), each judged against
seed 1's healthy record (with a tacho where the case has one).

The records and their labels are the folder README's (a record is judged against the
case-1 run of its box, speed and load that is not itself, run 2 first; with
``--every-baseline``, against every such run, as a user gives every healthy record of the
operating point he has); a case whose every component is
good is a healthy record. Cite the PHM Society 2009 Data Challenge where you report
results.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.gear.component_judge import judge_components  # noqa: E402
from pydiag.gear.machine_file import load_machine  # noqa: E402
from pydiag.gear.machine_indicators import machine_record  # noqa: E402
from pydiag.gear.speed import SpeedSettings  # noqa: E402
from pydiag.gear.stage_judge import judge_stages  # noqa: E402
from pydiag.io.readers import read_measurement  # noqa: E402

NAME = re.compile(r"(spur|helical) (\d+)_(\d+)hz_(High|Low)_(\d+)")
RATE_HZ = 200_000 / 3
#: The folder README's labels, by (box, case): component name -> state (gears by teeth and
#: shaft as pydiag names them; the data set says "chipped", "broken", "eccentric", and the
#: component judge can say "changed" of a gear).
LABELS = {
    ("spur", 1): {},
    ("spur", 2): {"32T pinion of input stage": "chipped",
                  "48T pinion of output stage": "eccentric"},
    ("spur", 4): {"48T pinion of output stage": "eccentric",
                  "80T gear of output stage": "broken", "IS:IS": "ball"},
    ("spur", 6): {"80T gear of output stage": "broken", "IS:IS": "inner", "ID:IS": "ball",
                  "OS:IS": "outer", "input": "imbalance"},
    ("spur", 7): {"IS:IS": "inner", "output": "looseness"},
    ("helical", 1): {},
    ("helical", 4): {"IS:OS": "outer/inner", "ID:OS": "ball", "input": "imbalance"},
    ("helical", 6): {"input": "bent"},
}


def size(verdict) -> str:
    """What a verdict's evidence says of its size: a swing's degrees (of the input's turn),
    a bearing's defect line's rise, a shaft's largest order's, a gear's shaft's residual
    energy's (dB against the baseline)."""
    e = verdict.evidence
    kind = verdict.component.kind
    if "swing_1x_deg" in e:
        return f"{e['swing_1x_deg']:.3f} deg swing"
    if kind == "bearing" and f"{verdict.state}_db" in e:
        return f"{e[verdict.state + '_db']:+.1f} dB {verdict.state}"
    if kind == "shaft" and e:
        k, v = max(e.items(), key=lambda kv: kv[1] if math.isfinite(kv[1]) else -math.inf)
        return f"{v:+.1f} dB at {k.split('_')[1]}x"
    if "residual_energy_db" in e:
        return f"{e['residual_energy_db']:+.1f} dB residual"
    return "-"


def healthy_runs(path: Path, files: list[Path]) -> list[Path]:
    """The healthy runs among ``files`` of the box, speed and load of the record at
    ``path``, but itself, run 2 first (the README's baseline)."""
    box, _, hz, load, _ = NAME.search(path.name).groups()
    return sorted((p for p in files if p != path
                   and NAME.search(p.name).groups()[:4] == (box, "1", hz, load)),
                  key=lambda p: NAME.search(p.name).group(5) != "2")


def names(said: str, truth: str) -> bool:
    """A state said names the labelled fault (a gear "changed" is its fault not told)."""
    return said in truth.split("/") or (said == "changed" and truth in ("chipped", "broken",
                                                                          "eccentric"))


#: The simulator's cases: (name, box, the record's faults, what they are: component ->
#: state). Sizes as tests/unit/gear/test_component_judge.py's (a chip: a dip of its mesh
#: of depth 0.3, a broken tooth's 0.8; a runout: its mesh swinging by 0.2 once a turn); a
#: gear's fault is said "changed" (the judge tells a gear's change, not its kind).
SIMULATED = [
    ("healthy", "BOX", {}, {}),
    ("healthy (short box)", "SHORT_BOX", {}, {}),
    ("output unbalance", "BOX", dict(unbalance=((2, 0.3),)), {"output": "imbalance"}),
    ("input bend", "BOX", dict(bend=((0, 0.3),)), {"input": "bent"}),
    ("broken tooth, stage 2's gear", "BOX", dict(faulty_shaft=2, stage=1),
     {"54T gear of stage 2": "changed"}),
    ("broken tooth, short box's output gear", "SHORT_BOX", dict(faulty_shaft=2, stage=1),
     {"50T gear of stage 2": "changed"}),
    ("chipped input pinion", "BOX", dict(faulty_shaft=0, stage=0, depth=0.3),
     {"20T pinion of stage 1": "changed"}),
    ("chipped idler gear (short box)", "SHORT_BOX", dict(faulty_shaft=1, stage=0, depth=0.3),
     {"36T gear of stage 1": "changed"}),
    ("eccentric output gear", "BOX", dict(runout=((2, 1, 0.2),)),
     {"54T gear of stage 2": "changed"}),
    ("eccentric idler pinion", "BOX", dict(runout=((1, 1, 0.2),)),
     {"24T pinion of stage 2": "changed"}),
    # with a 10-pulse tacho on the input, and the runout swinging the whole drive by 0.002
    # of an input turn once its shaft's turn (a transmission error the tacho sees)
    ("healthy (tacho)", "BOX", dict(tacho_pulses=10), {}),
    ("eccentric idler pinion, drive swinging", "BOX",
     dict(runout=((1, 1, 0.2),), swing=((1, 0.002),), tacho_pulses=10),
     {"24T pinion of stage 2": "eccentric"}),
    ("eccentric output gear, drive swinging", "BOX",
     dict(runout=((2, 1, 0.2),), swing=((2, 0.002),), tacho_pulses=10),
     {"54T gear of stage 2": "eccentric"}),
    ("intermediate inner race", "SHORT_BOX", dict(bearing=((1, "inner", 6.0),)),
     {"intermediate bearing": "inner"}),
    ("input outer race", "SHORT_BOX", dict(bearing=((0, "outer", 6.0),)),
     {"input bearing": "outer"}),
    ("output ball", "SHORT_BOX", dict(bearing=((2, "ball", 6.0),)),
     {"output bearing": "ball"}),
    ("input ball", "SHORT_BOX", dict(bearing=((0, "ball", 6.0),)), {"input bearing": "ball"}),
    ("input bend + intermediate inner race", "SHORT_BOX",
     dict(bend=((0, 0.3),), bearing=((1, "inner", 6.0),)),
     {"input": "bent", "intermediate bearing": "inner"}),
    ("output unbalance + broken tooth", "BOX",
     dict(unbalance=((2, 0.3),), faulty_shaft=2, stage=1),
     {"output": "imbalance", "54T gear of stage 2": "changed"}),
    ("input outer race + broken tooth", "SHORT_BOX",
     dict(bearing=((0, "outer", 6.0),), faulty_shaft=2, stage=1),
     {"input bearing": "outer", "50T gear of stage 2": "changed"}),
]


def simulator_rows(seeds: tuple[int, ...] = (2, 3, 4)) -> tuple[list, list]:
    """Each of :data:`SIMULATED` on ``seeds`` against seed 1's healthy record: a row a
    record (case, seed, faulty said, seconds) and a row a labelled or said component."""
    sys.path.append(str(ROOT / "tests"))
    from truth import gearbox as sim

    from pydiag.gear.machine_file import machine_from_dict
    records, rows = [], []
    for case, box_name, faults, labels in SIMULATED:
        box = getattr(sim, box_name)
        machine = machine_from_dict(sim.described(box))
        pulses = faults.get("tacho_pulses", 0)
        speed = (SpeedSettings(tacho="tacho", pulses_per_rev=pulses) if pulses
                 else SpeedSettings("mesh"))
        baseline = machine_record(sim.gearbox_record(1, box=box, tacho_pulses=pulses), machine,
                                  speed, sim.INPUT_HZ)
        for seed in seeds:
            started = time.perf_counter()
            seen = machine_record(sim.gearbox_record(seed, box=box, **faults), machine,
                                  speed, sim.INPUT_HZ)
            verdicts, _ = judge_stages(machine, seen, [baseline])
            judged = {v.component.name: v for v in judge_components(machine, seen, [baseline],
                                                                    verdicts)}
            faulty = [v for v in judged.values() if v.faulty]
            records.append((case, seed, len(faulty), time.perf_counter() - started))
            for name, truth in labels.items():
                rows.append((case, seed, name, truth, judged[name].state, judged[name].margin,
                             size(judged[name])))
            rows += [(case, seed, v.component.name, "good", v.state, v.margin, size(v))
                     for v in faulty if v.component.name not in labels]
    return records, rows


def simulator_main(seeds: tuple[int, ...]) -> int:
    records, rows = simulator_rows(seeds)
    print(f"{'case':<40}{'seed':>5}{'faulty said':>12}{'s':>6}")
    for case, seed, said, seconds in records:
        print(f"{case:<40}{seed:>5}{said:>12}{seconds:>6.1f}")
    print()
    print(f"{'case':<40}{'seed':>5}  {'component':<22}{'truth':<11}{'said':<11}{'x thr':>6}"
          f"  size")
    for case, seed, name, truth, said, margin, seen in rows:
        shown = "-" if margin is None else f"{margin:.2f}"
        print(f"{case:<40}{seed:>5}  {name:<22}{truth:<11}{said:<11}{shown:>6}  {seen}")
    labelled = [r for r in rows if r[3] != "good"]
    right = sum(r[4] == r[3] for r in labelled)
    wrong = sum(r[3] == "good" for r in rows)
    clean = sum(said == 0 for case, _, said, _ in records if case.startswith("healthy"))
    print(f"\nfaults named on their component: {right} of {len(labelled)}; components called "
          f"faulty that are not: {wrong}; healthy records with every component good: "
          f"{clean} of {sum(case.startswith('healthy') for case, *_ in records)}")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default=str(ROOT.parent / "shared" / "data" / "phm09"))
    ap.add_argument("--every-baseline", action="store_true",
                    help="judge each record against every healthy run of its box, speed and "
                         "load but itself, not only the first")
    ap.add_argument("--simulator", action="store_true",
                    help="the independent gearbox simulator's cases instead")
    ap.add_argument("--seeds", default="2,3,4",
                    help="with --simulator: the records' seeds (default 2,3,4; 1 is the baseline)")
    args = ap.parse_args()
    if args.simulator:
        seeds = tuple(int(s) for s in args.seeds.split(","))
        print(f"# {platform.machine()}, {os.cpu_count()} cores, Python "
              f"{platform.python_version()}, the gearbox simulator, seeds {list(seeds)}")
        return simulator_main(seeds)
    files = sorted(p for p in Path(args.folder).iterdir() if NAME.search(p.name))
    print(f"# {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"{len(files)} records")
    machines = {box: load_machine(ROOT / "examples" / f"phm09_{box}.toml")
                for box in ("spur", "helical")}
    rows, counts = [], dict(faults=0, right=0, said=0, wrong=0, healthy=0, clean=0)
    print(f"{'record':<28}{'baseline':<28}{'faulty said':>12}{'s':>6}")
    for path in files:
        box, case, hz, load, run = NAME.search(path.name).groups()
        labels = LABELS.get((box, int(case)))
        healthy = healthy_runs(path, files)
        baselines = healthy if args.every_baseline else healthy[:1]
        if labels is None or not baselines:
            continue
        machine = machines[box]
        started = time.perf_counter()
        units = {s.channel: s.unit for s in machine.sensors}
        sensitivity = {s.channel: s.sensitivity for s in machine.sensors}
        speed = SpeedSettings(tacho=machine.tacho.channel,
                              pulses_per_rev=machine.tacho.pulses_per_rev)
        seen = [machine_record(read_measurement(p, RATE_HZ, units=units,
                                                sensitivities=sensitivity),
                               machine, speed, float(hz)) for p in (path, *baselines)]
        verdicts, _ = judge_stages(machine, seen[0], seen[1:])
        judged = {v.component.name: v for v in judge_components(machine, seen[0], seen[1:],
                                                                verdicts)}
        seconds = time.perf_counter() - started
        faulty = [v for v in judged.values() if v.faulty]
        named = baselines[0].stem + "".join(f",{NAME.search(b.name).group(5)}"
                                            for b in baselines[1:])  # "..._High_2,1"
        print(f"{path.stem:<28}{named:<28}{len(faulty):>12}{seconds:>6.1f}")
        if not labels:
            counts["healthy"] += 1
            counts["clean"] += not faulty
        for name, truth in labels.items():
            v = judged[name]
            counts["faults"] += 1
            counts["right"] += names(v.state, truth)
            rows.append((path.stem, name, truth, v.state, v.margin, size(v)))
        for v in faulty:
            counts["said"] += 1
            if v.component.name not in labels:
                counts["wrong"] += 1
                rows.append((path.stem, v.component.name, "good", v.state, v.margin,
                             size(v)))
    print()
    print(f"{'record':<28}{'component':<28}{'truth':<12}{'said':<12}{'x thr':>6}  size")
    for record, name, truth, said, margin, seen in rows:
        shown = "-" if margin is None else f"{margin:.2f}"
        print(f"{record:<28}{name:<28}{truth:<12}{said:<12}{shown:>6}  {seen}")
    print()
    print(f"labelled faults named on their component: {counts['right']} of {counts['faults']}; "
          f"components called faulty that are not labelled: {counts['wrong']} of "
          f"{counts['said']}; healthy records with every component good: {counts['clean']} "
          f"of {counts['healthy']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
