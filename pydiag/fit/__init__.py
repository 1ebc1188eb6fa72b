"""Stage 6: fitting: the weighted spectral error (Eq. 12), the fit problem, the swarm, the
estimator."""
