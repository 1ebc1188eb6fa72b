"""Stage 0: the types every other stage shares (errors, bounded parameters, measurements)."""
