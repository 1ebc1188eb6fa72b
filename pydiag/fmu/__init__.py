"""Stage 3: running FMUs: safe extraction, model descriptions, the plant, the compiled
engine, isolated worker processes, inspection. Knows nothing of gears."""
