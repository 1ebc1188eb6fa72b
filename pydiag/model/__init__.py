"""Stage 5: what an FMU is to pydiag (adapters, the GearDiag defaults), records made from
it, and its regression check against golden records."""
