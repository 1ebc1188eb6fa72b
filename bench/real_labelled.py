"""Benchmark: model-based diagnosis against the classical condition indicators, on
labelled real records.

A record set in the layout of ``../shared/data/gfd``: files named
``<condition letter><speed>hz<load>.csv.gz`` (``h`` healthy, any other letter a fault),
several accelerometer columns. For each record: the model-based diagnosis (GearPair FMU,
gain fitted, so ``a0`` fitted too: the tooth contrast ``|a_f/a0 - 1|``, mode, severity)
and the indicators of ``pydiag indicators`` on the pinion's synchronous average.

Scores, per quantity: how many healthy/faulty pairs at the same speed and load it orders
correctly (higher for the fault), and for the model, how many records its classification
gets right (healthy called healthy, a fault called anything else). Nothing is tuned to
the records: the model's classification edges are the paper's.

Usage:
    .venv/bin/python bench/real_labelled.py [--data ../shared/data/gfd] [--channel a1]
        [--teeth 32,80] [--sample-rate 12900] [--unit g] [--plot out.png] [--markdown out.md]
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import sys
import time
from pathlib import Path


ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.fit.estimator import FaultEstimator  # noqa: E402
from pydiag.fit.build import build_problem  # noqa: E402
from pydiag.gear.indicators import INDICATORS, condition_indicators  # noqa: E402
from pydiag.gear.kinematics import GearKinematics  # noqa: E402
from pydiag.gear.speed import SpeedSettings  # noqa: E402
from pydiag.io.readers import read_measurement  # noqa: E402
from pydiag.diagnose.diagnosis import diagnose  # noqa: E402

NAME = re.compile(r"^(?P<condition>[a-z])(?P<speed>\d+)hz(?P<load>\d+)\.", re.IGNORECASE)
MODEL = ("a_f", "a0", "tooth_contrast")


def records(folder: Path) -> list[tuple[Path, str, int, int]]:
    found = []
    for path in sorted(folder.iterdir()):
        match = NAME.match(path.name)
        if match:
            found.append((path, match["condition"].lower(), int(match["speed"]),
                          int(match["load"])))
    return found


def analyse(path: Path, speed_hz: int, args) -> dict:
    m = read_measurement(path, args.sample_rate, [f"{args.channel}=acc"], [args.unit])
    n_pinion, n_gear = args.teeth
    kin = GearKinematics(n_pinion, n_gear, float(speed_hz))
    started = time.perf_counter()
    problem = build_problem(args.fmu, m, operating_point={"n_pinion": n_pinion,
                            "n_gear": n_gear, "f_pinion_hz": float(speed_hz)},
                            speed=SpeedSettings("auto"), fit_gain=None)
    result = diagnose(problem, FaultEstimator(seed=0))
    diagnose_s = time.perf_counter() - started
    started = time.perf_counter()
    report = condition_indicators(m, kin, SpeedSettings("auto"))
    indicators_s = time.perf_counter() - started
    return {**{k: result.parameters.get(k) for k in ("a_f", "a0", "f_f", "f_ate", "f_dte")},
            "tooth_contrast": result.tooth_contrast, "fault_mode": result.fault_mode,
            "severity": result.severity, "error": result.error, "diagnose_s": diagnose_s,
            "indicators_s": indicators_s, **report.indicators["acc"]}


def scores(rows: list[dict]) -> dict[str, tuple[int, int]]:
    """Quantity -> (pairs ordered correctly, pairs)."""
    pairs = {}
    for r in rows:
        pairs.setdefault((r["speed"], r["load"]), {}).setdefault(
            "healthy" if r["condition"] == "h" else "faulty", r)
    complete = [p for p in pairs.values() if len(p) == 2]
    return {q: (sum(p["faulty"][q] > p["healthy"][q] for p in complete), len(complete))
            for q in MODEL + INDICATORS}


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    quantities = MODEL + INDICATORS
    cols = 5
    fig, axes = plt.subplots(-(-len(quantities) // cols), cols, figsize=(3.2 * cols, 9))
    for ax, q in zip(axes.flat, quantities):
        for condition, style in (("healthy", "o-"), ("faulty", "s--")):
            pts = sorted((r["load"], r[q]) for r in rows
                         if (r["condition"] == "h") == (condition == "healthy"))
            ax.plot([p[0] for p in pts], [p[1] for p in pts], style, label=condition)
        ax.set_title(q)
        ax.set_xlabel("load %")
    for ax in list(axes.flat)[len(quantities):]:
        ax.axis("off")
    axes.flat[0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data" / "gfd")
    p.add_argument("--fmu", default=str(ROOT / "build" / "GearPair.fmu"))
    p.add_argument("--channel", default="a1")
    p.add_argument("--unit", default="g")
    p.add_argument("--teeth", type=lambda t: tuple(int(v) for v in t.split(",")), default=(32, 80))
    p.add_argument("--sample-rate", type=float, default=12_900.0)
    p.add_argument("--plot", type=Path, help="PNG of each quantity, healthy vs faulty, by load")
    p.add_argument("--markdown", type=Path)
    args = p.parse_args()

    rows = []
    for path, condition, speed, load in records(args.data):
        rows.append({"record": path.name, "condition": condition, "speed": speed, "load": load,
                     **analyse(path, speed, args)})
    lines = [f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
             f"{platform.python_version()}; {args.data.name}: channel {args.channel}, teeth "
             f"{args.teeth}, {args.sample_rate:g} Hz", "",
             "| record | " + " | ".join(MODEL + ("fault_mode", "severity", "error") + INDICATORS)
             + " | diagnose s | indicators s |",
             "|---" * (len(MODEL) + 3 + len(INDICATORS) + 3) + "|"]
    for r in rows:
        values = [f"{r[q]:.3g}" for q in MODEL] + [r["fault_mode"], r["severity"],
                                                   f"{r['error']:.3f}"]
        values += [f"{r[q]:.3g}" for q in INDICATORS]
        lines.append(f"| {r['record']} | " + " | ".join(values)
                     + f" | {r['diagnose_s']:.1f} | {r['indicators_s']:.1f} |")
    lines += ["", "| quantity | healthy/faulty pairs ordered correctly |", "|---|---|"]
    for q, (right, total) in scores(rows).items():
        lines.append(f"| {q} | {right}/{total} |")
    right = sum((r["fault_mode"] == "healthy") == (r["condition"] == "h") for r in rows)
    lines += ["", f"model classification right (healthy vs fault): {right}/{len(rows)}"]
    text = "\n".join(lines)
    print(text)
    if args.markdown:
        args.markdown.write_text(text + "\n")
    if args.plot:
        plot(rows, args.plot)


if __name__ == "__main__":
    main()
