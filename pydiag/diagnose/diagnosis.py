"""A diagnosis: the fit of a problem, what its parameters say of the machine (failure mode
and severity), what was analysed, and why the result may not be trusted. ``diagnose``,
``batch`` and ``demo`` make theirs here, the same way."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from pydiag.fit.estimator import FaultEstimator, FitResult
from pydiag.fit.problem import FitProblem
from pydiag.gear.classify import GROUPS, classify, group_level, healthy, tooth_contrast
from pydiag.gear.conventions import CLASSIFIED_PARAMETERS
from pydiag.diagnose.support import GroupSupport, fault_support, unprefixed

#: A fit whose relative error (Eq. 12, root-mean-square over channels) reaches this is
#: not a diagnosis: a model with no lines at all scores about 1.
UNEXPLAINED_ERROR = 1.0
#: The fault mode of a fit that explains none of the record: its parameters say nothing.
NO_DIAGNOSIS = "no_diagnosis"
#: A fitted channel gain outside this range is a level mismatch (mm/s^2 read as m/s^2 is
#: 1000), not a transfer path (a housing accelerometer sees the mesh attenuated by up to
#: some hundred times).
PLAUSIBLE_GAINS = (1 / 300, 300.0)
#: Level ratios (record / model) that a unit mistake makes: g read as m/s2 and back, a
#: milli- or micro- prefix missed, inches for metres. A ratio within UNIT_FACTOR_TOLERANCE
#: of one of these on a record whose level the model predicts is named as one.
UNIT_FACTORS = {9.80665: "g read as m/s2", 1 / 9.80665: "m/s2 read as g",
                1000.0: "a milli- prefix missed", 1e-3: "a milli- prefix too many",
                1e6: "a micro- prefix missed", 1e-6: "a micro- prefix too many",
                39.37: "metres read as inches", 1 / 39.37: "inches read as metres"}
UNIT_FACTOR_TOLERANCE = 0.15
#: A fitted parameter within this share of its range below its top is at the top.
TOP_OF_RANGE = 0.01


@dataclass
class Diagnosis:
    """A fit (:class:`pydiag.fit.estimator.FitResult`) and what it says of the machine.

    ``fault_mode``, ``severity``, ``tooth_severity``, ``te_severity``: the paper's classes
    of the GearDiag fault parameters ("not_classified" / "unknown" for a model without
    them; :data:`NO_DIAGNOSIS` / "unknown" for a fit that explains none of the record,
    :attr:`explained`); ``tooth_contrast``: |a_f/a0 - 1| when the tooth was estimated;
    ``facts``: what was analysed (speed, periods, gains); ``warnings``: why it may not be
    trusted; ``support``: the test of each group the fit found faulty
    (:mod:`pydiag.diagnose.support`): a group the record does not support is classified
    healthy."""

    fit: FitResult
    fault_mode: str
    severity: str
    tooth_severity: str
    te_severity: str
    tooth_contrast: float | None = None
    facts: dict = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    support: list[GroupSupport] = field(default_factory=list)

    @property
    def explained(self) -> bool:
        """Whether the fit explains the record at all (else its classes say nothing)."""
        return self.fault_mode != NO_DIAGNOSIS

    @property
    def parameters(self) -> dict[str, float]:
        return self.fit.parameters

    @property
    def error(self) -> float:
        return self.fit.error

    def to_dict(self) -> dict:
        """The JSON of ``diagnose``: the fit's fields, the classes, the facts, the warnings."""
        return {**self.fit.to_dict(), "fault_mode": self.fault_mode, "severity": self.severity,
                "tooth_severity": self.tooth_severity, "te_severity": self.te_severity,
                "tooth_contrast": self.tooth_contrast, **self.facts,
                "fault_support": [g.to_dict() for g in self.support],
                "warnings": self.warnings}


def classified(problem: FitProblem, fit: FitResult, facts: dict | None = None,
               speed_warning: bool = True, prefix: str = "") -> Diagnosis:
    """The diagnosis of ``fit``, a fit of ``problem``; ``facts`` as :func:`diagnose` finds
    them (default: the record's alone, no gains); ``speed_warning``: :func:`fit_warnings`'s
    ``speed``; ``prefix``: what the names of the classified parameters begin with (a stage
    of a machine's model: ``"<stage>."``; the pair's own: none)."""
    values = unprefixed({**problem.fixed_values, **fit.parameters}, prefix)
    fitted = {p.name for p in problem.parameters} & set(fit.parameters)
    fitted = {n[len(prefix):] for n in fitted if n.startswith(prefix)}
    facts = problem.record_facts() if facts is None else facts
    support: list[GroupSupport] = []
    if unexplained(problem, fit.error):
        labels, contrast = (NO_DIAGNOSIS,) + ("unknown",) * 3, None
    elif any(name in fitted for name in CLASSIFIED_PARAMETERS):
        found = classify(values)
        support = fault_support(problem, fit.parameters,
                                [g for g in GROUPS if group_level(found, g) != "none"], prefix)
        supported = values
        for test in support:
            if not test.supported:
                supported = healthy(supported, test.group)
        cls = classify(supported)
        labels = (cls.fault_mode, cls.severity, cls.tooth_severity, cls.te_severity)
        contrast = tooth_contrast(values) if "a_f" in fitted else None
    else:
        labels, contrast = ("not_classified",) + ("unknown",) * 3, None
    return Diagnosis(fit, *labels, contrast, facts,
                     fit_warnings(problem, fit.error, facts.get("gains"), fit.parameters,
                                  speed=speed_warning),
                     support)


