"""Records in the PHM 2009 challenge's naming (``spur N_XXhz_Load_R``, zipped or not), seen
through the machine file: the speed from every mesh against the tacho's, and every stage
judged against the healthy records (case ``spur 1``) of the same speed and load, each
record leaving itself out. Prints a table a record and the time each took. Usage:

    .venv/bin/python bench/phm09.py [DIR]     # default ../shared/data/phm09
    .venv/bin/python bench/phm09.py --model   # and every stage fitted without a baseline
    .venv/bin/python bench/phm09.py --batch   # pydiag batch --machine: local pool and Dask
    .venv/bin/python bench/phm09.py --per-record  # one record's diagnose --machine, timed

With ``--model`` each record's stages are also fitted (``diagnose --machine`` without a
baseline: the pair model's classes on the paper's simulated scale), side by side with the
baseline's verdicts: the model must earn its place against the indicators.

With ``--batch`` the folder is diagnosed by ``pydiag batch --machine`` with the first
healthy record as baseline, once on the local pool and once on a Dask cluster on this
machine (as many single-threaded worker processes as cores): wall time and records a
minute of each.

With ``--per-record`` the first faulty record (else the first) is diagnosed by whole
``pydiag diagnose --machine`` processes (both stages fitted at the default budget, the
tacho used), three times with a healthy record of its speed and load read as
``--baseline FILE`` and three times with it kept (``pydiag baseline``) and taken as
``--baseline kept``: medians of the wall time and of the user CPU of the three.

With ``--tacho-angle`` the stages are judged on every shaft's TSA along the tacho's angle
(the speed column stays the mesh's, found without the tacho).

With ``--angle-swing`` each record's input-shaft angle is compared along the tacho and
along the mesh: the tacho's angle's swing once a turn of each slower shaft (degrees of
the input's turn, as ``indicators --machine`` reports it), and the input shaft's FM4
(mean of the channels) along four angles: the tacho's; the tacho's without what swings
above half the slowest shaft's speed (low-passed); the mesh's; the mesh's with the
tacho's swing between half the slowest shaft's speed and half the input's added back.
Which of them show a local fault of the input pinion says whether the mesh's angle loses
it by not following that swing.

Labels: ``spur 1`` all good; ``spur 2`` the 32-tooth input pinion chipped and the
48-tooth idler pinion eccentric (both stages); other cases are shown without a label.
Cite the PHM Society 2009 Data Challenge where you report results.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.gear.machine_file import load_machine  # noqa: E402
from pydiag.gear.machine_indicators import machine_record  # noqa: E402
from pydiag.fit.build import ProblemSettings  # noqa: E402
from pydiag.gear.speed import SpeedSettings, estimate_speed  # noqa: E402
from pydiag.gear.stage_judge import judge_stages  # noqa: E402
from pydiag.io.readers import read_measurement  # noqa: E402
from pydiag.diagnose.stages import diagnose_machine  # noqa: E402

NAME = re.compile(r"spur (\d+)_(\d+)hz_(High|Low)_(\d+)")
RATE_HZ = 200_000 / 3
LABELS = {1: ("healthy", "healthy"), 2: ("changed", "changed")}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default=str(ROOT.parent / "shared" / "data" / "phm09"))
    ap.add_argument("--model", action="store_true", help="also fit every stage (no baseline)")
    ap.add_argument("--batch", action="store_true", help="time pydiag batch --machine instead")
    ap.add_argument("--tacho-angle", action="store_true",
                    help="judge the stages on TSAs along the tacho's angle (the speed column "
                         "is still the mesh's)")
    ap.add_argument("--angle-swing", action="store_true",
                    help="the input's angle along the tacho and the mesh, and its FM4 along each")
    ap.add_argument("--per-record", action="store_true",
                    help="time one record's diagnose --machine, baseline read and kept")
    args = ap.parse_args()
    machine = load_machine(ROOT / "examples" / "phm09_spur.toml")
    files = sorted(p for p in Path(args.folder).iterdir() if NAME.search(p.name)
                   and p.suffix in (".zip", ".txt"))
    if not files:
        print(f"no record named like 'spur 1_30hz_High_1' in {args.folder}", file=sys.stderr)
        return 2
    print(f"# {platform.machine()}, {os.cpu_count()} cores, {platform.python_version()}, "
          f"{len(files)} records")
    if args.batch:
        return batch_throughput(args.folder, files)
    if args.per_record:
        return per_record(files)
    if args.angle_swing:
        return angle_swing(machine, files)
    seen = {}
    for path in files:
        case, hz, load, run = NAME.search(path.name).groups()
        started = time.perf_counter()
        m = read_measurement(path, RATE_HZ)
        kin = machine.stage_kinematics(0, float(hz))
        tacho = estimate_speed(m, kin, SpeedSettings("tacho", tacho="ch3", pulses_per_rev=10))
        record = machine_record(m, machine, SpeedSettings("mesh", tacho="ch3"), float(hz))
        if args.tacho_angle:  # the mesh's speed kept for the table, the shafts' TSAs redone
            along = machine_record(m, machine, SpeedSettings("tacho", tacho="ch3",
                                                             pulses_per_rev=10), float(hz))
            record = dataclasses.replace(record, shafts=along.shafts)
        model = None
        if args.model:
            fitted = diagnose_machine(str(ROOT / "build" / "GearPair.fmu"), m, machine,
                                      float(hz), ProblemSettings(
                                          speed=SpeedSettings("mesh", tacho="ch3")))
            model = [st.fault_mode for st in fitted.stages]
        seen[path.name] = (int(case), hz, load, record, time.perf_counter() - started,
                           tacho.speed_hz, model)
    print(f"{'record':<24}{'tacho Hz':>10}{'mesh Hz':>10}{'err %':>9}{'conf dB':>8}  "
          f"{'stage 1':<22}{'stage 2':<22}{'thr dB':>7}  {'label':<18}{'s':>5}")
    right = total = model_right = model_total = 0
    models = []
    for name, (case, hz, load, record, took, tacho_hz, model) in seen.items():
        baselines = [r for n, (c, h, ld, r, _, _, _) in seen.items()
                     if c == 1 and h == hz and ld == load and n != name]
        if model is not None:
            models.append(f"{name[:23]:<24}{model[0]:<22}{model[1]:<22}"
                          f"{'/'.join(LABELS.get(case, ('?', '?')))}")
            if case in LABELS:
                model_total += 2
                model_right += sum((m == "healthy") == (lab == "healthy")
                                   for m, lab in zip(model, LABELS[case]))
        speed = record.speed
        cells, threshold = [], ""
        if baselines:
            verdicts, _ = judge_stages(machine, record, baselines)
            cells = [f"{'changed' if v.changed else 'healthy'}"
                     f"{', ' + v.suspect if v.suspect else ''} "
                     f"{max(abs(v.pinion.change_db), abs(v.gear.change_db)):.1f}dB"
                     for v in verdicts]
            threshold = f"{verdicts[0].threshold_db:.2f}"
            label = LABELS.get(case)
            if label:
                total += 2
                right += sum(v == lab for v, lab in
                             zip(("changed" if v.changed else "healthy" for v in verdicts),
                                 label))
        label_text = "/".join(LABELS.get(case, ("?", "?")))
        cells = cells or ["no baseline", ""]
        print(f"{name[:23]:<24}{tacho_hz:>10.4f}{speed.speed_hz:>10.4f}"
              f"{100 * (speed.speed_hz / tacho_hz - 1):>+9.4f}{speed.confidence_db:>8.1f}  "
              f"{cells[0]:<22}{cells[1]:<22}{threshold:>7}  {label_text:<18}{took:>5.1f}")
    if total:
        print(f"stage verdicts as labelled: {right} of {total}")
    if models:
        print(f"\nthe pair model per stage, no baseline (paper's scale):\n"
              f"{'record':<24}{'stage 1':<22}{'stage 2':<22}label")
        print("\n".join(models))
        print(f"healthy or not as labelled: {model_right} of {model_total}")
    return 0


def per_record(files: list[Path], repeat: int = 3) -> int:
    """One record's ``diagnose --machine`` in whole processes, its baseline read or kept."""
    import resource
    import statistics
    parsed = {p: NAME.search(p.name).groups() for p in files}
    record = next((p for p, (case, *_) in parsed.items() if case != "1"), files[0])
    _, hz, load, _ = parsed[record]
    baseline = next((p for p, (case, h, ld, _) in parsed.items()
                     if case == "1" and h == hz and ld == load and p != record), None)
    if baseline is None:
        print(f"no healthy record at {hz} Hz, {load} load besides {record.name}", file=sys.stderr)
        return 2
    print(f"record: {record.name}; baseline: {baseline.name}; {_cpu_model()}")
    common = ["--machine", str(ROOT / "examples" / "phm09_spur.toml"), "--sample-rate",
              str(RATE_HZ), "--rpm", str(60 * int(hz))]
    print(f"{'baseline':<12}{'wall s (median)':>16}{'user s':>8}  runs")
    with tempfile.TemporaryDirectory() as tmp:
        history = ["--history", str(Path(tmp) / "history.sqlite")]
        kept = subprocess.run([sys.executable, "-m", "pydiag", "baseline", "--measurement",
                               str(baseline), *common, *history], capture_output=True,
                              text=True, cwd=ROOT)
        if kept.returncode != 0:
            print(f"pydiag baseline failed: {kept.stderr.strip()}", file=sys.stderr)
            return 1
        for how, given in (("read", str(baseline)), ("kept", "kept")):
            walls, users = [], []
            for _ in range(repeat):
                before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
                started = time.perf_counter()
                res = subprocess.run(
                    [sys.executable, "-m", "pydiag", "diagnose", "--fmu",
                     str(ROOT / "build" / "GearPair.fmu"), "--measurement", str(record),
                     *common, *history, "--baseline", given, "--quiet"],
                    capture_output=True, text=True, cwd=ROOT)
                walls.append(time.perf_counter() - started)
                users.append(resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - before)
                if res.returncode not in (0, 1):  # 1: a stage the model does not explain
                    print(f"diagnose failed: {res.stderr.strip()}", file=sys.stderr)
                    return 1
            print(f"{how:<12}{statistics.median(walls):>16.2f}"
                  f"{statistics.median(users):>8.1f}  " + " ".join(f"{w:.2f}" for w in walls))
    return 0


