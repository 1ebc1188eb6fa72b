"""Gear-pair kinematics: the characteristic frequencies of a pinion/gear mesh, and the
machine facts beside the pair that put lines in its spectrum (another shaft, a bearing, the
other stages of its gearbox)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from pydiag.core.errors import UsageError

#: The shaft-order sidebands of a mesh harmonic that are its pair's own lines.
MESH_SIDEBANDS = 6

@dataclass(frozen=True)
class Bearing:
    """A rolling bearing: its geometry, the shaft it is on by name (a gear pair's bearing:
    "pinion" or "gear"; a machine's: the machine file's shaft) and its own name (a
    machine's bearings are judged by it)."""

    n_balls: int
    ball_diameter_m: float
    pitch_diameter_m: float
    contact_angle_rad: float = 0.0
    shaft: str = "pinion"
    name: str = ""

    def frequencies(self, f_shaft_hz: float) -> dict[str, float]:
        """BPFO, BPFI, BSF, FTF in Hz for an inner race turning at f_shaft (outer fixed)."""
        r = self.ball_diameter_m / self.pitch_diameter_m * math.cos(self.contact_angle_rad)
        return {"bpfo": self.n_balls / 2 * f_shaft_hz * (1 - r),
                "bpfi": self.n_balls / 2 * f_shaft_hz * (1 + r),
                "bsf": self.pitch_diameter_m / (2 * self.ball_diameter_m) * f_shaft_hz * (1 - r * r),
                "ftf": f_shaft_hz / 2 * (1 - r)}


def crowded(n_balls: int, ball_diameter_mm: float, pitch_diameter_mm: float) -> str:
    """Why ``n_balls`` balls of ``ball_diameter_mm`` cannot sit on a pitch circle of
    ``pitch_diameter_mm``: neighbours' centres, a chord ``pitch * sin(pi / n_balls)``
    apart, closer than a ball; "" when they fit."""
    if n_balls < 2:
        return ""
    room = pitch_diameter_mm * math.sin(math.pi / n_balls)
    if room > ball_diameter_mm:
        return ""
    most = int(math.pi / math.asin(min(1.0, ball_diameter_mm / pitch_diameter_mm)))
    return (f"{n_balls} balls of {ball_diameter_mm:g} mm do not fit on a pitch circle of "
            f"{pitch_diameter_mm:g} mm: neighbours' centres are {room:.3g} mm apart, less "
            f"than a ball (at most {max(most, 1)} balls of that size)")


@dataclass(frozen=True)
class OtherStage:
    """Another stage of the pair's gearbox: its teeth, its shafts' names, and its pinion
    shaft's speed over the pair's pinion speed."""

    name: str
    pinion_teeth: int
    gear_teeth: int
    pinion_ratio: float
    pinion_shaft: str
    gear_shaft: str

    @property
    def gear_ratio(self) -> float:
        """Its gear shaft's speed over the pair's pinion speed."""
        return self.pinion_ratio * self.pinion_teeth / self.gear_teeth


@dataclass(frozen=True)
class OtherShaft:
    """A shaft of the gearbox that is neither of the pair's: its name and its speed over
    the pair's pinion speed."""

    name: str
    ratio: float


@dataclass(frozen=True)
class Surroundings:
    """The rest of a gearbox around one of its stages: what puts lines in the stage's
    spectrum that are none of the pair's own (every speed relative to the pair's pinion,
    so they hold at any speed). Not a machine: a stage's view of the rest of it,
    made by :meth:`pydiag.gear.machine.Machine.stage_kinematics`.

    ``fundamental_order``: set when the model simulates every stage (a machine model,
    :mod:`pydiag.loop.machine_model`): the machine's fundamental frequency over the pair's
    pinion speed, with which every stage's lines repeat; the pair's kinematics then have
    the machine's period and analyse every stage's bands. None: the pair's own.
    ``bearings``: the gearbox's bearings but the pair's own, each on a shaft of the
    machine by name: one of ``shafts`` or of ``pair_shafts`` (the pair's pinion and gear
    shafts' names in the machine)."""

    stages: tuple[OtherStage, ...] = ()
    shafts: tuple[OtherShaft, ...] = ()
    bearings: tuple[Bearing, ...] = ()
    fundamental_order: float | None = None
    pair_shafts: tuple[str, str] = ("pinion", "gear")


@dataclass(frozen=True)
class GearKinematics:
    """Teeth counts and pinion speed; every frequency of the pair follows from these three
    numbers. A machine with another shaft (a second stage's, a motor's behind a first
    stage) adds its speed ratio: that shaft's orders are kinematic lines too.

    Attributes:
        n_pinion: pinion teeth (Np)
        n_gear: gear teeth (Ng)
        f_pinion_hz: pinion shaft speed
        other_shaft_ratio: the other shaft's speed over the pinion's, or None: no other
            shaft known. A motor shaft whose z1 teeth drive z2 on the pinion's shaft: z2/z1;
            a second stage whose z3 teeth on the gear's shaft drive z4: Np/Ng * z3/z4
        bearing: a rolling bearing's geometry (its lines are kinematic, and a bearing
            effect's model takes it), or None: none known
        gear_bearing: a bearing on the gear's shaft that the pair's gear-bearing effects
            model (in a machine, one on the shaft no stage's pinion turns: the output's),
            or None
        surroundings: the other stages, shafts and bearings of the pair's gearbox (their lines
            are kinematic; no effect of the pair models them), or None: a pair alone
    """

    n_pinion: int
    n_gear: int
    f_pinion_hz: float
    other_shaft_ratio: float | None = None
    bearing: Bearing | None = None
    surroundings: Surroundings | None = None
    gear_bearing: Bearing | None = None

    def __post_init__(self) -> None:
        if self.n_pinion < 1 or self.n_gear < 1:
            raise UsageError(f"teeth counts must be positive, got Np={self.n_pinion}, "
                             f"Ng={self.n_gear}")
        if not self.f_pinion_hz > 0:
            raise UsageError(f"pinion speed must be positive, got {self.f_pinion_hz} Hz")
        ratio = self.other_shaft_ratio
        if ratio is not None and not (math.isfinite(ratio) and ratio > 0):
            raise UsageError(f"the other shaft's speed ratio must be positive, got {ratio}")

    def shaft_hz(self, shaft: str) -> float:
        """The speed of the shaft called ``shaft``: the pinion's or the gear's ("pinion",
        "gear", or their names in the machine), or another shaft of the machine's."""
        names = self.surroundings.pair_shafts if self.surroundings is not None else ()
        if shaft in ("pinion", *names[:1]):
            return self.f_pinion_hz
        if shaft in ("gear", *names[1:]):
            return self.f_pinion_hz * self.n_pinion / self.n_gear
        other = next((s for s in self.surroundings.shafts if s.name == shaft), None) \
            if self.surroundings is not None else None
        if other is None:
            raise UsageError(f"no shaft called {shaft!r} beside the pair")
        return other.ratio * self.f_pinion_hz

    @property
    def pair(self) -> "GearKinematics":
        """The gear pair alone: what a pair model's parameters say (no other shaft, no
        bearing)."""
        return GearKinematics(self.n_pinion, self.n_gear, self.f_pinion_hz)

    @property
    def f_mesh_hz(self) -> float:
        return self.n_pinion * self.f_pinion_hz

    @property
    def f_gear_hz(self) -> float:
        return self.f_mesh_hz / self.n_gear

    @property
    def f_other_shaft_hz(self) -> float | None:
        """The other shaft's speed, or None when there is none known."""
        ratio = self.other_shaft_ratio
        return None if ratio is None else ratio * self.f_pinion_hz

    @property
    def n_assembly_phases(self) -> int:
        """N_ap = lcm(Np, Ng)/Np: pinion turns until the same tooth pair meets again."""
        return math.lcm(self.n_pinion, self.n_gear) // self.n_pinion

    @property
    def f_assembly_hz(self) -> float:
        """Geometric-TE (assembly-phase) frequency of the paper, f_mesh / N_ap."""
        return self.f_mesh_hz / self.n_assembly_phases

    @property
    def f_hunting_hz(self) -> float:
        """Hunting-tooth frequency f_mesh / lcm(Np, Ng): the fundamental of the whole mesh."""
        return self.f_mesh_hz / math.lcm(self.n_pinion, self.n_gear)

    @property
    def modelled_machine(self) -> bool:
        """Whether the model simulates every stage of the pair's machine (``surroundings``'
        ``fundamental_order`` is set)."""
        return self.surroundings is not None and self.surroundings.fundamental_order is not None

    @property
    def period_s(self) -> float:
        """Fundamental period: every shaft, tooth and assembly-phase line is a harmonic of
        1/period (of every stage's, for a modelled machine)."""
        if self.modelled_machine:
            return 1.0 / (self.surroundings.fundamental_order * self.f_pinion_hz)
        return 1.0 / self.f_hunting_hz

    def stages(self) -> tuple["GearKinematics", ...]:
        """The pair, then every other stage of its machine as a pair at its own speed."""
        others = self.surroundings.stages if self.surroundings is not None else ()
        return (self.pair,) + tuple(GearKinematics(o.pinion_teeth, o.gear_teeth,
                                                   o.pinion_ratio * self.f_pinion_hz)
                                    for o in others)

    def mesh_lines_hz(self, max_freq_hz: float,
                      n_sidebands: int = MESH_SIDEBANDS) -> tuple[float, ...]:
        """The mesh harmonics and their sidebands 1 to ``n_sidebands`` at both shafts'
        orders, in (0, ``max_freq_hz``], sorted."""
        lines = {h * self.f_mesh_hz + k * f
                 for h in range(1, int(max_freq_hz / self.f_mesh_hz) + 2)
                 for f in (self.f_pinion_hz, self.f_gear_hz)
                 for k in range(-n_sidebands, n_sidebands + 1)}
        return tuple(sorted(f for f in lines if 0 < f <= max_freq_hz))
