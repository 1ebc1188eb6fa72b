"""The kinematic frequency map: every characteristic frequency of a gear pair, named.

Families (each line carries its family and order):

- ``pinion``, ``gear``: shaft harmonics k*f_pinion, k*f_gear
- ``mesh``: mesh harmonics h*f_mesh
- ``mesh_sb_pinion``, ``mesh_sb_gear``: sidebands h*f_mesh +- k*f_shaft (order = k, signed)
- ``assembly``: f_mesh / N_ap and its harmonics; ``hunting``: f_mesh / lcm(Np, Ng) harmonics
  that belong to no family above
- ``bpfo``, ``bpfi``, ``bsf``, ``ftf``: bearing defect frequencies and harmonics (when a
  bearing geometry is given), ``bpfi_sb``: BPFI +- shaft speed sidebands
- ``gear_bpfo``, ``gear_bpfi``, ``gear_bpfi_sb``, ``gear_bsf``, ``gear_ftf``: the same of
  the bearing on the gear's shaft that the pair's gear-bearing effects model
  (``GearKinematics.gear_bearing``)
- ``other_shaft``: k*f_other, the orders of another shaft of the machine (when its speed
  ratio is given: ``GearKinematics.other_shaft_ratio``), up to :data:`SHAFT_ORDERS`

The rest of a gearbox (``GearKinematics.surroundings``), lines no effect of the pair models:

- ``stage_mesh``: another stage's mesh harmonics; ``stage_mesh_sb``: their sidebands at
  both of its shafts' orders (order = k, signed)
- ``stage_assembly``: another stage's assembly-phase and hunting-tooth lines
- ``machine_shaft``: the orders of the machine's other shafts (but the ``other_shaft``),
  up to :data:`SHAFT_ORDERS`
- ``machine_bearing``: the defect frequencies of bearings on the machine's other shafts

A frequency is matched to the nearest line within ``tolerance_hz``; families earlier in
``PRIORITY`` win ties: a mesh harmonic is also a pinion harmonic and is named ``mesh``; a
line within ``n_sidebands`` shaft orders of a mesh harmonic is named as its sideband. Each
line lists the other families with a line at the very same frequency (``also``).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

from pydiag.gear.kinematics import GearKinematics

PRIORITY = ("mesh", "stage_mesh", "mesh_sb_pinion", "mesh_sb_gear", "stage_mesh_sb", "pinion",
            "gear", "assembly", "bpfo", "bpfi", "bpfi_sb", "bsf", "ftf", "gear_bpfo",
            "gear_bpfi", "gear_bpfi_sb", "gear_bsf", "gear_ftf", "machine_bearing",
            "other_shaft", "machine_shaft", "stage_assembly", "hunting")
#: The shaft orders a shaft's own vibration is modelled at (GearDiag.Components.ShaftOrders):
#: an unbalance at 1x, a misalignment at 1x-2x, a coupling or a looseness up to about 10x.
#: The map names another shaft's orders up to this (higher ones its own mesh would make,
#: whose teeth the map does not know).
SHAFT_ORDERS = 10


@dataclass(frozen=True)
class KinematicLine:
    freq_hz: float
    family: str
    order: int
    label: str
    # the other families with a line at this very frequency (a pinion order that is also a
    # gear order: 2x pinion is 3x gear on 14/21 teeth), which this line's family outranks
    also: tuple[str, ...] = ()


def kinematic_map(kin: GearKinematics, max_freq_hz: float,
                  n_sidebands: int = 6) -> list[KinematicLine]:
    """All named lines up to ``max_freq_hz``, sorted by frequency (a bearing's when
    ``kin`` has one)."""
    lines: list[KinematicLine] = []

    def add(f: float, family: str, order: int, label: str) -> None:
        if 0 < f <= max_freq_hz:
            lines.append(KinematicLine(f, family, order, label))

    fp, fg, fm = kin.f_pinion_hz, kin.f_gear_hz, kin.f_mesh_hz
    for k in range(1, int(max_freq_hz / fp) + 1):
        add(k * fp, "pinion", k, f"{k}x pinion")
    for k in range(1, int(max_freq_hz / fg) + 1):
        add(k * fg, "gear", k, f"{k}x gear")
    for h in range(1, int(max_freq_hz / fm) + 2):
        add(h * fm, "mesh", h, f"{h}x mesh")
        for k in range(1, n_sidebands + 1):
            for sign in (-1, 1):
                add(h * fm + sign * k * fp, "mesh_sb_pinion", sign * k,
                    f"{h}x mesh {'+' if sign > 0 else '-'} {k}x pinion")
                add(h * fm + sign * k * fg, "mesh_sb_gear", sign * k,
                    f"{h}x mesh {'+' if sign > 0 else '-'} {k}x gear")
    fa = kin.f_assembly_hz
    for k in range(1, int(max_freq_hz / fa) + 1):
        add(k * fa, "assembly", k, f"{k}x assembly phase")
    fh = kin.f_hunting_hz
    for k in range(1, int(max_freq_hz / fh) + 1):
        add(k * fh, "hunting", k, f"{k}x hunting tooth")
    f_other = kin.f_other_shaft_hz
    if f_other is not None:
        for k in range(1, min(SHAFT_ORDERS, int(max_freq_hz / f_other)) + 1):
            add(k * f_other, "other_shaft", k, f"{k}x other shaft")
    for bearing, prefix, whose in ((kin.bearing, "", ""),
                                   (kin.gear_bearing, GEAR_BEARING_PREFIX, " (gear's bearing)")):
        if bearing is None:
            continue
        f_shaft = kin.shaft_hz(bearing.shaft)
        for family, f in bearing.frequencies(f_shaft).items():
            for k in range(1, int(max_freq_hz / f) + 1):
                add(k * f, prefix + family, k, f"{k}x {family.upper()}{whose}")
                if family == "bpfi":
                    for sign in (-1, 1):
                        add(k * f + sign * f_shaft, prefix + "bpfi_sb", sign * k,
                            f"{k}x BPFI {'+' if sign > 0 else '-'} shaft{whose}")
    if kin.surroundings is not None:
        _machine_lines(kin, max_freq_hz, n_sidebands, add)
    return coinciding(lines)


def _machine_lines(kin: GearKinematics, max_freq_hz: float, n_sidebands: int, add) -> None:
    """The lines of the rest of the gearbox (module docstring), through ``add``."""
    fp, context = kin.f_pinion_hz, kin.surroundings
    for stage in context.stages:
        f_in, f_out = stage.pinion_ratio * fp, stage.gear_ratio * fp
        fm = stage.pinion_teeth * f_in
        for h in range(1, int(max_freq_hz / fm) + 2):
            add(h * fm, "stage_mesh", h, f"{h}x {stage.name} mesh")
            for k in range(1, n_sidebands + 1):
                for sign in (-1, 1):
                    for shaft, f in ((stage.pinion_shaft, f_in), (stage.gear_shaft, f_out)):
                        add(h * fm + sign * k * f, "stage_mesh_sb", sign * k,
                            f"{h}x {stage.name} mesh {'+' if sign > 0 else '-'} {k}x {shaft}")
        pair = GearKinematics(stage.pinion_teeth, stage.gear_teeth, f_in)
        for name, f in (("assembly phase", pair.f_assembly_hz), ("hunting tooth", pair.f_hunting_hz)):
            for k in range(1, int(max_freq_hz / f) + 1):
                add(k * f, "stage_assembly", k, f"{k}x {stage.name} {name}")
    named = kin.other_shaft_ratio
    for shaft in context.shafts:
        if named is not None and math.isclose(shaft.ratio, named, rel_tol=1e-12):
            continue  # the other shaft's own family
        f = shaft.ratio * fp
        for k in range(1, min(SHAFT_ORDERS, int(max_freq_hz / f)) + 1):
            add(k * f, "machine_shaft", k, f"{k}x {shaft.name}")
    for b in context.bearings:
        for family, f in b.frequencies(kin.shaft_hz(b.shaft)).items():
            for k in range(1, int(max_freq_hz / f) + 1):
                add(k * f, "machine_bearing", k, f"{k}x {family.upper()} {b.name} ({b.shaft})")


#: What the families of the gear's bearing's lines begin with.
GEAR_BEARING_PREFIX = "gear_"
#: The families of the pair's bearing's lines.
PAIR_BEARING_FAMILIES = ("bpfo", "bpfi", "bpfi_sb", "bsf", "ftf")
#: The families of a rolling bearing's lines: the pair's bearing's, then the gear's
#: bearing's.
BEARING_FAMILIES = PAIR_BEARING_FAMILIES + tuple(GEAR_BEARING_PREFIX + f
                                                 for f in PAIR_BEARING_FAMILIES)


def with_gear_bearing(table: dict) -> dict:
    """``table`` (by family) with each entry of a pair's bearing family given to the same
    family of the gear's bearing as well."""
    return {**table, **{GEAR_BEARING_PREFIX + f: v for f, v in table.items()
                        if f in PAIR_BEARING_FAMILIES}}


