"""Condition indicators of every shaft of a machine, and each stage judged against the
machine's own healthy state.

Every shaft's time-synchronous average (TSA) is taken from the record order-tracked at that
shaft (:mod:`pydiag.gear.speed`), in every channel, with the harmonics of every mesh on it
and their first sidebands taken as regular (an intermediate shaft carries two gears), and
so are another stage's mesh harmonics that fall on the shaft's orders (they survive its
TSA). A faster shaft that turns a whole number n of times per turn of this one (the PHM09
box's input, 3 turns an idler turn) survives its TSA too, on every n-th order: those lines
are the faster shaft's and are left out of this one's residual (a chipped input pinion
changes the input shaft, not the idler). The measure of change is the **residual energy**
of a shaft's TSA (what is left when the shaft's first two orders, its meshes and the faster
shafts' lines are removed: a local tooth fault, an eccentric gear's sidebands): its level
in dB against the baseline's, averaged over the channels.

How much two healthy records of the machine differ is estimated from the baselines
themselves: the residual energy of each half of a baseline against the other half, and,
with two or more baselines, of each baseline against the others, pooled over every shaft
and channel as a root mean square (``spread_db``). A stage is **changed** when one of its
two shafts' change (up or down) exceeds ``K_SPREAD`` times that spread; its ``suspect`` is
the shaft whose change stands higher than the other's by more than the same margin (null:
neither clearly does). Where a faster shaft turns a whole number of times per turn of the
slower one, the slower shaft's fault reaches the faster shaft's TSA on their common lines
(a local fault's lines cover every order), so a change of both is no evidence against
the slower one: the suspect stays null unless one stands clearly higher. Without a
baseline nothing is judged: there is no absolute scale of a real machine's residual
energy.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pydiag.core.errors import MeasurementError
from pydiag.core.measurement import Measurement
from pydiag.gear.machine import Machine
from pydiag.gear.speed import SpeedEstimate, SpeedSettings, SpeedSource, estimate_speed
from pydiag.gear.tracking import Upsampled, track_revolutions, upsampled_record
from pydiag.signal.condition import (TrendReference, synchronous_average,
                                     tsa_indicators, tsa_signals)

#: A stage is changed when a shaft's residual energy moved by more than this many times
#: the spread of healthy records (module docstring): ~4 standard deviations, so that the
#: eight or so comparisons of a record stay clear of chance.
K_SPREAD = 4.0
#: The spread is never taken below this (dB): two halves of one record agree better than
#: two records taken on different days can.
MIN_SPREAD_DB = 0.1
#: A baseline is at a record's operating point when its input speed lies within this share
#: of the record's nominal input speed (:func:`at_speed`): a motor slips a few percent
#: under load, and a machine's operating speeds lie further apart. The load is not told
#: by a record: which baselines share it is the user's to say.
BASELINE_SPEED_SHARE = 0.05
#: Indicators of a shaft's TSA in the report, after the residual energy.
SHAFT_INDICATORS = ("fm0", "fm4", "na4", "nb4", "er", "ser")


@dataclass(frozen=True)
class ShaftRecord:
    """One shaft's TSA in one record.

    Attributes:
        shaft: its name; index: 0 the input
        speed_hz: its mean speed; revolutions: averaged; samples_per_rev: TSA length
        teeth: the teeth of the gears on it (one or two)
        residual_energy: channel -> variance of the TSA's residual (signal units squared)
        halves: channel -> the same for the first and the second half of the record
        indicators: channel -> indicator -> value (NA4/NB4 against the record itself)
    """

    shaft: str
    index: int
    speed_hz: float
    revolutions: int
    samples_per_rev: int
    teeth: tuple[int, ...]
    residual_energy: dict[str, float]
    halves: dict[str, tuple[float, float]]
    indicators: dict[str, dict[str, float]]


def _teeth_on(machine: Machine, shaft: int) -> tuple[int, ...]:
    """The teeth of the gears on shaft ``shaft``: the previous stage's gear, the next's
    pinion."""
    teeth = []
    if shaft > 0:
        teeth.append(machine.stages[shaft - 1].gear_teeth)
    if shaft < len(machine.stages):
        teeth.append(machine.stages[shaft].pinion_teeth)
    return tuple(teeth)


def _synchronous_meshes(machine: Machine, shaft: int) -> tuple[int, ...]:
    """The orders of shaft ``shaft`` at which the other stages' mesh harmonics fall on its
    orders: a mesh at p/q orders (lowest terms) has every q-th harmonic there, at the
    multiples of p. They survive its TSA, so they are regular too, not residual."""
    own = set(_teeth_on(machine, shaft))
    found = []
    for k in range(len(machine.stages)):
        order = machine.mesh_order(k) / machine.shaft_ratio(shaft)
        if order.numerator not in own and order.numerator not in found:
            found.append(order.numerator)
    return tuple(found)


def _faster_shafts(machine: Machine, shaft: int) -> tuple[int, ...]:
    """The turns per turn of shaft ``shaft`` of the shafts that turn a whole number (>= 2)
    of times per turn of it: their lines survive its TSA (module docstring)."""
    own = machine.shaft_ratio(shaft)
    ratios = (machine.shaft_ratio(j) / own for j in range(len(machine.shafts)) if j != shaft)
    return tuple(sorted({r.numerator for r in ratios if r.denominator == 1 and r > 1}))


def shaft_records(measurement: Measurement, machine: Machine, estimate: SpeedEstimate,
                  drop: tuple[str, ...] = (), upsampled: Upsampled | None = None
                  ) -> list[ShaftRecord]:
    """Every shaft's TSA of every channel but ``drop`` (module docstring), from the input
    shaft's angle ``estimate``; ``upsampled``: the record upsampled for tracking
    (:func:`~pydiag.gear.tracking.upsampled_record`), made here when not given."""
    upsampled = upsampled or upsampled_record(measurement, estimate, drop)
    out = []
    for index, name in enumerate(machine.shafts):
        ratio = float(machine.shaft_ratio(index))
        speed_hz = estimate.speed_hz * ratio
        teeth = _teeth_on(machine, index)
        others = _synchronous_meshes(machine, index)
        faster = _faster_shafts(machine, index)
        samples_per_rev = int(math.ceil(measurement.sample_rate_hz / speed_hz))
        if 1.5 * max(teeth) >= samples_per_rev / 2:
            raise MeasurementError(
                f"the {name} shaft's mesh (order {max(teeth)}) and its sidebands need a sample "
                f"rate above {3 * max(teeth) * speed_hz:.5g} Hz; the record has "
                f"{measurement.sample_rate_hz:g}")
        names, tracked, n_revs = track_revolutions(measurement, estimate, samples_per_rev,
                                                   ratio, drop, name, upsampled)
        if n_revs < 4:
            raise MeasurementError(f"the record holds {n_revs} whole turns of the {name} shaft: "
                                   "too few to average (at least 4)")
        energy, halves, table = {}, {}, {}
        half = (n_revs // 2) * samples_per_rev
        for channel, x in zip(names, tracked):
            parts = [tsa_signals(synchronous_average(y, samples_per_rev), teeth[-1],
                                 other_meshes=teeth[:-1] + others, faster_shafts=faster)
                     for y in (x, x[:half], x[half:2 * half])]
            energy[channel] = float(np.var(parts[0].residual))
            halves[channel] = (float(np.var(parts[1].residual)),
                               float(np.var(parts[2].residual)))
            values = tsa_indicators(parts[0], TrendReference())
            table[channel] = {k: float(values[k]) for k in SHAFT_INDICATORS}
        out.append(ShaftRecord(name, index, speed_hz, n_revs, samples_per_rev, teeth, energy,
                               halves, table))
    return out


@dataclass(frozen=True)
class MachineRecord:
    """A record seen through the machine: the input speed found, and every shaft's TSA."""

    speed: SpeedEstimate
    shafts: tuple[ShaftRecord, ...]
    file: str

    def to_dict(self) -> dict:
        """Plain data that :meth:`from_dict` reads back (a baseline kept in the history):
        the speed without its angle at every sample, every shaft's TSA facts."""
        speed = self.speed
        return {"file": self.file,
                "speed": {"speed_hz": speed.speed_hz, "variation_pct": speed.variation_pct,
                          "method": speed.method, "nominal_hz": speed.nominal_hz,
                          "source": speed.source.value, "confidence_db": _finite(
                              speed.confidence_db), "mesh_speed_hz": speed.mesh_speed_hz,
                          "band_pct": speed.band_pct},
                "shafts": [{"shaft": s.shaft, "index": s.index, "speed_hz": s.speed_hz,
                            "revolutions": s.revolutions, "samples_per_rev": s.samples_per_rev,
                            "teeth": list(s.teeth), "residual_energy": s.residual_energy,
                            "halves": {c: list(h) for c, h in s.halves.items()},
                            "indicators": {c: {k: _finite(v) for k, v in t.items()}
                                           for c, t in s.indicators.items()}}
                           for s in self.shafts]}

    @classmethod
    def from_dict(cls, data: dict) -> "MachineRecord":
        """The record :meth:`to_dict` wrote (its speed has no angle at every sample: it
        judges, it is not tracked again)."""
        speed = dict(data["speed"])
        source = SpeedSource(speed.pop("source"))
        shafts = tuple(ShaftRecord(
            s["shaft"], s["index"], s["speed_hz"], s["revolutions"], s["samples_per_rev"],
            tuple(s["teeth"]), dict(s["residual_energy"]),
            {c: (h[0], h[1]) for c, h in s["halves"].items()},
            {c: {k: (math.nan if v is None else v) for k, v in t.items()}
             for c, t in s["indicators"].items()}) for s in data["shafts"])
        return cls(SpeedEstimate(revolutions=np.empty(0), source=source, **speed), shafts,
                   data["file"])


