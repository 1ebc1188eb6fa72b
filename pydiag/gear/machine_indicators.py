"""Condition indicators of every shaft of a machine: a record seen through the machine.

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
in dB against the baseline's, averaged over the channels
(:mod:`pydiag.gear.stage_judge` judges each stage by it).

Part of that energy is not the shaft's: whatever in the record does not repeat with the
shaft (noise, a bearing's strikes, another shaft's lines) is averaged down in the TSA, not
away, and lands in its residual. How much is read from the record itself (the **noise**):
the TSAs of the record's two halves hold the same synchronous part and independent
non-synchronous parts, so their difference's residual energy is four times what the
whole record's TSA keeps of them (and a deterministic line at another shaft's frequency,
which a TSA averages down faster than noise, is counted as the TSA counts it). The same
from the quarters gives each half's.

With a tacho on the input shaft, each slower shaft also gets the **swing** of the input's
angle once its turn (:func:`~pydiag.signal.angle.turn_swing` at its first order, in
degrees of the input's turn): a runout or an eccentric gear on that shaft swings the whole drive once a
turn, which the tacho sees and a mesh's phase, followed in a band narrower than the
shaft's speed, does not (docs/gearbox.md). The swing at the shaft's first
:data:`SWING_ORDERS` orders is kept with how much noise moves each
(:func:`~pydiag.signal.angle.swing_noise`: the speed's wander at rates beside the line,
read in the record itself), for :mod:`pydiag.gear.component_judge`.

Each shaft's first orders in its TSA (a shaft's unbalance, bend, looseness) and each
bearing's defect lines (:mod:`pydiag.gear.bearing_lines`) are kept too, of the whole
record and of each half, for :mod:`pydiag.gear.component_judge`; and each shaft's TSA's
power at every order, which tells whose a line two shafts' TSAs share is
(:mod:`pydiag.gear.shared_lines`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from pydiag.core.errors import MeasurementError
from pydiag.core.measurement import Measurement
from pydiag.gear.bearing_lines import BearingRecord, bearing_records
from pydiag.gear.machine import Machine
from pydiag.gear.speed import SpeedEstimate, SpeedSettings, SpeedSource, estimate_speed
from pydiag.gear.tracking import Upsampled, track_revolutions, upsampled_record
from pydiag.signal.angle import swing_noise, turn_swing, whole_turns
from pydiag.signal.condition import (TrendReference, TsaSignals, order_masks,
                                     synchronous_average, tsa_indicators, tsa_signals)

#: Indicators of a shaft's TSA in the report, after the residual energy.
SHAFT_INDICATORS = ("fm0", "fm4", "na4", "nb4", "er", "ser")
#: A shaft's first orders kept of each record (its own vibration: unbalance, bend, looseness).
SHAFT_ORDERS = 5
#: A slower shaft's first orders of the input's swing kept of each record (an eccentric
#: gear's is once a turn; a transmission error of another form repeats more often).
SWING_ORDERS = 3


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
        fm4_halves: channel -> FM4 of the first and the second half (empty: not known, a
            baseline kept before it was)
        swing_deg: how far the input's angle swings once a turn of this shaft, degrees of
            the input's turn (module docstring); None without a tacho, for the input and
            for a shaft not slower than it, or a baseline kept before it was measured
        swing_lines_deg: the swing at each of the shaft's first :data:`SWING_ORDERS`
            orders and how much noise moves it (:func:`~pydiag.signal.angle.swing_noise`),
            (degrees, degrees); empty where ``swing_deg`` is None or a baseline was kept
            before they were read
        orders: channel -> the amplitudes of the TSA's first :data:`SHAFT_ORDERS` orders
            (a shaft's unbalance, bend or looseness); order_halves: the same of each half
            (empty: a baseline kept before they were)
        noise: channel -> how much of ``residual_energy`` the record's non-synchronous
            vibration leaves in a TSA of that many turns (module docstring);
            noise_halves: the same of each half (empty: a baseline kept before they were)
        residual_orders: how many orders the TSA's residual keeps (0: not known)
        power: channel -> the TSA's power at each order, 0 to half its samples (signal
            units squared: the residual energy is its sum over the residual's orders);
            empty: a baseline kept before it was read
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
    fm4_halves: dict[str, tuple[float, float]]
    swing_deg: float | None = None
    orders: dict[str, tuple[float, ...]] = field(default_factory=dict)
    order_halves: dict[str, tuple[tuple[float, ...], tuple[float, ...]]] = \
        field(default_factory=dict)
    noise: dict[str, float] = field(default_factory=dict)
    noise_halves: dict[str, tuple[float, float]] = field(default_factory=dict)
    residual_orders: int = 0
    power: dict[str, tuple[float, ...]] = field(default_factory=dict)
    swing_lines_deg: tuple[tuple[float, float], ...] = ()


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


def faster_shafts(machine: Machine, shaft: int) -> tuple[int, ...]:
    """The turns per turn of shaft ``shaft`` of the shafts that turn a whole number (>= 2)
    of times per turn of it: their lines survive its TSA (module docstring)."""
    own = machine.shaft_ratio(shaft)
    ratios = (machine.shaft_ratio(j) / own for j in range(len(machine.shafts)) if j != shaft)
    return tuple(sorted({r.numerator for r in ratios if r.denominator == 1 and r > 1}))


def residual_mask(machine: Machine, shaft: int, samples_per_rev: int) -> np.ndarray:
    """Which orders of shaft ``shaft``'s TSA of ``samples_per_rev`` samples its residual
    keeps (:func:`shaft_records`, :func:`~pydiag.signal.condition.tsa_signals`)."""
    teeth = _teeth_on(machine, shaft)
    n = samples_per_rev // 2 + 1
    mesh, _, first, foreign = order_masks(
        n, teeth[-1], other_meshes=teeth[:-1] + _synchronous_meshes(machine, shaft),
        faster_shafts=faster_shafts(machine, shaft))
    return ~(mesh | first | foreign) & (np.arange(n) > 0)


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
        faster = faster_shafts(machine, index)
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
        energy, halves, table, fm4_halves, orders, order_halves = {}, {}, {}, {}, {}, {}
        noise, noise_halves, residual_orders, power = {}, {}, 0, {}
        half = (n_revs // 2) * samples_per_rev
        quarter = (n_revs // 4) * samples_per_rev
        signals = functools.partial(tsa_signals, mesh_order=teeth[-1],
                                    other_meshes=teeth[:-1] + others, faster_shafts=faster)
        left = functools.partial(_noise_left, samples_per_rev=samples_per_rev,
                                 signals=signals)
        for channel, x in zip(names, tracked):
            parts = [signals(synchronous_average(y, samples_per_rev))
                     for y in (x, x[:half], x[half:2 * half])]
            energy[channel] = float(np.var(parts[0].residual))
            residual_orders = parts[0].residual_orders
            halves[channel] = (float(np.var(parts[1].residual)),
                               float(np.var(parts[2].residual)))
            noise[channel] = left(x[:half], x[half:2 * half])
            noise_halves[channel] = (left(x[:quarter], x[quarter:2 * quarter]),
                                     left(x[half:half + quarter],
                                          x[half + quarter:half + 2 * quarter]))
            values = tsa_indicators(parts[0], TrendReference())
            table[channel] = {k: float(values[k]) for k in SHAFT_INDICATORS}
            fm4_halves[channel] = tuple(float(tsa_indicators(p)["fm4"]) for p in parts[1:])
            first = [tuple(float(a) for a in p.spectrum[1:SHAFT_ORDERS + 1]) for p in parts]
            orders[channel], order_halves[channel] = first[0], (first[1], first[2])
            power[channel] = tuple((np.square(parts[0].spectrum) / 2).tolist())
        swing = _swing_lines_deg(estimate, machine, index)
        out.append(ShaftRecord(name, index, speed_hz, n_revs, samples_per_rev, teeth, energy,
                               halves, table, fm4_halves, swing[0][0] if swing else None,
                               orders, order_halves, noise, noise_halves, residual_orders,
                               power, swing))
    return out


def _noise_left(first: np.ndarray, second: np.ndarray, samples_per_rev: int,
                signals: Callable[[np.ndarray], TsaSignals]) -> float:
    """The residual energy the non-synchronous part of two equal runs of turns leaves in
    the TSA of both: a quarter of their TSAs' difference's (module docstring)."""
    difference = (synchronous_average(first, samples_per_rev)
                  - synchronous_average(second, samples_per_rev))
    return float(np.var(signals(difference).residual)) / 4


def _swing_lines_deg(estimate: SpeedEstimate, machine: Machine, shaft: int
                     ) -> tuple[tuple[float, float], ...]:
    """(swing, its deviation in noise) at each of shaft ``shaft``'s first
    :data:`SWING_ORDERS` orders, degrees of the input's turn; () where the swing is not
    measured: without a tacho, for a shaft not slower than the input, or over fewer than
    two of its turns. The noise is read beside each line, away from every shaft's orders
    (in this shaft's turns); the first line's swing is ``ShaftRecord.swing_deg``."""
    ratio = float(machine.shaft_ratio(shaft))
    if estimate.source is not SpeedSource.TACHO or not ratio < 1:
        return ()
    a, b = estimate.valid
    revs = estimate.revolutions[a:(b + 1) or None]
    if whole_turns(revs, ratio) < 2:
        return ()
    top = SWING_ORDERS + 1
    lines = [k * r for r in (float(machine.shaft_ratio(j)) / ratio
                             for j in range(len(machine.shafts)))
             for k in range(1, int(top / r) + 2)]
    orders = np.arange(1, SWING_ORDERS + 1, dtype=float)
    swings = turn_swing(revs, ratio, orders)
    return tuple((float(360 * w), float(360 * swing_noise(revs, ratio, k, lines)))
                 for k, w in zip(orders, swings))


@dataclass(frozen=True)
class MachineRecord:
    """A record seen through the machine: the input speed found, every shaft's TSA, and
    every bearing's defect lines (:mod:`pydiag.gear.bearing_lines`)."""

    speed: SpeedEstimate
    shafts: tuple[ShaftRecord, ...]
    file: str
    #: each channel's level as read (:func:`channel_levels`); None: not known (a baseline
    #: kept before pydiag kept it)
    units: dict[str, str] | None = None
    #: empty for a machine without bearings or a baseline kept before they were read
    bearings: tuple[BearingRecord, ...] = ()

    def to_dict(self) -> dict:
        """Plain data that :meth:`from_dict` reads back (a baseline kept in the history):
        the speed without its angle at every sample, every shaft's TSA facts."""
        speed = self.speed
        return {"file": self.file, "units": self.units,
                "speed": {"speed_hz": speed.speed_hz, "variation_pct": speed.variation_pct,
                          "method": speed.method, "nominal_hz": speed.nominal_hz,
                          "source": speed.source.value, "confidence_db": finite_or_none(
                              speed.confidence_db), "mesh_speed_hz": speed.mesh_speed_hz,
                          "band_pct": speed.band_pct},
                "shafts": [{"shaft": s.shaft, "index": s.index, "speed_hz": s.speed_hz,
                            "revolutions": s.revolutions, "samples_per_rev": s.samples_per_rev,
                            "teeth": list(s.teeth), "residual_energy": s.residual_energy,
                            "halves": {c: list(h) for c, h in s.halves.items()},
                            "indicators": {c: {k: finite_or_none(v) for k, v in t.items()}
                                           for c, t in s.indicators.items()},
                            "fm4_halves": {c: [finite_or_none(v) for v in h]
                                           for c, h in s.fm4_halves.items()},
                            "swing_deg": s.swing_deg,
                            "orders": {c: list(o) for c, o in s.orders.items()},
                            "order_halves": {c: [list(h) for h in o]
                                             for c, o in s.order_halves.items()},
                            "noise": s.noise,
                            "noise_halves": {c: list(h) for c, h in s.noise_halves.items()},
                            "residual_orders": s.residual_orders,
                            "power": {c: list(p) for c, p in s.power.items()},
                            "swing_lines_deg": [[finite_or_none(v) for v in line]
                                                for line in s.swing_lines_deg]}
                           for s in self.shafts],
                "bearings": [b.to_dict() for b in self.bearings]}

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
            {c: {k: _number(v) for k, v in t.items()} for c, t in s["indicators"].items()},
            {c: (_number(h[0]), _number(h[1])) for c, h in s.get("fm4_halves", {}).items()},
            s.get("swing_deg"),
            {c: tuple(o) for c, o in s.get("orders", {}).items()},
            {c: (tuple(o[0]), tuple(o[1])) for c, o in s.get("order_halves", {}).items()},
            dict(s.get("noise", {})),
            {c: (h[0], h[1]) for c, h in s.get("noise_halves", {}).items()},
            s.get("residual_orders", 0),
            {c: tuple(p) for c, p in s.get("power", {}).items()},
            tuple((_number(a), _number(n)) for a, n in s.get("swing_lines_deg", [])))
            for s in data["shafts"])
        return cls(SpeedEstimate(revolutions=np.empty(0), source=source, **speed), shafts,
                   data["file"], data.get("units"),
                   tuple(BearingRecord.from_dict(b) for b in data.get("bearings", [])))


