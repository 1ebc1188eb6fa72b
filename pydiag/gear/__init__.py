"""Stage 4: gear knowledge: kinematics and their named lines, the paper's features and
classification, its Table 1, the effect catalogue, and the GearDiag conventions."""
