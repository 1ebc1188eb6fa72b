"""Estimate fault parameters by particle swarm optimisation of the spectral error.

Each evaluation simulates the FMU for a start-up ``warmup_s`` plus one fundamental
period (the model is periodic, so one period holds all its lines exactly) and
compares its features with the measurement's, channel by channel. The measurement
may be long: its features average the noise over all of its whole periods.

The swarm (pyswarms GlobalBestPSO) is seeded; a bounded Nelder-Mead polish from the
swarm's best refines the answer. Particles are evaluated in worker processes, each
with its own FMU instance; the result does not depend on the number of workers.
"""

from __future__ import annotations

import logging
import multiprocessing as mp
import os
import time
from dataclasses import asdict, dataclass, field
from typing import Callable

import numpy as np
import scipy.optimize

from pydiag.classify import classify
from pydiag.features import Features, max_band_freq_hz, signal_features
from pydiag.kinematics import GearKinematics
from pydiag.measurement import Measurement
from pydiag.objective import spectral_error
from pydiag.plant import FmuPlant, PlantError


class EstimationError(Exception):
    """The estimate cannot be made as asked; the message says why."""


@dataclass(frozen=True)
class FaultParameter:
    """A parameter to estimate and its search bounds."""

    name: str
    low: float
    high: float


#: The paper's four fault parameters (a0 is known) with their physical ranges.
GEAR_FAULT_PARAMETERS = (
    FaultParameter("a_f", 0.0, 0.9),
    FaultParameter("f_f", 0.0, 0.95),
    FaultParameter("f_ate", 0.0, 1.0),
    FaultParameter("f_dte", 0.0, 1.0),
)


@dataclass(frozen=True)
class PlantSpec:
    """Everything needed to open an FmuPlant in another process."""

    fmu_path: str
    sensors: tuple[str, ...]
    sample_rate_hz: float
    fixed_values: dict = field(default_factory=dict)
    relative_tolerance: float = 1e-6

    def open(self) -> FmuPlant:
        return FmuPlant(self.fmu_path, self.sensors, self.sample_rate_hz,
                        self.relative_tolerance, self.fixed_values)


@dataclass
class DiagnosisResult:
    """Plain-data result of :meth:`FaultEstimator.fit`."""

    parameters: dict[str, float]
    fault_mode: str
    severity: str
    tooth_severity: str
    te_severity: str
    error: float
    evaluations: int
    elapsed_s: float
    best_error_history: list[float]

    def to_dict(self) -> dict:
        return asdict(self)


class SpectralObjective:
    """Parameter vector -> spectral error against fixed reference features."""

    def __init__(self, spec: PlantSpec, kinematics: GearKinematics, names: list[str],
                 reference: dict[str, Features], feature_mode: str, warmup_s: float) -> None:
        self.spec = spec
        self.kinematics = kinematics
        self.names = names
        self.reference = reference
        self.feature_mode = feature_mode
        self.warmup_s = warmup_s
        self._plant: FmuPlant | None = None

    def model_features(self, x: np.ndarray) -> dict[str, Features]:
        if self._plant is None:
            self._plant = self.spec.open()
        values = dict(zip(self.names, map(float, x)))
        y = self._plant.simulate(values, self.kinematics.period_s, self.warmup_s)
        return {s: signal_features(y[i], self.spec.sample_rate_hz, self.kinematics,
                                   self.feature_mode) for i, s in enumerate(self.spec.sensors)}

    def __call__(self, x: np.ndarray) -> float:
        """Root-sum-square of the per-channel Eq. (12) errors; inf if the simulation fails."""
        try:
            model = self.model_features(x)
        except PlantError:
            return float("inf")
        errors = [spectral_error(model[s].amplitude, self.reference[s].amplitude,
                                 self.reference[s].noise_power) for s in self.spec.sensors]
        return float(np.sqrt(np.sum(np.square(errors))))

    def close(self) -> None:
        if self._plant is not None:
            self._plant.close()
            self._plant = None


# One objective per worker process, created by the pool initializer.
_WORKER_OBJECTIVE: SpectralObjective | None = None


def _init_worker(objective: SpectralObjective) -> None:
    global _WORKER_OBJECTIVE
    _WORKER_OBJECTIVE = objective


def _evaluate_in_worker(x: np.ndarray) -> float:
    assert _WORKER_OBJECTIVE is not None
    return _WORKER_OBJECTIVE(x)