def diagnose(problem: FitProblem, estimator: FaultEstimator | None = None,
             speed_warning: bool = True) -> Diagnosis:
    """Fit ``problem`` and classify the estimate; the facts include the channel gains;
    ``speed_warning``: :func:`fit_warnings`'s ``speed``.

    A record whose level the model is held to (no gain fitted) that the fit cannot explain
    is fitted again with its level free: a gain that is a unit factor names the likely
    unit mistake (:data:`UNIT_FACTORS`)."""
    estimator = estimator or FaultEstimator()
    fit = estimator.fit(problem)
    result = classified(problem, fit, problem.facts(fit.parameters), speed_warning)
    if not problem.fit_gain and not result.explained:
        free = dataclasses.replace(problem, fit_gain=True)
        refit = estimator.fit(free)
        if not unexplained(free, refit.error):
            result.warnings += unit_warnings(free.facts(refit.parameters)["gains"])
    return result


def unit_warnings(gains: dict[str, float]) -> list[str]:
    """A warning for each channel whose fitted gain (model -> record) is a unit factor."""
    found = []
    for channel, gain in gains.items():
        for factor, why in UNIT_FACTORS.items():
            if gain > 0 and abs(np.log(gain / factor)) < np.log1p(UNIT_FACTOR_TOLERANCE):
                found.append(f"channel {channel}: with its level free the model fits at "
                             f"{gain:.4g}x the level it predicts, a unit factor ({why}?): "
                             "check --unit, or fit the gain (--gain fit)")
    return found


def unexplained(problem: FitProblem, error: float) -> bool:
    """Whether a fit of ``problem`` with this ``error`` explains none of the record."""
    return error / np.sqrt(len(problem.channels)) >= UNEXPLAINED_ERROR


def fit_warnings(problem: FitProblem, error: float, gains: dict[str, float] | None = None,
                 parameters: dict[str, float] | None = None, speed: bool = True) -> list[str]:
    """Why a fit of ``problem`` with this ``error`` (and these fitted ``gains`` and
    ``parameters``, by name) is not to be trusted: an empty list when nothing looks wrong.
    ``speed``: with the warning of the problem's speed estimate (a machine's stage leaves it
    to the machine's, whose speed its own is derived from).

    A parameter at the top of its range is named: the record asks for more of it than the
    model allows, so the model's form or range is wrong there (at the bottom, a fault
    parameter says "none of it", a normal answer). A gain far from 1 is named where the
    level is a unit's check: not on a channel in volts (any level is right) nor on one
    whose gain is a curve (a housing between the mesh and the sensor sets its level)."""
    found = []
    for p in problem.parameters:
        value = (parameters or {}).get(p.name)
        if value is not None and not p.periodic and value >= p.high - TOP_OF_RANGE * (p.high - p.low):
            found.append(f"{p.name} = {value:.4g} is at the top of its range [{p.low:g}, "
                         f"{p.high:g}]: the record asks for more than the model allows (its "
                         "form or its range is wrong there)")
    check = "check the units (--unit), the channel mapping (--channel) and the sample rate"
    per_channel = error / np.sqrt(len(problem.channels))
    if unexplained(problem, error):
        found.append(f"the fit's error is {per_channel:.3g} per channel (1 = as large as the "
                     "measured lines): the model explains none of the record; "
                     f"{check}, the speed and the teeth (--rpm, --teeth), or give the fit "
                     "a larger budget")
    said = problem.speed.warning() if speed and problem.speed is not None else None
    if said:
        found.append(said)
    low, high = PLAUSIBLE_GAINS
    volts = problem.measurement.metadata.get("unknown_level", [])
    for channel, gain in (gains or {}).items():
        if not low <= gain <= high and channel not in volts and \
                channel not in problem.gain_curve:
            found.append(f"channel {channel}: the model had to be scaled by {gain:.3g} to "
                         f"match the record's level; {check}")
    return found
