"""Global-best particle swarm optimisation with no process-wide state.

The algorithm is pyswarms' ``GlobalBestPSO`` (star topology, ``periodic`` boundary
handling, unclamped velocities, constant coefficients) step for step, but its random
numbers come from a generator owned by the run instead of NumPy's global one. pyswarms
draws from ``numpy.random``'s global state and configures the root logger, so two fits in
threads of one process (a Dask worker) would disturb each other; here the same seed gives
the same swarm in any thread. ``RandomState(seed)`` reproduces the stream pyswarms drew
after ``numpy.random.seed(seed)``, so results equal pyswarms' bit for bit
(tests/unit/fit/test_pso.py runs both).

Coefficients: Clerc's constriction values (c1 = c2 = 1.49618, w = 0.7298).

Pinned dimensions (``pinned``): a particle never moves along them, so each keeps its
start value there (a discrete parameter such as a tooth's index, each value searched by
its own particles); the random draws are the same, so a swarm with none pinned is
pyswarms'.

Early stop, as pyswarms' ``ftol``/``ftol_iter``: the swarm stops when, in each of the
last ``ftol_iter`` iterations, the global best cost moved by less than
``ftol x (1 + |best cost before|)``. The default (``ftol = -inf``) never stops early.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

CLERC = {"c1": 1.49618, "c2": 1.49618, "w": 0.7298}


@dataclass
class SwarmResult:
    """Personal bests of every particle and the global best cost after each iteration.

    ``best_cost_history`` stops early when no evaluation of an iteration was finite
    (every simulation failed): there is no best position to steer towards.
    """

    pbest_pos: np.ndarray
    pbest_cost: np.ndarray
    best_cost_history: list[float] = field(default_factory=list)


def periodic(position: np.ndarray, lows: np.ndarray, highs: np.ndarray) -> np.ndarray:
    """Wrap out-of-bounds coordinates into the box, tiling it periodically (pyswarms')."""
    span = np.abs(highs - lows)
    lo = np.broadcast_to(lows, position.shape)
    hi = np.broadcast_to(highs, position.shape)
    width = np.broadcast_to(span, position.shape)
    out = position.copy()
    below = out < lo
    above = out > hi
    out[below] = hi[below] - np.mod(lo[below] - out[below], width[below])
    out[above] = lo[above] + np.mod(out[above] - hi[above], width[above])
    return out


def global_best_pso(cost: Callable[[np.ndarray], np.ndarray], init_pos: np.ndarray,
                    lows: np.ndarray, highs: np.ndarray, iterations: int, seed: int,
                    options: dict[str, float] | None = None, ftol: float = -np.inf,
                    ftol_iter: int = 1, pinned: np.ndarray | None = None) -> SwarmResult:
    """Minimise ``cost`` (rows of positions -> costs, ``inf`` for a failure) from ``init_pos``.

    ``init_pos``: (n_particles, dimensions) start positions inside ``[lows, highs]``;
    ``ftol``, ``ftol_iter``: the early stop of the module docstring; ``pinned``: a boolean
    per dimension, True where particles do not move (module docstring).
    """
    opts = {**CLERC, **(options or {})}
    rng = np.random.RandomState(seed)
    position = np.array(init_pos, dtype=float)
    rng.random_sample(size=position.shape)  # pyswarms creates its swarm twice: skip one draw
    velocity = rng.random_sample(size=position.shape)
    pbest_pos = position.copy()
    pbest_cost = np.full(position.shape[0], np.inf)
    best_pos, best_cost = None, np.inf
    history: list[float] = []
    still = deque(maxlen=ftol_iter)  # did the best cost stand still, in the last iterations
    for i in range(iterations):
        current = np.asarray(cost(position), dtype=float)
        better = current < pbest_cost
        pbest_pos = np.where(better[:, None], position, pbest_pos)
        pbest_cost = np.where(better, current, pbest_cost)
        before = best_cost
        if np.min(pbest_cost) < best_cost:
            best_pos = pbest_pos[np.argmin(pbest_cost)]
            best_cost = float(np.min(pbest_cost))
        if best_pos is None:
            break
        history.append(best_cost)
        still.append(abs(best_cost - before) < ftol * (1 + abs(before)))
        if i == iterations - 1 or (i >= ftol_iter and all(still)):
            break  # pyswarms moves the swarm once more, but never evaluates that move
        cognitive = opts["c1"] * rng.uniform(0, 1, position.shape) * (pbest_pos - position)
        social = opts["c2"] * rng.uniform(0, 1, position.shape) * (best_pos - position)
        velocity = opts["w"] * velocity + cognitive + social
        if pinned is not None:
            velocity[:, pinned] = 0.0
        position = periodic(position + velocity, lows, highs)
    return SwarmResult(pbest_pos, pbest_cost, history)