def channel_levels(measurement: Measurement) -> dict[str, str]:
    """Each channel's level as it was read: its SI unit (converted from g, or from volts at
    a sensitivity), ``V (level unknown)``, or ``as recorded`` (no unit said): records
    compared by level must agree on it."""
    meta = measurement.metadata
    si, volts = meta.get("si_units", {}), meta.get("unknown_level", [])
    return {c: si.get(c) or ("V (level unknown)" if c in volts else "as recorded")
            for c in measurement.channels}


def finite_or_none(value: float | None) -> float | None:
    """``value``, None where JSON has no number for it (inf, nan)."""
    return value if value is not None and math.isfinite(value) else None


def _number(value: float | None) -> float:
    """What :func:`finite_or_none` wrote, read back: None is nan."""
    return math.nan if value is None else value


def machine_record(measurement: Measurement, machine: Machine, speed: SpeedSettings,
                   input_hz: float, found: SpeedEstimate | None = None,
                   upsampled: Upsampled | None = None) -> MachineRecord:
    """``measurement`` seen through the machine: its speed (from every mesh, or the tacho)
    around the nominal ``input_hz``, or ``found`` when already found, and the TSA of every
    shaft (from ``upsampled``, the record upsampled once for every shaft, when given). The
    one route for a record, a baseline and a kept baseline alike."""
    if found is None:
        kin = machine.stage_kinematics(0, input_hz)
        slowest = min(float(machine.shaft_ratio(k)) for k in range(len(machine.shafts)))
        tracked_s = 8 / (input_hz * slowest)  # a few turns of the slowest shaft beyond the edges
        found = estimate_speed(measurement, kin, speed, tracked_s, machine=machine)
    drop = (speed.tacho,) if speed.tacho else ()
    upsampled = upsampled or upsampled_record(measurement, found, drop)
    return MachineRecord(found, tuple(shaft_records(measurement, machine, found, drop,
                                                    upsampled)),
                         str(measurement.metadata.get("file", "(in memory)")),
                         channel_levels(measurement),
                         tuple(bearing_records(measurement, machine, found, drop, upsampled)))
