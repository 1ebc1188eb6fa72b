"""Every bearing of a machine judged against the machine's own healthy state
(:mod:`pydiag.gear.component_judge` judges the rest).

A bearing is judged by its defect lines in the envelope (:mod:`pydiag.gear.bearing_lines`),
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

from pydiag.gear.bearing_lines import (COMB_FIRST, DEFECT_LINES, READ_LINES, SLIP_SHARE,
                                       defect_orders)
from pydiag.gear.component import ComponentVerdict, components, finite_mean, finite_rms
from pydiag.gear.faults import GOOD, NOT_JUDGED
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import MachineRecord
from pydiag.gear.stage_judge import K_SPREAD, healthy_differences

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
    return finite_rms(healthy_differences(baselines, lambda rec: rec.bearings, halves, whole,
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


def judge_bearings(machine: Machine, record: MachineRecord,
                   baselines: Sequence[MachineRecord]) -> list[ComponentVerdict]:
    """Every bearing of ``machine`` in ``record`` against the ``baselines`` (module
    docstring), in the machine file's order."""
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
                per_channel.append(t[d] - finite_mean([b.levels_db[ch][d] for b in before]))
                deviations.append(math.hypot(br.sd_db[ch][d], finite_mean(
                    [b.sd_db[ch][d] for b in before]) / math.sqrt(len(before))))
            seen[br.bearing][d] = (finite_mean(per_channel), K_SPREAD * scale * finite_mean(deviations))
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
