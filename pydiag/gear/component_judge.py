"""Every gear, bearing and shaft of a machine judged against the machine's own healthy
state, by the record's indicators: the fast first look (the model's verdict on a
component is the loop's, held out).

Each measure is judged as :mod:`pydiag.gear.stage_judge` judges a stage's residual
energy: its change against the baselines' mean, in dB, averaged over the channels, beside
``K_SPREAD`` times how much two healthy halves (and, with several baselines, two healthy
records) differ by the same measure, pooled over the machine's components of that kind.

- **A gear** is its stage's: a stage that did not change has good gears; a changed
  stage's suspect shaft names its gear there, and without a suspect both are "changed".
- **A shaft** by its first orders in its own TSA (those that are none of a faster
  shaft's, whose lines survive it): its 1x alone rose, "imbalance"; its 1x and 2x, "bent"
  (a bend or a misalignment: twice a turn); three or more of its first five, "looseness"
  (a loose fit, a sheared key: a turn that repeats with harmonics); any other rise,
  "changed".
- **A bearing** by its defect lines in the envelope (:mod:`pydiag.gear.bearing_lines`),
  each line held to its own threshold: ``K_SPREAD`` times its change's deviation in noise
  (a slow shaft's line of few bins reads less surely than a fast one's) times how many
  times that the healthy halves differ (:func:`bearing_scale`, at least once). The defect
  whose line rose most over its threshold, beyond it, names the fault ("outer", "inner",
  "ball", "cage"); the threshold reported is that line's. A line whose frequency is
  within :data:`ON_ORDER_SHARE` of one of a shaft's orders falls on that order's bins,
  which the envelope's line of the shaft holds (a shaft's turn modulates the noise the
  envelope is taken of): it is not judged, and a bearing all of whose lines are such is
  "not judged". Two bearings of one geometry on one shaft have the same lines and get the
  same verdict, which says so: the record does not tell them apart. A line of one
  bearing that is another's line's harmonic (a shaft turning once in n turns of a faster
  one; a ball's spin, whose line a spalled ball makes beside twice it) is read as both:
  the other may rise as much and be named instead or as well (known misses,
  tests/unit/gear/test_component_judge.py).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pydiag.gear.bearing_lines import DEFECT_LINES, defect_orders
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import (SHAFT_ORDERS, MachineRecord, faster_shafts,
                                           finite_or_none)
from pydiag.gear.stage_judge import K_SPREAD, MIN_SPREAD_DB, StageVerdict, healthy_differences

#: Shaft orders a bearing's line is checked against (each shaft's, up to this order).
CHECKED_ORDERS = 20
#: A bearing's line this close to a shaft's order (a share of its frequency) falls on the
#: order's bins in a record of a few hundred turns: it is not told from the shaft's.
ON_ORDER_SHARE = 0.002

GOOD, CHANGED, NOT_JUDGED = "good", "changed", "not judged"


@dataclass(frozen=True)
class Component:
    """A part of a machine a fault is named on: a gear (on its shaft, with its teeth, in
    its stage, as the stage's "pinion" or "gear"), a bearing (by its name, on its shaft)
    or a shaft (by its name)."""

    kind: str
    name: str
    shaft: str
    teeth: int | None = None
    stage: str | None = None
    role: str | None = None


@dataclass(frozen=True)
class ComponentVerdict:
    """One component judged: its ``state`` ("good", the fault, "changed" where something
    changed and the fault is not told, "not judged" and why), the changes it was judged by
    (``evidence``, dB, or FM4 for a gear's impulsiveness), the threshold they were held
    to (dB), and how sure: the largest change over that threshold (None: not judged)."""

    component: Component
    state: str
    evidence: dict[str, float] = field(default_factory=dict)
    threshold_db: float | None = None
    margin: float | None = None
    reason: str = ""

    @property
    def faulty(self) -> bool:
        return self.state not in (GOOD, NOT_JUDGED)

    def to_dict(self) -> dict:
        c = self.component
        out = {"kind": c.kind, "name": c.name, "shaft": c.shaft}
        if c.kind == "gear":
            out.update(teeth=c.teeth, stage=c.stage, role=c.role)
        return {**out, "state": self.state,
                "evidence": {k: finite_or_none(v) for k, v in self.evidence.items()},
                "threshold_db": self.threshold_db, "margin": finite_or_none(self.margin),
                "reason": self.reason}


def components(machine: Machine) -> tuple[Component, ...]:
    """Every gear (stage by stage, pinion then gear), bearing and shaft of ``machine``."""
    gears = []
    for k, s in enumerate(machine.stages):
        gears += [Component("gear", f"{s.pinion_teeth}T pinion of {s.name}", machine.shafts[k],
                            s.pinion_teeth, s.name, "pinion"),
                  Component("gear", f"{s.gear_teeth}T gear of {s.name}", machine.shafts[k + 1],
                            s.gear_teeth, s.name, "gear")]
    bearings = [Component("bearing", b.name, b.shaft) for b in machine.bearings]
    return tuple(gears + bearings + [Component("shaft", name, name) for name in machine.shafts])


def _rms(diffs: list[float]) -> float:
    finite = [d for d in diffs if math.isfinite(d)]
    return max(float(np.sqrt(np.mean(np.square(finite)))) if finite else 0.0, MIN_SPREAD_DB)


def _mean(values: list[float]) -> float:
    """The mean of the finite ``values`` (nan when none is)."""
    finite = [v for v in values if math.isfinite(v)]
    return float(np.mean(finite)) if finite else math.nan


def _ratio_db(a: float, b: float) -> float:
    return 20 * math.log10(a / b) if a > 0 and b > 0 else math.nan


def _gears(machine: Machine, verdicts: Sequence[StageVerdict]) -> list[ComponentVerdict]:
    out = []
    gears = [c for c in components(machine) if c.kind == "gear"]
    for c in gears:
        v = verdicts[[s.name for s in machine.stages].index(c.stage)]
        change = v.pinion if c.role == "pinion" else v.gear
        evidence = {"residual_energy_db": change.change_db, "fm4_change": change.fm4_change}
        margin = change.margin(v.threshold_db)
        if not v.changed:
            out.append(ComponentVerdict(c, GOOD, evidence, v.threshold_db, margin,
                                        "its stage did not change"))
        elif v.suspect == c.role:
            out.append(ComponentVerdict(c, CHANGED, evidence, v.threshold_db, margin,
                                        f"its stage changed, its shaft the suspect "
                                        f"({v.suspect_by})"))
        elif v.suspect is None:
            out.append(ComponentVerdict(c, CHANGED, evidence, v.threshold_db, margin,
                                        "its stage changed; which of its gears is not told"))
        else:
            out.append(ComponentVerdict(c, GOOD, evidence, v.threshold_db, margin,
                                        "its stage changed, the other shaft the suspect"))
    return out


def _own_orders(machine: Machine, shaft: int) -> list[int]:
    """The orders of shaft ``shaft`` (1..SHAFT_ORDERS) that are none of a faster shaft's
    turning a whole number of times per its turn (:func:`faster_shafts`)."""
    faster = faster_shafts(machine, shaft)
    return [k for k in range(1, SHAFT_ORDERS + 1) if not any(k % n == 0 for n in faster)]


def _shaft_state(rises: list[int]) -> str:
    if not rises:
        return GOOD
    if len(rises) >= 3:
        return "looseness"
    if 1 in rises and 2 in rises:
        return "bent"
    if rises == [1]:
        return "imbalance"
    return CHANGED


def _shafts(machine: Machine, record: MachineRecord, baselines: Sequence[MachineRecord]
            ) -> list[ComponentVerdict]:
    shafts = [c for c in components(machine) if c.kind == "shaft"]
    if any(not s.order_halves for b in baselines for s in b.shafts):
        return [ComponentVerdict(c, NOT_JUDGED, reason="a baseline was kept before pydiag "
                                 "read a shaft's orders: keep it again") for c in shafts]
    diffs = healthy_differences(
        baselines, lambda rec: rec.shafts,
        lambda s: {(c, k): (h[0][k - 1], h[1][k - 1]) for c, h in s.order_halves.items()
                   for k in _own_orders(machine, s.index)},
        lambda s: {(c, k): o[k - 1] for c, o in s.orders.items()
                   for k in _own_orders(machine, s.index)},
        _ratio_db)
    threshold = K_SPREAD * _rms(diffs)
    out = []
    for c, s in zip(shafts, record.shafts):
        changes = {}
        for k in _own_orders(machine, s.index):
            per_channel = [_ratio_db(a[k - 1], float(np.mean([b.shafts[s.index].orders[ch][k - 1]
                                                              for b in baselines])))
                           for ch, a in s.orders.items()]
            changes[k] = _mean(per_channel)
        rises = sorted(k for k, v in changes.items() if v > threshold)
        state = _shaft_state(rises)
        biggest = max((abs(v) for v in changes.values() if math.isfinite(v)), default=math.nan)
        out.append(ComponentVerdict(
            c, state, {f"order_{k}_db": v for k, v in changes.items()}, threshold,
            biggest / threshold,
            f"orders risen: {', '.join(f'{k}x' for k in rises)}" if rises else ""))
    return out


def _told(machine: Machine) -> dict[str, dict[str, str]]:
    """Bearing -> defect -> "" where its line is its own, else why it is not judged."""
    out = {}
    for name, lines in defect_orders(machine).items():
        out[name] = {}
        for defect, order in lines.items():
            why = ""
            for j, shaft in enumerate(machine.shafts):
                ratio = float(machine.shaft_ratio(j))
                k = round(order / ratio)
                if 1 <= k <= CHECKED_ORDERS and abs(order - k * ratio) <= ON_ORDER_SHARE * order:
                    why = f"its line lies on the {shaft} shaft's {k}x"
                    break
            out[name][defect] = why
    return out


def _normalised(a: tuple[float, float], b: tuple[float, float]) -> float:
    """The difference of two (level, deviation) readings over the deviation it has in
    noise."""
    return (a[0] - b[0]) / math.hypot(a[1], b[1])


def bearing_scale(baselines: Sequence[MachineRecord], told: dict[str, dict[str, str]]
                  ) -> float:
    """How many times what noise alone makes two healthy records' bearing lines differ
    they do differ: the RMS of the baselines' halves' differences (and, with several
    baselines, of each pair's), each over its deviation in noise; never below 1."""
    def halves(br) -> dict:
        return {(c, d): ((h[0], br.halves_sd_db[c][d][0]), (h[1], br.halves_sd_db[c][d][1]))
                for c, t in br.halves_db.items() for d, h in t.items() if not told[br.bearing][d]}

    def whole(br) -> dict:
        return {(c, d): (t[d], br.sd_db[c][d]) for c, t in br.levels_db.items()
                for d in DEFECT_LINES if not told[br.bearing][d]}
    diffs = [d for d in healthy_differences(baselines, lambda rec: rec.bearings, halves, whole,
                                            _normalised) if math.isfinite(d)]
    return max(float(np.sqrt(np.mean(np.square(diffs)))) if diffs else 1.0, 1.0)


def _bearings(machine: Machine, record: MachineRecord, baselines: Sequence[MachineRecord]
              ) -> list[ComponentVerdict]:
    bearings = [c for c in components(machine) if c.kind == "bearing"]
    if not record.bearings or any(not b.bearings or not b.bearings[0].sd_db
                                  for b in baselines):
        why = ("the record holds too few periods, or its rate no band above the gears'"
               if not record.bearings else
               "a baseline was kept before pydiag read the bearings' lines: keep it again")
        return [ComponentVerdict(c, NOT_JUDGED, reason=why) for c in bearings]
    told = _told(machine)
    scale = bearing_scale(baselines, told)
    lines = defect_orders(machine)
    out = []
    for i, (c, br) in enumerate(zip(bearings, record.bearings)):
        changes, thresholds = {}, {}
        for d in DEFECT_LINES:
            if told[br.bearing][d]:
                continue
            per_channel, deviations = [], []
            for ch, t in br.levels_db.items():
                seen = [b.bearings[i] for b in baselines]
                per_channel.append(t[d] - _mean([b.levels_db[ch][d] for b in seen]))
                deviations.append(math.hypot(br.sd_db[ch][d], _mean(
                    [b.sd_db[ch][d] for b in seen]) / math.sqrt(len(seen))))
            changes[d] = _mean(per_channel)
            thresholds[d] = K_SPREAD * scale * _mean(deviations)
        not_told = [f"{d}: {why}" for d, why in told[br.bearing].items() if why]
        if not changes:
            out.append(ComponentVerdict(c, NOT_JUDGED, reason="; ".join(not_told)))
            continue
        ratio = {d: changes[d] / thresholds[d] if math.isfinite(changes[d] / thresholds[d])
                 else -math.inf for d in changes}
        worst = max(ratio, key=ratio.get)
        margin = max((abs(changes[d]) / thresholds[d] for d in changes
                      if math.isfinite(changes[d] / thresholds[d])), default=math.nan)
        twins = [b.name for b in machine.bearings if b.name != br.bearing
                 and b.shaft == br.shaft and lines[b.name] == lines[br.bearing]]
        if twins and ratio[worst] > 1:
            not_told.insert(0, f"its lines are {', '.join(twins)}'s too (one geometry on "
                               "one shaft): the record does not tell which")
        out.append(ComponentVerdict(c, worst if ratio[worst] > 1 else GOOD,
                                    {f"{d}_db": v for d, v in changes.items()},
                                    thresholds[worst], margin, "; ".join(not_told)))
    return out


def judge_components(machine: Machine, record: MachineRecord,
                     baselines: Sequence[MachineRecord],
                     verdicts: Sequence[StageVerdict]) -> tuple[ComponentVerdict, ...]:
    """Every component of ``machine`` in ``record`` against the ``baselines`` (module
    docstring); ``verdicts``: the stages' (:func:`~pydiag.gear.stage_judge.judge_stages`).
    Faulty ones first, then in the machine's order (gears, bearings, shafts)."""
    judged = (_gears(machine, verdicts) + _bearings(machine, record, baselines)
              + _shafts(machine, record, baselines))
    return tuple(sorted(judged, key=lambda v: not v.faulty))
