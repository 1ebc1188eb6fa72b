"""A diagnosis per stage of a machine: each stage is a gear pair, fitted on its own lines at
its own shafts, the other stages' lines named and left out, and judged against the
machine's own healthy state where baselines are given.

For stage k: the record order-tracked at the stage's pinion shaft (the input shaft's angle,
found from every mesh or from the tacho, times the shaft's speed ratio); the pair model at
the stage's teeth and speed fitted on the stage's kinematic bands, without the other
stages' mesh harmonics and sidebands that are none of its own lines
(:class:`~pydiag.gear.features.KinematicFeaturizer`); the fit classified on the paper's
simulated scale (:mod:`pydiag.diagnose.diagnosis`).

With baselines, each stage is also judged by the change of its shafts' residual energy
against them (:mod:`pydiag.gear.stage_judge`): a stage that did not change is
``healthy`` whatever the paper's scale says of it; one that changed keeps the model's
fault mode and severity (``changed`` where the model finds nothing it can classify), and
its suspect is the shaft that changed clearly more. Without baselines the classes are
the paper's scale, and the suspect is the shaft whose orders modulate the stage's mesh
twice as strongly as the other's (the sidebands 1 to 3 orders either side of each mesh
harmonic in the measured lines), for a stage the model finds faulty.

A stage is fitted on the sensors the machine file places near it (``near_stage``), else
on every sensor it describes.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Collection, Sequence

import numpy as np

from pydiag.core.measurement import Measurement
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.build import ProblemSettings, build_problem
from pydiag.fit.problem import FitProblem
from pydiag.gear.component import asked_of_model, judged_by_model
from pydiag.gear.features import KinematicFeaturizer, max_band_freq_hz
from pydiag.gear.machine import Machine
from pydiag.gear.machine_indicators import MachineRecord, machine_record
from pydiag.gear.machine_report import (SCALE_PAPER, MachineReport, StageReport, judged_report,
                                        stage_report)
from pydiag.gear.speed import SpeedEstimate, SpeedSettings, estimate_speed
from pydiag.gear.stage_judge import StageVerdict
from pydiag.gear.tracking import Upsampled, order_track, upsampled_record
from pydiag.diagnose.diagnosis import Diagnosis, classified, diagnose
from pydiag.loop.machine_fit import fit_machine, machine_problem, refit_machine, stage_view
from pydiag.loop.machine_model import MachineModel
from pydiag.loop.own_changes import (HealthyModel, fit_healthy, lacking_tries,
                                     record_changes, with_lacking)
from pydiag.model.adapter import Adapter

#: Without baselines, a shaft is the suspect when its sidebands carry this many times the
#: other shaft's energy.
SUSPECT_RATIO = 2.0
#: Sideband orders either side of a mesh harmonic that the suspect is judged by.
SUSPECT_SIDEBANDS = 3


def pair_json(name: str, problem: FitProblem, fit: Diagnosis) -> dict:
    """The machine-level JSON fields of a gear pair diagnosed alone (``diagnose
    --teeth``, or a machine of one stage without a baseline), a machine of one stage
    called ``name``: ``stages`` (that one, :func:`stage_diagnosis`), no baselines, and
    the paper's scale; the pair's own fields stay at the top beside them. None of them for
    a model that is no gear pair (no kinematics: an adapter's mass and spring)."""
    if problem.kinematics is None:
        return {}
    return {"stages": [stage_diagnosis(name, problem, fit).to_dict()], "baselines": [],
            "healthy_spread_db": None, "severity_scale": SCALE_PAPER}


def machine_speed(measurement: Measurement, machine: Machine, input_hz: float,
                  speed: SpeedSettings = SpeedSettings()) -> SpeedEstimate:
    """The input shaft's speed in ``measurement``, around the nominal ``input_hz``: from
    the tacho, else from every stage's mesh at once (:mod:`pydiag.gear.speed`)."""
    return estimate_speed(measurement, machine.stage_kinematics(0, input_hz), speed,
                          machine=machine)


def stage_speed(speed: SpeedEstimate, machine: Machine, stage: int) -> SpeedEstimate:
    """The input shaft's ``speed`` at stage ``stage``'s pinion shaft (times its ratio)."""
    ratio = float(machine.shaft_ratio(stage))
    return dataclasses.replace(
        speed, speed_hz=speed.speed_hz * ratio, nominal_hz=speed.nominal_hz * ratio,
        revolutions=speed.revolutions * ratio,
        mesh_speed_hz=None if speed.mesh_speed_hz is None else speed.mesh_speed_hz * ratio)


def stage_problem(fmu_path: str, measurement: Measurement, machine: Machine, stage: int,
                  speed: SpeedEstimate, settings: ProblemSettings = ProblemSettings(),
                  adapter: Adapter | None = None,
                  fixed_values: dict[str, float] | None = None,
                  upsampled: Upsampled | None = None) -> FitProblem:
    """The fit problem of stage ``stage``: the record tracked at its pinion shaft, the
    other stages' lines left out (module docstring); its kinematics name every line of
    the machine (:meth:`~pydiag.gear.machine.Machine.stage_kinematics`); ``upsampled``: the
    record upsampled for tracking at ``speed``
    (:func:`~pydiag.gear.tracking.upsampled_record`), when made once for every stage."""
    estimate = stage_speed(speed, machine, stage)
    kin = machine.stage_kinematics(stage, speed.speed_hz)
    top = max_band_freq_hz(kin)
    others = tuple(f for j in range(len(machine.stages)) if j != stage
                   for f in machine.stage_lines(j, speed.speed_hz, top))
    tracked = _stage_channels(order_track(measurement, estimate, settings.dropped, upsampled),
                              machine, stage)
    return build_problem(fmu_path, tracked, adapter, kinematics=kin,
                         featurizer=KinematicFeaturizer(kin, settings.feature_mode, others),
                         fit_gain=settings.fit_gain, speed_estimate=estimate,
                         fixed_values=fixed_values, gain_curve=settings.gain_curve)


def _stage_channels(measurement: Measurement, machine: Machine, stage: int) -> Measurement:
    """The channels a stage is fitted on, named as the model outputs they measure: the
    sensors the machine places near the stage, else every sensor it describes (the first
    of those that measure one output), else every channel as it is named. A sensor the
    machine file places sits on its housing: its level against the pair's is the
    housing's, not a unit's check (``unknown_level``, as a channel in volts)."""
    sensors = [s for s in machine.sensors if s.channel in measurement.channels]
    near = [s for s in sensors if s.near_stage == stage] or sensors
    if not near:
        return measurement
    chosen: dict[str, str] = {}
    for s in near:
        chosen.setdefault(s.output, s.channel)
    meta = dict(measurement.metadata)
    meta["unknown_level"] = list(chosen)
    return dataclasses.replace(measurement, channels={out: measurement.channels[c]
                                                      for out, c in chosen.items()},
                               metadata=meta)


def _sideband_suspect(problem: FitProblem) -> str | None:
    """The shaft whose orders modulate the mesh :data:`SUSPECT_RATIO` times more, from
    the measured lines of the problem's first channel."""
    kin, ref = problem.kinematics, problem.reference[problem.channels[0]]
    tolerance = 0.25 * kin.f_hunting_hz
    energy = {}
    for shaft, f in (("pinion", kin.f_pinion_hz), ("gear", kin.f_gear_hz)):
        total = 0.0
        for h in range(1, 5):
            for k in range(1, SUSPECT_SIDEBANDS + 1):
                for line in (h * kin.f_mesh_hz - k * f, h * kin.f_mesh_hz + k * f):
                    near = np.abs(ref.freq_hz - line) < tolerance
                    total += float(np.sum(ref.amplitude[near] ** 2))
        energy[shaft] = total
    if energy["pinion"] >= SUSPECT_RATIO * energy["gear"]:
        return "pinion"
    if energy["gear"] >= SUSPECT_RATIO * energy["pinion"]:
        return "gear"
    return None


def diagnose_machine(fmu_path: str, measurement: Measurement, machine: Machine,
                     input_hz: float, settings: ProblemSettings = ProblemSettings(),
                     estimator: FaultEstimator | None = None,
                     baselines: Sequence[MachineRecord] = (),
                     adapter: Adapter | None = None) -> MachineReport:
    """Every stage of ``measurement`` diagnosed (module docstring), around the nominal input
    speed ``input_hz``; ``baselines``: records of the machine in a known healthy state, as
    :func:`~pydiag.gear.machine_indicators.machine_record` sees them (made once for a
    batch of records)."""
    estimator = estimator or FaultEstimator()
    found = machine_speed(measurement, machine, input_hz, settings.tracking)
    # once for every shaft and stage
    upsampled = upsampled_record(measurement, found, settings.dropped)
    judged = _judged(measurement, machine, found, settings.tracking, upsampled, baselines)
    stages = []
    for k, stage in enumerate(machine.stages):
        problem = stage_problem(fmu_path, measurement, machine, k, found, settings, adapter,
                                upsampled=upsampled)
        fit = diagnose(problem, estimator, speed_warning=False)
        stages.append(stage_diagnosis(stage.name, problem, fit, _verdict(judged, k)))
    return dataclasses.replace(judged, stages=tuple(stages))


def _judged(measurement: Measurement, machine: Machine, found: SpeedEstimate,
            speed: SpeedSettings, upsampled: Upsampled | None,
            baselines: Sequence[MachineRecord]) -> MachineReport:
    """The record's report at speed ``found`` without a model: with ``baselines`` every
    shaft's TSA and every stage and component judged against them; without, the speed
    alone (no stage)."""
    if not baselines:
        return MachineReport(machine, found, ())
    record = machine_record(measurement, machine, speed, found.nominal_hz, found, upsampled)
    return judged_report(machine, record, baselines)


def _verdict(judged: MachineReport, stage: int) -> StageVerdict | None:
    """Stage ``stage``'s verdict in ``judged`` (None: not judged)."""
    return judged.stages[stage].verdict if judged.stages else None


def diagnose_machine_model(fmu_path: str, model: MachineModel, measurement: Measurement,
                           machine: Machine, input_hz: float,
                           settings: ProblemSettings = ProblemSettings(),
                           estimator: FaultEstimator | None = None,
                           baselines: Sequence[MachineRecord] = (),
                           healthy: HealthyModel | None = None,
                           effect_model: Callable[[Machine], str] | None = None,
                           grow: Callable[[HealthyModel, Collection[tuple[str, str]]],
                                          HealthyModel] | None = None
                           ) -> MachineReport:
    """Every stage of ``measurement`` diagnosed by the machine's own model (``model``,
    built at ``fmu_path``: :mod:`pydiag.loop.machine_model`): every stage fitted at once
    (:func:`~pydiag.loop.machine_fit.fit_machine`, from the machine file's ``[start]``
    too; with a ``healthy`` model, its fit polished on the record:
    :func:`~pydiag.loop.machine_fit.refit_machine`), each stage classified from its own
    fault parameters and tested on the lines seen from its own shafts
    (:func:`~pydiag.loop.machine_fit.stage_view`), and judged against ``baselines`` as
    :func:`diagnose_machine` judges. With the machine's ``healthy`` model
    (:func:`healthy_model`) held to a healthy repeat, the model's own verdict too
    (:func:`~pydiag.loop.own_changes.record_changes`: each of its effects, and each it
    lacks where it could name a component the indicators ask about,
    :func:`~pydiag.gear.component.asked_of_model`, refitted held out on the record, the
    change held to its repeats'), which joins the indicators' on every
    component an effect of that model sizes
    (:func:`~pydiag.gear.component.judged_by_model`); ``effect_model``: the FMU of the
    machine with one effect more (for the effects it lacks). A lacking effect the record
    is asked for that the healthy model has not yet tried on its own records is tried
    there first by ``grow`` (the model and the tries: the model grown, say by
    :func:`grown_healthy`, and kept); without ``grow``, it is not asked."""
    estimator = estimator or FaultEstimator()
    found = machine_speed(measurement, machine, input_hz, settings.tracking)
    judged = _judged(measurement, machine, found, settings.tracking, None, baselines)
    problem = machine_problem(fmu_path, model, measurement, machine, found, settings)
    fit = (fit_machine(problem, model, estimator, start=machine.fit_start()) if healthy is None
           else refit_machine(problem, model, estimator, healthy.parameters))
    facts = problem.facts(fit.parameters)
    stages = []
    for k, stage in enumerate(machine.stages):
        view = dataclasses.replace(stage_view(problem, machine, model, k, fit.parameters),
                                   speed=stage_speed(found, machine, k))
        prefix = f"{model.stages[k]}."
        stages.append(stage_diagnosis(stage.name, view, classified(view, fit, facts, False,
                                                                   prefix),
                                      _verdict(judged, k), prefix))
    changes = []
    if healthy is not None and healthy.repeat_z:  # without a repeat it judges nothing
        asked = asked_of_model(judged.components)
        tries = lacking_tries(healthy, machine, model, asked)
        if tries - set(healthy.held) and grow is not None:
            healthy = grow(healthy, tries)
        changes = record_changes(healthy, machine, model, problem, effect_model=effect_model,
                                 asked=asked)
    return dataclasses.replace(judged, stages=tuple(stages), model_changes=tuple(changes),
                               components=judged_by_model(judged.components, changes))


def asked_tries(model: MachineModel, measurement: Measurement, machine: Machine,
                input_hz: float, healthy: HealthyModel, baselines: Sequence[MachineRecord],
                settings: ProblemSettings = ProblemSettings()) -> set[tuple[str, str]]:
    """The (stage, effect) of ``healthy.lacking`` that :func:`diagnose_machine_model` asks
    of ``measurement``: where they could name a component the indicators ask about
    against ``baselines`` (:func:`~pydiag.gear.component.asked_of_model`); the
    indicators alone, no fit (a batch asks every record first, so that the healthy model
    is grown once, before any record is judged)."""
    found = machine_speed(measurement, machine, input_hz, settings.tracking)
    judged = _judged(measurement, machine, found, settings.tracking, None, baselines)
    return lacking_tries(healthy, machine, model, asked_of_model(judged.components))


def grown_healthy(healthy: HealthyModel, fmu_path: str, model: MachineModel,
                  machine: Machine, healthy_records: Sequence[Measurement], input_hz: float,
                  settings: ProblemSettings, tries: Collection[tuple[str, str]],
                  effect_model: Callable[[Machine], str]) -> HealthyModel:
    """``healthy`` with the lacking ``tries`` it has not held yet tried on its own records
    (``healthy_records``: the one it was fitted to, then its repeats), each at its own
    speed (:func:`~pydiag.loop.own_changes.with_lacking`)."""
    if not set(tries) - set(healthy.held):
        return healthy
    first, *others = healthy_problems(fmu_path, model, machine, healthy_records, input_hz,
                                      settings)
    return with_lacking(healthy, machine, model, first, others, tries, effect_model)


def healthy_model(fmu_path: str, model: MachineModel, machine: Machine,
                  healthy: Sequence[Measurement], input_hz: float,
                  settings: ProblemSettings = ProblemSettings(),
                  estimator: FaultEstimator | None = None, lacking: Sequence[str] = ()
                  ) -> HealthyModel:
    """The machine's healthy model (:func:`~pydiag.loop.own_changes.fit_healthy`): its
    own model (``model``, built at ``fmu_path``, with the effects the machine file gives
    its stages, say from ``pydiag loop`` on the first record) fitted to the first of the
    ``healthy`` records and held to the others; ``lacking``: catalogue effects it lacks
    that a record may be asked about (tried on these records when one first is:
    :func:`diagnose_machine_model`). Of one record, it has no repeat to hold a change to
    and judges nothing: its fit is where a record's own starts."""
    if not healthy:
        raise ValueError("a healthy model needs its record")
    first, *others = healthy_problems(fmu_path, model, machine, healthy, input_hz, settings)
    return fit_healthy(machine, model, first, others, estimator or FaultEstimator(),
                       lacking=lacking)


def healthy_problems(fmu_path: str, model: MachineModel, machine: Machine,
                     healthy: Sequence[Measurement], input_hz: float,
                     settings: ProblemSettings = ProblemSettings()) -> list[FitProblem]:
    """The problems of the machine's model on each of the ``healthy`` records, each at
    its own speed found from the record."""
    return [machine_problem(fmu_path, model, m, machine,
                            machine_speed(m, machine, input_hz, settings.tracking), settings)
            for m in healthy]


def stage_diagnosis(name: str, problem: FitProblem, fit: Diagnosis,
                    verdict: StageVerdict | None = None, prefix: str = "") -> StageReport:
    """A stage called ``name``: ``fit``, the diagnosis of its pair's ``problem``, and what
    the baselines say of it (``verdict``: :func:`~pydiag.gear.machine_report.stage_report`).
    A gear pair diagnosed alone (``diagnose --teeth``) is a machine of this one stage.
    Without a verdict, the suspect of a stage the model finds faulty is read from the
    record's sidebands (module docstring). ``prefix``: what the stage's parameters' names
    begin with in ``fit`` (:attr:`~pydiag.gear.machine_report.StageReport.prefix`)."""
    suspect = (_sideband_suspect(problem) if verdict is None and fit.explained
               and fit.fault_mode != "healthy" else None)
    kin = problem.kinematics  # at the model's speed if it cannot be set: the record's here
    pinion_hz = problem.speed.speed_hz if problem.speed is not None else kin.f_pinion_hz
    return stage_report(name, kin.n_pinion, kin.n_gear, pinion_hz, verdict, fit, suspect,
                        prefix)
