"""Each stage of a machine judged against the machine's own healthy state: the shafts' TSA
facts of a record (:mod:`pydiag.gear.machine_indicators`) against those of its baselines.

A shaft's change is that of its residual's **synchronous** energy: the residual energy
less the noise in it, what the record's non-synchronous vibration (noise, a bearing's
strikes, another shaft's lines) leaves in a TSA of that many turns
(:mod:`pydiag.gear.machine_indicators`). A bearing's strikes or a louder noise raise the
residual energy of every shaft, and not the synchronous part of any; a baseline kept
before pydiag read the noise is judged by the whole energy, as the record then is.

How much two healthy records of the machine differ is estimated from the baselines
themselves: the synchronous energy of each half of a baseline against the other half,
and, with two or more baselines, of each baseline against the others, each difference over
its deviation (:func:`synchronous_db`: a shaft whose residual is mostly noise reads less
surely than one whose residual is its gears'), pooled over every shaft and channel as a
root mean square, never below 1 (:func:`synchronous_spread`). A stage is **changed** when
one of its two shafts' change (up or down) exceeds its own threshold, ``K_SPREAD`` times
its deviation times that scale. The same differences in dB, pooled, are the reported
healthy spread (``spread_db``); by the whole energy, the one threshold is ``K_SPREAD``
times it.

A shaft's residual can rise with another shaft's change: where their harmonics meet, what
repeats with one lands in the other's TSA too (the short box's output turns once in five
input turns, so its broken tooth rises on every input order). A risen shaft whose rise the
other risen shafts' own change accounts for, read in their TSAs beside the shared lines
(:mod:`pydiag.gear.shared_lines`), did not change itself (``ShaftChange.explained_by``);
two that account for each other's are both judged whole, as is a rise accounted for only
in part.

Its ``suspect`` is named first by **impulsiveness**: a local tooth fault (a chip, a crack)
strikes once a turn of its shaft, so that shaft's TSA grows impulsive, and its kurtosis
(FM4 of the difference signal, the classical detector of a local fault) rises; a runout,
wear or another stage's change spreads over the turn and does not raise it. A shaft whose
FM4 rose by more than ``K_SPREAD`` times FM4's healthy spread (the RMS of its halves'
and baselines' differences), and by as much more than the other shaft's, is the suspect,
if its gear on this stage is its only one (a shaft carrying two gears says which shaft,
not which of its gears). A slower shaft's local fault reaches a faster shaft's TSA once in
every n of its turns, at 1/n of its weight, so it raises the faster shaft's FM4 less than
its own. Otherwise the suspect is the shaft whose change over its threshold exceeds the
other's by more than one (null: neither clearly did). Where a faster shaft turns a whole
number of times per turn of the slower one, the slower shaft's fault reaches the faster
shaft's TSA on their common lines (a local fault's lines cover every order), so a change of
both is no evidence against the slower one: the suspect stays null unless one stands
clearly higher. A shaft carrying two gears changes with either stage's change (a runout of its
second stage's pinion moves its residual energy), which is why impulsiveness, the
specific evidence, is asked first. Without a baseline nothing is judged: there is no
absolute scale of a real machine's residual energy.

A shaft's swing (with a tacho, :mod:`pydiag.gear.machine_indicators`) is reported against
the baselines' mean in dB, and judges nothing.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from pydiag.core.errors import MeasurementError
from pydiag.gear.comparable import check_comparable
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import MachineRecord, ShaftRecord, finite_or_none
from pydiag.gear.shared_lines import explained_rise

#: A stage is changed when a shaft's residual energy moved by more than this many times
#: the spread of healthy records (module docstring): ~4 standard deviations, so that the
#: eight or so comparisons of a record stay clear of chance.
K_SPREAD = 4.0
#: The spread is never taken below this (dB): two halves of one record agree better than
#: two records taken on different days can.
MIN_SPREAD_DB = 0.1
#: Nor FM4's below this (a kurtosis, 3 for Gaussian noise), for the same reason.
MIN_FM4_SPREAD = 0.1
#: A synchronous residual energy is never taken below this share of the noise in the
#: residual (:func:`synchronous_db`): it is the difference of two estimates, each good to
#: a few percent of the noise (a residual of a few hundred orders or more).
NOISE_FLOOR = 0.1


@dataclass(frozen=True)
class ShaftChange:
    """A shaft's residual energy against the baseline's, dB (mean over channels), with
    each channel's; and its FM4 against the baseline's (mean over channels; nan: not
    known)."""

    shaft: str
    change_db: float
    channels_db: dict[str, float]
    fm4_change: float = math.nan
    #: the change beyond which the shaft changed (dB; nan: the stage's, a baseline kept
    #: before its noise was read)
    threshold_db: float = math.nan
    #: the change left when what the other changed shafts' change puts on this one's
    #: lines is taken out (dB; nan: none was, :func:`judge_stages`)
    own_change_db: float = math.nan
    #: the shafts whose change accounts for this one's rise (its own change within its
    #: threshold: the shaft did not change), empty where none does; a rise they account
    #: for in part is judged whole
    explained_by: tuple[str, ...] = ()

    def margin(self, stage_threshold_db: float) -> float:
        """The shaft's change over its threshold (the stage's where it has none); its own
        change where the other shafts' change accounts for its rise."""
        own = self.threshold_db if math.isfinite(self.threshold_db) else stage_threshold_db
        return abs(self.own_change_db if self.explained_by else self.change_db) / own


