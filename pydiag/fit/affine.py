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
    residuals = _residuals(problem, y_low, np.array(slopes))

    def error(u: np.ndarray) -> float:
        return float(np.linalg.norm(residuals(u)))

    import scipy.optimize  # here: importing it takes 0.3 s of every command's start

    if len(params) == 1:
        found = scipy.optimize.minimize_scalar(lambda u: error(np.array([u])), bounds=(0.0, 1.0),
                                               method="bounded", options={"xatol": XTOL})
        candidates = [np.array([float(found.x)]), np.zeros(1), np.ones(1)]
    else:  # from the middle of the box, from where every parameter is off, and from each
        # parameter's own best with the others off (a line added to a weak one of another
        # phase first lowers its amplitude: from off, the descent can stop short of it)
        off = np.clip([(p.off - p.low) / (p.high - p.low) for p in params], XTOL, 1 - XTOL)
        starts = [np.full(len(params), 0.5)]
        starts += [off] if np.any(np.abs(off - 0.5) > XTOL) else []
        alone = np.array([_alone(error, off, j) for j in range(len(params))])
        starts.append(alone)
        candidates = [scipy.optimize.least_squares(
            residuals, u0, bounds=(0.0, 1.0), xtol=XTOL).x
            for u0 in starts]
    u = min(candidates, key=error)
    return {p.name: p.low + uj * (p.high - p.low) for p, uj in zip(params, u)}, error(u)


#: Steps from a parameter's off value towards each end of its range, as shares of the way,
#: where its own best is looked for (:func:`_alone`): a line's amplitude may be anywhere
#: from a ten-thousandth of its range up.
ALONE_GRID = np.geomspace(1e-4, 1.0, 25)


def _alone(error, off: np.ndarray, j: int) -> float:
    """Parameter ``j``'s place in its range (0..1) with the lowest ``error`` when the others
    are ``off``: the best of steps spaced by ratio towards each end, refined by a bounded
    search between its neighbours."""
    import scipy.optimize

    def along(v: float) -> float:
        u = off.copy()
        u[j] = v
        return error(u)
    grid = np.unique(np.concatenate([[off[j]], off[j] + ALONE_GRID * (1.0 - off[j]),
                                     off[j] - ALONE_GRID * off[j]]))
    values = [along(v) for v in grid]
    k = int(np.argmin(values))
    low, high = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    if high <= low:
        return float(grid[k])
    found = scipy.optimize.minimize_scalar(along, bounds=(low, high), method="bounded",
                                           options={"xatol": XTOL * (high - low)})
    return float(found.x) if found.fun < values[k] else float(grid[k])


def _residuals(problem: FitProblem, y_low: np.ndarray, slopes: np.ndarray):
    """u (each parameter's place in its range, 0..1) -> the Eq. (12) residuals there. Where
    the features are linear in the signals (a spectrum's complex values), they are taken
    once of ``y_low`` and of each slope, and each evaluation is a product of those: a
    least-squares fit of many parameters evaluates it many times, each a spectrum else."""
    low_features = problem.linear_features(y_low)
    if low_features is None:
        return lambda u: problem.residuals_of(y_low + np.tensordot(u, slopes, axes=1))
    columns = [problem.linear_features(s) for s in slopes]
    per_channel = [np.array([c[i] for c in columns]) for i in range(len(low_features))]
    return lambda u: problem.residuals_of_amplitudes(
        [np.abs(z0 + u @ s) for z0, s in zip(low_features, per_channel)])
