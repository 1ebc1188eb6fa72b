"""Every gear, bearing and shaft of a machine judged against the machine's own healthy
state, by the record's indicators: the fast first look (the model's verdict on a
component is the loop's, held out).

Each measure is judged as :mod:`pydiag.gear.stage_judge` judges a stage's residual
energy: its change against the baselines' mean, in dB, averaged over the channels, beside
``K_SPREAD`` times how much two healthy halves (and, with several baselines, two healthy
records) differ by the same measure, pooled over the machine's components of that kind.

- **A gear** is its stage's: a stage that did not change has good gears. In a changed
  stage, a shaft's only gear is "changed" when its shaft changed beyond its own
  threshold (no other gear of the shaft to blame), unless the stage's suspect is named
  by impulsiveness; otherwise the suspect shaft names its gear, and without a suspect
  both are "changed" (an idler's change does not say which of its two gears). A gear
  whose shaft's rise another shaft's change accounts for (on the lines they share,
  :mod:`pydiag.gear.shared_lines`) is good, and says so.
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
  same verdict, which says so: the record does not tell them apart. A defect's strikes
  make a comb of lines at its rate's multiples, and one bearing's line can be a harmonic
  of another's comb (a shaft turning once in n turns of a faster one; a spalled ball,
  whose comb starts at its spin, half its named line): a line beyond its threshold that
  is one of the first :data:`HARMONICS` of another bearing's comb whose first line rose
  by :data:`EXPLAINS` of its threshold is that bearing's (:func:`_explainer`), which is
  named with its defect, and the line's own bearing is not (unless another of its lines
  is its own). Two combs that hold each other's lines are both named.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pydiag.gear.bearing_lines import (COMB_FIRST, DEFECT_LINES, READ_LINES, SLIP_SHARE,
                                       defect_orders)
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import (SHAFT_ORDERS, MachineRecord, faster_shafts,
                                           finite_or_none)
from pydiag.gear.stage_judge import K_SPREAD, MIN_SPREAD_DB, StageVerdict, healthy_differences

#: Shaft orders a bearing's line is checked against (each shaft's, up to this order).
CHECKED_ORDERS = 20
#: A bearing's line this close to a shaft's order (a share of its frequency) falls on the
#: order's bins in a record of a few hundred turns: it is not told from the shaft's.
ON_ORDER_SHARE = 0.002
#: A defect's comb whose first line rose by this share of its threshold holds another
#: bearing's line that is one of its first HARMONICS harmonics (:func:`_explainer`): that
#: line's rise is its. Half the threshold: the rise is asked of a line the other
#: bearing's rise already says is struck.
EXPLAINS = 0.5
#: The highest harmonic of a comb a line is told to be: the j-th harmonic is looked for
#: within the slip (SLIP_SHARE of the line, so j x SLIP_SHARE of the comb's spacing either
#: side), and beyond 1 / (4 SLIP_SHARE) that window is more than half the spacing: any
#: line would lie within the slip of some harmonic more often than not.
HARMONICS = int(1 / (4 * SLIP_SHARE))

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


def _rms(diffs: list[float], floor: float = MIN_SPREAD_DB) -> float:
    """The RMS of the finite ``diffs``, never below ``floor`` (``floor`` when none is)."""
    finite = [d for d in diffs if math.isfinite(d)]
    return max(float(np.sqrt(np.mean(np.square(finite)))) if finite else 0.0, floor)


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
        held = change.threshold_db if math.isfinite(change.threshold_db) else v.threshold_db
        if change.explained_by:
            whose = " and ".join(change.explained_by) + (
                " shafts'" if len(change.explained_by) > 1 else " shaft's")
            out.append(ComponentVerdict(c, GOOD if v.suspect != c.role else CHANGED, evidence,
                                        held, margin, f"the {whose} change accounts for its "
                                        "shaft's rise, on the lines they share"))
        elif not v.changed:
            out.append(ComponentVerdict(c, GOOD, evidence, held, margin,
                                        "its stage did not change"))
        elif sum(g.shaft == c.shaft for g in gears) == 1 and v.suspect_by != "impulsiveness":
            # its shaft's only gear: the shaft's own change is the gear's
            out.append(ComponentVerdict(c, CHANGED if margin > 1 else GOOD, evidence, held,
                                        margin, "its stage changed, and its shaft"
                                        + (" with it" if margin > 1 else " did not")))
        elif v.suspect == c.role:
            out.append(ComponentVerdict(c, CHANGED, evidence, held, margin,
                                        f"its stage changed, its shaft the suspect "
                                        f"({v.suspect_by})"))
        elif v.suspect is None:
            out.append(ComponentVerdict(c, CHANGED, evidence, held, margin,
                                        "its stage changed; which of its gears is not told"))
        else:
            out.append(ComponentVerdict(c, GOOD, evidence, held, margin,
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
        return {(c, d): (v, br.sd_db[c][d]) for c, t in br.levels_db.items()
                for d, v in t.items() if not told[br.bearing][d]}
    return _rms(healthy_differences(baselines, lambda rec: rec.bearings, halves, whole,
                                    _normalised), 1.0)


def _explainer(machine: Machine, orders: dict[str, dict[str, float]],
               ratios: dict[str, dict[str, float]], bearing: str, defect: str
               ) -> tuple[str, str, int] | None:
    """The other bearing, its defect and the harmonic whose comb holds ``bearing``'s
    ``defect`` line, if any: a comb whose first line rose by :data:`EXPLAINS` of its
    threshold, the line one of its first :data:`HARMONICS` (within the slip); the
    strongest such comb. ``ratios``: bearing -> line -> its change over its threshold."""
    line = orders[bearing][defect]
    found = []
    for other in machine.bearings:
        if other.name == bearing or orders[other.name] == orders[bearing]:
            continue  # itself, or its twin (one geometry on one shaft)
        rates = other.frequencies(float(machine.shaft_ratio(other.shaft)))
        for d, first in COMB_FIRST.items():
            rose = ratios[other.name].get(first, -math.inf)
            rate = rates[DEFECT_LINES[d][0]]
            j = round(line / rate)
            if (rose >= EXPLAINS and 1 <= j <= HARMONICS
                    and abs(line - j * rate) <= SLIP_SHARE * line):
                found.append((rose, other.name, d, j))
    return max(found)[1:] if found else None


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
    orders = defect_orders(machine)
    read = [d for d in READ_LINES if all(d in t for rec in (record, *baselines)
                                         for br in rec.bearings for t in br.levels_db.values())]
    seen: dict[str, dict[str, tuple[float, float]]] = {}  # bearing -> line -> (dB, threshold)
    for i, br in enumerate(record.bearings):
        seen[br.bearing] = {}
        for d in read:
            if told[br.bearing][d]:
                continue
            per_channel, deviations = [], []
            for ch, t in br.levels_db.items():
                before = [b.bearings[i] for b in baselines]
                per_channel.append(t[d] - _mean([b.levels_db[ch][d] for b in before]))
                deviations.append(math.hypot(br.sd_db[ch][d], _mean(
                    [b.sd_db[ch][d] for b in before]) / math.sqrt(len(before))))
            seen[br.bearing][d] = (_mean(per_channel), K_SPREAD * scale * _mean(deviations))
    ratios = {b: {d: (c / t if math.isfinite(c / t) else -math.inf) for d, (c, t) in lines.items()}
              for b, lines in seen.items()}
    # each bearing's defects beyond their thresholds, the strongest first; one whose line
    # is a harmonic of another bearing's comb (its first line risen) is that bearing's
    named: dict[str, tuple[str, float, str]] = {}  # bearing -> (defect, margin, why)
    explained: dict[str, str] = {}
    for b, r in ratios.items():
        for d in sorted((d for d in r if d in DEFECT_LINES and r[d] > 1), key=lambda d: -r[d]):
            by = _explainer(machine, orders, ratios, b, d)
            if by is None:
                if b not in named or named[b][2]:  # its own line, before another's
                    named[b] = (d, r[d], "")
                break
            other, d2, j = by
            explained.setdefault(b, f"its {d} line ({r[d]:.2f} x) is the {_nth(j)} harmonic "
                                    f"of {other}'s {d2} comb, whose first line rose too")
            if other not in named or named[other][2]:
                named[other] = (d2, max(r[d], named.get(other, ("", 0.0, ""))[1]),
                                f"named by {b}'s {d} line, the {_nth(j)} harmonic of its "
                                f"{d2} comb")
    out = []
    for c, br in zip(bearings, record.bearings):
        lines = {d: v for d, v in seen[br.bearing].items() if d in DEFECT_LINES}
        not_told = [f"{d}: {why}" for d, why in told[br.bearing].items()
                    if why and d in DEFECT_LINES]
        if not lines:
            out.append(ComponentVerdict(c, NOT_JUDGED, reason="; ".join(not_told)))
            continue
        r = ratios[br.bearing]
        worst = max((d for d in lines), key=lambda d: r[d])
        margin = max((abs(v) for d, v in r.items() if d in lines and math.isfinite(v)),
                     default=math.nan)
        state = GOOD
        if br.bearing in named:
            worst, shown, why = named[br.bearing]
            state, margin = worst, max(margin, shown)
            not_told.insert(0, why)
        elif br.bearing in explained:
            not_told.insert(0, explained[br.bearing])
        twins = [b.name for b in machine.bearings if b.name != br.bearing
                 and b.shaft == br.shaft and orders[b.name] == orders[br.bearing]]
        if twins and state != GOOD:
            not_told.insert(0, f"its lines are {', '.join(twins)}'s too (one geometry on "
                               "one shaft): the record does not tell which")
        out.append(ComponentVerdict(c, state, {f"{d}_db": v for d, (v, _) in lines.items()},
                                    lines[worst][1] if worst in lines else None, margin,
                                    "; ".join(w for w in not_told if w)))
    return out


def _nth(j: int) -> str:
    return {1: "1st", 2: "2nd", 3: "3rd"}.get(j, f"{j}th")


def judge_components(machine: Machine, record: MachineRecord,
                     baselines: Sequence[MachineRecord],
                     verdicts: Sequence[StageVerdict]) -> tuple[ComponentVerdict, ...]:
    """Every component of ``machine`` in ``record`` against the ``baselines`` (module
    docstring); ``verdicts``: the stages' (:func:`~pydiag.gear.stage_judge.judge_stages`).
    Faulty ones first, then in the machine's order (gears, bearings, shafts)."""
    judged = (_gears(machine, verdicts) + _bearings(machine, record, baselines)
              + _shafts(machine, record, baselines))
    return tuple(sorted(judged, key=lambda v: not v.faulty))