class FaultEstimator:
    """Fit fault parameters of an FMU to a measurement.

    Args:
        fmu_path: the plant FMU
        kinematics: gear kinematics; read from the FMU's Np, Ng, f_pinion when None
        parameters: what to estimate, with bounds
        fixed_values: FMU start values set in every run (not estimated)
        n_particles, iterations: swarm size and iterations
        seed: seed of the swarm; the same seed gives the same answer
        polish_evaluations: budget of the Nelder-Mead polish (0 disables it)
        feature_mode: "lines" or "paper" (see :mod:`pydiag.features`)
        warmup_s: simulated start-up time discarded before the analysed period
        n_workers: worker processes (default: all cores); 1 evaluates in this process
        progress: called as progress(done, total, best_error) after each batch
    """

    def __init__(self, fmu_path: str, kinematics: GearKinematics | None = None,
                 parameters: tuple[FaultParameter, ...] = GEAR_FAULT_PARAMETERS,
                 fixed_values: dict[str, float] | None = None, n_particles: int = 16,
                 iterations: int = 20, seed: int = 0, polish_evaluations: int = 80,
                 feature_mode: str = "lines", warmup_s: float = 0.05,
                 n_workers: int | None = None, relative_tolerance: float = 1e-6,
                 progress: Callable[[int, int, float], None] | None = None) -> None:
        if n_particles < 2 or iterations < 1:
            raise EstimationError("need at least 2 particles and 1 iteration")
        for p in parameters:
            if not p.low < p.high:
                raise EstimationError(f"bounds of '{p.name}' must satisfy low < high, "
                                      f"got [{p.low}, {p.high}]")
        self.fmu_path = str(fmu_path)
        self.kinematics = kinematics
        self.parameters = tuple(parameters)
        self.fixed_values = dict(fixed_values or {})
        self.n_particles = n_particles
        self.iterations = iterations
        self.seed = seed
        self.polish_evaluations = polish_evaluations
        self.feature_mode = feature_mode
        self.warmup_s = warmup_s
        self.n_workers = n_workers or os.cpu_count() or 1
        self.relative_tolerance = relative_tolerance
        self.progress = progress

    # ------------------------------------------------------------------ set-up
    def objective_for(self, measurement: Measurement) -> SpectralObjective:
        """The objective this estimator minimises for ``measurement`` (for checks and plots)."""
        spec = PlantSpec(self.fmu_path, tuple(measurement.channels), measurement.sample_rate_hz,
                         self.fixed_values, self.relative_tolerance)
        kin = self.kinematics
        if kin is None:
            try:
                with spec.open() as plant:
                    kin = plant.kinematics()
            except PlantError as err:
                raise EstimationError(str(err)) from None
        top = max_band_freq_hz(kin)
        if measurement.sample_rate_hz < 2 * top:
            raise EstimationError(
                f"sample rate {measurement.sample_rate_hz:g} Hz is below twice the highest band "
                f"edge ({top:g} Hz): need at least {2 * top:g} Hz")
        if measurement.duration_s < kin.period_s:
            raise EstimationError(
                f"measurement of {measurement.duration_s:.4g} s is shorter than one fundamental "
                f"period ({kin.period_s:.4g} s = {kin.n_assembly_phases} pinion turns)")
        reference = {name: signal_features(sig, measurement.sample_rate_hz, kin, self.feature_mode)
                     for name, sig in measurement.channels.items()}
        return SpectralObjective(spec, kin, [p.name for p in self.parameters], reference,
                                 self.feature_mode, self.warmup_s)

    # ------------------------------------------------------------------ fit
    def fit(self, measurement: Measurement) -> DiagnosisResult:
        started = time.perf_counter()
        objective = self.objective_for(measurement)
        lows = np.array([p.low for p in self.parameters])
        highs = np.array([p.high for p in self.parameters])
        total = self.n_particles * self.iterations + self.polish_evaluations
        counter = {"n": 0, "best": float("inf")}
        history: list[float] = []

        pool = None
        if self.n_workers > 1:
            pool = mp.get_context("fork").Pool(self.n_workers, _init_worker, (objective,))

        def batch(xs: np.ndarray) -> np.ndarray:
            xs = np.clip(xs, lows, highs)
            costs = np.array(pool.map(_evaluate_in_worker, list(xs)) if pool
                             else [objective(x) for x in xs])
            counter["n"] += len(xs)
            counter["best"] = min(counter["best"], float(np.min(costs)))
            if self.progress:
                self.progress(counter["n"], total, counter["best"])
            return costs

        try:
            best_x, best_cost = self._swarm(batch, lows, highs, history)
            if self.polish_evaluations > 0:
                best_x, best_cost = self._polish(batch, best_x, best_cost, lows, highs)
        finally:
            if pool is not None:
                pool.terminate()
                pool.join()
            objective.close()
        if not np.isfinite(best_cost):
            raise EstimationError("every simulation of the plant failed")
        params = {p.name: float(v) for p, v in zip(self.parameters, best_x)}
        cls = classify({**self.fixed_values, **params})
        return DiagnosisResult(params, cls.fault_mode, cls.severity, cls.tooth_severity,
                               cls.te_severity, best_cost, counter["n"],
                               time.perf_counter() - started, history)

    def _swarm(self, batch, lows, highs, history) -> tuple[np.ndarray, float]:
        from pyswarms.single import GlobalBestPSO

        rng = np.random.default_rng(self.seed)
        init = lows + rng.random((self.n_particles, lows.size)) * (highs - lows)
        # pyswarms draws from numpy's global generator: seed it for this run only.
        saved = np.random.get_state()
        np.random.seed(self.seed)
        quiet = logging.getLogger("pyswarms")
        level = quiet.level
        quiet.setLevel(logging.WARNING)
        try:
            pso = GlobalBestPSO(self.n_particles, lows.size,
                                options={"c1": 0.5, "c2": 0.3, "w": 0.9},
                                bounds=(lows, highs), init_pos=init)
            cost, pos = pso.optimize(batch, iters=self.iterations, verbose=False)
            history.extend(float(c) for c in pso.cost_history)
        finally:
            np.random.set_state(saved)
            quiet.setLevel(level)
        return np.asarray(pos, dtype=float), float(cost)

    def _polish(self, batch, x0, cost0, lows, highs) -> tuple[np.ndarray, float]:
        step = 0.02 * (highs - lows)
        simplex = [x0] + [np.clip(x0 + np.eye(x0.size)[i] * step[i] * (1 if x0[i] + step[i] <= highs[i]
                                                                        else -1), lows, highs)
                          for i in range(x0.size)]
        res = scipy.optimize.minimize(
            lambda x: float(batch(np.atleast_2d(x))[0]), x0, method="Nelder-Mead",
            bounds=list(zip(lows, highs)),
            options={"maxfev": self.polish_evaluations, "initial_simplex": np.array(simplex),
                     "xatol": 1e-4, "fatol": 1e-7})
        if res.fun < cost0:
            return np.asarray(res.x, dtype=float), float(res.fun)
        return x0, cost0