def _finite(value: float | None) -> float | None:
    """``value``, None where JSON has no number for it (inf, nan)."""
    return value if value is not None and math.isfinite(value) else None


def machine_record(measurement: Measurement, machine: Machine, speed: SpeedSettings,
                   input_hz: float) -> MachineRecord:
    """``measurement``'s speed (from every mesh, or the tacho) around the nominal
    ``input_hz`` and the TSA of every shaft."""
    kin = machine.stage_kinematics(0, input_hz)
    slowest = min(float(machine.shaft_ratio(k)) for k in range(len(machine.shafts)))
    tracked_s = 8 / (input_hz * slowest)  # a few turns of the slowest shaft beyond the edges
    estimate = estimate_speed(measurement, kin, speed, tracked_s, machine=machine)
    drop = (speed.tacho,) if speed.tacho else ()
    return MachineRecord(estimate, tuple(shaft_records(measurement, machine, estimate, drop)),
                         str(measurement.metadata.get("file", "(in memory)")))


@dataclass(frozen=True)
class ShaftChange:
    """A shaft's residual energy against the baseline's, dB (mean over channels), with
    each channel's."""

    shaft: str
    change_db: float
    channels_db: dict[str, float]


@dataclass(frozen=True)
class StageVerdict:
    """One stage judged against the baseline (module docstring).

    Attributes:
        stage: its name; pinion_teeth, gear_teeth; mesh_hz: its mesh frequency
        pinion, gear: the change of its two shafts
        changed: a shaft changed beyond ``threshold_db``; suspect: "pinion", "gear" or None
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

    def to_dict(self) -> dict:
        return {"name": self.stage, "pinion_teeth": self.pinion_teeth,
                "gear_teeth": self.gear_teeth, "mesh_hz": self.mesh_hz,
                "pinion_shaft": {"name": self.pinion.shaft, "change_db": self.pinion.change_db,
                                 "channels_db": self.pinion.channels_db},
                "gear_shaft": {"name": self.gear.shaft, "change_db": self.gear.change_db,
                               "channels_db": self.gear.channels_db},
                "threshold_db": self.threshold_db,
                "verdict": "changed" if self.changed else "healthy",
                "suspect": self.suspect}


def _db(a: float, b: float) -> float:
    return 10 * math.log10(max(a, 1e-300) / max(b, 1e-300))


def at_speed(baselines: Sequence[MachineRecord], nominal_hz: float) -> list[MachineRecord]:
    """The ``baselines`` whose input speed is within :data:`BASELINE_SPEED_SHARE` of the
    nominal input speed ``nominal_hz``."""
    return [b for b in baselines
            if abs(b.speed.speed_hz / nominal_hz - 1) <= BASELINE_SPEED_SHARE]


def healthy_spread_db(baselines: list[MachineRecord]) -> float:
    """The RMS difference in residual energy (dB) between two healthy records of the
    machine, estimated from the baselines' halves and, with several, from each pair of
    baselines (module docstring)."""
    diffs = [_db(a, b) for rec in baselines for shaft in rec.shafts
             for a, b in shaft.halves.values()]
    for i, first in enumerate(baselines):
        for second in baselines[i + 1:]:
            for s1, s2 in zip(first.shafts, second.shafts):
                diffs += [_db(s1.residual_energy[c], s2.residual_energy[c])
                          for c in s1.residual_energy if c in s2.residual_energy]
    return max(float(np.sqrt(np.mean(np.square(diffs)))), MIN_SPREAD_DB)


def judge_stages(machine: Machine, record: MachineRecord,
                 baselines: list[MachineRecord]) -> tuple[list[StageVerdict], float]:
    """Each stage of ``record`` against the ``baselines`` (same channels, a similar
    operating point), and the healthy spread (dB) it was judged by."""
    if not baselines:
        raise MeasurementError("judging a stage needs a baseline record of the machine")
    spread = healthy_spread_db(baselines)
    threshold = K_SPREAD * spread
    changes = []
    for shaft in record.shafts:
        per_channel = {}
        for channel, energy in shaft.residual_energy.items():
            reference = [b.shafts[shaft.index].residual_energy.get(channel) for b in baselines]
            if any(r is None for r in reference):
                raise MeasurementError(f"the baseline has no channel {channel}")
            per_channel[channel] = _db(energy, float(np.mean(reference)))
        changes.append(ShaftChange(shaft.shaft, float(np.mean(list(per_channel.values()))),
                                   per_channel))
    verdicts = []
    for k, stage in enumerate(machine.stages):
        pinion, gear = changes[k], changes[k + 1]
        p, g = abs(pinion.change_db), abs(gear.change_db)
        changed = max(p, g) > threshold
        suspect = None
        if changed and abs(p - g) > threshold:
            suspect = "pinion" if p > g else "gear"
        verdicts.append(StageVerdict(stage.name, stage.pinion_teeth, stage.gear_teeth,
                                     float(record.speed.speed_hz * machine.mesh_order(k)),
                                     pinion, gear, threshold, changed, suspect))
    return verdicts, spread


@dataclass(frozen=True)
class MachineReport:
    """What ``indicators --machine`` says of a record: the speed, every shaft's TSA, and
    (with baselines) every stage's verdict and the healthy spread it was judged by."""

    machine: Machine
    record: MachineRecord
    baselines: tuple[str, ...]
    stages: tuple[StageVerdict, ...]
    spread_db: float | None

    def to_dict(self) -> dict:
        """Plain data for JSON: ``speed_hz`` the input shaft's; ``shafts`` and ``stages`` in
        the machine's order; ``stages`` empty without a baseline."""
        return {
            "machine": self.machine.name, **self.record.speed.to_dict(),
            "shafts": [{"name": s.shaft, "speed_hz": s.speed_hz, "teeth": list(s.teeth),
                        "revolutions": s.revolutions,
                        "residual_energy": s.residual_energy,
                        "indicators": {c: {k: (v if math.isfinite(v) else None)
                                           for k, v in t.items()}
                                       for c, t in s.indicators.items()}}
                       for s in self.record.shafts],
            "baselines": list(self.baselines), "healthy_spread_db": self.spread_db,
            "stages": [v.to_dict() for v in self.stages],
            "severity_scale": ("change against the baselines" if self.baselines else
                               "none: without a baseline no stage is judged")}


def machine_report(measurement: Measurement, machine: Machine, speed: SpeedSettings,
                   input_hz: float, baselines: Sequence[MachineRecord] = ()) -> MachineReport:
    """Every shaft of ``measurement`` and, with ``baselines`` (healthy records as
    :func:`machine_record` sees them), every stage judged."""
    record = machine_record(measurement, machine, speed, input_hz)
    base = list(baselines)
    verdicts, spread = judge_stages(machine, record, base) if base else ([], None)
    return MachineReport(machine, record, tuple(b.file for b in base), tuple(verdicts), spread)
