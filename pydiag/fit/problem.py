"""The fit problem: built once from (FMU, adapter, measurement), then fitted, compared,
extended with an effect.

:func:`build_problem` opens the FMU to check the adapter against it and to resolve the
kinematics; for a real record it finds the speed and order-tracks the record
(:mod:`pydiag.gear.speed`) and puts the model at that speed; it chooses the featurizer,
checks the sample rate and the record length, and computes the measured features from the
whole record. The result is plain, picklable data: worker processes get it whole and open
their own plant (:class:`ProblemObjective`).

Channel gains: a real accelerometer sits on a housing, behind a transfer path and in
units of its own, so the model's level is not the measurement's. With ``fit_gain`` each
channel's model features are scaled by the gain that fits them best in least squares,
in closed form (it enters linearly): ``g = sum(S R~) / sum(S^2)`` with the noise taken out
of the measured amplitudes, ``R~ = sqrt(max(R^2 - P, 0))``. The fault parameters then
match the shape of the spectrum, never its overall level.

With the level free, the stiffness variation of the faulty tooth (``a_f``) and of the
healthy ones (``a0``, fixed at the paper's 0.1 otherwise) both scale the mesh lines, so
only their ratio is identifiable: on the GearDiag model with the gain fitted, ``a0`` is
fitted too (:data:`pydiag.gear.conventions.HEALTHY_TOOTH`), and the tooth is judged by its
contrast ``a_f / a0 - 1`` (:mod:`pydiag.gear.classify`). Measured on the shared real
records before this: with ``a0`` fixed, ``a_f`` came out 0.64-0.67 on the healthy records
and 0.16-0.17 on the broken-tooth ones; with ``a0`` fitted, the contrast is 0.30/0.37
healthy and 0.54/0.68 broken (0 % / 90 % load), the same for three swarm seeds.
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
from pydiag.gear.conventions import HEALTHY_TOOTH
from pydiag.gear.features import KinematicFeaturizer
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.speed import SpeedEstimate, SpeedSettings, estimate_speed, order_track
from pydiag.model.adapter import Adapter, check_against_fmu, gear_default
from pydiag.model.simulate import SIMULATED_SOURCE
from pydiag.signal.features import Features, Featurizer, SpectrumFeaturizer

#: Co-Simulation: communication steps per period of the highest analysed frequency,
#: unless the adapter says otherwise.
CS_STEPS_PER_PERIOD = 20.0
#: A fit whose relative error (Eq. 12, root-mean-square over channels) reaches this is
#: not a diagnosis: a model with no lines at all scores about 1 (measured: a record in
#: mm/s^2 read as m/s^2 scored 1.70 with the level fixed, parameters on their bounds).
UNEXPLAINED_ERROR = 1.0
#: A fitted channel gain outside this range is a level mismatch (mm/s^2 read as m/s^2 is
#: 1000), not a transfer path (a housing accelerometer sees the mesh attenuated, by up to
#: some hundred times: the shared real records fit gains of 0.0145-0.40).
PLAUSIBLE_GAINS = (1 / 300, 300.0)
#: Two consecutive simulated fundamental periods that differ by no more than this share of
#: the channel's peak make the model periodic (:func:`simulate_periodic`). Measured on
#: GearPair and the effect models at rest: 2e-5 to 4e-5 (the integrator's tolerance); a
#: component that is not periodic and stays below this lies 60 dB under the peak.
PERIODIC_TOLERANCE = 1e-3


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
        fit_gain: scale each channel's model by its least-squares gain (module docstring)
        speed: the speed found in the record and how (None: the record was taken as it is)
        fixed_gains: channel -> gain (model -> measurement) held instead of fitted, e.g. a
            fit's gains carried to features that cannot tell a gain from a parameter
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
    fit_gain: bool = False
    speed: SpeedEstimate | None = None
    fixed_gains: dict[str, float] = field(default_factory=dict)

    @property
    def lows(self) -> np.ndarray:
        return np.array([p.low for p in self.parameters])

    @property
    def highs(self) -> np.ndarray:
        return np.array([p.high for p in self.parameters])

    def fmu_values(self, estimates: dict[str, float]) -> dict[str, float]:
        """FMU variable -> value for estimates by parameter name."""
        return fmu_values(self.parameters, estimates)

    @property
    def n_periods(self) -> int | None:
        """Whole fundamental periods of the record the measured features come from."""
        if self.kinematics is None:
            return None
        return int(np.floor(self.measurement.duration_s / self.kinematics.period_s + 1e-9))

    def record_facts(self) -> dict:
        """What was analysed: speed (when found), periods and seconds of the record."""
        facts = dict(self.speed.to_dict()) if self.speed is not None else {}
        n = self.n_periods
        facts["n_periods"] = n
        facts["duration_s"] = (n * self.kinematics.period_s if n is not None
                               else self.featurizer.duration_s)
        return facts

    def facts(self, estimates: dict[str, float]) -> dict:
        """:meth:`record_facts` and, with ``fit_gain``, the channel gains at ``estimates``
        (by parameter name; one simulation)."""
        facts = self.record_facts()
        if self.fit_gain:
            with self.spec.open() as plant:
                facts["gains"] = self.gains(plant, np.array([estimates[p.name]
                                                              for p in self.parameters]))
        return facts

    def warnings(self, error: float, gains: dict[str, float] | None = None) -> list[str]:
        """Why a fit with this ``error`` (and these fitted ``gains``) is not to be trusted:
        an empty list when nothing looks wrong."""
        found = []
        check = ("check the units (--unit), the channel mapping (--channel) and the sample "
                 "rate")
        per_channel = error / np.sqrt(len(self.channels))
        if per_channel >= UNEXPLAINED_ERROR:
            found.append(f"the fit's error is {per_channel:.3g} per channel (1 = as large as the "
                         "measured lines): the model explains none of the record; "
                         f"{check}, the speed and the teeth (--rpm, --teeth), or give the fit "
                         "a larger budget")
        low, high = PLAUSIBLE_GAINS
        for channel, gain in (gains or {}).items():
            if not low <= gain <= high:
                found.append(f"channel {channel}: the model had to be scaled by {gain:.3g} to "
                             f"match the record's level; {check}")
        return found

    def _simulate(self, plant: FmuPlant, x: np.ndarray, duration_s: float) -> np.ndarray:
        values = {p.fmu_variable: p.fmu_value(v) for p, v in zip(self.parameters, x)}
        return np.asarray(self.scales)[:, None] * simulate_periodic(
            plant, values, duration_s, self.warmup_s,
            None if self.kinematics is None else self.kinematics.period_s)

    def _gain(self, model: np.ndarray, channel: str) -> float:
        if channel in self.fixed_gains:
            return self.fixed_gains[channel]
        if not self.fit_gain:
            return 1.0
        ref = self.reference[channel]
        clean = np.sqrt(np.maximum(ref.amplitude ** 2 - ref.noise_power, 0.0))
        power = float(np.dot(model, model))
        return max(float(np.dot(model, clean)) / power, 0.0) if power > 0 else 1.0

    def gains(self, plant: FmuPlant, x: np.ndarray) -> dict[str, float]:
        """Channel -> the model's gain at ``x`` (1.0 everywhere without ``fit_gain``)."""
        y = self._simulate(plant, x, self.featurizer.duration_s)
        return {c: self._gain(self.featurizer(y[i], self.spec.sample_rate_hz).amplitude, c)
                for i, c in enumerate(self.channels)}

    def model_signals(self, plant: FmuPlant, x: np.ndarray, duration_s: float | None = None) -> np.ndarray:
        """Channel signals (channel units, gains applied) of the model at ``x``."""
        duration_s = self.featurizer.duration_s if duration_s is None else duration_s
        y = self._simulate(plant, x, max(duration_s, self.featurizer.duration_s))
        if self.fit_gain:
            fs = self.spec.sample_rate_hz
            y = np.array([self._gain(self.featurizer(y[i], fs).amplitude, c) * y[i]
                          for i, c in enumerate(self.channels)])
        return y[:, :int(round(duration_s * self.spec.sample_rate_hz))]

    def residuals(self, plant: FmuPlant, x: np.ndarray) -> np.ndarray:
        """Eq. (12) residuals of every channel at ``x``, concatenated; PlantError on failure."""
        return self.residuals_of(self.simulate(plant, x))

    def simulate(self, plant: FmuPlant, x: np.ndarray) -> np.ndarray:
        """Channel signals of the model at ``x`` over the featurizer's duration (channel
        units, before the gains :meth:`residuals_of` fits); PlantError on failure."""
        return self._simulate(plant, x, self.featurizer.duration_s)

    def residuals_of(self, y: np.ndarray) -> np.ndarray:
        """Eq. (12) residuals of every channel of the signals ``y`` (:meth:`simulate`'s)."""
        out = []
        for i, c in enumerate(self.channels):
            model = self.featurizer(y[i], self.spec.sample_rate_hz).amplitude
            ref = self.reference[c]
            out.append(spectral_residuals(self._gain(model, c) * model, ref.amplitude,
                                          ref.noise_power))
        return np.concatenate(out)

    def derive(self, fmu_path: str | None = None, parameters: tuple[Parameter, ...] | None = None,
               fixed_values: dict[str, float] | None = None,
               featurizer: Featurizer | None = None,
               fixed_gains: dict[str, float] | None = None) -> "FitProblem":
        """The same measurement, adapter and settings with another FMU (an effect's model),
        other parameters, more fixed values (in FMU variable names), another featurizer or
        more channel gains held (:attr:`fixed_gains`)."""
        return dataclasses.replace(build_problem(
            fmu_path or self.spec.fmu_path, self.measurement, self.adapter,
            parameters=parameters or self.parameters,
            fixed_values={**self.fixed_values, **(fixed_values or {})},
            kinematics=self.kinematics, featurizer=featurizer or self.featurizer,
            warmup_s=self.warmup_s, relative_tolerance=self.spec.relative_tolerance,
            engine=self.spec.engine, fit_gain=self.fit_gain, speed_estimate=self.speed),
            fixed_gains={**self.fixed_gains, **(fixed_gains or {})})


