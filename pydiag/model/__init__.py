"""Stage 5: what an FMU is to pydiag (adapters, the GearDiag defaults) and records made
from it."""
