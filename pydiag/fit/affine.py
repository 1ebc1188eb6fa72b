"""The fit of one parameter the model's outputs are affine in.

When every output is ``y(a) = y(low) + (a - low) / (high - low) * (y(high) - y(low))``
(a bearing's strike amplitude added to what the sensor sees of the mesh), two
simulations give the outputs at every value of the parameter; its Eq. (12) error is then
minimised over the range on those two, with no further simulation (a bounded scalar
search, Brent's method, and both ends).
"""

from __future__ import annotations

import numpy as np
import scipy.optimize

from pydiag.core.errors import UsageError
from pydiag.fit.problem import FitProblem

#: The search stops within this share of the parameter's range.
XTOL = 1e-4


def fit_affine(problem: FitProblem) -> tuple[dict[str, float], float]:
    """(value of ``problem``'s one parameter, the root-sum-square Eq. (12) error there), for
    a model whose outputs are affine in that parameter (the caller knows they are)."""
    if len(problem.parameters) != 1:
        raise UsageError("fit_affine fits one parameter, not "
                         f"{len(problem.parameters)}")
    p = problem.parameters[0]
    with problem.spec.open() as plant:
        y_low = problem.simulate(plant, np.array([p.low]))
        y_high = problem.simulate(plant, np.array([p.high]))
    slope = y_high - y_low

    def error(u: float) -> float:  # u: the parameter's place in its range, 0..1
        return float(np.linalg.norm(problem.residuals_of(y_low + u * slope)))

    found = scipy.optimize.minimize_scalar(error, bounds=(0.0, 1.0), method="bounded",
                                           options={"xatol": XTOL})
    u, cost = min(((float(found.x), float(found.fun)), (0.0, error(0.0)), (1.0, error(1.0))),
                  key=lambda t: t[1])
    return {p.name: p.low + u * (p.high - p.low)}, cost