@dataclass(frozen=True)
class StageVerdict:
    """One stage judged against the baseline (module docstring).

    Attributes:
        stage: its name; pinion_teeth, gear_teeth; mesh_hz: its mesh frequency
        pinion, gear: the change of its two shafts
        changed: a shaft changed beyond its threshold (``ShaftChange.threshold_db``, else
            ``threshold_db``: the larger of the two shafts'); suspect: "pinion", "gear" or
            None
        fm4_threshold: the FM4 rise that names a suspect (None: FM4's spread not known)
        suspect_by: "impulsiveness" or "residual energy" (module docstring), None with no
            suspect
    """

    stage: str
    pinion_teeth: int
    gear_teeth: int
    mesh_hz: float
    pinion: ShaftChange
    gear: ShaftChange
    threshold_db: float
    changed: bool
    suspect: str | None
    fm4_threshold: float | None = None
    suspect_by: str | None = None

    def to_dict(self) -> dict:
        def shaft(change: ShaftChange) -> dict:
            return {"name": change.shaft, "change_db": change.change_db,
                    "threshold_db": finite_or_none(change.threshold_db),
                    "own_change_db": finite_or_none(change.own_change_db),
                    "explained_by": list(change.explained_by),
                    "channels_db": change.channels_db,
                    "fm4_change": finite_or_none(change.fm4_change)}
        return {"pinion_shaft": shaft(self.pinion), "gear_shaft": shaft(self.gear),
                "threshold_db": self.threshold_db, "fm4_threshold": self.fm4_threshold,
                "verdict": "changed" if self.changed else "healthy",
                "suspect": self.suspect, "suspect_by": self.suspect_by}


def _db(a: float, b: float) -> float:
    return 10 * math.log10(max(a, 1e-300) / max(b, 1e-300))


def healthy_differences(baselines: Sequence[MachineRecord],
                        parts: Callable[[MachineRecord], Sequence],
                        halves: Callable[[object], dict[object, tuple[float, float]]],
                        whole: Callable[[object], dict[object, float]],
                        difference: Callable[[float, float], float]) -> list[float]:
    """How one healthy record differs from another, by a measure of each of a record's
    ``parts`` (its shafts, its bearings): each baseline's halves (``halves``, keyed by
    channel and what is measured) against each other, and with several baselines each
    pair's whole records (``whole``, keyed alike), every part and key both have."""
    diffs = [difference(a, b) for rec in baselines for part in parts(rec)
             for a, b in halves(part).values()]
    for i, first in enumerate(baselines):
        for second in baselines[i + 1:]:
            for p1, p2 in zip(parts(first), parts(second)):
                one, other = whole(p1), whole(p2)
                diffs += [difference(one[c], other[c]) for c in one if c in other]
    return diffs


def _rms(diffs: list[float], floor: float) -> float:
    return max(float(np.sqrt(np.mean(np.square(diffs)))), floor)


def synchronous_db(a: tuple[float, float, int], b: tuple[float, float, int]
                   ) -> tuple[float, float]:
    """How far the synchronous residual energy of ``a`` lies above ``b``'s, and that
    difference's standard deviation, dB: each an (energy, noise, orders) triple of a
    shaft's TSA residual (:class:`ShaftRecord`), its synchronous part S the energy less
    the noise N, never taken below :data:`NOISE_FLOOR` of the larger noise of the two
    (below it neither is told from none). Over m orders of noise (each order's power
    exponentially distributed) the energy is read to within sqrt(N (N + 2 S) / m), the
    noise to N / sqrt(m), so the synchronous part to sqrt(2 N (N + S) / m)."""
    floor = NOISE_FLOOR * max(a[1], b[1])

    def part(e: float, n: float, m: int) -> tuple[float, float]:
        s = max(e - n, floor)
        return s, 10 / math.log(10) * math.sqrt(2 * n * (n + max(e - n, 0.0)) / max(m, 1)) / s
    (sa, da), (sb, db) = part(*a), part(*b)
    return _db(sa, sb), math.hypot(da, db)


