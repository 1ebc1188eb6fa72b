"""Stage 7: the model-improvement loop: compare a fitted model with a measurement,
discover the missing effect, write it into the machine's model, keep the run history,
render the report."""
