"""Every component of the gearbox simulator's short box judged by the machine's healthy
model (``diagnose --machine`` with the loop's healthy model, tests/golden/short_box.loop.toml,
its effects refitted held out and, by default, every component fault of the catalogue it
lacks tried where the indicators see a change, held to healthy repeats) beside the indicators alone (``indicators --machine``, the same
baselines), on the independent simulator's records (tests/truth/gearbox.py: faults written
from the shafts' angles and the bearings' own geometry, not the catalogue's equations).
Prints a row a record (seconds of each command; the first diagnose also fits the healthy
model and builds the models with one effect more) and a row a labelled or said component:
the truth, the indicators' state, the joined state and its judge, the model's margin and
the size it fitted. Usage:

    .venv/bin/python bench/model_components.py [--seeds 2,5]
    .venv/bin/python bench/model_components.py --phm09 [DIR]   # default ../shared/data/phm09
    .venv/bin/python bench/model_components.py --phm09 --one-baseline

Baselines: healthy seeds 1 (the healthy model's record), 3 and 4 (its repeats); each case's
record on each seed of ``--seeds``. The commands run as a user runs them, with their
defaults, a history and build folder of their own (a temporary folder).

``--phm09``: the PHM 2009 records of the folder whose box, speed and load have two healthy
runs (run 2, the healthy model's record, then run 1, its repeat), each judged with the
machine files of examples/ as they are (no effects: the model is the stages alone, asked
for the catalogue's component faults), beside the data set's labels (bench/components.py's).
``--one-baseline``: every record of the folder with a healthy run of its operating point
but itself, judged against that one file (run 2 first), as the README's command runs it: the
model then judges nothing, but its fit to the file is kept and each record's fit is its
polish; a row a record (seconds: the first of each file fits it) and the counts.
Cite the PHM Society 2009 Data Challenge where you report results.
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

from components import LABELS, NAME, SIMULATED, healthy_runs, names  # noqa: E402

from pydiag.io.measurements import write_measurement  # noqa: E402

HEALTHY_MODEL = ROOT / "tests" / "golden" / "short_box.loop.toml"
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


def _phm09_files(folder: Path, how: str) -> list[Path]:
    """The PHM 2009 records of ``folder``, in order, the machine's line printed first."""
    print(f"# {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, PHM 2009 records of {folder}{how}")
    return sorted(p for p in folder.iterdir() if NAME.search(p.name))


def phm09_main(folder: Path) -> int:
    """The shared PHM 2009 records with two healthy runs of their operating point: a row a
    record (seconds), a row a labelled or said component, the counts."""
    files = _phm09_files(folder, "")
    records, rows, skipped = [], [], []
    with tempfile.TemporaryDirectory() as scratch:
        tmp = Path(scratch)
        print(f"{'record':<28}{'indicators s':>14}{'diagnose s':>12}")
        for path in files:
            box, case, hz, load, run = NAME.search(path.name).groups()
            labels = LABELS.get((box, int(case)))
            healthy = healthy_runs(path, files)
            if labels is None or case == "1":
                continue
            if len(healthy) < 2:
                skipped.append(path.stem)
                continue
            common = ["--machine", str(ROOT / "examples" / f"phm09_{box}.toml"),
                      "--sample-rate", "66666.67", "--rpm", str(60 * int(hz)),
                      "--measurement", str(path), "--force",
                      *(a for h in healthy for a in ("--baseline", str(h)))]
            alone, s_ind = _run("indicators", *common, "--json", str(tmp / "ind.json"))
            joined, s_diag = _run("diagnose", *common, "--build-dir", str(tmp / "build"),
                                  "--quiet", "--history", str(tmp / "history.sqlite"),
                                  "--json", str(tmp / "diag.json"))
            print(f"{path.stem:<28}{s_ind:>14.1f}{s_diag:>12.1f}", flush=True)
            records.append((path.stem, s_ind, s_diag))
            _rows_of(path.stem, 0, labels, alone, joined, rows)
    _report(rows, records, healthy_records=[], firsts=False)
    print(f"not judged by the model (one healthy run of their operating point): "
          f"{', '.join(skipped) or 'none'}")
    return 0