def knows_noise(records: Sequence[MachineRecord]) -> bool:
    """Whether every shaft of every one of ``records`` knows, in each channel, the noise
    its residual holds (a baseline kept before pydiag read it does not)."""
    return all(set(s.noise) == set(s.residual_energy) and set(s.noise_halves) == set(s.halves)
               and s.residual_orders > 0 for r in records for s in r.shafts)


def _synchronous_differences(baselines: list[MachineRecord]) -> list[tuple[float, float]]:
    """:func:`healthy_differences` of the shafts' synchronous residual energies: (dB, its
    deviation) of each pair."""
    return healthy_differences(
        baselines, lambda rec: rec.shafts,
        lambda s: {c: ((h[0], s.noise_halves[c][0], s.residual_orders),
                       (h[1], s.noise_halves[c][1], s.residual_orders))
                   for c, h in s.halves.items()},
        lambda s: {c: (e, s.noise[c], s.residual_orders) for c, e in s.residual_energy.items()},
        synchronous_db)


def healthy_spread_db(baselines: list[MachineRecord]) -> float:
    """The RMS difference in a shaft's whole residual energy (dB) between two healthy
    records of the machine, estimated from the baselines' halves and, with several, from
    each pair of baselines (module docstring): the spread a baseline kept before pydiag
    read the noise is judged by."""
    return _rms(healthy_differences(baselines, lambda rec: rec.shafts, lambda s: s.halves,
                                    lambda s: s.residual_energy, _db), MIN_SPREAD_DB)


def synchronous_spread(baselines: list[MachineRecord]) -> tuple[float, float]:
    """(spread, scale): the RMS difference in a shaft's synchronous residual energy (dB)
    between two healthy records, estimated as :func:`healthy_spread_db` estimates the
    whole energy's, and how many times their deviations (:func:`synchronous_db`) they
    differ, the RMS of the differences each over its deviation, never below 1."""
    diffs = _synchronous_differences(baselines)
    ratios = [d / sd for d, sd in diffs if sd > 0]
    return (_rms([d for d, _ in diffs], MIN_SPREAD_DB),
            _rms(ratios, 1.0) if ratios else 1.0)


def healthy_fm4_spread(baselines: list[MachineRecord]) -> float | None:
    """The RMS difference in FM4 between two healthy records of the machine, estimated as
    :func:`healthy_spread_db` estimates the energy's; None where a baseline does not know
    its halves' FM4 or any is not a number."""
    if any(set(s.fm4_halves) != set(s.residual_energy) for b in baselines for s in b.shafts):
        return None
    diffs = healthy_differences(baselines, lambda rec: rec.shafts, lambda s: s.fm4_halves,
                                lambda s: {c: t["fm4"] for c, t in s.indicators.items()},
                                lambda a, b: a - b)
    if not diffs or not np.all(np.isfinite(diffs)):
        return None
    return _rms(diffs, MIN_FM4_SPREAD)


def _fm4_change(shaft: ShaftRecord, baselines: list[MachineRecord]) -> float:
    """``shaft``'s FM4 less the baselines' mean, averaged over its channels."""
    rises = [values["fm4"] - float(np.mean([b.shafts[shaft.index].indicators[channel]["fm4"]
                                            for b in baselines]))
             for channel, values in shaft.indicators.items()]
    return float(np.mean(rises))


def _suspect(pinion: ShaftChange, gear: ShaftChange, threshold_db: float,
             fm4_threshold: float | None, alone: tuple[bool, bool]
             ) -> tuple[str | None, str | None]:
    """A changed stage's suspect and what named it (module docstring); ``alone``: whether
    the pinion's and the gear's shaft carry no other stage's gear."""
    if fm4_threshold is not None:
        for name, this, other, only in (("pinion", pinion, gear, alone[0]),
                                        ("gear", gear, pinion, alone[1])):
            rise, rest = this.fm4_change, other.fm4_change
            if only and math.isfinite(rest) and rise - max(rest, 0.0) > fm4_threshold:
                return name, "impulsiveness"
    p, g = pinion.margin(threshold_db), gear.margin(threshold_db)
    if abs(p - g) > 1:
        return ("pinion" if p > g else "gear"), "residual energy"
    return None, None


