"""What an FMU declares: its model description, its variables, and which can be set.

:func:`settability` is the one rule for "can this variable be set, and when" (FMI 2.0 and
3.0); the plant, adapters and ``pydiag inspect`` all ask it.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import fmpy
from fmpy.model_description import ModelDescription

from pydiag.core.errors import PlantError, PydiagError


@dataclass(frozen=True)
class FmuVariable:
    name: str
    causality: str
    variability: str | None
    start: float | None
    unit: str | None
    description: str | None


def _float(value) -> float | None:
    try:
        return float(value)
    except (TypeError, ValueError):
        return None


def read_model_description(fmu_path: str | Path) -> tuple[ModelDescription, list[str]]:
    """The model description and fmpy's validation problems (as warnings, not errors).

    Many vendor FMUs fail fmpy's schema validation yet run, so its complaints are
    returned for the caller to show; only an unreadable description is an error. A file
    is read once while it is unchanged (its size and modification time): treat the
    description as read-only.
    """
    fmu_path = Path(fmu_path)
    if not fmu_path.is_file():
        raise PlantError(f"no such FMU: {fmu_path}")
    stat = fmu_path.stat()
    md, warnings = _read(str(fmu_path.resolve()), stat.st_size, stat.st_mtime_ns)
    return md, list(warnings)


@functools.lru_cache(maxsize=32)
def _read(fmu_path: str, size: int, mtime_ns: int) -> tuple[ModelDescription, tuple[str, ...]]:
    warnings: list[str] = []
    try:
        md = fmpy.read_model_description(str(fmu_path), validate=True)
    except Exception as err:  # fmpy raises plain Exception with the problems listed
        warnings = [line.strip("- ").strip() for line in str(err).splitlines()[1:] if line.strip()]
        warnings = warnings or [str(err)]
        try:
            md = fmpy.read_model_description(str(fmu_path), validate=False)
        except Exception as err2:
            raise PlantError(f"cannot read {fmu_path}: {err2}") from err2
    return md, tuple(warnings)


def variables_of(model_description: ModelDescription) -> dict[str, FmuVariable]:
    return {v.name: FmuVariable(v.name, v.causality, v.variability, _float(v.start), v.unit,
                                v.description)
            for v in model_description.modelVariables}


def outputs_of(model_description: ModelDescription) -> list[str]:
    return [v.name for v in model_description.modelVariables if v.causality == "output"]


def settability(causality: str, variability: str | None) -> tuple[str, str]:
    """When a variable can be set ("before init", "any time" or "no") and why, per FMI."""
    if variability == "constant":
        return "no", "constant: fixed when the FMU was exported"
    if causality == "parameter":
        if variability == "tunable":
            return "any time", "tunable parameter: before initialisation and at events/steps"
        return "before init", "fixed parameter: only before initialisation (pydiag does so)"
    if causality == "input":
        return "any time", "input"
    if causality == "calculatedParameter":
        return "no", ("calculatedParameter: the FMU computes it from other parameters, so "
                      "setting it has no effect; set those instead")
    if causality == "independent":
        return "no", "the independent variable (time)"
    return "no", f"causality '{causality}': computed by the FMU; only parameters and inputs can be set"


def require_settable(variables: dict[str, FmuVariable], name: str, what: str,
                     error: type[PydiagError] = PlantError) -> None:
    """Raise ``error`` naming ``what`` unless ``name`` exists and can be set before init."""
    v = variables.get(name)
    if v is None:
        raise error(f"{what} '{name}' is not in the FMU")
    when, why = settability(v.causality, v.variability)
    if when == "no":
        raise error(f"{what} '{name}' cannot be set: {why}")