def one_baseline_main(folder: Path) -> int:
    """Every record of ``folder`` with a healthy run of its operating point but itself,
    ``diagnose --machine`` against that one file (run 2 first), a history for all: a row a
    record (its baseline, seconds: the first of each baseline fits it, its faulty
    components), the counts."""
    files = _phm09_files(folder, ", one baseline file")
    baseline = {path: next(iter(healthy_runs(path, files)), None) for path in files}
    rows, firsts, kept = [], [], []
    print(f"{'record':<28}{'baseline':<24}{'diagnose s':>11}  faulty components")
    with tempfile.TemporaryDirectory() as scratch:
        tmp = Path(scratch)
        for path, first in baseline.items():
            if first is None:
                print(f"{path.stem:<28}{'none':<24}")
                continue
            box, case, hz, _, _ = NAME.search(path.name).groups()
            report, seconds = _run(
                "diagnose", "--machine", str(ROOT / "examples" / f"phm09_{box}.toml"),
                "--sample-rate", "66666.67", "--rpm", str(60 * int(hz)), "--measurement",
                str(path), "--baseline", str(first), "--force", "--quiet",
                "--build-dir", str(tmp / "build"), "--history", str(tmp / "history.sqlite"),
                "--json", str(tmp / "diag.json"))
            (kept if first in {b for b, _ in firsts} else firsts).append((first, seconds))
            faulty = [f"{c['name']}={c['state']}" for c in report["components"]
                      if c["state"] != "good"]
            print(f"{path.stem:<28}{first.stem:<24}{seconds:>11.1f}  "
                  f"{'; '.join(faulty) or '-'}", flush=True)
            _rows_of(path.stem, 0, LABELS.get((box, int(case)), {}), report, report, rows)
    labelled = [r for r in rows if r[3] != "good"]
    print(f"faults named on their component {sum(names(r[5], r[3]) for r in labelled)} of "
          f"{len(labelled)}; components called faulty that are not "
          f"{sum(r[3] == 'good' and r[5] != 'good' for r in rows)}")
    print(f"the first record of each baseline file (its fit kept): "
          f"{', '.join(f'{s:.1f}' for _, s in firsts)} s; the others: "
          f"{', '.join(f'{s:.1f}' for _, s in kept)} s")
    return 0


def _rows_of(case: str, seed: int, labels: dict, alone: dict, joined: dict,
             rows: list) -> None:
    """A row a component the labels name or either verdict calls faulty."""
    ind = {c["name"]: c for c in alone["components"]}
    for c in joined["components"]:
        truth = labels.get(c["name"], "good")
        faulty = c["state"] != "good" or ind[c["name"]]["state"] != "good"
        if truth != "good" or faulty:
            rows.append((case, seed, c["name"], truth, ind[c["name"]]["state"], c["state"],
                         c["judge"], c["margin"], _fitted(c, joined["model_changes"])))


def _report(rows: list, records: list, healthy_records: list, firsts: bool = True) -> None:
    """The table of ``rows`` (:func:`_rows_of`) and the counts, each verdict's; ``firsts``:
    the records are of one machine, the first fitting its healthy model (a line of the
    times)."""
    print()
    print(f"{'case':<40}{'seed':>5}  {'component':<28}{'truth':<12}{'indicators':<11}"
          f"{'joined':<11}{'judge':<11}{'x thr':>7}  model's size")
    for case, seed, name, truth, ind, said, judge, margin, fitted in rows:
        shown = "-" if margin is None else f"{margin:.2f}"
        print(f"{case:<40}{seed:>5}  {name:<28}{truth:<12}{ind:<11}{said:<11}{judge:<11}"
              f"{shown:>7}  {fitted}")
    labelled = [r for r in rows if r[3] != "good"]
    for title, k in (("indicators alone", 4), ("joined with the model", 5)):
        right = sum(names(r[k], r[3]) for r in labelled)
        wrong = sum(r[3] == "good" and r[k] != "good" for r in rows)
        clean = sum(not any(r[0] == case and r[1] == seed and r[3] == "good" and r[k] != "good"
                            for r in rows) for case, seed in healthy_records)
        print(f"{title}: faults named on their component {right} of {len(labelled)}; "
              f"components called faulty that are not {wrong}"
              + (f"; healthy records all good {clean} of {len(healthy_records)}"
                 if healthy_records else ""))
    diag = sorted(r[-1] for r in records[1:])
    if diag and firsts:
        print(f"diagnose with the healthy model kept: median {diag[len(diag) // 2]:.1f} s, "
              f"first (fitting it, building the models) {records[0][-1]:.1f} s")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="2,5", help="the records' seeds (default 2,5)")
    ap.add_argument("--phm09", nargs="?", const=str(ROOT.parent / "shared" / "data" / "phm09"),
                    help="the shared PHM 2009 records instead (folder)")
    ap.add_argument("--one-baseline", action="store_true",
                    help="with --phm09: every record against one healthy file")
    args = ap.parse_args()
    if args.phm09:
        return (one_baseline_main if args.one_baseline else phm09_main)(Path(args.phm09))
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
                                      "--json", str(tmp / "diag.json"))
                print(f"{case:<40}{seed:>5}{s_ind:>14.1f}{s_diag:>12.1f}", flush=True)
                records.append((case, seed, s_ind, s_diag))
                _rows_of(case, seed, labels, alone, joined, rows)
    _report(rows, records, [(case, seed) for case, seed, *_ in records
                            if case.startswith("healthy")])
    return 0


if __name__ == "__main__":
    sys.exit(main())
