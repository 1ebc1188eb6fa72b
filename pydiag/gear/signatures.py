"""What points to each effect of the catalogue: its signature (the weight of a residual
line, by its kinematic family and order) and its hint (the bounds the residual's peaks
narrow its parameters to), one function each, as :mod:`pydiag.gear.effects` names them
(the bearing effects' in :mod:`pydiag.gear.bearing_signatures`).

A signature weighs unexplained residual peaks by their kinematic family and order:
1 for the effect's defining lines, 0.5 for lines it also produces, 0 otherwise. An
effect's score is the share of the unexplained peak energy its signature covers.

A housing mode reweights every line the gear pair makes on its way to the sensor, so
its signature is all of them; its frequency is fitted inside the band where those lines'
unexplained energy bunches (:func:`resonance_band`), or above the analysed band when the
bunch reaches its top or there is none (``Effect.free_start``).
"""

from __future__ import annotations

import math

from pydiag.gear.features import max_band_freq_hz
from pydiag.gear.kinematic_map import (BEARING_FAMILIES, SHAFT_ORDERS, coinciding,
                                      kinematic_map, match)
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.peaks import Peak


def _runout(shaft: str):
    """A runout of the ``shaft`` ("pinion" or "gear") gear: a transmission error once its
    turn, its shaft's 1x (2x at half weight) and the mesh's first sidebands of it."""
    def weight(line, freq, kin):
        if line is None:
            return 0.0
        if line.family == shaft:
            return 1.0 if line.order == 1 else 0.5 if line.order == 2 else 0.0
        return 1.0 if line.family == f"mesh_sb_{shaft}" and abs(line.order) == 1 else 0.0
    return weight


gear_eccentricity = _runout("gear")
pinion_eccentricity = _runout("pinion")


def mesh_modulation(line, freq, kin):
    # amplitude modulation once per turn of a shaft: the first sideband of that shaft's
    # order either side of every mesh harmonic, and, at half weight, the shaft's first
    # order (the deflection under load)
    if line is None:
        return 0.0
    if line.family in ("mesh_sb_pinion", "mesh_sb_gear"):
        return 1.0 if abs(line.order) == 1 else 0.0
    return 0.5 if line.family in ("pinion", "gear") and line.order == 1 else 0.0


def shaft_swing(line, freq, kin):
    # the mesh's phase modulated at each shaft's speed: the first sideband of that shaft
    # either side of every mesh harmonic; no line at the shaft's own order (the phase of a
    # force, not its size, swings). Only the first: a shallow modulation of the phase and
    # one of the size (mesh_modulation, which claims these lines and more) make the same
    # first sidebands in an amplitude spectrum, so wherever the swing is tried on its
    # score the modulation is too, and the record, held out, tells them apart; a claim on
    # the second sidebands (a deep swing's) would try it alone on a comb a local fault
    # makes, and make it confident with its rival untried
    if line is None or line.family not in ("mesh_sb_pinion", "mesh_sb_gear"):
        return 0.0
    return 1.0 if abs(line.order) == 1 else 0.0


def gear_tooth_fault(line, freq, kin):
    if line is None:
        return 0.0
    if line.family == "gear":
        return 1.0 if line.order >= 2 else 0.5
    if line.family == "mesh_sb_gear":
        return 1.0 if abs(line.order) >= 2 else 0.5
    return 0.0


def second_pinion_tooth(line, freq, kin):
    if line is None:
        return 0.0
    if line.family == "mesh_sb_pinion":
        return 1.0
    return 0.5 if line.family == "pinion" and line.order >= 2 else 0.0


def backlash(line, freq, kin):
    # the contact lost where the deflection is lowest: every mesh harmonic, the higher
    # ones above all, and, at half weight, the lines of the pinion's turn (its faulty
    # tooth's, its runout's) whose troughs the loss clips
    if line is None:
        return 0.0
    if line.family == "mesh":
        return 1.0 if line.order >= 2 else 0.5
    return 0.5 if line.family in ("mesh_sb_pinion", "pinion") else 0.0


#: The largest line of a shaft order the shaft effects fit, m/s2 at the model's sensor, like
#: a bearing strike (MAX_STRIKE_M_S2): a fitted gain of 0.0145 makes it 7 g.
MAX_SHAFT_ORDER_M_S2 = 5000.0


