"""Does a record need, held out, what the machine's healthy model lacks? An experiment for
the component verdict (issue 60): the machine's own model (no ``--fmu``; the effects the
machine file lists, and its ``[start]``, as compare takes them) is fitted once to a healthy
baseline record; each other record is then seen through that healthy model (its
stages' parameters held at the baseline's fit, the channels' gains the record's own), and
every effect each stage can have is tried held out against it (``discover --machine``'s
test, on a base not fitted to the record; with ``--refit``, on that fit polished on the
record: what the healthy model can do there). The baseline itself is tried the same way
against its own fit: what the healthy model lacks on a healthy record. With ``--own``,
instead, each effect the machine file gives a stage (the healthy model's own, say from
``pydiag loop`` on the baseline) is polished on half A from the baseline's values and
scored on half B against them: whether the record asks for other values of it. With
``--repeat`` (with ``--own``), the first record is a healthy repeat of the baseline: its
rise of each (stage, effect) is the healthy spread every later record's rise is held to
(:func:`pydiag.loop.own_changes.own_changes`: over ``K_SPREAD`` times it, never below a z
of 1), and a change beyond it is named on the part its largest change sizes. Prints, per
record, every (stage, effect) tried with its held-out z, the baseline's own, the rise,
whether it is confident and what it fitted, the largest rise first. Usage:

    .venv/bin/python bench/healthy_model.py BASELINE RECORD [RECORD ...]
        [--machine examples/phm09_spur.toml] [--channel ch1] [--rpm 1800] [--effects K,K] [--refit]
        [--own] [--repeat]
        [--sample-rate HZ]     # default the PHM09 records' 66666.67; 0: the record's own

Records are the PHM 2009 challenge's (cite the PHM Society 2009 Data Challenge where you
report results); the machine file gives their sensor's sensitivity and the tacho.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _setup(machine: str, record: str, channel: str, rpm: float, build_dir: str,
           sample_rate_hz: float = 200_000 / 3):
    """The record and the machine's model as `pydiag discover --machine` sees them (the
    command line's defaults: the file's sensors and sensitivity, the tacho's speed)."""
    from pydiag.app import loop_commands as lc
    from pydiag.app.cli import build_parser
    from pydiag.app.machine_options import apply_machine
    from pydiag.app.models import machine_models
    from pydiag.app.reading import read_input
    args = build_parser().parse_args(
        ["discover", "--machine", machine, "--measurement", record, "--channel", channel,
         "--rpm", str(rpm), "--quiet", "--build-dir", build_dir]
        + (["--sample-rate", str(sample_rate_hz)] if sample_rate_hz else []))
    args.machine_description = apply_machine(args)
    m = read_input(args)
    machines = machine_models(args)
    problem, (model, _built) = lc._machine_problem(args, m, machines)
    return args, machines, problem, model


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("baseline")
    ap.add_argument("records", nargs="+")
    ap.add_argument("--machine", default=str(ROOT / "examples" / "phm09_spur.toml"))
    ap.add_argument("--channel", default="ch1")
    ap.add_argument("--rpm", type=float, default=1800.0)
    ap.add_argument("--effects", help="comma-separated effect keys (default: the catalogue)")
    ap.add_argument("--sample-rate", type=float, default=200_000 / 3,
                    help="the records' sample rate, Hz (0: read from the record)")
    ap.add_argument("--refit", action="store_true",
                    help="each record's base is the healthy fit polished on the record (its "
                         "own healthy refit), not the baseline's fit held")
    ap.add_argument("--own", action="store_true",
                    help="refit the effects the machine file gives its stages from the "
                         "baseline's values, held out, instead of trying those they lack")
    ap.add_argument("--repeat", action="store_true",
                    help="the first record is a healthy repeat of the baseline: its rises "
                         "are the healthy spread the others' are held to")
    a = ap.parse_args()
    from pydiag.app.commands import estimator_settings
    from pydiag.fit.estimator import FaultEstimator
    from pydiag.loop.compare import compare
    from pydiag.loop.effect_fit import EFFECT_REFIT
    from pydiag.loop.machine_discover import discover_machine, refit_own_effects
    from pydiag.loop.machine_fit import compare_machine
    from pydiag.loop.own_changes import own_changes
    print(f"# {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; {Path(a.machine).name}, {a.channel}, "
          f"{a.rpm:g} rpm nominal; baseline {Path(a.baseline).name}")
    refit = FaultEstimator(**EFFECT_REFIT)  # an effect's refit, as discover's defaults
    with tempfile.TemporaryDirectory() as tmp:
        build_dir = str(Path(tmp) / "build")
        started = time.perf_counter()
        seen = _setup(a.machine, a.baseline, a.channel, a.rpm, build_dir, a.sample_rate)
        args, _, problem, model = seen
        healthy = compare_machine(problem, model, FaultEstimator(**estimator_settings(args)),
                                  refit, start=args.machine_description.fit_start())
        print(f"healthy fit: error {healthy.fit_error:.3f}, "
              f"{time.perf_counter() - started:.0f} s", flush=True)
        own: dict[tuple[str, str], float] = {}  # the baseline's z against its own fit
        baseline_rows: list = []
        repeat_rows: list | None = None  # the healthy repeat's (--repeat)
        for index, record in enumerate([a.baseline] + a.records):
            started = time.perf_counter()
            if index:  # the baseline's is read and built once, above
                seen = _setup(a.machine, record, a.channel, a.rpm, build_dir,
                              a.sample_rate)
            args, machines, problem, model = seen
            values = healthy.parameters
            if a.refit and index:  # the healthy model at its best on this record
                values = FaultEstimator(**estimator_settings(args)).refine(
                    problem, {p.name: values[p.name] for p in problem.parameters}).parameters
            base = compare(problem, None, healthy.false_alarm_rate, parameters=values)
            base = dataclasses.replace(base, fit_error=base.error)
            if a.own:
                found = refit_own_effects(problem, args.machine_description, model, base,
                                          refit)
            else:
                found = discover_machine(problem, args.machine_description, model, base,
                                         lambda machine, ms=machines: str(ms(machine)[1].fmu),
                                         refit, a.effects.split(",") if a.effects else None)
            took = time.perf_counter() - started
            print(f"\n## {Path(record).name}: healthy model's error {base.error:.3f}, "
                  f"{took:.0f} s", flush=True)
            print("| stage | effect | z | baseline's z | rise | x thr | named | confident | "
                  "explained | error base -> with | fitted |")
            print("|---|---|---|---|---|---|---|---|---|---|---|")
            rows = [d for d in found if d.held_out is not None and d.held_out.tried]
            if index == 0:
                own = {(d.stage, d.effect): d.held_out.z for d in rows}
                baseline_rows = found
            elif index == 1 and a.repeat:
                repeat_rows = found
            changes = {(c.stage, c.effect): c for c in own_changes(
                args.machine_description, model, values, found, baseline_rows,
                [repeat_rows] if repeat_rows is not None else [])} if a.own else {}
            rows.sort(key=lambda d: -(d.held_out.z - own.get((d.stage, d.effect), 0.0)))
            stages = [s.name for s in args.machine_description.stages]
            for d in rows:
                h = d.held_out
                zb = own.get((d.stage, d.effect), float("nan"))
                change = changes.get((d.stage, d.effect))
                margin = change.margin if change else float("nan")
                named = ", ".join(change.components) if change and change.changed else ""
                names = {p.name for p in
                         model.stage_effects(stages.index(d.stage))[d.effect].parameters}
                fitted = ", ".join(f"{k.split('.', 1)[1]} "
                                   + (f"{values[k]:.3g} -> " if a.own else "") + f"{v:.3g}"
                                   for k, v in h.parameters.items() if k in names)
                print(f"| {d.stage} | {d.effect} | {h.z:.1f} | {zb:.1f} | {h.z - zb:+.1f} | "
                      f"{margin:.2f} | {named} | {'yes' if d.confident else ''} | "
                      f"{h.explained:.2f} | "
                      f"{h.error_base:.3f} -> {h.error_effect:.3f} | {fitted} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
