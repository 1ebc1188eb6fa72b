"""A two-stage gearbox's vibration, written from the shafts' angles (not by any model the
tests fit): each stage's mesh harmonics amplitude-modulated by its two shafts, a local
tooth defect as a short dip of its mesh's amplitude once per turn of the shaft carrying
it, a runout as a once-a-turn swing of its mesh's amplitude and timing, white noise, and
an input speed that wanders by 0.05 %; optionally a tacho on the input shaft, the whole
drive swinging once a turn of a shaft (every angle moved with the input's), a shaft's
unbalance or bend (its 1x, or its 1x and 2x, at the sensor) and a rolling bearing's
defect: impacts at the instants its balls pass the defect, each pass's interval jittered
by the balls' slip, each impact ringing a structural mode, an inner race's impacts
stronger in the load zone once a turn of its shaft. The bearing's defect frequencies are
the simulator's own: from its balls' count and diameters (contact angle 0)."""

from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from pydiag.core.measurement import Measurement

FS, DURATION, INPUT_HZ = 20_000.0, 6.0, 25.0


@dataclass(frozen=True)
class Box:
    """A gearbox as the simulator knows it: its stages' (pinion, gear) teeth from the input,
    stage k+1's pinion on stage k's gear shaft; its kinematics are its own, not pydiag's."""

    name: str
    teeth: tuple[tuple[int, int], ...]

    def turns(self, shaft: int) -> Fraction:
        """Turns of shaft ``shaft`` (0: the input) per turn of the input."""
        out = Fraction(1)
        for pinion, gear in self.teeth[:shaft]:
            out *= Fraction(pinion, gear)
        return out

    def meshes(self, stage: int) -> Fraction:
        """Tooth contacts of stage ``stage`` per turn of the input."""
        return self.teeth[stage][0] * self.turns(stage)


#: 20/64 then 24/54 teeth (whole periods of 16 and 9 pinion turns: a pair model needs one,
#: and a hunting-tooth pair's lasts as many turns as its gear has teeth); its record's
#: channel is "acc".
BOX = Box("two-stage test box", ((20, 64), (24, 54)))
#: A box whose stages repeat together every 10 input turns (18/36 then 20/50 teeth, no
#: hunting tooth), 0.4 s: short enough for a model that simulates both stages.
SHORT_BOX = Box("short-period test box", ((18, 36), (20, 50)))


def gearbox_record(seed: int, faulty_shaft: int | None = None, stage: int = 0,
                   depth: float = 0.8, noise: float = 0.3, box: Box = BOX,
                   also: tuple[tuple[int, int], ...] = (),
                   runout: tuple[tuple[int, int, float], ...] = (),
                   tacho_pulses: int = 0,
                   swing: tuple[tuple[int, float], ...] = (),
                   unbalance: tuple[tuple[int, float], ...] = (),
                   bend: tuple[tuple[int, float], ...] = (),
                   bearing: tuple[tuple[int, str, float], ...] = ()) -> Measurement:
    """A record of ``box`` at 1 % below ``INPUT_HZ``; ``faulty_shaft`` (0 input .. 2
    output) carries a broken tooth of ``depth`` on stage ``stage``'s mesh, and so does each
    (shaft, stage) of ``also``; each (shaft, stage, size) of ``runout``: the gear of that
    shaft on that stage runs out, its mesh's amplitude swinging by ``size`` and its timing
    by ``size`` radians of the mesh once a turn; ``tacho_pulses`` > 0: a channel "tacho" of
    that many pulses a turn of the input; each (shaft, size) of ``swing``: the input's angle,
    and every angle after it, swings by ``size`` turns of the input once a turn of that
    shaft; each (shaft, size) of ``unbalance``: that shaft's 1x at the sensor, of amplitude
    ``size``, and of ``bend`` its 1x and 2x; each (shaft, defect, size) of ``bearing``: the
    :data:`BEARING` on that shaft has a defect ("outer" or "inner") whose impacts ring at
    the sensor with peak ``size``."""
    rng = np.random.default_rng(seed)
    n = int(FS * DURATION)
    t = np.arange(n) / FS
    speed = INPUT_HZ * 0.99 * (1 + 0.0005 * np.sin(2 * np.pi * 0.2 * t + seed))
    revs = np.cumsum(speed) / FS
    for shaft, size in swing:
        revs = revs + size * np.sin(2 * np.pi * float(box.turns(shaft)) * revs + 1.0)
    x = np.zeros(n)
    for k in range(len(box.teeth)):
        order = float(box.meshes(k))
        gain = np.ones(n)
        for shaft in (k, k + 1):
            gain += 0.1 * np.cos(2 * np.pi * float(box.turns(shaft)) * revs + shaft)
        faults = ((faulty_shaft, stage),) if faulty_shaft is not None else ()
        for shaft, on_stage in faults + also:
            if on_stage == k:
                angle = np.mod(float(box.turns(shaft)) * revs, 1.0)
                gain -= depth * np.exp(-0.5 * ((angle - 0.3) / 0.01) ** 2)
        timing = np.zeros(n)
        for shaft, on_stage, size in runout:
            if on_stage == k:
                turn = 2 * np.pi * float(box.turns(shaft)) * revs
                gain += size * np.cos(turn)
                timing += size * np.sin(turn)
        x += gain * sum(np.cos(2 * np.pi * h * order * revs + h * timing + h) / h
                        for h in (1, 2, 3))
    for shaft, size, second in ([(k, a, 0.0) for k, a in unbalance]
                                + [(k, a, 0.8) for k, a in bend]):
        turn = 2 * np.pi * float(box.turns(shaft)) * revs
        x += size * (np.cos(turn + 0.7) + second * np.cos(2 * turn + 2.1))
    for shaft, defect, size in bearing:
        x += _bearing_impacts(float(box.turns(shaft)) * revs, defect, size, rng)
    channels = {"acc": x + noise * rng.standard_normal(n)}
    if tacho_pulses:
        channels["tacho"] = (np.mod(tacho_pulses * revs, 1.0) < 0.5).astype(float)
    return Measurement(channels, FS)


