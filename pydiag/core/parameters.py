"""One type for a bounded parameter: what pydiag estimates, and where it goes in the FMU."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pydiag.core.errors import UsageError


@dataclass(frozen=True)
class Parameter:
    """A parameter to estimate within ``[low, high]``.

    Attributes:
        name: the name results use (for GearDiag models, the role in the paper: a_f, ...)
        low, high: bounds of the estimate, finite, ``low < high``
        variable: the FMU variable it sets (default: ``name``)
        scale: FMU value = ``scale`` x estimate (unit conversions such as um -> m)
        periodic: an angle, ``[low, high]`` one turn: never "at a bound"
        step: a discrete quantity (a tooth's index, step 1): an estimate is a multiple of
            ``step`` (:func:`snap`), and a swarm starts a particle at every multiple in
            ``[low, high]`` (:meth:`starts`)
    """

    name: str
    low: float
    high: float
    variable: str | None = None
    scale: float = 1.0
    periodic: bool = False
    step: float | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.low) and math.isfinite(self.high) and self.low < self.high):
            raise UsageError(f"bounds of '{self.name}' must be finite with low < high, "
                             f"got [{self.low}, {self.high}]")
        if not (math.isfinite(self.scale) and self.scale != 0):
            raise UsageError(f"scale of '{self.name}' must be finite and non-zero, "
                             f"got {self.scale}")

    def starts(self) -> list[float]:
        """The multiples of :attr:`step` in ``[low, high]`` (``high`` excluded when periodic:
        it is ``low``); empty without a step."""
        if self.step is None:
            return []
        first, last = math.ceil(self.low / self.step), math.floor(self.high / self.step)
        values = [k * self.step for k in range(first, last + 1)]
        return [v for v in values if not (self.periodic and v >= self.high)]

    @property
    def off(self) -> float:
        """The estimate nearest zero in range: what switches an effect's amplitude off (its
        lower bound for a non-negative amplitude, 0 for a signed coefficient)."""
        return min(max(0.0, self.low), self.high)

    @property
    def fmu_variable(self) -> str:
        return self.variable or self.name

    def fmu_value(self, estimate: float) -> float:
        """The value to set in the FMU for an estimate of this parameter."""
        return self.scale * float(estimate)


def fmu_values(parameters: tuple[Parameter, ...] | list[Parameter],
               estimates: dict[str, float]) -> dict[str, float]:
    """FMU variable -> value for estimates given by parameter name; unknown names pass as is."""
    by_name = {p.name: p for p in parameters}
    out = {}
    for name, value in estimates.items():
        p = by_name.get(name)
        out[p.fmu_variable if p else name] = p.fmu_value(value) if p else float(value)
    return out


def snap(parameters: tuple[Parameter, ...] | list[Parameter], xs: np.ndarray) -> np.ndarray:
    """Positions (rows of estimates in ``parameters``' order) with each stepped parameter
    moved to its nearest multiple of the step in range (a periodic one wrapped into
    ``[low, high)``); a copy."""
    xs = np.array(xs, dtype=float)
    for j, p in enumerate(parameters):
        if p.step is None:
            continue
        column = xs[..., j]
        if p.periodic:
            column = p.low + np.mod(column - p.low, p.high - p.low)
        column = np.round(column / p.step) * p.step
        if p.periodic:
            column = np.where(column >= p.high, column - (p.high - p.low), column)
        else:
            column = np.clip(column, math.ceil(p.low / p.step) * p.step,
                             math.floor(p.high / p.step) * p.step)
        xs[..., j] = column
    return xs