def _synchronous_change(shaft: ShaftRecord, seen: list[ShaftRecord],
                        less: dict[str, float] | None = None
                        ) -> tuple[dict[str, float], list[float]]:
    """Each channel's change of ``shaft``'s synchronous residual energy against the mean
    of its baselines' (``seen``), dB, and each one's deviation (:func:`synchronous_db`);
    ``less``: channel -> energy taken out of the record's first (:func:`_explained`)."""
    per_channel, deviations = {}, []
    for channel, energy in shaft.residual_energy.items():
        # the baselines' mean, read to 1/sqrt(n) of one's deviation
        change, deviation = synchronous_db(
            (energy - (less or {}).get(channel, 0.0), shaft.noise[channel],
             shaft.residual_orders),
            (float(np.mean([b.residual_energy[channel] for b in seen])),
             float(np.mean([b.noise[channel] for b in seen])),
             len(seen) * shaft.residual_orders))
        per_channel[channel] = change
        deviations.append(deviation)
    return per_channel, deviations


def _explained(machine: Machine, record: MachineRecord, baselines: list[MachineRecord],
               changes: list[ShaftChange]) -> list[ShaftChange]:
    """``changes`` with each risen shaft's own change: its rise less what the other risen
    shafts' change accounts for on the lines it shares with them
    (:mod:`pydiag.gear.shared_lines`). A shaft whose own rise is within its threshold is
    explained by them."""
    risen = [k for k, c in enumerate(changes) if c.change_db > 0 and c.margin(math.nan) > 1]
    out = list(changes)
    for k in risen:
        less, by = explained_rise(machine, record.shafts, [b.shafts for b in baselines], k,
                                  [j for j in risen if j != k])
        if not by:
            continue
        per_channel, _ = _synchronous_change(record.shafts[k],
                                             [b.shafts[k] for b in baselines], less)
        own = max(float(np.mean(list(per_channel.values()))), 0.0)  # a rise, in part theirs
        by = tuple(changes[j].shaft for j in by)
        out[k] = replace(changes[k], own_change_db=own,
                         explained_by=by if own <= changes[k].threshold_db else ())
    # two shafts that account for each other's rise: the record does not tell which
    # changed, so neither is explained away
    mutual = {c.shaft for c in out for o in out
              if o.shaft in c.explained_by and c.shaft in o.explained_by}
    return [replace(c, explained_by=()) if c.shaft in mutual else c for c in out]


def judge_stages(machine: Machine, record: MachineRecord,
                 baselines: list[MachineRecord]) -> tuple[list[StageVerdict], float]:
    """Each stage of ``record`` against the ``baselines`` (same channels, a similar
    operating point), and the healthy spread (dB) it was judged by."""
    if not baselines:
        raise MeasurementError("judging a stage needs a baseline record of the machine")
    check_comparable(record, baselines)
    synchronous = knows_noise([record, *baselines])
    spread, scale = (synchronous_spread(baselines) if synchronous
                     else (healthy_spread_db(baselines), math.nan))
    threshold = K_SPREAD * spread
    fm4_spread = healthy_fm4_spread(baselines)
    fm4_threshold = None if fm4_spread is None else K_SPREAD * fm4_spread
    changes = []
    for shaft in record.shafts:
        seen = [b.shafts[shaft.index] for b in baselines]
        for channel in shaft.residual_energy:
            if any(channel not in b.residual_energy for b in seen):
                raise MeasurementError(f"the baseline has no channel {channel}")
        fm4 = _fm4_change(shaft, baselines) if fm4_threshold is not None else math.nan
        if not synchronous:
            per_channel = {c: _db(e, float(np.mean([b.residual_energy[c] for b in seen])))
                           for c, e in shaft.residual_energy.items()}
            changes.append(ShaftChange(shaft.shaft, float(np.mean(list(per_channel.values()))),
                                       per_channel, fm4))
            continue
        per_channel, deviations = _synchronous_change(shaft, seen)
        changes.append(ShaftChange(shaft.shaft, float(np.mean(list(per_channel.values()))),
                                   per_channel, fm4,
                                   K_SPREAD * scale * float(np.mean(deviations))))
    if synchronous:
        changes = _explained(machine, record, baselines, changes)
    verdicts = []
    for k, stage in enumerate(machine.stages):
        pinion, gear = changes[k], changes[k + 1]
        stage_threshold = (max(pinion.threshold_db, gear.threshold_db) if synchronous
                           else threshold)
        changed = max(pinion.margin(threshold), gear.margin(threshold)) > 1
        alone = (len(record.shafts[k].teeth) == 1, len(record.shafts[k + 1].teeth) == 1)
        suspect, by = (_suspect(pinion, gear, threshold, fm4_threshold, alone) if changed
                       else (None, None))
        verdicts.append(StageVerdict(stage.name, stage.pinion_teeth, stage.gear_teeth,
                                     float(record.speed.speed_hz * machine.mesh_order(k)),
                                     pinion, gear, stage_threshold, changed, suspect,
                                     fm4_threshold, by))
    return verdicts, spread
