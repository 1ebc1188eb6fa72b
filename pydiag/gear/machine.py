"""A machine description: the shafts, gear stages, bearings, sensors and tacho of one
gearbox, read from a TOML file (one file a machine).

Stages are listed from the input; stage k+1's pinion sits on stage k's gear shaft, so a
machine of n stages has n + 1 shafts, shaft 0 the input. Every speed follows from the
input shaft's: shaft k turns at ``Machine.shaft_ratio(k)`` times it. The format, every
table and key with an example, is documented once, in ``docs/machine-file.md``.

Planetary stages (``type = "planetary"``) are recognised and refused: their kinematics
are not built yet. Every mistake is a :class:`~pydiag.core.errors.MachineError` naming the
file and the key.

One concern: what a gearbox is (the speeds and periods that follow from its teeth); its
file is read and checked by :mod:`pydiag.gear.machine_file`, what is fitted to it lives in
:mod:`pydiag.loop`.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import re
from dataclasses import dataclass
from fractions import Fraction

from pydiag.core.errors import MachineError
from pydiag.gear.kinematics import (Bearing, GearKinematics, Surroundings,
                                    OtherShaft, OtherStage)

#: Stage types whose kinematics are those of a parallel-axis pair.
PARALLEL_TYPES = ("spur", "helical")
#: Stage types known but not built yet.
LATER_TYPES = ("planetary",)


@dataclass(frozen=True)
class Stage:
    """One parallel-axis gear stage: ``pinion_teeth`` on its input shaft drive
    ``gear_teeth`` on its output shaft."""

    pinion_teeth: int
    gear_teeth: int
    name: str
    type: str = "spur"


@dataclass(frozen=True)
class Sensor:
    """What a record's channel is: its ``unit`` as recorded, the ``sensitivity`` that
    turns volts into it (text as written, e.g. "100 mV/g"), the stage it is near and the
    model output it maps to (default ``acc``)."""

    channel: str
    unit: str | None = None
    sensitivity: str | None = None
    near_stage: int | None = None
    output: str = "acc"


@dataclass(frozen=True)
class Tacho:
    channel: str
    pulses_per_rev: int = 1
    shaft: int = 0


@dataclass(frozen=True)
class StageEffect:
    """A catalogue effect (:mod:`pydiag.gear.effects`, by key) the machine's own model
    has on the stage with index ``stage``; ``off``: its parameters held at their neutral
    value (a shaft's orders whose lines its try found another shaft's)."""

    key: str
    stage: int
    off: tuple[str, ...] = ()


@dataclass(frozen=True)
class Machine:
    """A gearbox: stages from the input, shaft names (input first), bearings, sensors,
    tacho; ``input_hz`` the nominal input speed or None (then ``--rpm`` must say it);
    ``effects``: what its own model adds; ``start``: (name, value) of each parameter of a
    fit of that model before, which every fit of it also polishes from."""

    name: str
    stages: tuple[Stage, ...]
    shafts: tuple[str, ...]
    input_hz: float | None = None
    bearings: tuple[Bearing, ...] = ()
    sensors: tuple[Sensor, ...] = ()
    tacho: Tacho | None = None
    source: str = "(in memory)"
    effects: tuple[StageEffect, ...] = ()
    start: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        if not self.stages:
            raise MachineError(f"{self.source}: a machine needs at least one stage")
        if len(self.shafts) != len(self.stages) + 1:
            raise MachineError(f"{self.source}: shafts: {len(self.stages)} stage(s) make "
                               f"{len(self.stages) + 1} shafts, {len(self.shafts)} named")

    @property
    def identity(self) -> str:
        """What a record of this machine is seen through (its name, shafts and stages'
        teeth) as a key: a baseline kept for it is found again by it, whatever else of
        the file (sensors, effects, comments) changes. Two boxes of one design are two
        machines: their names tell them apart."""
        facts = {"name": self.name, "shafts": list(self.shafts),
                 "stages": [[s.pinion_teeth, s.gear_teeth] for s in self.stages]}
        return hashlib.sha256(json.dumps(facts, sort_keys=True).encode()).hexdigest()

    def fit_start(self) -> dict[str, float] | None:
        """The ``[start]`` table as a dict (parameter name -> value), or None when the file
        has none: what a fit of the machine's model polishes from besides its own swarm."""
        return dict(self.start) or None

    def shaft_ratio(self, shaft: int | str) -> Fraction:
        """Speed of shaft ``shaft`` (its index from 0 at the input, or its name) over the
        input shaft's (exact)."""
        if isinstance(shaft, str):
            if shaft not in self.shafts:
                raise MachineError(f"no shaft called {shaft!r}; the shafts are "
                                   f"{', '.join(self.shafts)}")
            shaft = self.shafts.index(shaft)
        ratio = Fraction(1)
        for stage in self.stages[:shaft]:
            ratio *= Fraction(stage.pinion_teeth, stage.gear_teeth)
        return ratio

    def stage_index(self, text: str) -> int:
        """The index of the stage called ``text``, or numbered ``text`` from 1 at the input;
        a :class:`~pydiag.core.errors.MachineError` naming the stages otherwise."""
        names = [s.name for s in self.stages]
        if text in names:
            return names.index(text)
        if re.fullmatch(r"\s*[0-9]+\s*", text) and 1 <= int(text) <= len(names):
            return int(text) - 1
        raise MachineError(f"{self.source}: no stage {text!r}; the stages are "
                           + ", ".join(f"{k} ({n})" for k, n in enumerate(names, 1)))

    def stage_choices(self) -> str:
        """How a stage may be named, for a message: "1 or 'first', 2 or 'second'"."""
        return ", ".join(f"{k} or {s.name!r}" for k, s in enumerate(self.stages, 1))

    def effect_keys(self, stage: int) -> set[str]:
        """The keys of the effects the file gives stage ``stage``, whatever they hold off."""
        return {e.key for e in self.effects if e.stage == stage}

    def mesh_order(self, stage: int) -> Fraction:
        """Stage ``stage``'s mesh frequency in orders of the input shaft."""
        return self.stages[stage].pinion_teeth * self.shaft_ratio(stage)

    def stage_kinematics(self, stage: int, input_hz: float) -> GearKinematics:
        """Stage ``stage`` as a gear pair at ``input_hz`` on the input shaft, in its
        machine: the pair's bearing is the first on its pinion shaft (and its gear's
        bearing the first on its gear's shaft, if no stage's pinion turns it); its other
        shaft (the one the other-shaft effect models, :meth:`other_shaft`) the next shaft
        downstream of its gear, else the one upstream of its pinion; every other stage,
        shaft and bearing is its
        :class:`~pydiag.gear.kinematics.Surroundings`."""
        s = self.stages[stage]
        own = self.pair_bearing(stage)
        gear_own = self.gear_bearing(stage)
        mine = {b.name for b in (own, gear_own) if b is not None}
        base = self.shaft_ratio(stage)

        def ratio(shaft: int) -> float:
            return float(self.shaft_ratio(shaft) / base)

        others = [k for k in range(len(self.shafts)) if k not in (stage, stage + 1)]
        neighbour = self.other_shaft(stage)
        context = Surroundings(
            tuple(OtherStage(o.name, o.pinion_teeth, o.gear_teeth, ratio(j), self.shafts[j],
                             self.shafts[j + 1])
                  for j, o in enumerate(self.stages) if j != stage),
            tuple(OtherShaft(self.shafts[k], ratio(k)) for k in others),
            tuple(b for b in self.bearings if b.name not in mine),
            pair_shafts=(self.shafts[stage], self.shafts[stage + 1]))
        return GearKinematics(s.pinion_teeth, s.gear_teeth, float(input_hz * base),
                              other_shaft_ratio=None if neighbour is None else ratio(neighbour),
                              bearing=own, gear_bearing=gear_own,
                              surroundings=context if len(self.stages) > 1 or context.bearings
                              else None)

    def gear_bearing(self, stage: int) -> Bearing | None:
        """Stage ``stage``'s gear's bearing as its gear pair sees it: the first on its gear's
        shaft, on the "gear", if no stage's pinion turns that shaft (the last stage's
        output shaft; every other shaft's bearings are a pinion's) (None: none)."""
        return None if stage + 1 < len(self.stages) else \
            self._first_bearing(self.shafts[stage + 1], "gear")

    def other_shaft(self, stage: int) -> int | None:
        """The index of the shaft stage ``stage``'s other-shaft effect models: the next
        downstream of its gear, else the one upstream of its pinion (None: the machine has
        no shaft beyond the pair's)."""
        if len(self.shafts) <= 2:
            return None
        return stage + 2 if stage + 2 < len(self.shafts) else stage - 1

    def pair_bearing(self, stage: int) -> Bearing | None:
        """Stage ``stage``'s bearing as its gear pair sees it: the first on its pinion
        shaft, on the "pinion" (None: none there)."""
        return self._first_bearing(self.shafts[stage], "pinion")

    def _first_bearing(self, shaft: str, side: str) -> Bearing | None:
        """The first bearing on ``shaft``, on the pair's ``side`` ("pinion", "gear"), or
        None: none there."""
        own = next((b for b in self.bearings if b.shaft == shaft), None)
        return None if own is None else dataclasses.replace(own, shaft=side)

    def fundamental_order(self) -> Fraction:
        """The machine's fundamental frequency in input-shaft orders: the largest of which
        every stage's hunting-tooth frequency is a whole multiple (exact)."""
        out = Fraction(0)
        for k, s in enumerate(self.stages):
            hunting = self.mesh_order(k) / math.lcm(s.pinion_teeth, s.gear_teeth)
            out = Fraction(math.gcd(out.numerator * hunting.denominator,
                                    hunting.numerator * out.denominator),
                           out.denominator * hunting.denominator)
        return out

    def model_kinematics(self, input_hz: float, stage: int = 0) -> GearKinematics:
        """Stage ``stage``'s kinematics (:meth:`stage_kinematics`) for a model that
        simulates every stage: the machine's fundamental period, every stage's bands
        (:attr:`~pydiag.gear.kinematics.GearKinematics.modelled_machine`); each stage's
        names the same lines from its own shafts."""
        kin = self.stage_kinematics(stage, input_hz)
        context = kin.surroundings or Surroundings()
        return dataclasses.replace(kin, surroundings=dataclasses.replace(
            context, fundamental_order=float(self.fundamental_order()
                                             / self.shaft_ratio(stage))))

    def stage_lines(self, stage: int, input_hz: float, max_freq_hz: float
                    ) -> tuple[float, ...]:
        """Stage ``stage``'s mesh harmonics and their sidebands at both of its shafts'
        orders up to ``max_freq_hz``, with ``input_hz`` on the input shaft
        (:meth:`~pydiag.gear.kinematics.GearKinematics.mesh_lines_hz`): the lines another
        stage's fit names and leaves out."""
        return self.stage_kinematics(stage, input_hz).mesh_lines_hz(max_freq_hz)
