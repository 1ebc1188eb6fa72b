"""A record's bearing lines: how far each of a machine's bearings' defect lines stands out of
the envelope of what does not repeat with the machine.

The record is order-tracked at the input shaft over whole fundamental periods of the
machine, and what repeats every period (every gear's line) is taken out
(:func:`~pydiag.signal.spectra.without_synchronous`); a bearing's strikes do not repeat
with the machine, so what is left carries them. They ring the structure kHz above the
gears' lines: the envelope of the band from the top of the gears' analysed bands to
:data:`~pydiag.signal.spectra.ENVELOPE_TOP` of the rate beats at the strike frequency
(envelope analysis). Each defect's line is read at its order of the input shaft (the
bearing's shaft's speed ratio times its defect frequency per turn:
:meth:`~pydiag.gear.kinematics.Bearing.frequencies`, inner race turning, outer fixed) as
the envelope's mean power within :data:`SLIP_SHARE` of it (the rolling elements slip a
percent or two, which spreads the line over those bins) over its mean power around it
(within :data:`FLOOR_SHARE`, the line's own bins left out), in dB: means over many bins,
so that two records of a healthy bearing read nearly the same (the largest bin of a
window of noise varies by several dB from record to record). The bins of every shaft's orders are left out of both:
a shaft's turn modulates the noise the envelope is taken of, so the envelope has lines at
its orders, exactly on their bins in a record tracked by the shaft's angle, where a
bearing's slipping line is not (the ER-10K's inner race strikes at 4.95 times its
shaft's speed, beside its 5th order). A ball's defect strikes both races, twice a turn of
the ball (2 x BSF). Each level comes with its standard deviation where the envelope is
noise: a bin's power of noise is exponentially distributed, so the mean of ``n`` bins has
a relative spread of 1/sqrt(n), and the level's, in dB, is 10/ln 10 x sqrt(1/n_line +
1/n_floor) (a line of few bins, a slow shaft's, reads far less surely than a fast one's).
The same is read on each half of the record (whole periods each): how much two healthy
halves differ, against those deviations, is what a change is judged by
(:mod:`pydiag.gear.component_judge`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pydiag.core.measurement import Measurement
from pydiag.gear.features import max_band_freq_hz
from pydiag.gear.machine import Machine
from pydiag.gear.speed import SpeedEstimate
from pydiag.gear.tracking import Upsampled, track_revolutions
from pydiag.signal.spectra import (ENVELOPE_TOP, amplitude_spectrum, band_envelope,
                                   without_synchronous)

#: A defect's line is sought within this share of its frequency: the rolling elements slip
#: (and within LINE_BINS bins of it at least, so that its power is a mean of several).
SLIP_SHARE = 0.015
LINE_BINS = 4
#: The floor a line is measured against: the mean within this share of its frequency (and
#: at least 4 x LINE_BINS bins on either side of the line's own).
FLOOR_SHARE = 0.15
#: The bins of a shaft's order left out of a bearing's line and floor: this many on
#: either side of it.
ORDER_BINS = 2
#: Each defect, the line it strikes at (a multiple of one of Bearing.frequencies' keys).
DEFECT_LINES = {"outer": ("bpfo", 1.0), "inner": ("bpfi", 1.0), "ball": ("bsf", 2.0),
                "cage": ("ftf", 1.0)}
#: A defect's strikes make a comb of lines at its rate's multiples; this is the line of
#: each comb's first ("spin": the ball's spin, which a spalled ball striking its two races
#: unequally makes beside twice it). Another bearing's line may be one of its harmonics
#: (:mod:`pydiag.gear.component_judge`).
COMB_FIRST = {"outer": "outer", "inner": "inner", "ball": "spin", "cage": "cage"}
#: Every line read of a bearing: its defects' and the ball's spin.
READ_LINES = {**DEFECT_LINES, "spin": ("bsf", 1.0)}


@dataclass(frozen=True)
class BearingRecord:
    """One bearing's lines in one record: channel -> line (a defect's, "outer", "inner",
    "ball", "cage", or the ball's "spin": :data:`READ_LINES`) -> the line over its floor,
    dB, for the whole record (``levels_db``) and for each half (``halves_db``), and the
    standard deviation of each where the envelope is noise (``sd_db``, ``halves_sd_db``;
    empty: a record kept before pydiag read them; without "spin": before it read that)."""

    bearing: str
    shaft: str
    levels_db: dict[str, dict[str, float]]
    halves_db: dict[str, dict[str, tuple[float, float]]]
    sd_db: dict[str, dict[str, float]] = field(default_factory=dict)
    halves_sd_db: dict[str, dict[str, tuple[float, float]]] = field(default_factory=dict)

    def to_dict(self) -> dict:
        def pairs(table):
            return {c: {d: list(h) for d, h in t.items()} for c, t in table.items()}
        return {"bearing": self.bearing, "shaft": self.shaft, "levels_db": self.levels_db,
                "halves_db": pairs(self.halves_db), "sd_db": self.sd_db,
                "halves_sd_db": pairs(self.halves_sd_db)}

    @classmethod
    def from_dict(cls, data: dict) -> "BearingRecord":
        def pairs(table):
            return {c: {d: (h[0], h[1]) for d, h in t.items()} for c, t in table.items()}
        return cls(data["bearing"], data["shaft"], dict(data["levels_db"]),
                   pairs(data["halves_db"]), dict(data.get("sd_db", {})),
                   pairs(data.get("halves_sd_db", {})))


def defect_orders(machine: Machine) -> dict[str, dict[str, float]]:
    """Each bearing's (by name) lines (:data:`READ_LINES`) in orders of the input shaft."""
    out = {}
    for b in machine.bearings:
        per_turn = b.frequencies(float(machine.shaft_ratio(b.shaft)))
        out[b.name] = {line: per_turn[key] * times for line, (key, times) in READ_LINES.items()}
    return out


