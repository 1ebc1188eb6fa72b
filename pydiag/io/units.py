"""Signal units: convert a channel given in the user's unit to SI, with pint.

``g`` means standard gravity (9.80665 m/s2), as on every accelerometer data sheet, not
gram; everything else is pint's unit language (``m/s**2``, ``mm/s^2``, ``um``, ``in/s``,
``mV`` is refused: a voltage needs the sensor's sensitivity first, :func:`si_factor`'s
``sensitivity``: ``100 mV/g``, ``10.2 mV/(m/s2)``).
"""

from __future__ import annotations

import re
from functools import lru_cache

from pydiag.core.errors import UsageError

#: Names engineers write that pint reads otherwise (pint's ``g`` is gram).
ALIASES = {"g": "standard_gravity", "G": "standard_gravity", "gn": "standard_gravity",
           "m/s2": "m/s**2", "mm/s2": "mm/s**2", "ms-2": "m/s**2"}
#: What a vibration channel can be: acceleration, velocity, displacement.
DIMENSIONS = {"[length] / [time] ** 2": "m/s2", "[length] / [time]": "m/s", "[length]": "m"}


@lru_cache(maxsize=1)
def _registry():
    import pint
    return pint.UnitRegistry()


def dimension(unit: str) -> str | None:
    """The SI unit of what ``unit`` measures ("m/s2", "m/s", "m"), or None: not a vibration
    unit pint knows (a force, a voltage, a unit it cannot read)."""
    try:
        quantity = _registry().Quantity(1.0, _expression(unit))
    except Exception:  # noqa: BLE001
        return None
    return DIMENSIONS.get(str(quantity.dimensionality))


def si_factor(unit: str) -> tuple[float, str]:
    """(factor, SI unit): a value in ``unit`` times factor is the value in the SI unit.

    UsageError for a unit pint does not know or one that is not an acceleration, a
    velocity or a displacement."""
    text = ALIASES.get(unit.strip(), unit.strip())
    try:
        quantity = _registry().Quantity(1.0, text)
    except Exception as err:  # pint's parser raises many kinds on the user's text  # noqa: BLE001
        raise UsageError(f"unknown unit '{unit}' (try g, m/s2, mm/s, um)") from err
    dim = str(quantity.dimensionality)
    if dim not in DIMENSIONS:
        raise UsageError(f"unit '{unit}' is not an acceleration, velocity or displacement "
                         f"(its dimension is {dim})")
    base = quantity.to_base_units()
    return float(base.magnitude), DIMENSIONS[dim]


#: The dimension of a voltage, as pint writes it.
VOLTAGE = "[mass] * [length] ** 2 / [time] ** 3 / [current]"


def _expression(text: str) -> str:
    """``text`` with the engineers' names of :data:`ALIASES` replaced inside it too
    (``100 mV/g``: g is standard gravity)."""
    text = re.sub(r"m/s2\b", "m/s**2", text.strip())
    return re.sub(r"(?<![A-Za-z_])[gG](?![A-Za-z_])", "standard_gravity", text)


def is_voltage(unit: str) -> bool:
    """Whether ``unit`` is a voltage (V, mV): a channel whose level needs a sensitivity."""
    try:
        return str(_registry().Quantity(1.0, _expression(unit)).dimensionality) == VOLTAGE
    except Exception:  # pint's parser raises many kinds on the user's text  # noqa: BLE001
        return False


def sensitivity_factor(unit: str, sensitivity: str) -> tuple[float, str]:
    """(factor, SI unit) of a channel recorded in the voltage ``unit`` from a sensor of
    ``sensitivity`` (voltage per acceleration, velocity or displacement: ``100 mV/g``):
    value in ``unit`` times factor is the measured quantity in SI."""
    if not is_voltage(unit):
        raise UsageError(f"a sensitivity converts volts; the channel's unit '{unit}' is not a "
                         "voltage")
    if "=" in sensitivity:
        raise UsageError(f"cannot read the sensitivity '{sensitivity}': one value, as "
                         "100 mV/g or 10.2 mV/(m/s2)")
    try:
        quantity = _registry().parse_expression(f"({_expression(unit)}) / "
                                                f"({_expression(sensitivity)})")
    except Exception as err:  # noqa: BLE001
        raise UsageError(f"cannot read the sensitivity '{sensitivity}' (try 100 mV/g or "
                         "10.2 mV/(m/s2))") from err
    dim = str(getattr(quantity, "dimensionality", ""))
    if dim not in DIMENSIONS or not float(quantity.to_base_units().magnitude) > 0:
        raise UsageError(f"the sensitivity '{sensitivity}' is not a positive voltage per "
                         "acceleration, velocity or displacement")
    return float(quantity.to_base_units().magnitude), DIMENSIONS[dim]
