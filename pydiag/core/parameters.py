"""One type for a bounded parameter: what pydiag estimates, and where it goes in the FMU."""

from __future__ import annotations

import math
from dataclasses import dataclass

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
    """

    name: str
    low: float
    high: float
    variable: str | None = None
    scale: float = 1.0
    periodic: bool = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.low) and math.isfinite(self.high) and self.low < self.high):
            raise UsageError(f"bounds of '{self.name}' must be finite with low < high, "
                             f"got [{self.low}, {self.high}]")
        if not (math.isfinite(self.scale) and self.scale != 0):
            raise UsageError(f"scale of '{self.name}' must be finite and non-zero, "
                             f"got {self.scale}")

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
