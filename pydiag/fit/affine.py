"""The fit of parameters the model's outputs are affine in.

When every output is ``y(a) = y(low) + sum_j (a_j - low_j) / (high_j - low_j) * (y_j -
y(low))``, with ``y_j`` the outputs with parameter j at its upper bound and the others at
their lower ones (a bearing's strike amplitude, a shaft's lines at its orders, added to
what the sensor sees of the mesh), one simulation more than there are parameters gives
the outputs at every point of the box; the Eq. (12) error is then minimised over it with
no further simulation: a bounded scalar search (Brent's method) and both ends for one
parameter, bounded least squares (trust-region reflective) for several.
"""

from __future__ import annotations

import numpy as np

from pydiag.fit.problem import FitProblem

#: The search stops within this share of a parameter's range.
XTOL = 1e-4


def fit_affine(problem: FitProblem) -> tuple[dict[str, float], float]:
    """(value of each of ``problem``'s parameters, the root-sum-square Eq. (12) error
    there), for a model whose outputs are affine in them (the caller knows they are)."""
    params = problem.parameters
    low = np.array([p.low for p in params])
    with problem.spec.open() as plant:
        y_low = problem.simulate(plant, low)
        slopes = []
        for j, p in enumerate(params):
            x = low.copy()
            x[j] = p.high
            slopes.append(problem.simulate(plant, x) - y_low)

    def outputs(u: np.ndarray) -> np.ndarray:  # u: each parameter's place in its range, 0..1
        return y_low + sum(uj * s for uj, s in zip(u, slopes))

    def error(u: np.ndarray) -> float:
        return float(np.linalg.norm(problem.residuals_of(outputs(u))))

    import scipy.optimize  # here: importing it takes 0.3 s of every command's start

    if len(params) == 1:
        found = scipy.optimize.minimize_scalar(lambda u: error(np.array([u])), bounds=(0.0, 1.0),
                                               method="bounded", options={"xatol": XTOL})
        candidates = [np.array([float(found.x)]), np.zeros(1), np.ones(1)]
    else:  # from the middle of the box and from its lower corner (every line off)
        candidates = [scipy.optimize.least_squares(
            lambda u: problem.residuals_of(outputs(u)), u0, bounds=(0.0, 1.0), xtol=XTOL).x
            for u0 in (np.full(len(params), 0.5), np.full(len(params), XTOL))]
    u = min(candidates, key=error)
    return {p.name: p.low + uj * (p.high - p.low) for p, uj in zip(params, u)}, error(u)
