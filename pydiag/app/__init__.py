"""Stage 8: the command line (parse, call the library, print) and batch diagnosis."""
