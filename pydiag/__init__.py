"""pydiag: diagnose gear faults by fitting an FMU's fault parameters to a vibration spectrum."""

from pydiag.kinematics import GearKinematics
from pydiag.plant import FmuPlant, PlantError

__all__ = ["GearKinematics", "FmuPlant", "PlantError"]