#: A pinion order another shaft turns at too is fitted only where its unexplained line
#: stands this many times above that shaft's neighbouring orders' (pinion_shaft_hint).
SHARED_ORDER_MARGIN = 2.0
#: Families of the other shafts' orders (a pair's gear, the other shaft named, a
#: gearbox's other shafts).
OTHER_SHAFTS = ("gear", "other_shaft", "machine_shaft")


def pinion_shaft(line, freq, kin):
    # the pinion shaft's own lines: its first orders, far below the mesh's sidebands. An
    # order another shaft turns at too (2x pinion is 3x gear on 14/21 teeth; every order
    # of the PHM09 box's 32-tooth input pinion is an order of its idler's and of its
    # output's) is claimed only where the pinion has no order of its own (each is another
    # shaft's too), as a line it may make (0.5), which the hint fits only where the line
    # stands above the other shaft's orders around it; where the pinion has orders of its
    # own, those are the evidence of its vibration, and a shared line, which the other
    # shaft's comb may make (a broken gear tooth strikes at every gear order), is left to
    # neither. One a bearing's line falls on (in a spectrum of joined halves, within half
    # a bin: 2x BPFO on 7x pinion on the catalogue's 6205) is no evidence for it
    if (line is None or line.family != "pinion" or line.order > SHAFT_ORDERS
            or set(line.also) & set(BEARING_FAMILIES)):
        return 0.0
    if not set(line.also) & set(OTHER_SHAFTS):
        return 1.0
    return 0.5 if _every_order_shared(kin) else 0.0


def _every_order_shared(kin: GearKinematics) -> bool:
    """Whether the pinion's 1x, and so each of its orders, is an order of another shaft
    (a 32-tooth pinion driving 96: the gear turns once in 3 of its turns)."""
    fp = kin.f_pinion_hz
    return any(abs(fp / f - round(fp / f)) <= 1e-6 for f in _other_speeds(kin))


def _other_speeds(kin: GearKinematics) -> list[float]:
    """The speeds of the shafts other than the pinion's that the kinematics know, each
    once (a gearbox's list holds the pair's two shafts too)."""
    fp = kin.f_pinion_hz
    speeds = [kin.f_gear_hz] + ([kin.f_other_shaft_hz] if kin.f_other_shaft_hz else [])
    if kin.surroundings is not None:
        speeds += [shaft.ratio * fp for shaft in kin.surroundings.shafts]
    out: list[float] = []
    for f in speeds:
        if not any(math.isclose(f, seen, rel_tol=1e-9) for seen in [fp, *out]):
            out.append(f)
    return out


def pinion_shaft_hint(peaks: list[Peak], bin_hz: float, kin: GearKinematics | None) -> dict:
    """The orders whose line it does not claim (:func:`pinion_shaft`: one a
    bearing's line falls on, a mesh sideband on a pinion of few teeth, one another shaft
    turns at too where the pinion has orders of its own) are not fitted, nor a shared
    one whose residual's line does not stand :data:`SHARED_ORDER_MARGIN` times above each
    other shaft's orders 1 and 2 either side of it that are no pinion order: a line of
    another shaft's comb is as high as its neighbours, the pinion's own vibration stands
    out of it. Without a spectrum (``bin_hz`` 0: what the pair alone says) a shared order
    it claims may be fitted."""
    if kin is None:
        return {}
    fp = kin.f_pinion_hz
    lines = kinematic_map(kin, (SHAFT_ORDERS + 0.5) * fp)
    out = {}
    for k in range(1, SHAFT_ORDERS + 1):
        weight = pinion_shaft(match(k * fp, lines, 1e-6 * fp), k * fp, kin)
        if weight == 0 or (weight < 1 and bin_hz > 0
                           and not _stands_out(k * fp, peaks, bin_hz, kin)):
            out[f"A_s{k}"] = None
    return out


def _stands_out(freq_hz: float, peaks: list[Peak], bin_hz: float, kin: GearKinematics) -> bool:
    """Whether the residual's line at the pinion order ``freq_hz`` stands
    :data:`SHARED_ORDER_MARGIN` times above every other shaft's orders next to it (those
    that are no pinion order), in the largest excess over the model of any channel."""
    def excess(f: float) -> float:
        return max((p.amplitude for p in peaks if abs(p.freq_hz - f) <= 0.5 * bin_hz),
                   default=0.0)

    fp = kin.f_pinion_hz
    neighbours = []
    for f_shaft in _other_speeds(kin):
        order = freq_hz / f_shaft
        if abs(order - round(order)) > 1e-6:
            continue
        for step in (-2, -1, 1, 2):
            f = (round(order) + step) * f_shaft
            turns = f / fp
            if f > 0 and abs(turns - round(turns)) > 1e-6:
                neighbours.append(excess(f))
    own = excess(freq_hz)
    return own > 0 and own > SHARED_ORDER_MARGIN * max(neighbours, default=0.0)


