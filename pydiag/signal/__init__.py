"""Stage 1: spectra, noise floors, local maxima and measurement noise: arrays in, arrays out."""
