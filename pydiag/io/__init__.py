"""Stage 2: files the user owns: measurement records in, results out."""