def other_shaft(line, freq, kin):
    # another shaft's first orders, but for those a line of the gear pair (or a bearing)
    # falls on: which shaft makes such a line the record does not say
    ok = (line is not None and line.family == "other_shaft" and line.order <= SHAFT_ORDERS
          and not set(line.also) - {"hunting"})
    return 1.0 if ok else 0.0


def other_shaft_hint(peaks: list[Peak], bin_hz: float, kin: GearKinematics | None) -> dict:
    """Only the orders it claims (:func:`other_shaft`) at which the residual has a peak
    are fitted: none when the other shaft's speed is not known. Its lines are not
    synchronous with the pair's period, so in a spectrum of joined halves each leaks over
    the bins around it: an order with no line in the record, fitted, takes noise peaks of
    the fitted half by its leakage and predicts lines the other half lacks."""
    names = [f"A_o{k}" for k in range(1, SHAFT_ORDERS + 1)]
    f_other = None if kin is None else kin.f_other_shaft_hz
    if f_other is None:
        return dict.fromkeys(names)
    top = min((SHAFT_ORDERS + 0.5) * f_other, max_band_freq_hz(kin))
    own = {ln.order: ln for ln in coinciding(kinematic_map(kin, top), 0.5 * bin_hz)
           if ln.family == "other_shaft"}
    seen = {p.order for p in peaks if p.family == "other_shaft"}
    return {name: None for k, name in enumerate(names, 1) if k not in seen or k not in own
            or other_shaft(own[k], own[k].freq_hz, kin) == 0}


def other_shaft_values(kin) -> dict[str, float]:
    ratio = None if kin is None else kin.other_shaft_ratio
    return {} if ratio is None else {"r_other": ratio}


def other_shaft_missing(kin) -> str:
    return "the other shaft's speed ratio" if kin is None or kin.other_shaft_ratio is None else ""


def stiffness_shape(line, freq, kin):
    # an even harmonic of the healthy mesh's stiffness: the mesh harmonics, 2x above all
    if line is None or line.family != "mesh":
        return 0.0
    return 1.0 if line.order % 2 == 0 else 0.5


#: Kinematic families the base gear pair (GearDiag.GearPair) makes: the lines a transfer
#: path between its mesh and the sensor can reshape.
GEAR_PAIR_FAMILIES = ("mesh", "mesh_sb_pinion", "pinion", "assembly")
#: Half-width of a housing mode's band, relative to its frequency. A mode of damping
#: ratio zeta amplifies lines within about +-zeta of f_n by more than 1/sqrt(2) of its
#: peak; housing modes have zeta of 0.01-0.05, so +-10 % holds what it amplifies.
MODE_BAND = 0.1
#: The highest housing-mode frequency the housing-sensor effect fits, Hz.
MAX_HOUSING_HZ = 10_000.0


def resonance_band(peaks: list[Peak], families: tuple[str, ...] = GEAR_PAIR_FAMILIES,
                   half_width: float = MODE_BAND) -> tuple[float, float] | None:
    """The band (low, high), Hz, of relative half-width ``half_width`` around the peak
    frequency that gathers the most unexplained energy of lines of ``families``; None
    when there are no such peaks. The centre is the energy-weighted mean frequency of the
    peaks in the best window."""
    lines = [(p.freq_hz, p.energy_fraction) for p in peaks if p.family in families]
    if not lines:
        return None
    def window(fc):
        return [(f, e) for f, e in lines if abs(f - fc) <= half_width * fc]
    best = max((f for f, _ in lines), key=lambda fc: sum(e for _, e in window(fc)))
    inside = window(best)
    energy = sum(e for _, e in inside)
    fc = sum(f * e for f, e in inside) / energy if energy > 0 else best
    return fc * (1 - half_width), fc * (1 + half_width)


def housing_start(top_hz: float) -> dict[str, float]:
    # a mode a quarter above the analysed band, of a housing's usual damping: from there
    # the polish reaches a mode anywhere above the band; from below the band's top, or
    # from the held fit's start, it stays below it
    return {"f_housing": 1.25 * top_hz, "zeta_housing": 0.05}


