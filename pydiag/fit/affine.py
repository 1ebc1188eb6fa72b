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

A phase the amplitudes' terms are a first harmonic of (where a load zone peaks a
bearing's strikes) costs three simulations an amplitude instead of one: its best of a few
phases, the amplitudes fitted there, then both polished together, still with no
simulation. The outputs are combined where the features are still linear in them (a
spectrum's complex values, an envelope's analytic signal), so that an evaluation costs
at most the envelope's spectrum, not a spectrum of every signal.
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
    (the caller knows they are), but for at most one periodic parameter, a phase, which
    they depend on only through its cosine and sine, each parameter's change from off as
    a first harmonic of it (a strike amplitude modulated once a turn, the phase where the
    modulation peaks): three simulations a parameter then, at the phase's 0, a quarter and
    a half turn, give the outputs at every phase (:func:`_at_phase`). A parameter the
    problem's features do not see (:data:`UNSEEN`: a shaft order outside every feature
    band) stays at its off value, and so does a phase none they see is modulated by."""
    params = problem.parameters
    phases = [j for j, p in enumerate(params) if p.periodic]
    if len(phases) > 1:
        raise ValueError("fit_affine fits at most one phase")
    amplitudes = [p for p in params if not p.periodic]
    off = np.array([p.off for p in amplitudes])
    phase = params[phases[0]] if phases else None
    turns = (0.0, 0.5 * np.pi, np.pi) if phase else (0.0,)  # of the phase, from its low end

    def x_of(a: np.ndarray, turn: float) -> np.ndarray:  # in the problem's order
        x = list(a)
        if phase:
            x.insert(phases[0], phase.low + turn / (2 * np.pi) * (phase.high - phase.low))
        return np.array(x)
    with problem.spec.open() as plant:
        y_off = problem.simulate(plant, x_of(off, 0.0))
        form, residuals_of, at_off = _linear_form(problem, y_off)
        changes = []
        for j, p in enumerate(amplitudes):
            x = off.copy()
            x[j] = p.high if p.high - p.off >= p.off - p.low else p.low
            changes.append((x[j] - p.off, [form(problem.simulate(plant, x_of(x, t)) - y_off)
                                           for t in turns]))
    if phase is None:
        return _result(params, *_fit(residuals_of, amplitudes, at_off,
                                     [(step, c[0]) for step, c in changes]))

    def fit_at(turn: float) -> tuple[np.ndarray, float, np.ndarray]:
        return _fit(residuals_of, amplitudes, at_off, _at_phase(changes, turn))
    turn, best = 0.0, fit_at(0.0)
    if best[2].any():  # the phase with the amplitudes held there, then the amplitudes,
        other = _best_phase(lambda t: _error(residuals_of, amplitudes, at_off,  # then both
                                             _at_phase(changes, t), best[0]))
        again = fit_at(other)
        if again[1] < best[1]:
            turn, best = other, again
        turn, best = _together(residuals_of, amplitudes, at_off, changes, turn, best)
    u, error, seen = best
    place = (turn % (2 * np.pi)) / (2 * np.pi) if seen.any() else \
        (phase.off - phase.low) / (phase.high - phase.low)
    return _result(params, np.insert(u, phases[0], place), error,
                   np.insert(seen, phases[0], seen.any()))


def _at_phase(changes: list[tuple[float, list[np.ndarray]]], turn: float
              ) -> list[tuple[float, np.ndarray]]:
    """Each parameter's (step, change of the outputs over it) with the phase ``turn``
    radians from its low end, from its changes there at 0, a quarter and a half turn:
    ``c(t) = (c0 + c180) / 2 + cos t (c0 - c180) / 2 + sin t (c90 - (c0 + c180) / 2)``,
    exact for a first harmonic."""
    out = []
    for step, (c0, c90, c180) in changes:
        mean = 0.5 * (c0 + c180)
        out.append((step, mean + np.cos(turn) * 0.5 * (c0 - c180)
                    + np.sin(turn) * (c90 - mean)))
    return out


def _together(residuals_of, params, y_off: np.ndarray, changes, turn: float,
              fitted: tuple[np.ndarray, float, np.ndarray]
              ) -> tuple[float, tuple[np.ndarray, float, np.ndarray]]:
    """(the phase, the fit of ``params``) polished together by bounded least squares from
    ``turn`` and ``fitted`` (:func:`_fit`'s), those the features do not see left off; the
    better of the two is returned."""
    import scipy.optimize

    u0, error0, seen = fitted

    def residuals(v: np.ndarray) -> np.ndarray:
        u = u0.copy()
        u[seen] = v[:-1]
        return _every(residuals_of, *_slopes(params, y_off, _at_phase(changes, v[-1])))(u)
    n = int(np.count_nonzero(seen))
    found = scipy.optimize.least_squares(
        residuals, np.append(u0[seen], turn), xtol=XTOL,
        bounds=(np.append(np.zeros(n), -np.inf), np.append(np.ones(n), np.inf)))
    error = float(np.linalg.norm(residuals(found.x)))
    if not error < error0:
        return turn, fitted
    u = u0.copy()
    u[seen] = found.x[:-1]
    return float(found.x[-1]), (u, error, seen)


#: Phases a fit of one looks at first (:func:`_best_phase`), a turn divided evenly.
PHASE_GRID = 8


def _best_phase(error) -> float:
    """The phase (radians from its low end) with the lowest ``error(phase)``: the best of
    :data:`PHASE_GRID` phases, refined by a bounded search between its neighbours."""
    import scipy.optimize

    grid = 2 * np.pi * np.arange(PHASE_GRID) / PHASE_GRID
    values = [error(t) for t in grid]
    k = int(np.argmin(values))
    spacing = grid[1]
    found = scipy.optimize.minimize_scalar(error, bounds=(grid[k] - spacing, grid[k] + spacing),
                                           method="bounded",
                                           options={"xatol": XTOL * 2 * np.pi})
    return float(found.x) if found.fun < values[k] else float(grid[k])


def _result(params, u: np.ndarray, error: float, seen: np.ndarray) -> AffineFit:
    """:class:`AffineFit` of the places ``u`` (0..1) of ``params``."""
    return AffineFit({p.name: p.low + uj * (p.high - p.low) for p, uj in zip(params, u)},
                     error, tuple(p.name for p, s in zip(params, seen) if not s))


def _slopes(params, y_off: np.ndarray, steps: list[tuple[float, np.ndarray]]
            ) -> tuple[np.ndarray, np.ndarray]:
    """The outputs at each parameter's low end (all at once) and the change over its range:
    u_j, the place in the range, from 0 to 1 (outputs in their linear form,
    :func:`_linear_form`)."""
    y_low, slopes = y_off, []
    for p, (step, change) in zip(params, steps):
        if p.low != p.off:
            y_low = y_low + (p.low - p.off) / step * change
        slopes.append(change if step == p.high - p.low else (p.high - p.low) / step * change)
    return y_low, np.array(slopes)


def _every(residuals_of, y_low: np.ndarray, slopes: np.ndarray):
    """u (each parameter's place in its range, 0..1) -> the Eq. (12) residuals there."""
    return lambda u: residuals_of(y_low + np.tensordot(u, slopes, axes=1))


def _error(residuals_of, params, y_off: np.ndarray, steps: list[tuple[float, np.ndarray]],
           u: np.ndarray) -> float:
    """The Eq. (12) error at the places ``u`` of ``params``."""
    return float(np.linalg.norm(_every(residuals_of, *_slopes(params, y_off, steps))(u)))


def _fit(residuals_of, params, y_off: np.ndarray, steps: list[tuple[float, np.ndarray]]
         ) -> tuple[np.ndarray, float, np.ndarray]:
    """(the places 0..1 of ``params`` at their fit, its error, which of them the features
    see) from the outputs with every one off (``y_off``) and each one's (step from off,
    change of the outputs over it), in the linear form ``residuals_of`` takes."""
    every = _every(residuals_of, *_slopes(params, y_off, steps))
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
    return u, float(np.linalg.norm(every(u))), seen


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


def _linear_form(problem: FitProblem, y: np.ndarray):
    """(signals -> their linear form, a form -> the Eq. (12) residuals of its signals, the
    form of ``y``): what the features take of the signals linearly, so that a combination
    of simulations is combined there and each evaluation of a fit costs no spectrum of its
    own where it can (a spectrum's complex values at the feature bins; the analytic signal
    of an envelope's band, of which only the envelope's spectrum is left to take), else
    the signals themselves. ``y``: signals of the problem (to see which)."""
    for take, back in ((problem.linear_features, lambda parts: problem.residuals_of_amplitudes(
                            [np.abs(part) for part in parts])),
                       (problem.analytic, lambda parts: problem.residuals_of_analytic(parts))):
        parts = take(y)
        if parts is not None:
            cuts = np.cumsum([part.size for part in parts])[:-1]
            return (lambda signals, take=take: np.concatenate(take(signals)),
                    lambda form, back=back, cuts=cuts: back(np.split(form, cuts)),
                    np.concatenate(parts))
    return (lambda signals: signals), problem.residuals_of, y
