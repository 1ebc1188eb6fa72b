"""Stage 7: the model-improvement loop: compare a fitted model with a measurement,
discover the missing effect, check exported FMUs against goldens, keep the run history,
render the report."""