def simulate_periodic(plant: FmuPlant, values: dict[str, float], duration_s: float,
                      warmup_s: float, period_s: float | None) -> np.ndarray:
    """``plant.simulate(values, duration_s, warmup_s)``, from one period when the model is
    periodic.

    A gear model whose inputs are all synchronous with the fundamental period settles to a
    response of that period: then two periods after the warm-up are simulated and, when
    they agree (:data:`PERIODIC_TOLERANCE`), the second one is repeated over the duration.
    A record of 33 periods then costs 2 simulated periods instead of 33 (measured on
    GearPair, 2 cores x86_64: 10 ms instead of 134 ms). Anything that is not periodic
    in ``period_s`` (a bearing's strikes, a ripple at a free frequency, a subharmonic, a
    transient still decaying) makes the two periods differ, and the whole duration is
    simulated as before.
    """
    fs = plant.sample_rate_hz
    total = int(round(duration_s * fs))
    if period_s is not None:
        per = period_s * fs
        n = int(round(per))
        if n > 0 and abs(per - n) <= 1e-6 * per and total > 3 * n:
            y = plant.simulate(values, 2 * n / fs, warmup_s)
            first, last = y[:, :n], y[:, n:2 * n]
            peak = np.max(np.abs(last), axis=1)
            if np.all(np.max(np.abs(last - first), axis=1) <= PERIODIC_TOLERANCE * peak):
                return np.tile(last, (1, -(-total // n)))[:, :total]
    return plant.simulate(values, duration_s, warmup_s)


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


def _check_rate(measurement: Measurement, featurizer: Featurizer, what: str,
                top: float | None = None) -> None:
    top = featurizer.max_freq_hz if top is None else top
    if measurement.sample_rate_hz < 2 * top:
        raise EstimationError(
            f"sample rate {measurement.sample_rate_hz:g} Hz is below twice {what} "
            f"({top:g} Hz): need at least {2 * top:g} Hz")


def _nominal_kinematics(measurement: Measurement, fmu_kin: GearKinematics | None,
                        given: GearKinematics | None) -> GearKinematics | None:
    """The operating point to start from: the one given, else the record's own metadata
    (a record made by ``pydiag simulate``), else the FMU's."""
    if given is not None:
        return given
    meta = measurement.metadata.get("kinematics")
    if isinstance(meta, dict) and fmu_kin is not None:
        try:
            return GearKinematics(int(meta["Np"]), int(meta["Ng"]), float(meta["f_pinion"]))
        except (KeyError, TypeError, ValueError):
            pass  # not ours: the FMU's operating point
    return fmu_kin


def build_problem(fmu_path: str, measurement: Measurement, adapter: Adapter | None = None, *,
                  parameters: tuple[Parameter, ...] | None = None,
                  fixed_values: dict[str, float] | None = None,
                  kinematics: GearKinematics | None = None,
                  operating_point: dict[str, float] | None = None,
                  featurizer: Featurizer | None = None, feature_mode: str = "lines",
                  warmup_s: float | None = None, relative_tolerance: float | None = None,
                  engine: str | None = None, fit_gain: bool | None = False,
                  speed: SpeedSettings | None = None,
                  speed_estimate: SpeedEstimate | None = None) -> FitProblem:
    """The fit problem of ``measurement`` on ``fmu_path``.

    Args:
        adapter: what the FMU is; None: the GearDiag conventions (paper parameter names,
            channels named as outputs, kinematics from Np, Ng, f_pinion)
        parameters: override the adapter's fault parameters and bounds
        fixed_values: FMU values set in every run, on top of the adapter's start values
        kinematics: the nominal operating point (teeth, pinion speed), set in the model
            where the adapter maps it to parameters; default: the record's metadata (a
            record made by ``pydiag simulate``), else the FMU's
        operating_point: some of ``n_pinion``, ``n_gear``, ``f_pinion_hz`` (nominal),
            ``other_shaft_ratio``, ``bearing`` over that default (the command line's
            --teeth, --rpm, --other-shaft, --bearing)
        featurizer: override the features (see :class:`pydiag.signal.features.Featurizer`)
        feature_mode: "lines" or "paper" (gear models, :mod:`pydiag.gear.features`)
        warmup_s, relative_tolerance, engine: override the adapter's simulation settings
        fit_gain: fit a gain per channel in closed form (see the module docstring); None:
            fit it unless the record was made by ``pydiag simulate`` from a model (whose
            level is the model's by construction)
        speed: find the speed in the record and order-track it (gear models); None takes
            the record at the nominal speed as it is
        speed_estimate: a speed already found for this (already tracked) measurement
    """
    if fit_gain is None:
        fit_gain = measurement.metadata.get("source") != SIMULATED_SOURCE
    given = adapter
    adapter = adapter or gear_default(list(measurement.channels))
    tacho = speed.tacho if speed is not None else None
    maps = tuple(s for s in adapter.sensors if s.channel in measurement.channels
                 and s.channel != tacho)
    missing = [s.channel for s in adapter.sensors if s.channel not in measurement.channels]
    if given is not None and missing:
        raise EstimationError(f"the measurement lacks channel(s) {', '.join(missing)} that "
                              f"the adapter names; it has: {', '.join(measurement.channels)}")
    if not maps:
        raise EstimationError(f"no measurement channel to compare: it has "
                              f"{', '.join(measurement.channels)}")
    if not parameters:
        parameters = adapter.fault_parameters
        names = [p.name for p in parameters]
        if fit_gain and given is None and "a_f" in names and HEALTHY_TOOTH.name not in names:
            parameters = parameters + (HEALTHY_TOOTH,)
    parameters = tuple(parameters)
    fixed = dict(fixed_values or {})
    try:
        with adapter.plant_spec(fmu_path, measurement.sample_rate_hz, maps, fixed,
                                relative_tolerance, engine).open() as plant:
            check_against_fmu(adapter, plant.variables)
            for p in parameters:
                if p.fmu_variable not in plant.variables:
                    raise EstimationError(f"fault parameter '{p.fmu_variable}' is not in "
                                          f"{plant.fmu_path.name}")
            fmu_kin = adapter.resolve_kinematics({**plant.parameters(), **plant.fixed_values})
    except (PlantError, AdapterError) as err:
        raise EstimationError(str(err)) from err
    kin = _nominal_kinematics(measurement, fmu_kin, kinematics)
    if operating_point:
        if kin is None:
            raise EstimationError("--rpm, --teeth, --other-shaft need a gear model: this FMU has "
                                  "no Np, Ng, f_pinion and the adapter no [kinematics]")
        op = {k: (int(v) if k in ("n_pinion", "n_gear") else v if k == "bearing" else float(v))
              for k, v in operating_point.items()}
        kin = dataclasses.replace(kin, **op)
    if kin is not None and speed is not None and speed_estimate is None:
        _check_rate(measurement, featurizer or KinematicFeaturizer(kin, feature_mode),
                    "the highest band edge")  # before searching lines the record cannot hold
        settings = speed if speed.channel else dataclasses.replace(speed, channel=maps[0].channel)
        speed_estimate = estimate_speed(measurement, kin, settings)
        measurement = order_track(measurement, speed_estimate, drop=(tacho,) if tacho else ())
        kin = dataclasses.replace(kin, f_pinion_hz=speed_estimate.speed_hz)
    if kin is not None:
        fixed = {**adapter.kinematic_values(kin), **fixed}
        speed_fixed = adapter.kinematics["f_pinion_hz"].parameter is None
        if speed_fixed and fmu_kin is not None and fmu_kin != kin.pair:  # what the model knows
            # the model's operating point is fixed: analyse the record at it (an
            # order-tracked record is the same per revolution at any speed)
            if measurement.metadata.get("order_tracking"):
                measurement = dataclasses.replace(
                    measurement, sample_rate_hz=measurement.sample_rate_hz
                    * fmu_kin.f_pinion_hz / kin.f_pinion_hz)
            kin = dataclasses.replace(fmu_kin, other_shaft_ratio=kin.other_shaft_ratio,
                                      bearing=kin.bearing)
    spec = adapter.plant_spec(fmu_path, measurement.sample_rate_hz, maps, fixed,
                              relative_tolerance, engine)
    if featurizer is not None:
        top, what = featurizer.max_freq_hz, "the highest analysed frequency"
    elif kin is not None:
        featurizer = KinematicFeaturizer(kin, feature_mode)
        top, what = featurizer.max_freq_hz, "the highest band edge"
    else:
        featurizer = SpectrumFeaturizer(adapter.window_s, adapter.max_freq_hz)
        top, what = adapter.max_freq_hz, "the adapter's max_freq_hz"
    _check_rate(measurement, featurizer, what, top)
    if measurement.duration_s < featurizer.duration_s * (1 - 1e-9):
        raise EstimationError(f"measurement of {measurement.duration_s:.4g} s is shorter than "
                              f"{featurizer.describe_duration()}")
    spec = dataclasses.replace(spec, cs_step_s=adapter.cs_step_s or 1.0 / (CS_STEPS_PER_PERIOD * top))
    reference = {s.channel: featurizer(measurement.channels[s.channel], measurement.sample_rate_hz)
                 for s in maps}
    return FitProblem(spec, tuple(s.channel for s in maps), tuple(s.scale for s in maps),
                      parameters, reference, featurizer,
                      adapter.warmup_s if warmup_s is None else warmup_s, kin, measurement,
                      adapter, fixed, fit_gain, speed_estimate)
