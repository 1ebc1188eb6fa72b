"""The fit of parameters the model's outputs are affine in.

When every output is ``y(a) = y(off) + sum_j (a_j - off_j) / (end_j - off_j) * (y_j -
y(off))``, with ``off`` every parameter's off value (:attr:`Parameter.off`), ``end_j`` the
end of parameter j's range farther from its off value and ``y_j`` the outputs with it
there and the others off (a bearing's strike amplitude, a shaft's lines at its orders,
added to what the sensor sees of the mesh), one simulation more than there are
parameters gives the outputs at every point of the box; the Eq. (12) error is then
minimised over it with no further simulation: a bounded scalar search (Brent's method)
and both ends for one parameter, bounded least squares (trust-region reflective) for
several. Taken at the off values and one parameter at a time, the same simulations
linearise a model that is affine only near them (a signed coefficient of many, which at
a corner of the box would all be far out together) where the fit starts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pydiag.fit.problem import FitProblem

#: The search stops within this share of a parameter's range.
XTOL = 1e-4
#: A parameter whose whole range moves the residuals by no more than this (relative to
#: their size) is not seen by the problem's features (its lines lie outside every feature
#: bin: what is left is leakage, 1e-13 of a line): it stays off, not wherever the search
#: happened to leave it.
UNSEEN = 1e-9


@dataclass(frozen=True)
class AffineFit:
    """What :func:`fit_affine` found: each parameter's value (by name), the root-sum-square
    Eq. (12) error there, and the parameters the problem's features do not see (left off:
    a fit after this one must not move them either)."""

    values: dict[str, float]
    error: float
    unseen: tuple[str, ...]


def fit_affine(problem: FitProblem) -> AffineFit:
    """The fit of ``problem``'s parameters, for a model whose outputs are affine in them
    (the caller knows they are). A parameter the problem's features do not see
    (:data:`UNSEEN`: a shaft order outside every feature band) stays at its off value."""
    params = problem.parameters
    off = np.array([p.off for p in params])
    with problem.spec.open() as plant:
        y_off = problem.simulate(plant, off)
        steps = []
        for j, p in enumerate(params):
            x = off.copy()
            x[j] = p.high if p.high - p.off >= p.off - p.low else p.low
            steps.append((x[j] - p.off, problem.simulate(plant, x) - y_off))
    # the outputs at each parameter's low end (all at once) and the change over its range,
    # as _residuals takes them: u_j, the place in the range, from 0 to 1
    y_low, slopes = y_off, []
    for p, (step, change) in zip(params, steps):
        if p.low != p.off:
            y_low = y_low + (p.low - p.off) / step * change
        slopes.append(change if step == p.high - p.low else (p.high - p.low) / step * change)
    every = _residuals(problem, y_low, np.array(slopes))
    off_all = np.array([(p.off - p.low) / (p.high - p.low) for p in params])
    r0 = every(off_all)

    def moved(j: int, end: float) -> float:  # parameter j from off to an end, the rest off
        u = off_all.copy()
        u[j] = end
        return float(np.linalg.norm(every(u) - r0))
    seen = np.array([max(moved(j, 0.0), moved(j, 1.0)) > UNSEEN * (1.0 + np.linalg.norm(r0))
                     for j in range(len(params))])

    def full(u: np.ndarray) -> np.ndarray:  # the seen parameters' places, the others off
        out = off_all.copy()
        out[seen] = u
        return out

    def residuals(u: np.ndarray) -> np.ndarray:
        return every(full(u))

    def error(u: np.ndarray) -> float:
        return float(np.linalg.norm(residuals(u)))

    candidates = _search(residuals, error, off_all[seen]) if seen.any() else [np.empty(0)]
    u = full(min(candidates, key=error))
    return AffineFit({p.name: p.low + uj * (p.high - p.low) for p, uj in zip(params, u)},
                     float(np.linalg.norm(every(u))),
                     tuple(p.name for p, s in zip(params, seen) if not s))


def _search(residuals, error, off: np.ndarray) -> list[np.ndarray]:
    """Candidate places (0..1) of the parameters that ``residuals`` depend on, ``off``
    their off places: the bounded minimum for one, least squares from several starts for
    several (:func:`fit_affine`)."""
    import scipy.optimize  # here: importing it takes 0.3 s of every command's start

    if off.size == 1:
        found = scipy.optimize.minimize_scalar(lambda u: error(np.array([u])), bounds=(0.0, 1.0),
                                               method="bounded", options={"xatol": XTOL})
        return [np.array([float(found.x)]), np.zeros(1), np.ones(1)]
    # from the middle of the box, from where every parameter is off, and from each
    # parameter's own best with the others off (a line added to a weak one of another
    # phase first lowers its amplitude: from off, the descent can stop short of it)
    off = np.clip(off, XTOL, 1 - XTOL)
    starts = [np.full(off.size, 0.5)]
    starts += [off] if np.any(np.abs(off - 0.5) > XTOL) else []
    starts.append(np.array([_alone(error, off, j) for j in range(off.size)]))
    return [scipy.optimize.least_squares(residuals, u0, bounds=(0.0, 1.0), xtol=XTOL).x
            for u0 in starts]


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
