"""The fit problem: built once from (FMU, adapter, measurement), then fitted, compared,
extended with an effect (:meth:`FitProblem.derive`, which opens no FMU).

One concern: what a fit of a model to a record solves (the record's features, the
model's runs, their residuals); the record's preparation is
:mod:`pydiag.fit.operating_point`'s, a gain's arithmetic :mod:`pydiag.fit.gain`'s.

:func:`pydiag.fit.build.build_problem` makes it. It is plain, picklable data: worker
processes get it whole and open their own plant (:class:`ProblemObjective`).

Channel gains: a real accelerometer sits on a housing, behind a transfer path and in
units of its own, so the model's level is not the measurement's. With ``fit_gain`` each
channel's model features are scaled by the gain that fits them best in least squares,
in closed form (it enters linearly): ``g = sum(S R~) / sum(S^2)`` with the noise taken out
of the measured amplitudes, ``R~ = sqrt(max(R^2 - P, 0))``. The fault parameters then
match the shape of the spectrum, never its overall level. With ``gain_curve`` too, the
gain is a curve over frequency with a node at every mesh harmonic
(:mod:`pydiag.fit.gain`): the parameters then match the pattern of lines around each
harmonic, not the spectrum's shape.

With the level free, the stiffness variation of the faulty tooth (``a_f``) and of the
healthy ones (``a0``, fixed at the paper's 0.1 otherwise) both scale the mesh lines, so
only their ratio is identifiable: on the GearDiag model with the gain fitted, ``a0`` is
fitted too (:data:`pydiag.gear.conventions.HEALTHY_TOOTH`), and the tooth is judged by its
contrast ``a_f / a0 - 1`` (:mod:`pydiag.gear.classify`; bench/RESULTS.md, section 7).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pydiag.core.errors import EstimationError, PlantError
from pydiag.core.measurement import Measurement
from pydiag.core.parameters import Parameter, fmu_values
from pydiag.fit.gain import apply_curve, curve_basis, curve_nodes, fitted_curve, fitted_gain
from pydiag.fit.objective import spectral_residuals
from pydiag.fmu.description import read_model_description
from pydiag.fmu.periodic import simulate_period, simulate_periodic
from pydiag.fmu.plant import FmuPlant, PlantSpec
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.speed import SpeedEstimate
from pydiag.model.adapter import Adapter
from pydiag.signal.features import Featurizer
from pydiag.signal.ripple import OVERSAMPLE, Ripple
from pydiag.signal.spectra import Spectrum, whole_periods
from pydiag.signal.transfer import HousingMode

#: Co-Simulation: communication steps per period of the highest analysed frequency,
#: unless the adapter says otherwise.
CS_STEPS_PER_PERIOD = 20.0


@dataclass(frozen=True)
class FitProblem:
    """Everything a fit needs; see :func:`pydiag.fit.build.build_problem`.

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
        transfer: paths between the model's outputs and the sensors, applied to the
            simulated outputs (:mod:`pydiag.signal.transfer`); their variables are among
            the parameters and fixed values, never set in the FMU
        gain_curve: the channels whose fitted gain (with ``fit_gain``) is a curve over
            frequency with a node at every mesh harmonic (module docstring); the others'
            is one number
        ripple: a speed or torque ripple the model has (its size and frequency among the
            FMU's values), read from the model's periodic response without it
            (:mod:`pydiag.signal.ripple`) instead of simulated over the whole record
    """

    spec: PlantSpec
    channels: tuple[str, ...]
    scales: tuple[float, ...]
    parameters: tuple[Parameter, ...]
    reference: dict[str, Spectrum]
    featurizer: Featurizer
    warmup_s: float
    kinematics: GearKinematics | None
    measurement: Measurement
    adapter: Adapter
    fixed_values: dict[str, float] = field(default_factory=dict)
    fit_gain: bool = False
    speed: SpeedEstimate | None = None
    fixed_gains: dict[str, float] = field(default_factory=dict)
    transfer: tuple[HousingMode, ...] = ()
    gain_curve: frozenset[str] = frozenset()
    ripple: Ripple | None = None

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
        m = self.measurement
        return whole_periods(m.n_samples, m.sample_rate_hz, self.kinematics.period_s)[0]

    def record_facts(self) -> dict:
        """What was analysed: speed (when found), periods and seconds of the record, and
        ``gain_curve`` when the gains are curves (:meth:`gains` gives their level at the
        first mesh harmonic)."""
        facts = dict(self.speed.to_dict()) if self.speed is not None else {}
        n = self.n_periods
        facts["n_periods"] = n
        facts["duration_s"] = (n * self.kinematics.period_s if n is not None
                               else self.featurizer.duration_s)
        if self.gain_curve:
            facts["gain_curve"] = True
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

    def _simulate(self, plant: FmuPlant, x: np.ndarray, duration_s: float) -> np.ndarray:
        values = {p.fmu_variable: p.fmu_value(v) for p, v in zip(self.parameters, x)}
        paths = {v for path in self.transfer for v in path.variables}
        fmu = {k: v for k, v in values.items() if k not in paths}
        y = self._rippled(plant, fmu, duration_s) if self.ripple is not None else None
        if y is None:
            y = simulate_periodic(plant, fmu, duration_s, self.warmup_s,
                                  None if self.kinematics is None else self.kinematics.period_s)
        if self.transfer:
            y = np.array(y, dtype=float)
            at = {**self.fixed_values, **values}
            for path in self.transfer:
                i = self.spec.sensors.index(path.output)
                y[i] = path.apply(y[i], self.spec.sample_rate_hz, at)
        return np.asarray(self.scales)[:, None] * y

    def _rippled(self, plant: FmuPlant, values: dict[str, float], duration_s: float
                 ) -> np.ndarray | None:
        """The model's outputs with its :attr:`ripple`, read from periods of its response
        without it; None when that response does not repeat (the whole record is then
        simulated with the ripple in the model)."""
        if self.kinematics is None:
            return None
        ripple = self.ripple
        at = {name: float(plant.variables[name].start) for name in ripple.variables}
        at.update({k: v for k, v in {**plant.fixed_values, **values}.items() if k in at})
        fs = self.spec.sample_rate_hz
        return ripple.read(lambda changes: simulate_period(
            plant, {**values, **changes}, self.warmup_s, self.kinematics.period_s, OVERSAMPLE),
            at, self.spec.sensors, int(round(duration_s * fs)), fs, self.warmup_s)

    def _clean(self, channel: str) -> np.ndarray:
        ref = self.reference[channel]
        return np.sqrt(np.maximum(ref.amplitude ** 2 - ref.noise_power, 0.0))

    def _curved(self, channel: str) -> bool:
        return self.fit_gain and channel in self.gain_curve and channel not in self.fixed_gains

    def curve_nodes_hz(self) -> np.ndarray:
        """The gain curve's nodes (:func:`pydiag.fit.gain.curve_nodes`), Hz."""
        return curve_nodes(self.kinematics, max(float(s.freq_hz[-1])
                                                for s in self.reference.values()))

    def _basis(self, channel: str) -> np.ndarray:
        """The gain curve's hat functions at ``channel``'s feature bins."""
        return curve_basis(self.reference[channel].freq_hz, self.curve_nodes_hz())

    def _curve(self, model: np.ndarray, channel: str, basis: np.ndarray | None = None
               ) -> np.ndarray:
        """The gain curve's node values that fit ``model`` (features) to ``channel``;
        ``basis``: :meth:`_basis` of the channel when the caller has it."""
        basis = self._basis(channel) if basis is None else basis
        return fitted_curve(model, self._clean(channel), basis)

    def _gain(self, model: np.ndarray, channel: str) -> float | np.ndarray:
        """The gain of ``model`` (features) onto ``channel``: a number, or with
        ``gain_curve`` one a feature."""
        if channel in self.fixed_gains:
            return self.fixed_gains[channel]
        if not self.fit_gain:
            return 1.0
        if channel in self.gain_curve:  # the basis once: it runs at every evaluation of a fit
            basis = self._basis(channel)
            return basis @ self._curve(model, channel, basis)
        return fitted_gain(model, self._clean(channel))

    def gains(self, plant: FmuPlant, x: np.ndarray) -> dict[str, float]:
        """Channel -> the model's gain at ``x`` (1.0 everywhere without ``fit_gain``; with
        ``gain_curve``, the curve's value at the first mesh harmonic)."""
        y = self._simulate(plant, x, self.featurizer.duration_s)
        fs = self.spec.sample_rate_hz
        out = {}
        for i, c in enumerate(self.channels):
            model = self.featurizer(y[i], fs).amplitude
            out[c] = (float(self._curve(model, c)[0]) if self._curved(c)
                      else float(self._gain(model, c)))
        return out

    def model_signals(self, plant: FmuPlant, x: np.ndarray, duration_s: float | None = None) -> np.ndarray:
        """Channel signals (channel units, gains applied) of the model at ``x``."""
        duration_s = self.featurizer.duration_s if duration_s is None else duration_s
        y = self._simulate(plant, x, max(duration_s, self.featurizer.duration_s))
        if self.fit_gain:
            fs = self.spec.sample_rate_hz
            out = []
            for i, c in enumerate(self.channels):
                model = self.featurizer(y[i], fs).amplitude
                out.append(apply_curve(y[i], fs, self.curve_nodes_hz(), self._curve(model, c))
                           if self._curved(c) else self._gain(model, c) * y[i])
            y = np.array(out)
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
        return self.residuals_of_amplitudes(self._amplitudes(y))

    def _amplitudes(self, y: np.ndarray) -> list[np.ndarray]:
        return [self.featurizer(y[i], self.spec.sample_rate_hz).amplitude
                for i in range(len(self.channels))]

    def _scaled(self, amplitudes: list[np.ndarray]) -> list[np.ndarray]:
        return [self._gain(model, c) * model for model, c in zip(amplitudes, self.channels)]

    def residuals_of_amplitudes(self, amplitudes: list[np.ndarray]) -> np.ndarray:
        """Eq. (12) residuals of the model's feature amplitudes, one array a channel."""
        return np.concatenate([spectral_residuals(model, self.reference[c].amplitude,
                                                  self.reference[c].noise_power)
                               for model, c in zip(self._scaled(amplitudes), self.channels)])

    def fitted_features(self, plant: FmuPlant, x: np.ndarray) -> list[np.ndarray]:
        """The model's feature amplitudes at ``x``, one array a channel, with the gains
        the error fits (what :meth:`residuals` compares with the reference)."""
        return self._scaled(self._amplitudes(self.simulate(plant, x)))

    def linear_features(self, y: np.ndarray) -> list[np.ndarray] | None:
        """Complex values a channel whose moduli are the feature amplitudes of the signals
        ``y``, linear in them; None when the featurizer's are not
        (``FullSpectrumFeaturizer.linear``)."""
        linear = getattr(self.featurizer, "linear", None)
        if linear is None:
            return None
        out = [linear(y[i], self.spec.sample_rate_hz) for i in range(len(self.channels))]
        return None if any(v is None for v in out) else out

    def analytic(self, y: np.ndarray) -> list[np.ndarray] | None:
        """Complex signals a channel, linear in the signals ``y``, whose moduli are the
        envelopes the features are spectra of (``FullSpectrumFeaturizer.analytic``); None
        when the features are not an envelope's."""
        analytic = getattr(self.featurizer, "analytic", None)
        if analytic is None:
            return None
        out = [analytic(y[i], self.spec.sample_rate_hz) for i in range(len(self.channels))]
        return None if any(v is None for v in out) else out

    def residuals_of_analytic(self, analytic: list[np.ndarray]) -> np.ndarray:
        """:meth:`residuals_of` the signals whose :meth:`analytic` is ``analytic``."""
        fs = self.spec.sample_rate_hz
        return self.residuals_of_amplitudes([self.featurizer.of_analytic(z, fs).amplitude
                                             for z in analytic])

    def derive(self, fmu_path: str | None = None, parameters: tuple[Parameter, ...] | None = None,
               fixed_values: dict[str, float] | None = None,
               featurizer: Featurizer | None = None,
               fixed_gains: dict[str, float] | None = None,
               transfer: tuple[HousingMode, ...] | None = None,
               ripple: Ripple | None = None) -> "FitProblem":
        """The same record, adapter and settings with another FMU (an effect's model, which
        has every variable of this one), other parameters, more fixed values (in FMU
        variable names), another featurizer (the record's features computed again) or
        more channel gains held (:attr:`fixed_gains`), other transfer paths (to the
        sensors: their variables are not the FMU's), a ripple (:attr:`ripple`, kept
        when None). Nothing is simulated, and the FMU
        is not opened: its model description is read (once a file) to check that it has
        the variables set."""
        spec = self.spec if fmu_path is None else dataclasses.replace(self.spec,
                                                                      fmu_path=str(fmu_path))
        parameters = parameters or self.parameters
        transfer = self.transfer if transfer is None else tuple(transfer)
        paths = {v for path in transfer for v in path.variables}
        fixed = {**self.fixed_values, **(fixed_values or {})}
        spec = dataclasses.replace(spec, fixed_values={
            **spec.fixed_values, **{k: v for k, v in (fixed_values or {}).items()
                                    if k not in paths}})
        if fmu_path is not None or parameters is not self.parameters or fixed_values:
            _check_variables(spec.fmu_path, [name for name in [p.fmu_variable for p in parameters]
                                             + list(fixed_values or {}) if name not in paths])
        missing = [path.output for path in transfer if path.output not in spec.sensors]
        if missing:
            raise EstimationError(f"no model output {', '.join(missing)} to pass through a "
                                  "housing (the channels compared do not use it)")
        reference = self.reference
        if featurizer is not None and featurizer is not self.featurizer:
            m = self.measurement
            reference = {c: featurizer(m.channels[c], m.sample_rate_hz) for c in self.channels}
        return dataclasses.replace(self, spec=spec, parameters=tuple(parameters),
                                   fixed_values=fixed, featurizer=featurizer or self.featurizer,
                                   reference=reference,
                                   fixed_gains={**self.fixed_gains, **(fixed_gains or {})},
                                   transfer=transfer, ripple=ripple or self.ripple)


def _check_variables(fmu_path: str, names: list[str]) -> None:
    """Every one of ``names`` is a variable of the FMU, else an :class:`EstimationError`."""
    try:
        md, _ = read_model_description(fmu_path)
    except PlantError as err:
        raise EstimationError(str(err)) from err
    known = {v.name for v in md.modelVariables}
    missing = [n for n in names if n not in known]
    if missing:
        raise EstimationError(f"{', '.join(missing)} {'is' if len(missing) == 1 else 'are'} "
                              f"not in {Path(fmu_path).name}")


class ProblemObjective:
    """Parameter vector -> Eq. (12) residuals, with one plant per process, opened lazily."""

    def __init__(self, problem: FitProblem) -> None:
        self.problem = problem
        self._plant: FmuPlant | None = None

    def prepare(self) -> None:
        """Open the plant now (a worker process, before its first evaluation is timed)."""
        if self._plant is None:
            self._plant = self.problem.spec.open()

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Residuals at ``x``; a failed simulation raises PlantError with its cause."""
        self.prepare()
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
