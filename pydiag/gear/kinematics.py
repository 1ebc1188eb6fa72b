"""Gear-pair kinematics: the characteristic frequencies of a pinion/gear mesh."""

from __future__ import annotations

import math
from dataclasses import dataclass

from pydiag.core.errors import UsageError


@dataclass(frozen=True)
class GearKinematics:
    """Teeth counts and pinion speed; every frequency follows from these three numbers.

    Attributes:
        n_pinion: pinion teeth (Np)
        n_gear: gear teeth (Ng)
        f_pinion_hz: pinion shaft speed
    """

    n_pinion: int
    n_gear: int
    f_pinion_hz: float

    def __post_init__(self) -> None:
        if self.n_pinion < 1 or self.n_gear < 1:
            raise UsageError(f"teeth counts must be positive, got Np={self.n_pinion}, "
                             f"Ng={self.n_gear}")
        if not self.f_pinion_hz > 0:
            raise UsageError(f"pinion speed must be positive, got {self.f_pinion_hz} Hz")

    @property
    def f_mesh_hz(self) -> float:
        return self.n_pinion * self.f_pinion_hz

    @property
    def f_gear_hz(self) -> float:
        return self.f_mesh_hz / self.n_gear

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
    def period_s(self) -> float:
        """Fundamental period: every shaft, tooth and assembly-phase line is a harmonic of 1/period."""
        return 1.0 / self.f_hunting_hz
