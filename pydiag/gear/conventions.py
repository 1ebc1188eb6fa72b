"""The conventions of the GearDiag Modelica models, in one place.

Our FMUs need no adapter because they follow these: the fault parameters carry the
paper's names, the sensor channels are named as the outputs, and the kinematics come
from the parameters ``Np``, ``Ng`` and ``f_pinion``.
"""

from __future__ import annotations

from pydiag.core.parameters import Parameter
from pydiag.core.errors import UsageError
from pydiag.gear.kinematics import GearKinematics

#: The paper's four fault parameters (a0 = 0.1 is known) with their physical ranges.
#: a_f starts at a0: a fault raises the faulty tooth's amplitude (Table 1), and line
#: magnitudes see |a_f - a0|, so a_f < a0 would hold a false twin of every minimum
#: (measured: case 2 converged to a_f = 0.02 instead of 0.2 with a lower bound of 0).
GEAR_FAULT_PARAMETERS = (
    Parameter("a_f", 0.1, 0.9),
    Parameter("f_f", 0.0, 0.95),
    Parameter("f_ate", 0.0, 1.0),
    Parameter("f_dte", 0.0, 1.0),
)

#: The stiffness variation of the healthy teeth (GearPair's ``a0``, 0.1 in the paper's
#: cases). Fitted with a record's level (see :mod:`pydiag.fit.problem`): with the level
#: free, only the faulty tooth's variation relative to the others is identifiable.
HEALTHY_TOOTH = Parameter("a0", 0.02, 0.9)

#: Parameter names that feed the classification (any other estimate is only reported).
CLASSIFIED_PARAMETERS = tuple(p.name for p in GEAR_FAULT_PARAMETERS)

#: GearKinematics field -> the GearDiag model parameter that holds it.
KINEMATIC_PARAMETERS = {"n_pinion": "Np", "n_gear": "Ng", "f_pinion_hz": "f_pinion"}

#: Sensor channels of the GearDiag models: acceleration for mesh content, displacement
#: for the once-per-turn transmission error (docs/method.md has the measurement).
DEFAULT_SENSORS = ("acc", "disp")


def default_sensors(outputs: list[str]) -> tuple[str, ...]:
    """The GearDiag sensors among an FMU's outputs, else every output."""
    chosen = tuple(s for s in DEFAULT_SENSORS if s in outputs)
    return chosen or tuple(outputs)


def kinematics_from(values: dict[str, float]) -> GearKinematics | None:
    """Kinematics from GearDiag parameter values (Np, Ng, f_pinion); None if one is missing."""
    names = KINEMATIC_PARAMETERS
    if any(values.get(n) is None for n in names.values()):
        return None
    for name in (names["n_pinion"], names["n_gear"]):
        if abs(values[name] - round(values[name])) > 1e-9:
            raise UsageError(f"{name} = {values[name]:g}: a number of teeth must be whole")
    return GearKinematics(int(round(values[names["n_pinion"]])),
                          int(round(values[names["n_gear"]])),
                          float(values[names["f_pinion_hz"]]))


def kinematics_to_dict(kin: GearKinematics) -> dict[str, float]:
    """The GearDiag parameter values of ``kin`` (as stored in record and golden metadata)."""
    return {KINEMATIC_PARAMETERS["n_pinion"]: kin.n_pinion,
            KINEMATIC_PARAMETERS["n_gear"]: kin.n_gear,
            KINEMATIC_PARAMETERS["f_pinion_hz"]: kin.f_pinion_hz}