def coinciding(lines: list[KinematicLine], tolerance_hz: float = 0.0) -> list[KinematicLine]:
    """``lines`` sorted by frequency (and priority), each told the other families with a
    line within ``tolerance_hz`` of it (``also``; 0: at the very same frequency, to
    rounding). A spectrum of joined halves moves a line that is not synchronous
    (``FullSpectrumFeaturizer.joined_freq_hz``): within half a bin of a shaft order it
    is on that order's bin."""
    rank = {f: i for i, f in enumerate(PRIORITY)}
    lines = sorted(lines, key=lambda ln: (ln.freq_hz, rank[ln.family]))
    out, low = [], 0
    for i, line in enumerate(lines):
        tol = max(tolerance_hz, 1e-9 * line.freq_hz)
        while lines[low].freq_hz < line.freq_hz - tol:
            low += 1
        high = i
        while high + 1 < len(lines) and lines[high + 1].freq_hz <= line.freq_hz + tol:
            high += 1
        out.append(replace(line, also=tuple(dict.fromkeys(
            o.family for o in lines[low:high + 1] if o.family != line.family))))
    return out


def match(freq_hz: float, lines: list[KinematicLine], tolerance_hz: float) -> KinematicLine | None:
    """The line nearest ``freq_hz`` within the tolerance; the higher-priority family on ties."""
    rank = {f: i for i, f in enumerate(PRIORITY)}
    near = [ln for ln in lines if abs(ln.freq_hz - freq_hz) <= tolerance_hz]
    if not near:
        return None
    return min(near, key=lambda ln: (round(abs(ln.freq_hz - freq_hz) / max(tolerance_hz, 1e-12), 1),
                                    rank[ln.family]))


def match_each(freqs_hz: Sequence[float], lines: list[KinematicLine], tolerance_hz: float
               ) -> list[KinematicLine | None]:
    """:func:`match` of each of ``freqs_hz``, the same answers, each looking only at the
    lines within the tolerance (found by bisection of the lines sorted by frequency): a
    spectrum's thousands of bins against a gearbox's thousands of lines."""
    order = sorted(range(len(lines)), key=lambda i: lines[i].freq_hz)
    at = [lines[i].freq_hz for i in order]
    def near(f: float) -> list[KinematicLine]:  # in their order in ``lines``: ties as match's
        window = order[bisect.bisect_left(at, f - tolerance_hz):
                       bisect.bisect_right(at, f + tolerance_hz)]
        return [lines[i] for i in sorted(window)]
    return [match(f, near(f), tolerance_hz) for f in freqs_hz]
