"""A two-stage gearbox's vibration, written from the shafts' angles (not by any model the
tests fit): each stage's mesh harmonics amplitude-modulated by its two shafts, a local
tooth defect as a short dip of its mesh's amplitude once per turn of the shaft carrying
it, a runout as a once-a-turn swing of its mesh's amplitude and timing, white noise, and
an input speed that wanders by 0.05 %; optionally a tacho on the input shaft, and the whole
drive swinging once a turn of a shaft (every angle moved with the input's)."""

import numpy as np

from pydiag.core.measurement import Measurement
from pydiag.gear.machine_file import machine_from_dict

FS, DURATION, INPUT_HZ = 20_000.0, 6.0, 25.0
#: 20/64 then 24/54 teeth (whole periods of 16 and 9 pinion turns: a pair model needs one,
#: and a hunting-tooth pair's lasts as many turns as its gear has teeth); no sensor or
#: tacho described: the record's channel is "acc".
MACHINE = machine_from_dict({"name": "two-stage test box",
                             "stages": [{"pinion_teeth": 20, "gear_teeth": 64},
                                        {"pinion_teeth": 24, "gear_teeth": 54}]})


#: A box whose stages repeat together every 10 input turns (18/36 then 20/50 teeth, no
#: hunting tooth), 0.4 s: short enough for a model that simulates both stages.
SHORT_MACHINE = machine_from_dict({"name": "short-period test box",
                                   "stages": [{"pinion_teeth": 18, "gear_teeth": 36},
                                              {"pinion_teeth": 20, "gear_teeth": 50}]})


def gearbox_record(seed: int, faulty_shaft: int | None = None, stage: int = 0,
                   depth: float = 0.8, noise: float = 0.3, machine=MACHINE,
                   also: tuple[tuple[int, int], ...] = (),
                   runout: tuple[tuple[int, int, float], ...] = (),
                   tacho_pulses: int = 0,
                   swing: tuple[tuple[int, float], ...] = ()) -> Measurement:
    """A record of ``machine`` at 1 % below ``INPUT_HZ``; ``faulty_shaft`` (0 input .. 2
    output) carries a broken tooth of ``depth`` on stage ``stage``'s mesh, and so does each
    (shaft, stage) of ``also``; each (shaft, stage, size) of ``runout``: the gear of that
    shaft on that stage runs out, its mesh's amplitude swinging by ``size`` and its timing
    by ``size`` radians of the mesh once a turn; ``tacho_pulses`` > 0: a channel "tacho" of
    that many pulses a turn of the input; each (shaft, size) of ``swing``: the input's angle,
    and every angle after it, swings by ``size`` turns of the input once a turn of that
    shaft."""
    MACHINE = machine  # noqa: N806 (the box the record is of)
    rng = np.random.default_rng(seed)
    n = int(FS * DURATION)
    t = np.arange(n) / FS
    speed = INPUT_HZ * 0.99 * (1 + 0.0005 * np.sin(2 * np.pi * 0.2 * t + seed))
    revs = np.cumsum(speed) / FS
    for shaft, size in swing:
        revs = revs + size * np.sin(2 * np.pi * float(MACHINE.shaft_ratio(shaft)) * revs + 1.0)
    x = np.zeros(n)
    for k in range(len(MACHINE.stages)):
        order = float(MACHINE.mesh_order(k))
        gain = np.ones(n)
        for shaft in (k, k + 1):
            gain += 0.1 * np.cos(2 * np.pi * float(MACHINE.shaft_ratio(shaft)) * revs + shaft)
        faults = ((faulty_shaft, stage),) if faulty_shaft is not None else ()
        for shaft, on_stage in faults + also:
            if on_stage == k:
                angle = np.mod(float(MACHINE.shaft_ratio(shaft)) * revs, 1.0)
                gain -= depth * np.exp(-0.5 * ((angle - 0.3) / 0.01) ** 2)
        timing = np.zeros(n)
        for shaft, on_stage, size in runout:
            if on_stage == k:
                turn = 2 * np.pi * float(MACHINE.shaft_ratio(shaft)) * revs
                gain += size * np.cos(turn)
                timing += size * np.sin(turn)
        x += gain * sum(np.cos(2 * np.pi * h * order * revs + h * timing + h) / h
                        for h in (1, 2, 3))
    channels = {"acc": x + noise * rng.standard_normal(n)}
    if tacho_pulses:
        channels["tacho"] = (np.mod(tacho_pulses * revs, 1.0) < 0.5).astype(float)
    return Measurement(channels, FS)