def angle_swing(machine, files: list[Path]) -> int:
    """The input shaft's angle along the tacho and along the mesh (module docstring)."""
    import numpy as np
    from scipy.signal import butter, sosfiltfilt
    from pydiag.gear.machine_indicators import shaft_records

    ratios = [float(machine.shaft_ratio(k)) for k in range(len(machine.shafts))]

    def filtered(revs, valid, band_hz, btype):
        """``revs`` within ``valid`` with its deviation from a straight line filtered."""
        a, b = valid[0], valid[1] + 1
        n = np.arange(a, b)
        line = np.polyval(np.polyfit(n, revs[a:b], 1), n)
        sos = butter(4 if btype == "low" else 2, np.asarray(band_hz) / (RATE_HZ / 2),
                     btype=btype, output="sos")
        out = np.zeros_like(revs)
        out[a:b] = sosfiltfilt(sos, revs[a:b] - line) + (line if btype == "low" else 0)
        return out

    slower = [k for k, r in enumerate(ratios) if r < 1]
    print(f"{'record':<24}" + "".join(f"{machine.shafts[k] + ' deg':>12}" for k in slower)
          + f"{'tacho':>8}{'tacho lp':>10}{'mesh':>8}{'mesh+swing':>12}  (input FM4)")
    for path in files:
        m = read_measurement(path, RATE_HZ)
        hz = float(NAME.search(path.name).group(2))
        tacho = estimate_speed(m, machine.stage_kinematics(0, hz),
                               SpeedSettings("tacho", tacho="ch3", pulses_per_rev=10))
        mesh = estimate_speed(m, machine.stage_kinematics(0, hz),
                              SpeedSettings("mesh", tacho="ch3"), machine=machine)
        valid = (mesh.valid[0], mesh.valid[1] - 1)
        low = 0.5 * min(ratios) * tacho.speed_hz
        angles = [tacho,
                  dataclasses.replace(tacho, valid=valid, revolutions=filtered(
                      tacho.revolutions, valid, low, "low")),
                  mesh,
                  dataclasses.replace(mesh, valid=valid, revolutions=mesh.revolutions
                                      + filtered(tacho.revolutions - mesh.revolutions, valid,
                                                 [low, 0.5 * tacho.speed_hz], "band"))]
        fm4, swings = [], []
        for est in angles:
            shafts = shaft_records(m, machine, est, ("ch3",))
            swings = swings or [shafts[k].swing_deg for k in slower]  # the tacho's, as is
            fm4.append(float(np.mean([v["fm4"] for v in shafts[0].indicators.values()])))
        print(f"{path.stem[:23]:<24}" + "".join(f"{s:>12.4f}" for s in swings)
              + "".join(f"{v:>{w}.2f}" for v, w in zip(fm4, (8, 10, 8, 12))))
    print("deg: the swing of the tacho's angle once a turn of the shaft, degrees of the "
          "input's turn (as indicators --machine reports it); lp: below "
          f"{0.5 * min(ratios):.2f}x the input's speed; mesh+swing: the tacho's angle less "
          "the mesh's between that and 0.5x added")
    return 0


