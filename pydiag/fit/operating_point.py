"""The first two steps of a fit problem: the machine's operating point, and the record
prepared at it.

1. :func:`resolve_operating_point`: the nominal kinematics (teeth, pinion speed, the
   machine facts beside the pair) from what was given, else the record's own metadata (a
   record made by ``pydiag simulate``), else the FMU's parameters; then the command line's
   overrides (``--rpm``, ``--teeth``, ``--other-shaft``, ``--bearing``).
2. :func:`prepare_record`: the speed found in the record and the record order-tracked to
   it (:mod:`pydiag.gear.speed`); for a model whose speed is fixed, :func:`at_model_speed`.

The third, the :class:`~pydiag.fit.problem.FitProblem` itself, is
:func:`pydiag.fit.build.build_problem`'s.
"""

from __future__ import annotations

import dataclasses

from pydiag.core.errors import EstimationError, PydiagError
from pydiag.core.measurement import Measurement
from pydiag.gear.conventions import kinematics_from
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.speed import SpeedEstimate, SpeedSettings, estimate_speed
from pydiag.gear.tracking import order_track

#: The keys of an operating point (``build_problem``'s ``operating_point``) and their types.
OPERATING_POINT_KEYS = {"n_pinion": int, "n_gear": int, "f_pinion_hz": float,
                        "other_shaft_ratio": float, "bearing": None}


def record_kinematics(measurement: Measurement) -> GearKinematics | None:
    """The kinematics a record states in its metadata (one made by ``pydiag simulate``:
    ``{"kinematics": {"Np": .., "Ng": .., "f_pinion": ..}}``), or None: it states none."""
    meta = measurement.metadata.get("kinematics")
    if not isinstance(meta, dict):
        return None
    try:
        return kinematics_from(meta)
    except (PydiagError, TypeError, ValueError):
        return None  # not ours


def resolve_operating_point(measurement: Measurement, fmu_kinematics: GearKinematics | None,
                            given: GearKinematics | None = None,
                            overrides: dict | None = None) -> GearKinematics | None:
    """The nominal operating point (module docstring, step 1); None for a model without
    gear kinematics (an error when ``overrides`` need one)."""
    kin = given
    if kin is None and fmu_kinematics is not None:
        kin = record_kinematics(measurement) or fmu_kinematics
    if not overrides:
        return kin
    if kin is None:
        raise EstimationError("--rpm, --teeth, --other-shaft, --bearing need a gear model: this "
                              "FMU has no Np, Ng, f_pinion and the adapter no [kinematics]")
    unknown = sorted(set(overrides) - set(OPERATING_POINT_KEYS))
    if unknown:
        raise EstimationError(f"unknown operating-point key(s) {', '.join(unknown)}")
    return dataclasses.replace(kin, **{k: v if OPERATING_POINT_KEYS[k] is None
                                       else OPERATING_POINT_KEYS[k](v)
                                       for k, v in overrides.items()})


def prepare_record(measurement: Measurement, kin: GearKinematics, speed: SpeedSettings | None,
                   speed_estimate: SpeedEstimate | None, channel: str
                   ) -> tuple[Measurement, GearKinematics, SpeedEstimate | None]:
    """(the record to fit, its kinematics at the speed found, the speed): module
    docstring, step 2.

    ``speed`` None takes the record as it is, at the nominal speed; ``speed_estimate`` is
    one already found for this (already tracked) record; ``channel``: the one searched for
    mesh lines unless ``speed`` names one."""
    if speed is None or speed_estimate is not None:
        return measurement, kin, speed_estimate
    tacho = speed.tacho
    settings = speed if speed.channel else dataclasses.replace(speed, channel=channel)
    speed_estimate = estimate_speed(measurement, kin, settings)
    measurement = order_track(measurement, speed_estimate, drop=(tacho,) if tacho else ())
    return measurement, dataclasses.replace(kin, f_pinion_hz=speed_estimate.speed_hz), \
        speed_estimate


def at_model_speed(measurement: Measurement, kin: GearKinematics,
                   model_kinematics: GearKinematics) -> tuple[Measurement, GearKinematics]:
    """A model whose speed cannot be set (an adapter that maps no speed parameter) is
    analysed at its own operating point: an order-tracked record is put at the model's
    speed (it is the same per revolution at any speed)."""
    if model_kinematics == kin.pair:
        return measurement, kin
    if measurement.metadata.get("order_tracking"):
        measurement = dataclasses.replace(
            measurement, sample_rate_hz=measurement.sample_rate_hz
            * model_kinematics.f_pinion_hz / kin.f_pinion_hz)
    return measurement, dataclasses.replace(model_kinematics,
                                            other_shaft_ratio=kin.other_shaft_ratio,
                                            bearing=kin.bearing, surroundings=kin.surroundings,
                                            gear_bearing=kin.gear_bearing)