#: A rolling bearing as the simulator knows it: 9 balls of 7.9 mm on a 39 mm pitch circle,
#: contact angle 0; a structural mode at 7 kHz, damping 5 %, rung by each impact.
BEARING = dict(n_balls=9, ball_mm=7.9, pitch_mm=39.0, mode_hz=7000.0, zeta=0.05, slip=0.01)


#: The box's shafts as its description names them, input first.
SHAFT_NAMES = ("input", "intermediate", "output")


def described(box: Box) -> dict:
    """The box as its user would write it in a machine file (plain data, read by whatever
    reads machine files): its teeth, and a bearing on each shaft of the geometry its
    maker's sheet gives, named "<shaft> bearing"."""
    return {"name": box.name, "shafts": list(SHAFT_NAMES[:len(box.teeth) + 1]),
            "stages": [{"pinion_teeth": p, "gear_teeth": g} for p, g in box.teeth],
            "bearings": [{"name": f"{shaft} bearing", "shaft": shaft,
                          "n_balls": BEARING["n_balls"], "ball_diameter_mm": BEARING["ball_mm"],
                          "pitch_diameter_mm": BEARING["pitch_mm"]}
                         for shaft in SHAFT_NAMES[:len(box.teeth) + 1]]}


def cage_turns_per_turn() -> float:
    """The cage's turns a turn of the shaft: the balls' centres move at half the speed of
    the inner race's contact, (1 - d/D)/2 of the shaft's."""
    return (1 - BEARING["ball_mm"] / BEARING["pitch_mm"]) / 2


def bearing_passes_per_turn(defect: str) -> float:
    """How many times a defect strikes in a turn of the shaft. A race's: the outer race
    (fixed) meets the n balls n (1 - d/D)/2 times a turn, the inner race (turning with the
    shaft) n (1 + d/D)/2 times. A ball's: it meets a race twice a turn about its own
    axis (the outer, then the inner), and it turns (D + d)/d times a turn of the cage
    against the fixed outer race, whose surface passes it."""
    ratio = BEARING["ball_mm"] / BEARING["pitch_mm"]
    if defect == "ball":
        return 2 * cage_turns_per_turn() * (1 + ratio) / ratio
    sign = {"outer": -1.0, "inner": 1.0}[defect]
    return BEARING["n_balls"] / 2 * (1 + sign * ratio)


def _bearing_impacts(turns: np.ndarray, defect: str, size: float,
                     rng: np.random.Generator) -> np.ndarray:
    """The impacts of a defect on a bearing whose shaft has turned ``turns`` at each
    sample: one each time the passes (a ball every 1/passes of a turn, jittered by the
    slip) are due, ringing the mode; an inner race's strongest at the bottom of its turn, a
    ball's at the bottom of the cage's."""
    passes = bearing_passes_per_turn(defect)
    n = turns.size
    due = np.arange(1, int(turns[-1] * passes))
    due = (due + BEARING["slip"] * rng.standard_normal(due.size)) / passes
    at = np.searchsorted(turns, due)
    at = at[(at > 0) & (at < n)]
    strength = np.ones(at.size)
    if defect == "inner":
        strength = 0.6 + 0.4 * np.cos(2 * np.pi * turns[at])
    if defect == "ball":  # the inner strike through the ball's other contact is weaker,
        # and the cage carries the ball through the load zone once a turn of its own
        strength = (np.where(np.arange(at.size) % 2 == 0, 1.0, 0.6)
                    * (0.6 + 0.4 * np.cos(2 * np.pi * cage_turns_per_turn() * turns[at])))
    w = 2 * np.pi * BEARING["mode_hz"]
    ring_t = np.arange(int(8 / (BEARING["zeta"] * w) * FS)) / FS
    ring = np.exp(-BEARING["zeta"] * w * ring_t) * np.sin(w * ring_t)
    pulses = np.zeros(n)
    np.add.at(pulses, at, strength)
    return size * np.convolve(pulses, ring)[:n]