def _cpu_model() -> str:
    """The CPU's model name and family (Linux), else the platform's processor."""
    try:
        info = dict(line.split(":", 1) for line in Path("/proc/cpuinfo").read_text()
                    .splitlines() if ":" in line)
        info = {k.strip(): v.strip() for k, v in info.items()}
        return f"{info['model name']}, CPU family {info['cpu family']}"
    except (OSError, KeyError):
        return platform.processor() or "CPU not known"


def batch_throughput(folder: str, files: list[Path]) -> int:
    """``pydiag batch --machine`` over ``folder`` on the local pool and on a Dask cluster."""
    from dask.distributed import LocalCluster
    baseline = next((p for p in files if NAME.search(p.name).group(1) == "1"), None)
    if baseline is None:
        print("no healthy (spur 1) record to take as baseline", file=sys.stderr)
        return 2
    cores = os.cpu_count() or 1
    print(f"baseline: {baseline.name}; defaults of diagnose (both stages fitted)")
    print(f"{'scheduler':<28}{'records':>8}{'wall s':>9}{'records/min':>13}")
    with tempfile.TemporaryDirectory() as tmp, \
            LocalCluster(n_workers=cores, threads_per_worker=1, processes=True,
                         dashboard_address=None) as cluster:
        for name, scheduler in (("local pool", "local"), ("dask LocalCluster", cluster.scheduler_address)):
            out = Path(tmp) / f"{name.split()[0]}.csv"
            started = time.perf_counter()
            res = subprocess.run(
                [sys.executable, "-m", "pydiag", "batch", "--fmu",
                 str(ROOT / "build" / "GearPair.fmu"), "--machine",
                 str(ROOT / "examples" / "phm09_spur.toml"), "--measurements", folder,
                 "--sample-rate", str(RATE_HZ), "--baseline", str(baseline), "--out", str(out),
                 "--scheduler", scheduler, "--quiet"], capture_output=True, text=True, cwd=ROOT)
            took = time.perf_counter() - started
            if res.returncode != 0:
                print(f"{name}: failed: {res.stderr.strip()}", file=sys.stderr)
                return 1
            n = len(out.read_text().splitlines()) - 1
            print(f"{name:<28}{n:>8}{took:>9.1f}{60 * n / took:>13.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
