"""Estimate fault parameters by particle swarm optimisation of the spectral error.

One concern: one fit's search, from the swarm's start to the polish's stop, with the
simulations it asks for (a discrete parameter's rounds among them); what it fits is
:mod:`pydiag.fit.problem`'s, the swarm's arithmetic :mod:`pydiag.fit.pso`'s.

Each evaluation simulates the FMU for a start-up ``warmup_s`` plus the analysed window
(one fundamental period for gear models: the model is periodic, so one period holds all
its lines exactly) and compares its features with the measurement's, channel by
channel. The measurement may be long: its features average the noise over all of its
whole periods.

The swarm (:mod:`pydiag.fit.pso`, seeded, Clerc's constriction coefficients) finds
candidate basins; a bounded trust-region least-squares polish (scipy
``least_squares``, method "trf") on the residuals of Eq. (12) then converges in each of
the best few distinct personal-best positions, and the lowest error wins: polishing the
global best alone can converge in the wrong basin, and the valley is narrow in f_ate
(displacement channel) and shallow in a_f, f_f, which a Gauss-Newton step handles and a
simplex does not (docs/method.md). The Jacobian is by forward differences, its columns
simulated in parallel, and the polishes run side by side, their simulations batched
(:mod:`pydiag.fit.lockstep`: each takes the steps it would take alone).

Particles and Jacobian columns are evaluated in worker processes, each with its own
FMU instance; the result does not depend on the number of workers, and the same seed
gives the same result in any thread.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import inspect
import multiprocessing as mp
import os
import time
from dataclasses import asdict, dataclass, field
from typing import Callable

import numpy as np

from pydiag.core.errors import EstimationError, TooManyFailures, UsageError
from pydiag.core.parameters import snap
from pydiag.fit.lockstep import run_in_lockstep
from pydiag.fit.problem import FitProblem, ProblemObjective
from pydiag.fit.pso import global_best_pso
from pydiag.fmu.isolation import IsolatedPool

#: Wall-time limit of one simulation in a worker, seconds.
DEFAULT_EVAL_TIMEOUT_S = 60.0
#: Failed simulations in a row that stop a fit.
DEFAULT_MAX_CONSECUTIVE_FAILURES = 20
#: Values of a discrete parameter (which tooth) polished to the end, the best after one
#: least-squares step each (:meth:`FaultEstimator._first_steps`).
DISCRETE_FINALISTS = 4
#: A value whose cost after that step is within this share of the last finalist's is a
#: finalist too: a tie at the cut is polished, not settled by rounding.
FINALIST_TIE = 1e-3
#: The native engine's tolerance in the swarm's simulations (``swarm_tolerance``): the
#: swarm only ranks positions; the polish and the reported error keep the problem's
#: tolerance (its accuracy and speed: bench/speed.py, bench/RESULTS.md sections 1 and 12).
SWARM_TOLERANCE = 1e-4


@dataclass
class FitResult:
    """Plain-data result of :meth:`FaultEstimator.fit`: the estimate and how it was found
    (what it means for the machine is :mod:`pydiag.diagnose.diagnosis`'s)."""

    parameters: dict[str, float]
    error: float
    evaluations: int
    elapsed_s: float
    best_error_history: list[float]
    failed_evaluations: int = 0
    failure_reasons: dict[str, int] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return asdict(self)


class FaultEstimator:
    """Fit a :class:`~pydiag.fit.problem.FitProblem` (scikit-learn's idiom: ``__init__``
    stores the settings, :meth:`fit` validates and returns a plain result).

    Args:
        n_particles, iterations: swarm size (more when a parameter has a step: one particle
            for each of its multiples) and iterations
        seed: seed of the swarm; the same seed gives the same answer
        swarm_ftol, swarm_ftol_iter: stop the swarm early when its best cost moved by less
            than ``swarm_ftol x (1 + best)`` in each of its last ``swarm_ftol_iter``
            iterations (pyswarms' ``ftol``; the default never stops early)
        polish_evaluations: simulation budget of each least-squares polish (0 disables it)
        polish_starts: how many distinct swarm positions to polish from
        polish_xtol: the polish stops when its step is below this share of the parameters'
            ranges (it works on the parameters scaled to 0..1)
        polish_ftol: ... or when a step lowers the squared error by less than this share
        swarm_tolerance: the native engine's relative tolerance in the swarm's simulations
            where the problem asks for none (None: the problem's own): the swarm only ranks
            positions; its best distinct ones are simulated again at the problem's
            tolerance before the polish, and the polish and the reported error use it
        n_workers: worker processes (default: all cores, at most one per particle). The FMU
            always runs in workers (:mod:`pydiag.fmu.isolation`), except inside a daemonic
            process (a Dask worker), which may not start children: there it runs in-process.
        eval_timeout_s: wall-time limit of one simulation; a longer one is killed, penalised
            (None: the adapter's ``eval_timeout_s``, else ``DEFAULT_EVAL_TIMEOUT_S``)
        max_consecutive_failures: failed simulations in a row that stop the fit
        progress: called as progress(done, total, best_error) after each batch
    """

    def __init__(self, n_particles: int = 16, iterations: int = 20, seed: int = 0,
                 swarm_ftol: float = -np.inf, swarm_ftol_iter: int = 1,
                 polish_evaluations: int = 150, polish_starts: int = 3,
                 polish_xtol: float = 1e-4, polish_ftol: float = 1e-4,
                 swarm_tolerance: float | None = SWARM_TOLERANCE,
                 n_workers: int | None = None, eval_timeout_s: float | None = None,
                 max_consecutive_failures: int = DEFAULT_MAX_CONSECUTIVE_FAILURES,
                 progress: Callable[[int, int, float], None] | None = None) -> None:
        self.n_particles = n_particles
        self.iterations = iterations
        self.seed = seed
        self.swarm_ftol = swarm_ftol
        self.swarm_ftol_iter = swarm_ftol_iter
        self.polish_evaluations = polish_evaluations
        self.polish_starts = polish_starts
        self.polish_xtol = polish_xtol
        self.polish_ftol = polish_ftol
        self.swarm_tolerance = swarm_tolerance
        self.n_workers = n_workers
        self.eval_timeout_s = eval_timeout_s
        self.max_consecutive_failures = max_consecutive_failures
        self.progress = progress

    def replace(self, **settings) -> "FaultEstimator":
        """A new estimator with these settings changed (scikit-learn's ``clone`` then
        ``set_params``); this one is unchanged."""
        names = inspect.signature(FaultEstimator.__init__).parameters
        unknown = sorted(set(settings) - set(names))
        if unknown:
            raise UsageError(f"FaultEstimator has no setting {', '.join(unknown)}")
        return FaultEstimator(**{**{k: getattr(self, k) for k in names if k != "self"},
                                 **settings})

    def _validate(self) -> None:
        if self.n_particles < 2 or self.iterations < 1 or self.swarm_ftol_iter < 1:
            raise UsageError("need at least 2 particles, 1 iteration and swarm_ftol_iter >= 1")
        if self.polish_evaluations < 0 or self.polish_starts < 1 or \
                not (self.polish_xtol > 0 and self.polish_ftol > 0):
            raise UsageError("the polish budget must not be negative, needs at least 1 start "
                             "and positive tolerances")
        if self.swarm_tolerance is not None and not self.swarm_tolerance > 0:
            raise UsageError(f"the swarm's tolerance must be positive, got {self.swarm_tolerance}")
        if self.n_workers is not None and self.n_workers < 1:
            raise UsageError(f"need at least 1 worker, got {self.n_workers}")
        if (self.eval_timeout_s is not None and not self.eval_timeout_s > 0) or \
                self.max_consecutive_failures < 1:
            raise UsageError("the evaluation timeout and the failure limit must be positive")

    # ------------------------------------------------------------------ fit
    def fit(self, problem: FitProblem) -> FitResult:
        """The swarm over ``problem``'s box, then the polish from its best distinct
        positions.

        A discrete parameter (``Parameter.step``: which tooth) is searched exhaustively:
        every value gets particles of its own that never leave it, the best position of
        each value takes a least-squares step over the continuous parameters, and the
        best few after it are polished on (:meth:`_first_steps`), so the value chosen is
        the one whose own fit is best, not the one a particle happened to land near (a
        verdict must not hang on the last bits of floating point)."""
        self._validate()
        lows, highs = problem.lows, problem.highs
        ranking = self._ranking_problem(problem)
        seen: dict[bytes, np.ndarray | None] = {}  # the swarm's residuals, for the polish
        init = self._initial_positions(problem)
        total = len(init) * self.iterations + self.polish_evaluations * self.polish_starts
        with self._evaluations(ranking, total) as run:
            def costs(xs: np.ndarray) -> np.ndarray:  # the swarm's
                out = run.residuals(xs)
                if ranking is problem:
                    seen.update((x.tobytes(), r)
                                for x, r in zip(np.clip(xs, lows, highs), out))
                return np.array([np.inf if r is None else np.linalg.norm(r) for r in out])

            discrete = np.array([p.step is not None for p in problem.parameters])
            swarm = global_best_pso(costs, init, lows, highs, self.iterations, self.seed,
                                    ftol=self.swarm_ftol, ftol_iter=self.swarm_ftol_iter,
                                    pinned=discrete if discrete.any() else None)
            if ranking is problem:
                return self._from_swarm(problem, run, swarm, seen, discrete)
        with self._evaluations(problem, total, run) as run:
            return self._from_swarm(problem, run, swarm, None, discrete)

    def _from_swarm(self, problem: FitProblem, run: "_Run", swarm, seen: dict | None,
                    discrete: np.ndarray) -> FitResult:
        """The polish from the swarm's best distinct positions (or the best of each value of
        the discrete parameters); ``seen``: the swarm's residuals by position, None when it
        ranked them at another tolerance: then they are simulated again first."""
        lows, highs = problem.lows, problem.highs
        if discrete.any():
            starts, start_costs = _best_of_each(swarm.pbest_pos, swarm.pbest_cost, discrete)
        else:
            starts, start_costs = self._distinct_starts(swarm.pbest_pos, swarm.pbest_cost,
                                                        lows, highs)
        if seen is None:
            seen = {}
            ok = [i for i, c in enumerate(start_costs) if np.isfinite(c)]
            again = run.residuals(np.array([starts[i] for i in ok])) if ok else []
            for i, r in zip(ok, again):
                seen[np.clip(starts[i], lows, highs).tobytes()] = r
                start_costs[i] = np.inf if r is None else float(np.linalg.norm(r))
        first = int(np.argmin(start_costs))
        best_x, best_cost = starts[first], start_costs[first]
        if self.polish_evaluations > 0:
            kept = [(x0, c0) for x0, c0 in zip(starts, start_costs) if np.isfinite(c0)]
            if discrete.any() and len(kept) > DISCRETE_FINALISTS:
                kept = self._first_steps(run, kept, lows, highs, discrete, seen)
            polishes = [functools.partial(self._polish, x0=x0, cost0=c0, lows=lows,
                                          highs=highs, held=discrete,
                                          r0=seen.get(np.clip(x0, lows, highs).tobytes()))
                        for x0, c0 in kept]
            for x, c in run_in_lockstep(run.residuals, polishes):
                if c < best_cost:
                    best_x, best_cost = x, c
        return self._result(problem, run, best_x, best_cost, swarm.best_cost_history)

    def _first_steps(self, run: "_Run", kept: list, lows, highs, discrete: np.ndarray,
                     seen: dict) -> list:
        """The :data:`DISCRETE_FINALISTS` best of ``kept`` (each value of the discrete
        parameters' best start) after one least-squares step of each, to be polished to
        the end: the swarm's few steps per value rank the values poorly, one step each
        ranks them well, at a fraction of polishing every one (docs/method.md)."""
        one_step = self.replace(polish_evaluations=2 * (int((~discrete).sum()) + 1))
        polishes = [functools.partial(one_step._polish, x0=x0, cost0=c0, lows=lows,
                                      highs=highs, held=discrete,
                                      r0=seen.get(np.clip(x0, lows, highs).tobytes()))
                    for x0, c0 in kept]
        stepped = run_in_lockstep(run.residuals, polishes)
        return [stepped[i] for i in finalists([c for _, c in stepped])]

    def _ranking_problem(self, problem: FitProblem) -> FitProblem:
        """``problem`` as the swarm simulates it: at ``swarm_tolerance`` with the native
        engine where ``problem`` asks for no tolerance of its own."""
        if self.swarm_tolerance is None or problem.spec.relative_tolerance is not None:
            return problem
        return dataclasses.replace(problem, spec=dataclasses.replace(
            problem.spec, native_tolerance=self.swarm_tolerance))

    def _initial_positions(self, problem: FitProblem) -> np.ndarray:
        """The swarm's start: uniform in the box, except that a parameter with a step (a
        tooth's index) takes its multiples in turn
        (:meth:`pydiag.core.parameters.Parameter.starts`), the swarm as large as there are
        multiples if that is more than ``n_particles``: each tooth is tried from the first
        iteration."""
        lows, highs = problem.lows, problem.highs
        grids = [p.starts() for p in problem.parameters]
        n = max([self.n_particles] + [len(g) for g in grids])
        init = lows + np.random.default_rng(self.seed).random((n, lows.size)) * (highs - lows)
        for j, grid in enumerate(grids):
            if grid:
                init[:, j] = [grid[i % len(grid)] for i in range(n)]
        return init

    def refine(self, problem: FitProblem, start: dict[str, float]) -> FitResult:
        """The polish alone (``polish_evaluations`` simulations), from ``start``: a value of
        each of ``problem``'s parameters, e.g. a fit of fewer parameters extended by the
        new ones' fitted values. No swarm: it stays in the basin it starts in."""
        self._validate()
        missing = [p.name for p in problem.parameters if p.name not in start]
        if missing:
            raise UsageError(f"refine needs a start value of {', '.join(missing)}")
        lows, highs = problem.lows, problem.highs
        x0 = np.clip([start[p.name] for p in problem.parameters], lows, highs)
        with self._evaluations(problem, 1 + self.polish_evaluations) as run:
            r0 = run.residuals(x0)[0]
            best_x, best_cost = x0, (np.inf if r0 is None else float(np.linalg.norm(r0)))
            if self.polish_evaluations > 0 and r0 is not None:
                best_x, best_cost = self._polish(run.residuals, x0, best_cost, lows, highs, r0)
        return self._result(problem, run, best_x, best_cost, [best_cost])

    @contextlib.contextmanager
    def _evaluations(self, problem: FitProblem, total: int, after: "_Run | None" = None):
        """A :class:`_Run` of ``problem``'s simulations (worker pool, counters), closed on
        exit; ``total``: the evaluations expected, for progress; ``after``: an earlier
        run of the same fit whose counts and failures this one carries on."""
        started = time.perf_counter() if after is None else after.started
        objective = ProblemObjective(problem)
        pool = None
        timeout_s = self.eval_timeout_s or problem.adapter.eval_timeout_s or DEFAULT_EVAL_TIMEOUT_S
        if not mp.current_process().daemon:
            workers = self.n_workers or min(os.cpu_count() or 1, self.n_particles)
            pool = IsolatedPool(objective, workers, timeout_s, self.max_consecutive_failures)
            if after is not None and after.pool is not None:
                pool.failures = after.pool.failures
        run = _Run(problem, objective, pool, total, self.progress, started)
        if after is not None:
            run.count, run.best = after.count, after.best
        try:
            yield run
        except TooManyFailures as err:
            raise TooManyFailures(f"stopped: {err}", err.count, err.consecutive, err.last) from err
        finally:
            if pool is not None:
                pool.close()
            objective.close()

    def _result(self, problem: FitProblem, run: "_Run", best_x: np.ndarray, best_cost: float,
                history: list[float]) -> FitResult:
        failures = run.pool.failures if run.pool is not None else None
        if not np.isfinite(best_cost):
            why = f"; the first failed with: {failures.first}" if failures and failures.first else ""
            raise EstimationError(f"every simulation of the plant failed ({run.count} "
                                  f"evaluations){why}")
        best_x = in_box(problem, best_x)
        estimate = {p.name: float(v) for p, v in zip(problem.parameters, best_x)}
        return FitResult(estimate, best_cost, run.count, time.perf_counter() - run.started,
                         history, failures.count if failures else 0,
                         dict(failures.reasons) if failures else {})

    def _distinct_starts(self, positions, costs, lows, highs) -> tuple[list, list]:
        """The best personal bests, at least 5 % of the box apart from each other."""
        order = np.argsort(costs)
        starts: list[np.ndarray] = []
        chosen: list[float] = []
        for i in order:
            x = np.asarray(positions[i], dtype=float)
            if all(np.max(np.abs(x - y) / (highs - lows)) > 0.05 for y in starts):
                starts.append(x)
                chosen.append(float(costs[i]))
            if len(starts) == self.polish_starts:
                break
        return starts, chosen

    def _polish(self, residuals, x0, cost0, lows, highs, r0: np.ndarray | None = None,
                held: np.ndarray | None = None) -> tuple[np.ndarray, float]:
        """Bounded trust-region least squares from a swarm position, parallel FD Jacobian.

        It works on the parameters scaled to 0..1 (``polish_xtol`` is a share of each
        range); ``r0``, the residuals at ``x0`` when the swarm has them, saves a simulation;
        ``held``: a boolean per parameter, True for those it does not move (a discrete one).
        """
        import scipy.optimize  # here: importing it takes 0.3 s of every command's start

        n = x0.size
        span = highs - lows
        step = 1e-3
        cache: dict[bytes, np.ndarray] = {}
        last = None

        def fun(u: np.ndarray) -> np.ndarray:
            nonlocal last
            key = np.asarray(u, dtype=float).tobytes()
            if key not in cache:
                r = residuals(lows + u * span)[0]
                if r is None:  # a failed simulation: a large, finite residual keeps trf going
                    r = np.full(last.size if last is not None else 1, 1e3)
                cache[key] = r
                last = r
            return cache[key]

        free = np.ones(n, dtype=bool) if held is None else ~held

        def jac(u: np.ndarray) -> np.ndarray:
            f0 = fun(u)
            h = np.where(u + step <= 1.0, step, -step)
            cols = iter(residuals(lows + (u + np.diag(h)[free]) * span))
            out = np.zeros((f0.size, n))
            for j in np.flatnonzero(free):
                c = next(cols)
                out[:, j] = ((c if c is not None else f0) - f0) / h[j]
            return out

        u0 = (np.clip(x0, lows, highs) - lows) / span
        if r0 is not None:
            cache[u0.tobytes()] = last = r0
        budget = max(1, self.polish_evaluations // (int(free.sum()) + 1))
        res = scipy.optimize.least_squares(fun, u0, jac=jac, bounds=(0.0, 1.0), method="trf",
                                           max_nfev=budget, xtol=self.polish_xtol,
                                           ftol=self.polish_ftol, gtol=1e-8)
        cost = float(np.linalg.norm(fun(res.x)))
        if cost < cost0:
            return lows + np.asarray(res.x, dtype=float) * span, cost
        return x0, cost0


def finalists(costs: list[float]) -> list[int]:
    """The indices of the :data:`DISCRETE_FINALISTS` lowest ``costs``, best first, and of
    any other within :data:`FINALIST_TIE` of the last of them (a near tie at the cut is
    kept whole, so that which values go on does not hang on rounding)."""
    order = sorted(range(len(costs)), key=lambda i: (costs[i], i))
    if len(order) <= DISCRETE_FINALISTS:
        return order
    cut = costs[order[DISCRETE_FINALISTS - 1]] * (1.0 + FINALIST_TIE)
    if not np.isfinite(cut):
        return order[:DISCRETE_FINALISTS]
    return [i for k, i in enumerate(order) if k < DISCRETE_FINALISTS or costs[i] <= cut]


def _best_of_each(positions: np.ndarray, costs: np.ndarray, discrete: np.ndarray
                  ) -> tuple[list, list]:
    """The best personal best of each value of the ``discrete`` parameters, best first:
    the polish's starts when a discrete parameter is searched exhaustively."""
    best: dict[bytes, int] = {}
    for i, x in enumerate(np.asarray(positions, dtype=float)):
        key = np.round(x[discrete], 9).tobytes()
        if key not in best or costs[i] < costs[best[key]]:
            best[key] = i
    order = sorted(best.values(), key=lambda i: (costs[i], i))
    return ([np.asarray(positions[i], dtype=float) for i in order],
            [float(costs[i]) for i in order])


def in_box(problem: FitProblem, xs: np.ndarray) -> np.ndarray:
    """Positions clipped to ``problem``'s box, each stepped parameter on a multiple of its
    step (:func:`pydiag.core.parameters.snap`): what is simulated and what is estimated."""
    return snap(problem.parameters, np.clip(xs, problem.lows, problem.highs))


class _Run:
    """The simulations of one fit: put in the box (:func:`in_box`), on the pool (or
    in-process), counted, progress reported."""

    def __init__(self, problem: FitProblem, objective, pool, total, progress,
                 started: float) -> None:
        self.problem = problem
        self.objective, self.pool = objective, pool
        self.total, self.progress = total, progress
        self.count, self.best = 0, float("inf")
        self.started = started

    def residuals(self, xs: np.ndarray) -> list[np.ndarray | None]:
        xs = in_box(self.problem, np.atleast_2d(xs))
        out = (self.pool.map(xs) if self.pool
               else [self.objective.residuals_or_none(x) for x in xs])
        self.count += len(xs)
        self.best = min([self.best] + [float(np.linalg.norm(r)) for r in out if r is not None])
        if self.progress:
            self.progress(self.count, self.total, self.best)
        return out