def housing_hint(peaks: list[Peak], bin_hz: float, kin: GearKinematics | None) -> dict:
    """The mode's frequency inside the band its signature claims; when that band reaches
    the top of the analysed range, the lines there may be the skirt of a mode above it, so
    the mode may lie anywhere above the band's lower edge."""
    band = resonance_band(peaks)
    if band is None:
        return {}
    if kin is not None and band[1] >= max_band_freq_hz(kin):
        return {"f_housing": (band[0], MAX_HOUSING_HZ)}
    return {"f_housing": band}


#: The largest swing of a shaft's speed once a turn the shaft-swing effect fits, relative
#: to its mean speed: a drive train's torsional swing is a few per cent of it.
MAX_SWING = 0.05
#: The highest torque-ripple frequency the load-fluctuation effect models, Hz.
MAX_RIPPLE_HZ = 20.0


def load_fluctuation(line, freq, kin):
    # a torque ripple is not kinematic: its line (and its mesh sidebands) match no family.
    # It predicts lines only at its own frequency (<= MAX_RIPPLE_HZ) and within that of a
    # mesh harmonic; a non-kinematic line elsewhere (another shaft, the mains, a
    # resonance) is no evidence for it.
    if line is not None:
        return 0.0
    f_mesh = kin.f_mesh_hz
    harmonic = round(freq / f_mesh)
    near_mesh = harmonic >= 1 and abs(freq - harmonic * f_mesh) <= MAX_RIPPLE_HZ
    return 1.0 if freq <= MAX_RIPPLE_HZ or near_mesh else 0.0


def ripple_frequency(peaks: list[Peak], bin_hz: float, f_mesh_hz: float) -> float | None:
    """The torque-ripple frequency the unexplained peaks agree on, Hz, or None.

    A ripple f puts lines at f and its harmonics and modulates the mesh: sidebands at
    n f_mesh +- k f, the higher k the stronger the modulation. Each unexplained peak's
    offset from 0 or from the nearest mesh harmonic (up to half the mesh frequency) is a
    multiple of f; a candidate (every offset <= MAX_RIPPLE_HZ) is supported by the
    unexplained energy of the peaks whose offset is within k bins of its k-th multiple.
    The largest candidate with 90 % of the best support wins: a subharmonic f/2 is
    supported by every peak f is, and a single strong line near a shaft order by itself.
    """
    unexplained = [p for p in peaks if p.family == "unexplained"]
    def offset(f):
        harmonic = round(f / f_mesh_hz)
        return abs(f - harmonic * f_mesh_hz) if harmonic >= 1 else f
    offsets = [(offset(p.freq_hz), p.energy_fraction) for p in unexplained]
    candidates = {o for o, _ in offsets if 0.5 <= o <= MAX_RIPPLE_HZ}
    if not candidates:
        return None
    def support(d):
        # the k-th multiple carries k times the candidate's error of up to half a bin
        return sum(e for o, e in offsets
                   if round(o / d) >= 1 and abs(o - round(o / d) * d) <= round(o / d) * bin_hz)
    best = max(support(d) for d in candidates)
    return max(d for d in candidates if support(d) >= 0.9 * best)


def ripple_hint(name):
    def hint(peaks: list[Peak], bin_hz: float, kin: GearKinematics | None) -> dict:
        """The ripple frequency from the unexplained peaks' spacing, to within a bin."""
        f = ripple_frequency(peaks, bin_hz, kin.f_mesh_hz) if kin is not None else None
        return {} if f is None else {name: (max(0.5, f - bin_hz), f + bin_hz)}
    return hint


def tooth_hint(name, teeth, other_than_zero=False):
    def hint(peaks: list[Peak], bin_hz: float, kin: GearKinematics | None) -> dict:
        """The faulty tooth may be any of the wheel's (one turn of its index), or, when
        ``other_than_zero``, a tooth 1 to N/2 from tooth 0 (the base model's faulty tooth):
        a tooth k and a tooth N - k make patterns that are each other's time reverse, whose
        amplitude spectra are the same but for the mesh's dynamics, so the spectra cannot
        tell them apart and a search over both would choose between them by rounding
        (bench/RESULTS.md, changelog)."""
        if kin is None:
            return {}
        n = float(getattr(kin, teeth))
        return {name: (0.5, n // 2 + 0.5) if other_than_zero else (0.0, n)}
    return hint
