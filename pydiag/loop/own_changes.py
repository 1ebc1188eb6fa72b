"""The model's verdict on what a machine's healthy model already has: which of its effects
a record asks for at other values, held out, beside a healthy repeat of the baseline, and
the part of the machine that change sizes.

The healthy model is the machine's own model fitted to a healthy baseline (with the
effects the loop gave it there). Each effect a stage of it has is polished on half of a
record's periods from the healthy values and scored on the other half
(:func:`~pydiag.loop.machine_discover.refit_own_effects`): its held-out z says whether the
record asks for other values. On a real machine two healthy records differ by more than a
record's halves do (a z of a healthy repeat is not standard normal: bench/CHANGELOG.md), so
a record's rise of z over the baseline's own is held, as a component's change is
(:mod:`pydiag.gear.component_judge`), to ``K_SPREAD`` times the healthy repeats' rise of
the same effect on the same stage (their RMS), never below a z of 1. The effect's sizing parameter that
changed most names the part (:attr:`pydiag.gear.effect.Effect.parts`): a deeper pinion
modulation is its pinion, larger orders of the pinion shaft are that shaft.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from pydiag.gear.component import components
from pydiag.gear.effect import GEAR, MESH, PINION, PINION_BEARING, PINION_SHAFT, GEAR_SHAFT
from pydiag.gear.machine import Machine
from pydiag.gear.stage_judge import K_SPREAD
from pydiag.loop.machine_model import MachineModel
from pydiag.loop.results import Suggestion

#: A rise of held-out z is never held to less than this times ``K_SPREAD``: a z of noise
#: alone is about 1.
MIN_RISE = 1.0


@dataclass(frozen=True)
class OwnChange:
    """One effect of a stage of the healthy model as a record asks for it.

    ``z``: its held-out z on the record, ``baseline_z`` on the baseline, against the
    healthy fit; ``repeat_rise``: the RMS of the healthy repeats' rises of it over the
    baseline's (None: no repeat); ``margin``: the record's rise over ``K_SPREAD`` times
    that (never below :data:`MIN_RISE`; nan without a repeat); ``values``: each sizing parameter's
    healthy value and the record's fitted one, named as the model names them; ``part``:
    the part of the stage its largest change sizes, ``components``: the machine's
    components that part is (a mesh: both gears)."""

    stage: str
    effect: str
    z: float
    baseline_z: float
    repeat_rise: float | None
    margin: float
    values: dict[str, tuple[float, float]]
    part: str | None
    components: tuple[str, ...]

    @property
    def changed(self) -> bool:
        """Whether the record asks for other values beyond the healthy repeat's spread."""
        return self.margin > 1.0


def own_changes(machine: Machine, model: MachineModel, healthy: Mapping[str, float],
                record: Sequence[Suggestion], baseline: Sequence[Suggestion],
                repeats: Sequence[Sequence[Suggestion]] = (),
                k_spread: float = K_SPREAD) -> list[OwnChange]:
    """Every effect tried on ``record`` (rows of
    :func:`~pydiag.loop.machine_discover.refit_own_effects` against the ``healthy`` fit's
    values) as an :class:`OwnChange`, beside the same rows of the ``baseline`` the healthy
    model was fitted to and of each healthy repeat of it (``repeats``); the largest margin
    first. A row not tried (nothing of it to fit) is left out."""
    def z_of(rows: Sequence[Suggestion]) -> dict[tuple[str, str], float]:
        return {(r.stage, r.effect): r.held_out.z for r in rows
                if r.held_out is not None and r.held_out.tried}
    own, again = z_of(baseline), [z_of(rows) for rows in repeats]
    stages = [s.name for s in machine.stages]
    out = []
    for row in record:
        h = row.held_out
        if h is None or not h.tried or row.stage not in stages:
            continue
        key = (row.stage, row.effect)
        k = stages.index(row.stage)
        effect = model.stage_effects(k)[row.effect]
        base_z = own.get(key, 0.0)
        rises = [z[key] - base_z for z in again if key in z]
        repeat_rise = math.sqrt(sum(r * r for r in rises) / len(rises)) if rises else None
        held_to = k_spread * max(abs(repeat_rise), MIN_RISE) if repeat_rise is not None \
            else math.nan
        values = {name: (healthy[name], h.parameters[name]) for name, _ in effect.parts
                  if name in healthy and name in h.parameters}
        part = effect.part_of({name: after - before for name, (before, after) in values.items()})
        out.append(OwnChange(row.stage, row.effect, h.z, base_z, repeat_rise,
                             (h.z - base_z) / held_to, values, part,
                             part_components(machine, k, part)))
    return sorted(out, key=lambda c: -c.margin if math.isfinite(c.margin) else math.inf)


def part_components(machine: Machine, stage: int, part: str | None) -> tuple[str, ...]:
    """The names of ``machine``'s components that ``part`` of stage ``stage`` is: its
    pinion, its gear, both (the mesh), the shaft of either, the bearings of the pinion's
    shaft; none for no part."""
    name = machine.stages[stage].name
    roles = {PINION: ("pinion",), GEAR: ("gear",), MESH: ("pinion", "gear")}.get(part, ())
    shaft = {PINION_SHAFT: machine.shafts[stage],
             GEAR_SHAFT: machine.shafts[stage + 1]}.get(part)
    every = components(machine)
    return tuple(c.name for c in every
                 if (c.kind == "gear" and c.stage == name and c.role in roles)
                 or (c.kind == "shaft" and c.name == shaft)
                 or (part == PINION_BEARING and c.kind == "bearing"
                     and c.shaft == machine.shafts[stage]))
