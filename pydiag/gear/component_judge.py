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
  both are "changed". An idler's two gears both so called are told apart by their
  meshes' own sidebands (:mod:`pydiag.gear.gear_sidebands`): a gear whose own did not
  rise (or that has none) while the other's did is good. A gear whose shaft's rise
  another shaft's change accounts for (on the lines they share,
  :mod:`pydiag.gear.shared_lines`) is good, and says so.
  With a tacho, a shaft's **swing** (the input's angle once its turn and at its next
  orders, :mod:`pydiag.gear.machine_indicators`) is a transmission error of its gears:
  one that rose beyond ``K_SPREAD`` times how much noise moves it, in the record and the
  baselines, makes the shaft's gears "eccentric" when its first order alone rose (a
  transmission error once a turn: an eccentric gear, a runout), else "changed", whatever
  their stage's residual says (an eccentric gear moves the mesh's sidebands, which the
  residual energy of a two-gear shaft may not show beyond its spread); two gears so
  called are told apart by their sidebands as above.
- **A shaft** by its first orders in its own TSA (those that are none of a faster
  shaft's, whose lines survive it): its 1x alone rose, "imbalance"; its 1x and 2x, "bent"
  (a bend or a misalignment: twice a turn); three or more of its first five, "looseness"
  (a loose fit, a sheared key: a turn that repeats with harmonics); any other rise,
  "changed"; orders that fell beyond the threshold name no fault, and its line says so.
  A shaft whose swing rose as well is good, and says why: its gears'
  transmission error moves its orders (an eccentric gear's mass and mesh force turn with
  it), and a fault of the shaft itself is not told beside it.
- **A bearing** by its defect lines in the envelope (:mod:`pydiag.gear.bearing_judge`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from pydiag.gear.bearing_judge import judge_bearings
from pydiag.gear.component import ComponentVerdict, components, finite_mean, finite_rms
from pydiag.gear.faults import CHANGED, ECCENTRIC, GOOD, NOT_JUDGED, shaft_state
from pydiag.gear.gear_sidebands import sideband_change
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import (SHAFT_ORDERS, SWING_ORDERS, MachineRecord,
                                            faster_shafts)
from pydiag.gear.stage_judge import (K_SPREAD, StageVerdict, healthy_differences, knows_noise,
                                     synchronous_spread)


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
            suspect = v.suspect == c.role  # its shaft named by the stage all the same
            out.append(ComponentVerdict(c, CHANGED if suspect else GOOD, evidence, held,
                                        margin, f"the {whose} change accounts for its "
                                        "shaft's rise, on the lines they share"
                                        + (f", but its shaft is its stage's suspect "
                                           f"({v.suspect_by})" if suspect else "")))
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


def _told_apart(machine: Machine, record: MachineRecord, baselines: Sequence[MachineRecord],
                gears: list[ComponentVerdict]) -> list[ComponentVerdict]:
    """``gears`` with a shaft's two gears that are both "changed" told apart, where they
    can be, by their meshes' own sidebands (:mod:`pydiag.gear.gear_sidebands`), each
    held to ``K_SPREAD`` times its deviation scaled by the healthy halves (as a shaft's
    residual is)."""
    pairs = {}
    for v in gears:
        pairs.setdefault(v.component.shaft, []).append(v)
    pairs = {s: vs for s, vs in pairs.items()
             if len(vs) == 2 and all(v.state in (CHANGED, ECCENTRIC) for v in vs)}
    if not pairs or not knows_noise([record, *baselines]):
        return gears
    scale = synchronous_spread(list(baselines))[1]
    told = {}
    for shaft, pair in pairs.items():
        read = {v.component.name: sideband_change(machine, record, baselines,
                                                  machine.shafts.index(shaft), v.component.teeth)
                for v in pair}
        margin = {name: None if r is None else r[0] / (K_SPREAD * scale * r[1])
                  for name, r in read.items()}
        for v, w in (pair, pair[::-1]):
            mine, theirs = margin[v.component.name], margin[w.component.name]
            evidence = {**v.evidence, "own_sidebands_db": math.nan if read[v.component.name]
                        is None else read[v.component.name][0]}
            if mine is not None and mine > 1:
                other = ("the other gear has none" if theirs is None else
                         f"the other gear's too ({theirs:.2f} x)" if theirs > 1 else
                         f"the other gear's did not ({theirs:.2f} x)")
                why = f"{v.reason}; " if v.state == ECCENTRIC else "its shaft changed, and "
                told[v.component.name] = replace(
                    v, evidence=evidence, reason=f"{why}its mesh's own sidebands rose "
                    f"({mine:.2f} x their threshold); {other}")
            elif theirs is not None and theirs > 1:
                why = ("its mesh's harmonics are all that gear's: it has no sidebands of its "
                       "own" if mine is None else
                       f"its mesh's own sidebands did not ({mine:.2f} x)")
                told[v.component.name] = replace(
                    v, state=GOOD, evidence=evidence, reason=f"its shaft changed with the "
                    f"{w.component.name}, whose mesh's own sidebands rose ({theirs:.2f} x "
                    f"their threshold); {why}")
    return [told.get(v.component.name, v) for v in gears]


def _own_orders(machine: Machine, shaft: int, up_to: int = SHAFT_ORDERS) -> list[int]:
    """The orders of shaft ``shaft`` (1..``up_to``) that are none of a faster shaft's
    turning a whole number of times per its turn (:func:`faster_shafts`)."""
    faster = faster_shafts(machine, shaft)
    return [k for k in range(1, up_to + 1) if not any(k % n == 0 for n in faster)]


def _swing_rises(machine: Machine, record: MachineRecord, baselines: Sequence[MachineRecord],
                 shaft: int) -> dict[int, tuple[float, float]] | None:
    """Order -> (the swing's change in dB against the baselines' mean, its threshold in
    dB: ``K_SPREAD`` deviations in noise above that mean) at each of shaft ``shaft``'s own
    first :data:`SWING_ORDERS` orders; None where the record or a baseline has no swing
    read."""
    lines = [record.shafts[shaft].swing_lines_deg] + [b.shafts[shaft].swing_lines_deg
                                                      for b in baselines]
    if any(len(x) < SWING_ORDERS for x in lines):
        return None
    out = {}
    for k in _own_orders(machine, shaft, SWING_ORDERS):
        now, deviation = lines[0][k - 1]
        before = finite_mean([x[k - 1][0] for x in lines[1:]])
        spread = math.hypot(deviation, finite_mean([x[k - 1][1] for x in lines[1:]])
                            / math.sqrt(len(baselines)))
        out[k] = (_ratio_db(now, before), _ratio_db(before + K_SPREAD * spread, before))
    return out


def _risen(read: dict[int, tuple[float, float]] | None) -> dict[int, float]:
    """Order -> its change over its threshold, of the orders of a :func:`_swing_rises`
    reading that rose beyond their threshold."""
    return {k: c / t for k, (c, t) in (read or {}).items() if c / t > 1}


def _by_swing(machine: Machine, record: MachineRecord,
              swings: Sequence[dict[int, tuple[float, float]] | None],
              gears: list[ComponentVerdict]) -> list[ComponentVerdict]:
    """``gears`` with those on a shaft whose swing rose called "eccentric" or "changed"
    (module docstring); ``swings``: each shaft's :func:`_swing_rises`."""
    out = []
    for v in gears:
        read = swings[machine.shafts.index(v.component.shaft)]
        rose = _risen(read)
        if not rose:
            out.append(v)
            continue
        state = ECCENTRIC if list(rose) == [1] else CHANGED
        said = ", ".join(f"{k}x ({m:.2f} x its threshold)" for k, m in rose.items())
        swing = record.shafts[machine.shafts.index(v.component.shaft)].swing_lines_deg
        evidence = {**v.evidence, **{f"swing_{k}x_db": c for k, (c, _) in read.items()},
                    "swing_1x_deg": swing[0][0]}
        out.append(replace(v, state=state, evidence=evidence,
                           margin=max(max(rose.values()), v.margin or 0.0),
                           reason=f"its shaft's swing rose at {said}: a transmission error "
                                  + ("once its turn" if state == ECCENTRIC else
                                     "repeating with its turn")))
    return out


def _shafts(machine: Machine, record: MachineRecord, baselines: Sequence[MachineRecord],
            swings: Sequence[dict[int, tuple[float, float]] | None]) -> list[ComponentVerdict]:
    """Every shaft by its own orders (module docstring); ``swings``: each shaft's
    :func:`_swing_rises`."""
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
    threshold = K_SPREAD * finite_rms(diffs)
    out = []
    for c, s in zip(shafts, record.shafts):
        changes = {}
        for k in _own_orders(machine, s.index):
            per_channel = [_ratio_db(a[k - 1], float(np.mean([b.shafts[s.index].orders[ch][k - 1]
                                                              for b in baselines])))
                           for ch, a in s.orders.items()]
            changes[k] = finite_mean(per_channel)
        rises = sorted(k for k, v in changes.items() if v > threshold)
        state = shaft_state(rises)
        biggest = max((abs(v) for v in changes.values() if math.isfinite(v)), default=math.nan)
        fell = sorted(k for k, v in changes.items() if v < -threshold)
        why = (f"orders risen: {', '.join(f'{k}x' for k in rises)}" if rises else
               f"orders fell: {', '.join(f'{k}x' for k in fell)} (a fall names no fault)"
               if fell else "")
        swung = _risen(swings[s.index]) if rises else {}
        if swung:  # its gears' transmission error moves its orders (module docstring)
            state, why = GOOD, (f"{why}, with its swing ({', '.join(f'{k}x' for k in swung)}): "
                                "its gears' transmission error, which hides a fault of the "
                                "shaft itself")
        out.append(ComponentVerdict(
            c, state, {f"order_{k}_db": v for k, v in changes.items()}, threshold,
            biggest / threshold, why))
    return out


def _swing_unread(machine: Machine, record: MachineRecord,
                  baselines: Sequence[MachineRecord], gears: list[ComponentVerdict]
                  ) -> list[ComponentVerdict]:
    """``gears`` with those whose shaft's swing the record has and a baseline lacks (kept
    before pydiag read it) saying so."""
    out = []
    for v in gears:
        shaft = record.shafts[machine.shafts.index(v.component.shaft)]
        if shaft.swing_lines_deg and any(not b.shafts[shaft.index].swing_lines_deg
                                         for b in baselines):
            v = replace(v, reason="; ".join(w for w in (v.reason, (
                "its shaft's swing not judged: a baseline was kept before pydiag read it "
                "(keep it again)")) if w))
        out.append(v)
    return out


def judge_components(machine: Machine, record: MachineRecord,
                     baselines: Sequence[MachineRecord],
                     verdicts: Sequence[StageVerdict]) -> tuple[ComponentVerdict, ...]:
    """Every component of ``machine`` in ``record`` against the ``baselines`` (module
    docstring); ``verdicts``: the stages' (:func:`~pydiag.gear.stage_judge.judge_stages`).
    Faulty ones first, then in the machine's order (gears, bearings, shafts)."""
    swings = [_swing_rises(machine, record, baselines, i) for i in range(len(machine.shafts))]
    gears = _told_apart(machine, record, baselines,
                        _by_swing(machine, record, swings, _gears(machine, verdicts)))
    judged = (_swing_unread(machine, record, baselines, gears)
              + judge_bearings(machine, record, baselines)
              + _shafts(machine, record, baselines, swings))
    return tuple(sorted(judged, key=lambda v: not v.faulty))