def shaft_orders(machine: Machine, top: float) -> np.ndarray:
    """Every shaft's orders up to ``top``, in orders of the input shaft."""
    out = []
    for j in range(len(machine.shafts)):
        ratio = float(machine.shaft_ratio(j))
        out += [k * ratio for k in range(1, int(top / ratio) + 1)]
    return np.array(sorted(out))


def _levels_db(envelope: np.ndarray, samples_per_rev: int,
               orders: dict[str, dict[str, float]], shafts: np.ndarray
               ) -> dict[str, dict[str, tuple[float, float]]]:
    """Bearing -> defect -> (its line over its floor in ``envelope``'s spectrum, dB, that
    level's standard deviation in noise, dB), the bins of the shafts' orders (``shafts``,
    in input orders) left out."""
    freqs, amp = amplitude_spectrum(envelope, samples_per_rev)  # in orders of the input
    step = freqs[1] - freqs[0]
    padded = np.concatenate(([-np.inf], np.sort(shafts), [np.inf]))
    index = np.searchsorted(padded, freqs)
    kept = (np.minimum(freqs - padded[index - 1], padded[index] - freqs)
            > ORDER_BINS * step + 1e-12)
    out: dict[str, dict[str, tuple[float, float]]] = {}
    for name, lines in orders.items():
        out[name] = {}
        for defect, order in lines.items():
            half = max(SLIP_SHARE * order, LINE_BINS * step)
            near = (np.abs(freqs - order) <= half) & kept
            around = ((np.abs(freqs - order) <= max(FLOOR_SHARE * order,
                                                    half + 4 * LINE_BINS * step))
                      & ~near & kept)
            n_line, n_floor = int(np.sum(near)), int(np.sum(around))
            if not (n_line and n_floor):
                out[name][defect] = (math.nan, math.nan)
                continue
            level = 10 * math.log10(np.mean(amp[near] ** 2) / np.mean(amp[around] ** 2))
            out[name][defect] = (level, 10 / math.log(10) * math.sqrt(1 / n_line
                                                                      + 1 / n_floor))
    return out


def bearing_records(measurement: Measurement, machine: Machine, estimate: SpeedEstimate,
                    drop: tuple[str, ...] = (), upsampled: Upsampled | None = None
                    ) -> list[BearingRecord]:
    """Every bearing's defect lines in every channel but ``drop`` (module docstring), from
    the input shaft's angle ``estimate``; none for a machine without bearings or a record
    of fewer than two fundamental periods, or whose rate leaves no band above the gears'."""
    if not machine.bearings:
        return []
    samples_per_rev = int(math.ceil(measurement.sample_rate_hz / estimate.speed_hz))
    names, tracked, n_revs = track_revolutions(measurement, estimate, samples_per_rev, 1.0,
                                               drop, machine.shafts[0], upsampled)
    period_revs = 1 / machine.fundamental_order()
    periods = int(n_revs / period_revs)
    rate_hz = samples_per_rev * estimate.speed_hz
    band = (max_band_freq_hz(machine.model_kinematics(estimate.speed_hz)),
            ENVELOPE_TOP * rate_hz)
    if periods < 2 or not band[0] < band[1]:
        return []
    per_period = float(period_revs) * samples_per_rev
    orders = defect_orders(machine)
    top = (1 + FLOOR_SHARE) * max(o for lines in orders.values() for o in lines.values())
    shafts = shaft_orders(machine, top + 1.0)
    whole, halves = {}, {}
    for channel, x in zip(names, tracked):
        parts = []
        for first, count in ((0, periods), (0, periods // 2), (periods // 2, periods // 2)):
            y = x[int(round(first * per_period)):int(round((first + count) * per_period))]
            envelope = band_envelope(without_synchronous(y, count), rate_hz, band)
            parts.append(_levels_db(envelope, samples_per_rev, orders, shafts))
        whole[channel], halves[channel] = parts[0], (parts[1], parts[2])

    def of(name: str, i: int) -> dict:  # i 0: the levels, 1: their deviations
        return {c: {d: whole[c][name][d][i] for d in READ_LINES} for c in names}

    def halved(name: str, i: int) -> dict:
        return {c: {d: (halves[c][0][name][d][i], halves[c][1][name][d][i])
                    for d in READ_LINES} for c in names}
    return [BearingRecord(b.name, b.shaft, of(b.name, 0), halved(b.name, 0), of(b.name, 1),
                          halved(b.name, 1)) for b in machine.bearings]
