"""The fit problem of a record and a model (:func:`build_problem`), made in three steps: the
operating point and the record prepared at it (:mod:`pydiag.fit.operating_point`: the
speed found and the record order-tracked), then the problem itself: the FMU opened once
to check the adapter and the parameters against it, the featurizer chosen, the sample
rate and the record length checked, and the measured features computed from the whole
record (:class:`~pydiag.fit.problem.FitProblem`, whose docstring says what it solves).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from dataclasses import dataclass

from pydiag.core.errors import AdapterError, EstimationError, PlantError
from pydiag.core.measurement import Measurement
from pydiag.core.parameters import Parameter
from pydiag.fit.operating_point import at_model_speed, prepare_record, resolve_operating_point
from pydiag.fit.problem import CS_STEPS_PER_PERIOD, FitProblem
from pydiag.gear.conventions import HEALTHY_TOOTH
from pydiag.gear.features import KinematicFeaturizer
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.speed import SpeedEstimate, SpeedSettings
from pydiag.model.adapter import Adapter, check_against_fmu, check_units, gear_default
from pydiag.model.simulate import SIMULATED_SOURCE
from pydiag.signal.features import Featurizer, SpectrumFeaturizer


@dataclass(frozen=True)
class ProblemSettings:
    """How a record becomes a fit problem, set once (the command line's ``--features``,
    ``--gain``, ``--speed``/``--tacho``, ``--teeth``/``--rpm``) and the same for every
    command, stage and machine model.

    Attributes:
        feature_mode: "lines" or "paper" (:mod:`pydiag.gear.features`)
        fit_gain: fit each channel's level; None: unless ``pydiag simulate`` made the
            record (:func:`build_problem`)
        gain_curve: the fitted gain a curve over frequency: True on every channel; None
            the model's default (a machine's own: on the accelerometers its file places,
            :func:`pydiag.loop.machine_fit.machine_problem`; a pair's: none); False none
        speed: how the speed is found in the record; None: the record at the nominal
            speed as it is (a gear pair's; a machine's speed is always found)
        operating_point: overrides of the nominal operating point
            (:func:`build_problem`'s)
    """

    feature_mode: str = "lines"
    fit_gain: bool | None = None
    gain_curve: bool | None = None
    speed: SpeedSettings | None = None
    operating_point: dict | None = None

    @property
    def tracking(self) -> SpeedSettings:
        """How a machine's speed is found: ``speed``, else the defaults."""
        return self.speed or SpeedSettings()

    @property
    def dropped(self) -> tuple[str, ...]:
        """The channels that are no sensor: the tacho's."""
        return (self.speed.tacho,) if self.speed is not None and self.speed.tacho else ()

    def keywords(self) -> dict:
        """:func:`build_problem`'s keywords for a pair's problem."""
        return {"feature_mode": self.feature_mode, "fit_gain": self.fit_gain,
                "gain_curve": self.gain_curve, "speed": self.speed,
                "operating_point": self.operating_point}


def _check_rate(measurement: Measurement, featurizer: Featurizer, what: str,
                top: float | None = None) -> None:
    top = featurizer.max_freq_hz if top is None else top
    if measurement.sample_rate_hz < 2 * top:
        raise EstimationError(
            f"sample rate {measurement.sample_rate_hz:g} Hz is below twice {what} "
            f"({top:g} Hz): need at least {2 * top:g} Hz")


def build_problem(fmu_path: str, measurement: Measurement, adapter: Adapter | None = None, *,
                  parameters: tuple[Parameter, ...] | None = None,
                  fixed_values: dict[str, float] | None = None,
                  kinematics: GearKinematics | None = None,
                  operating_point: dict[str, float] | None = None,
                  featurizer: Featurizer | None = None, feature_mode: str = "lines",
                  warmup_s: float | None = None, relative_tolerance: float | None = None,
                  engine: str | None = None, fit_gain: bool | None = False,
                  speed: SpeedSettings | None = None,
                  speed_estimate: SpeedEstimate | None = None,
                  gain_curve: bool | Iterable[str] | None = False) -> FitProblem:
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
        gain_curve: with the gain fitted, a curve over frequency (a node at every mesh
            harmonic, :mod:`pydiag.fit.gain`) rather than one number: on every channel
            (True), on those named, or on none (False, None)
    """
    if fit_gain is None:
        fit_gain = measurement.metadata.get("source") != SIMULATED_SOURCE
    given = adapter
    tacho = speed.tacho if speed is not None else None
    # the built-in adapter: every channel but the tacho is a sensor of the same name
    adapter = adapter or gear_default([c for c in measurement.channels if c != tacho])
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
            check_units(measurement, maps, plant.variables)
    except (PlantError, AdapterError) as err:
        raise EstimationError(str(err)) from err
    kin = resolve_operating_point(measurement, fmu_kin, kinematics, operating_point)
    curved = frozenset(s.channel for s in maps) if gain_curve is True else \
        frozenset(gain_curve or ()) & {s.channel for s in maps}
    if curved and fit_gain and kin is None:
        raise EstimationError("a gain curve needs the gear's kinematics: its nodes are the "
                              "mesh harmonics (give the teeth and the speed)")
    if kin is not None:
        if speed is not None and speed_estimate is None:  # no lines the record cannot hold
            _check_rate(measurement, featurizer or KinematicFeaturizer(kin, feature_mode),
                        "the highest band edge")
        measurement, kin, speed_estimate = prepare_record(measurement, kin, speed,
                                                          speed_estimate, maps[0].channel)
        fixed = {**adapter.kinematic_values(kin), **fixed}
        if adapter.kinematics["f_pinion_hz"].parameter is None and fmu_kin is not None:
            measurement, kin = at_model_speed(measurement, kin, fmu_kin)
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
                      adapter, fixed, fit_gain, speed_estimate,
                      gain_curve=curved if fit_gain else frozenset())
