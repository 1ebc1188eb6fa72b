"""Signal units: convert a channel given in the user's unit to SI, with pint.

``g`` means standard gravity (9.80665 m/s2), as on every accelerometer data sheet, not
gram; everything else is pint's unit language (``m/s**2``, ``mm/s^2``, ``um``, ``in/s``,
``mV`` is refused: a voltage needs the sensor's sensitivity first).
"""

from __future__ import annotations

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
