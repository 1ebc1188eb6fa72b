"""The fit problem: built once from (FMU, adapter, measurement), then fitted, compared,
extended with an effect.

:func:`build_problem` opens the FMU once to check the adapter against it and to resolve
the kinematics, chooses the featurizer, checks the sample rate and the record length,
and computes the measured features. The result is plain, picklable data: worker
processes get it whole and open their own plant (:class:`ProblemObjective`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from pydiag.core.errors import AdapterError, EstimationError, PlantError
from pydiag.core.measurement import Measurement
from pydiag.core.parameters import Parameter, fmu_values
from pydiag.fit.objective import spectral_residuals
from pydiag.fmu.plant import FmuPlant, PlantSpec
from pydiag.gear.features import KinematicFeaturizer
from pydiag.gear.kinematics import GearKinematics
from pydiag.model.adapter import Adapter, check_against_fmu, gear_default
from pydiag.signal.features import Features, Featurizer, SpectrumFeaturizer

#: Co-Simulation: communication steps per period of the highest analysed frequency,
#: unless the adapter says otherwise.
CS_STEPS_PER_PERIOD = 20.0


@dataclass(frozen=True)
class FitProblem:
    """Everything a fit needs; see :func:`build_problem`.

    Attributes:
        spec: how to open the plant (sensor variables, start and fixed values, settings)
        channels: measurement channels compared, in the order of ``spec.sensors``
        scales: channel = scale x sensor output, per channel
        parameters: what is estimated, with bounds and FMU variables
        reference: measured features per channel
        featurizer: signal -> features, for model and measurement alike
        warmup_s: simulated start-up discarded before the analysed window
        kinematics: gear kinematics (None for models without)
        measurement: the measurement itself
        adapter: what the FMU is (the GearDiag defaults when none was given)
        fixed_values: FMU values set on every run on top of the adapter's start values
    """

    spec: PlantSpec
    channels: tuple[str, ...]
    scales: tuple[float, ...]
    parameters: tuple[Parameter, ...]
    reference: dict[str, Features]
    featurizer: Featurizer
    warmup_s: float
    kinematics: GearKinematics | None
    measurement: Measurement
    adapter: Adapter
    fixed_values: dict[str, float] = field(default_factory=dict)

    @property
    def lows(self) -> np.ndarray:
        return np.array([p.low for p in self.parameters])

    @property
    def highs(self) -> np.ndarray:
        return np.array([p.high for p in self.parameters])

    def fmu_values(self, estimates: dict[str, float]) -> dict[str, float]:
        """FMU variable -> value for estimates by parameter name."""
        return fmu_values(self.parameters, estimates)

    def model_signals(self, plant: FmuPlant, x: np.ndarray, duration_s: float | None = None) -> np.ndarray:
        """Channel signals (channel units) of the model at parameter vector ``x``."""
        values = {p.fmu_variable: p.fmu_value(v) for p, v in zip(self.parameters, x)}
        y = plant.simulate(values, self.featurizer.duration_s if duration_s is None else duration_s,
                           self.warmup_s)
        return np.asarray(self.scales)[:, None] * y

    def residuals(self, plant: FmuPlant, x: np.ndarray) -> np.ndarray:
        """Eq. (12) residuals of every channel at ``x``, concatenated; PlantError on failure."""
        y = self.model_signals(plant, x)
        out = []
        for i, c in enumerate(self.channels):
            model = self.featurizer(y[i], self.spec.sample_rate_hz)
            ref = self.reference[c]
            out.append(spectral_residuals(model.amplitude, ref.amplitude, ref.noise_power))
        return np.concatenate(out)

    def derive(self, fmu_path: str | None = None, parameters: tuple[Parameter, ...] | None = None,
               fixed_values: dict[str, float] | None = None,
               featurizer: Featurizer | None = None) -> "FitProblem":
        """The same measurement, adapter and settings with another FMU (an effect's model),
        other parameters, more fixed values (in FMU variable names) or another featurizer."""
        return build_problem(
            fmu_path or self.spec.fmu_path, self.measurement, self.adapter,
            parameters=parameters or self.parameters,
            fixed_values={**self.fixed_values, **(fixed_values or {})},
            kinematics=self.kinematics, featurizer=featurizer or self.featurizer,
            warmup_s=self.warmup_s, relative_tolerance=self.spec.relative_tolerance,
            engine=self.spec.engine)


class ProblemObjective:
    """Parameter vector -> Eq. (12) residuals, with one plant per process, opened lazily."""

    def __init__(self, problem: FitProblem) -> None:
        self.problem = problem
        self._plant: FmuPlant | None = None

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Residuals at ``x``; a failed simulation raises PlantError with its cause."""
        if self._plant is None:
            self._plant = self.problem.spec.open()
        return self.problem.residuals(self._plant, x)

    def residuals_or_none(self, x: np.ndarray) -> np.ndarray | None:
        try:
            return self.residuals(x)
        except PlantError:
            return None

    def __call__(self, x: np.ndarray) -> float:
        """Root-sum-square of the per-channel Eq. (12) errors; inf if the simulation fails."""
        r = self.residuals_or_none(x)
        return float("inf") if r is None else float(np.linalg.norm(r))

    def close(self) -> None:
        if self._plant is not None:
            self._plant.close()
            self._plant = None

    def __enter__(self) -> "ProblemObjective":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def build_problem(fmu_path: str, measurement: Measurement, adapter: Adapter | None = None, *,
                  parameters: tuple[Parameter, ...] | None = None,
                  fixed_values: dict[str, float] | None = None,
                  kinematics: GearKinematics | None = None,
                  featurizer: Featurizer | None = None, feature_mode: str = "lines",
                  warmup_s: float | None = None, relative_tolerance: float | None = None,
                  engine: str | None = None) -> FitProblem:
    """The fit problem of ``measurement`` on ``fmu_path``.

    Args:
        adapter: what the FMU is; None: the GearDiag conventions (paper parameter names,
            channels named as outputs, kinematics from Np, Ng, f_pinion)
        parameters: override the adapter's fault parameters and bounds
        fixed_values: FMU values set in every run, on top of the adapter's start values
        kinematics: override the adapter's gear kinematics
        featurizer: override the features (see :class:`pydiag.signal.features.Featurizer`)
        feature_mode: "lines" or "paper" (gear models, :mod:`pydiag.gear.features`)
        warmup_s, relative_tolerance, engine: override the adapter's simulation settings
    """
    given = adapter
    adapter = adapter or gear_default(list(measurement.channels))
    maps = tuple(s for s in adapter.sensors if s.channel in measurement.channels)
    missing = [s.channel for s in adapter.sensors if s.channel not in measurement.channels]
    if given is not None and missing:
        raise EstimationError(f"the measurement lacks channel(s) {', '.join(missing)} that "
                              f"the adapter names; it has: {', '.join(measurement.channels)}")
    parameters = tuple(parameters) if parameters else adapter.fault_parameters
    fixed = dict(fixed_values or {})
    spec = adapter.plant_spec(fmu_path, measurement.sample_rate_hz, maps, fixed,
                              relative_tolerance, engine)
    try:
        with spec.open() as plant:
            check_against_fmu(adapter, plant.variables)
            for p in parameters:
                if p.fmu_variable not in plant.variables:
                    raise EstimationError(f"fault parameter '{p.fmu_variable}' is not in "
                                          f"{plant.fmu_path.name}")
            kin = kinematics or adapter.resolve_kinematics({**plant.parameters(),
                                                            **spec.fixed_values})
    except (PlantError, AdapterError) as err:
        raise EstimationError(str(err)) from err
    if featurizer is not None:
        top, what = featurizer.max_freq_hz, "the highest analysed frequency"
    elif kin is not None:
        featurizer = KinematicFeaturizer(kin, feature_mode)
        top, what = featurizer.max_freq_hz, "the highest band edge"
    else:
        featurizer = SpectrumFeaturizer(adapter.window_s, adapter.max_freq_hz)
        top, what = adapter.max_freq_hz, "the adapter's max_freq_hz"
    if measurement.sample_rate_hz < 2 * top:
        raise EstimationError(
            f"sample rate {measurement.sample_rate_hz:g} Hz is below twice {what} "
            f"({top:g} Hz): need at least {2 * top:g} Hz")
    if measurement.duration_s < featurizer.duration_s:
        raise EstimationError(f"measurement of {measurement.duration_s:.4g} s is shorter than "
                              f"{featurizer.describe_duration()}")
    spec = dataclasses.replace(spec, cs_step_s=adapter.cs_step_s or 1.0 / (CS_STEPS_PER_PERIOD * top))
    reference = {s.channel: featurizer(measurement.channels[s.channel], measurement.sample_rate_hz)
                 for s in maps}
    return FitProblem(spec, tuple(s.channel for s in maps), tuple(s.scale for s in maps),
                      parameters, reference, featurizer,
                      adapter.warmup_s if warmup_s is None else warmup_s, kin, measurement,
                      adapter, fixed)
