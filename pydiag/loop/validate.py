"""Held-out validation of a suggested effect: does it explain the measurement, or the noise
and the base model's other misfits?

A missing effect is real when adding it predicts data it was not fitted to. The record
(order-tracked, whole fundamental periods) is cut into alternating periods: half A (0, 2,
4, ...) and half B (1, 3, 5, ...), two records of the same machine with independent noise
(:class:`pydiag.gear.features.FullSpectrumFeaturizer`, ``half``). The effect's parameters
(and the channel gains) are fitted on A, the base parameters held at their fit, then base
and effect are scored on B, on bins that A's measurement chose (so B's noise does not
choose them), and on the bins where the fitted effect predicts a line above the noise
that A's measurement has no peak at (chosen by A's fit: an effect that predicts lines the
record lacks pays for them). The base parameters come from the whole record, B included:
a few parameters over hundreds of lines, which leans the test slightly towards the base
model. Joining every other period keeps a synchronous line on its bin and moves one that
is not (``FullSpectrumFeaturizer.joined_freq_hz``): the lines are named where the halves
show them.

An effect that takes energy from the base model's own lines (``Effect.reshapes_base``: a
speed fluctuation, a second faulty tooth) found a base fit bent to make up for it, which
its own parameters alone cannot undo. For those, the swarm over the effect's parameters
(base held, its two best positions polished) is followed by one least-squares polish on
A with the base parameters free as well (:func:`pydiag.loop.compare.fit_effect`), and the
base model gets the same polish on A (:meth:`pydiag.fit.estimator.FaultEstimator.refine`),
so both models' last fit is on A alone (the base's start came from the whole record, as above).
Measured on the independent simulator's torque ripple (bench/independent_truth.py): the
speed fluctuation explained 29-47 % of its lines held out with the base held, 82-96 %
freed.

**The test.** On B, each compared bin holds a measured amplitude R, Rician around the
true line with noise power P per bin. Let mu0, mu1 be the Rician means of the base and the
effect model lines (:func:`pydiag.fit.objective.rician_mean`), V0 the Rician variance
around the base line, w = 1/V0 and d = mu1 - mu0. The held-out improvement is

    D = sum w [(R - mu0)^2 - (R - mu1)^2] = sum w d (2R - mu0 - mu1).

If the base model is right and the effect only fits A's noise (H0), R has mean mu0 and
variance V0 independently of d, so D is close to normal with mean -sum w d^2 and variance
4 sum w d^2, and

    z = (D + sum w d^2) / (2 sqrt(sum w d^2))

is standard normal. The effect **lowers the held-out error by more than noise alone would**
when z > the (1 - alpha) normal quantile; alpha (:data:`FALSE_ALARM_RATE`, 1 %) is the
chance that an effect which only fits noise passes. The test is one-sided and per effect.

A misfit of the base model's form is not noise: it is in both halves, and an effect that
fits part of it passes the test. So a confident effect must also **explain its lines**:
on B, the part of the residual above noise on the lines its signature claims, sum w
[(R - mu0)^2 - V0], must fall by at least :data:`MIN_EXPLAINED` (a half). And no fitted
parameter may sit at a bound of its range (an angle has none): then "the effect
saturates: its range or the model form is wrong".

A bearing's strikes ring a structural mode kHz above the gear's bands, and the rolling
elements' slip smears their harmonics there into a hump: they show as lines only in the
envelope of that band (``Effect.envelope``; McFadden and Smith's envelope analysis). Such
an effect is fitted and scored as above on the spectrum of the envelope of each channel,
its gear lines removed first (every line that repeats each fundamental period: the
discrete/random separation of bearing diagnostics, so a base model wrong at high mesh
harmonics does not matter), in the band from the top of the gear's analysed bands to
:data:`ENVELOPE_TOP` of the sample rate; the channel gains stay the base fit's (with the
gear gone, a gain and the strike amplitude are one); and it is tried whatever compare's
score (which is the spectrum's).

Competing effects: at most one is confident among those that claim the same lines,
either the same peaks of the whole record (compare) or the same non-synchronous lines of
half A (:func:`rivals`): joined halves can put two bearing frequencies a few hertz apart
on one bin. And only if the record tells it apart from them: a competitor that beat noise
too, with a z within the test's threshold of its own, makes neither confident
(:func:`outcompeted`; measured on the simulator's ripple with GearPair's paper parameters
as the base: a second pinion tooth, z 37.7, explaining 51 % of its lines, against the
first tooth's softening, z 36.5, 49 %; the simulator's first tooth is the weaker one).
The verdict then says what each of the two removes of the residual on the lines both
claim (:meth:`HeldOut.explained_on`), so the engineer sees whether they truly explain the
same lines. When they plainly do not (the effect removes at least half of the residual
there, the competitor less than half as much: :data:`TOLD_APART`), the record tells them
apart, and a competitor that is not confident itself does not count: on the shared real
records a faulty tooth's softening beat noise by its mesh sidebands (z 221.5 on b30hz90)
and claims the pinion shaft's first orders too, where it removed nothing and the shaft's
own lines 97 %. A confident competitor with a larger z still wins: the pinion shaft's
orders also explain a gear tooth's lines where they fall on the pinion's (on one record
of the simulator in three).

The lines an effect claims are among the bins scored: the synchronous lines and the
peaks of half A. An effect that claims none of them (a bearing whose lines are all in the
noise, or unknown without its geometry) has no residual on its lines, so it could never
explain half of it: it is not fitted, and its verdict says so ("not tried").

``discover`` ranks effects by z and also reports the Bayesian information criterion on
half A, dBIC = n ln(RSS_effect / RSS_base) + k ln n (n bins of all channels, RSS the
weighted squared residual of Eq. (12), k the parameters the effect adds). BIC assumes the
residual is white noise; a misfit of the model's form is not, so BIC alone takes any
systematic misfit as evidence for some effect: the held-out z is the ranking.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import asdict, dataclass, field
from typing import Callable

import numpy as np
from scipy.stats import norm

from fmu_build import ModelicaBuildError as BuildError

from pydiag.core.errors import EstimationError, PydiagError
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.objective import noise_corrected_error, rician_mean, spectral_error
from pydiag.fit.problem import FitProblem
from pydiag.fmu.description import read_model_description
from pydiag.gear.effects import EFFECTS, Effect
from pydiag.gear.features import FullSpectrumFeaturizer
from pydiag.gear.kinematic_map import coinciding, kinematic_map, match
from pydiag.loop.compare import (EFFECT_REFIT, NOT_VALIDATED, Comparison, effect_parameters,
                                 evidence_channels, fit_effect, free_polish, measured_spectra)
from pydiag.signal.spectra import local_maxima

#: Chance that an effect which only fits noise passes the held-out test.
FALSE_ALARM_RATE = 0.01
#: The least share of the residual above noise on its own lines a confident effect removes.
MIN_EXPLAINED = 0.5
#: On the lines two competitors both claim, one that removes less than this share of what
#: the other removes (which removes at least MIN_EXPLAINED there) is told apart from it.
TOLD_APART = 0.5
#: The top of the band whose envelope an effect with ``Effect.envelope`` is scored on, as a
#: share of the sample rate (its bottom: the top of the gear's analysed bands); below the
#: Nyquist frequency by the anti-alias filter's usual margin.
ENVELOPE_TOP = 0.45
#: The start of the status of an effect held-out validation did not fit.
NOT_TRIED = "not tried"
#: A parameter closer to a bound than this share of its range is at the bound.
AT_BOUND = 0.01
#: Parameters every model that extends GearDiag.GearPair has: what the effects build on.
GEARPAIR_PARAMETERS = {"a0", "a_f", "f_f", "f_ate", "f_dte", "k2", "phi2", "k4", "phi4", "Np",
                       "Ng", "f_pinion", "m", "K", "c", "T", "r_p", "xi_max", "gamma_max"}


@dataclass
class HeldOut:
    """An effect fitted on half A of the record and scored on half B."""

    effect: str
    z: float  # held-out improvement in standard deviations of noise alone
    threshold: float  # z above this: more than noise alone
    explained: float  # share of the residual above noise on the effect's lines removed (B)
    error_base: float  # noise-corrected Eq. (12) on B, base model
    error_effect: float  # the same with the effect
    parameters: dict[str, float]
    at_bound: list[str] = field(default_factory=list)
    n_periods: int = 0  # periods in each half
    delta_bic: float = 0.0  # on half A, where the effect was fitted (module docstring)
    tried: bool = True  # False: none of its lines is scored, so it was not fitted (z nan)
    envelope_band_hz: tuple[float, float] | None = None  # scored on this band's envelope
    # why it was not tried, when not for want of residual on its lines (``tried``)
    why_not: str = ""
    # the non-synchronous lines of half A it claims, at the frequencies the half shows them
    # ("acc envelope 87.50 Hz" for BPFO 89.62 Hz: ``joined_freq_hz``); an effect claiming
    # one of another's competes with it (:func:`rivals`)
    claimed: tuple[str, ...] = ()
    # on B, each bin of its lines, named as ``claimed`` names them: (its term of D, the
    # base's excess there), so competitors can be set side by side on the lines both claim
    line_terms: dict[str, tuple[float, float]] = field(default_factory=dict, repr=False)

    @property
    def significant(self) -> bool:
        return self.z > self.threshold

    @property
    def confident(self) -> bool:
        return self.significant and self.explained >= MIN_EXPLAINED and not self.at_bound

    @property
    def verdict(self) -> str:
        if self.envelope_band_hz is None:
            return self._verdict
        low, high = self.envelope_band_hz
        return f"{self._verdict} [on the envelope of {low:.0f}-{high:.0f} Hz]"

    @property
    def _verdict(self) -> str:
        if not self.tried and self.why_not:
            return f"{NOT_TRIED}: {self.why_not}"
        if not self.tried:
            return (f"{NOT_TRIED}: none of the bins the test scores (the synchronous lines, "
                    "the peaks of the fitted half) is one of its lines: no residual to explain")
        if not self.significant:
            return (f"not confirmed: held out, it lowers the error by no more than noise "
                    f"would (z {self.z:.1f} <= {self.threshold:.1f})")
        if self.explained < MIN_EXPLAINED:
            return (f"partial: held out, it explains {100 * max(self.explained, 0):.0f} % of "
                    "the residual on its lines; the model form there may be wrong")
        if self.at_bound:
            return (f"the effect saturates ({', '.join(self.at_bound)} at a bound): its range "
                    "or the model form is wrong")
        return (f"confirmed held out (z {self.z:.1f}, explains {100 * self.explained:.0f} % "
                "of the residual on its lines)")

    def to_dict(self) -> dict:
        out = {k: v for k, v in asdict(self).items() if k != "line_terms"}
        return {**out, "significant": self.significant, "confident": self.confident}

    def explained_on(self, lines) -> float:
        """The share of the base's residual above noise it removes on B on ``lines`` (keys
        of :attr:`line_terms`); nan when those lines have none."""
        fall = sum(self.line_terms[k][0] for k in lines if k in self.line_terms)
        excess = sum(self.line_terms[k][1] for k in lines if k in self.line_terms)
        return fall / excess if excess > 0 else math.nan


def held_out_statistic(measured: np.ndarray, base: np.ndarray, effect: np.ndarray,
                       noise_power: float) -> tuple[float, np.ndarray, np.ndarray]:
    """The parts of the test (module docstring) on some bins: sum w d^2, each bin's term
    of D, and each bin's base excess w [(R - mu0)^2 - V0]."""
    mu0, mu1 = rician_mean(base, noise_power), rician_mean(effect, noise_power)
    var0 = np.maximum(base ** 2 + noise_power - mu0 ** 2, 1e-300)
    w, d = 1.0 / var0, mu1 - mu0
    terms = w * d * (2 * measured - mu0 - mu1)
    excess = w * ((measured - mu0) ** 2 - var0)
    return float(np.sum(w * d * d)), terms, excess


def in_model(problem: FitProblem, effect: Effect) -> bool:
    """The base problem fits some of ``effect``'s parameters, and every one the effect
    fits on this gear pair whatever the record (its hint leaves out some: the pinion
    shaft's orders a gear line falls on are never fitted, so a model that has the shaft's
    lines lacks them; another shaft's orders are fitted only where the record has a line)."""
    fitted = {p.fmu_variable for p in problem.parameters}
    own = effect.bounds([], 0.0, problem.kinematics)  # no peaks: only what the pair says
    return (any(p.fmu_variable in fitted for p in effect.parameters)
            and all(p.fmu_variable in fitted for p in own))


def _at_bound(effect: Effect, fitted: dict[str, float]) -> list[str]:
    out = []
    for p in effect.parameters:
        if p.periodic or p.name not in fitted:
            continue
        margin = AT_BOUND * (p.high - p.low)
        if fitted[p.name] >= p.high - margin or (fitted[p.name] <= p.low + margin
                                                   and p.low > 0):
            out.append(p.name)
    return out


def held_out(problem: FitProblem, base: Comparison, effect: Effect,
             effect_fmu: str | Callable[[], str], estimator: FaultEstimator | None = None,
             false_alarm_rate: float = FALSE_ALARM_RATE) -> HeldOut:
    """Fit ``effect`` on half A, score it against the base model on half B.

    ``problem`` is the base fit's problem and ``base`` its comparison (parameters, peaks
    for the effect's bounds); ``effect_fmu`` the effect's FMU, or what builds it (called
    only when the effect is fitted: not for one with nothing to explain); ``estimator``
    defaults to ``FaultEstimator(**EFFECT_REFIT)``."""
    kin = problem.kinematics
    n_half = base.n_periods // 2
    if kin is None or n_half < 1:
        raise EstimationError("held-out validation needs a gear model and a record of at "
                              "least two fundamental periods")
    m = problem.measurement
    rate = m.sample_rate_hz
    top = problem.featurizer.max_freq_hz
    band = (top, ENVELOPE_TOP * rate) if effect.envelope else None
    if band is not None and not band[0] < band[1]:
        raise EstimationError(f"{effect.key} is scored on the envelope above the gear's bands "
                              f"({top:g} Hz), and a sample rate of {rate:g} Hz leaves none")
    def untried(why_not: str = "") -> HeldOut:  # nothing to explain (module docstring)
        return HeldOut(effect.key, math.nan, float(norm.ppf(1 - false_alarm_rate)), 0.0,
                       math.nan, math.nan, {}, n_periods=n_half, delta_bic=math.nan,
                       tried=False, envelope_band_hz=band, why_not=why_not)
    # before any spectrum: its lines unknown, or none it could fit stands above the noise
    if why_not := effect.unknown_lines(kin):
        return untried(why_not)
    if not effect_parameters(problem, base, effect):
        return untried("no line of it stands above the noise where it can be told from the "
                       "pair's")
    if band is not None:  # the gear's lines removed, no line left to tell a gain by
        problem = problem.derive(fixed_gains=base.gains)
    half_a = FullSpectrumFeaturizer(kin, n_half, top, half=0, envelope_band_hz=band)
    measured_a = measured_spectra(problem, base.false_alarm_rate, featurizer=half_a)
    fit_half = measured_a.featurizer
    bins = fit_half.bins
    test_half = fit_half.other_half()
    # the lines where the halves' spectra show them (a non-synchronous one moves)
    bin_hz = 1.0 / (n_half * kin.period_s)
    lines = coinciding([dataclasses.replace(line, freq_hz=fit_half.joined_freq_hz(line.freq_hz))
                        for line in kinematic_map(kin, fit_half.max_freq_hz)],
                       0.5 * bin_hz)
    weight = effect.weight
    changed = evidence_channels(problem, effect)  # on the others, none of its evidence
    all_freqs = next(iter(measured_a.spectra.values()))[0]
    def claim(mask: np.ndarray) -> np.ndarray:  # whether its signature claims each bin
        return np.array([weight(match(fk, lines, bin_hz), fk, kin.f_mesh_hz) > 0
                         for fk in all_freqs[mask]], dtype=bool)
    freqs = all_freqs[bins]
    claims = claim(bins)
    # the non-synchronous bins it claims: where effects that compare could not name from
    # the whole record's peaks (a half's own, an envelope's) compete for the same lines
    between = (np.flatnonzero(bins) + 1) % n_half != 0
    def line_name(channel: str, freq_hz: float) -> str:  # "acc envelope 87.50 Hz"
        return f"{channel}{' envelope' if band else ''} {freq_hz:.2f} Hz"
    claimed = tuple(line_name(c, fk) for c in sorted(changed) for fk in freqs[claims & between])
    if not (changed and claims.any()):
        return untried()
    estimator = estimator or FaultEstimator(**EFFECT_REFIT)
    base_problem = problem.derive(featurizer=fit_half)
    base_fit = dict(base.parameters)
    if callable(effect_fmu):
        effect_fmu = effect_fmu()
    effect_problem, fitted = fit_effect(problem, base, effect, effect_fmu, fit_half, estimator)
    if effect.reshapes_base:  # its fit freed the base: the base model gets the same polish
        base_fit = free_polish(estimator, len(base_problem.parameters)).refine(
            base_problem, base_fit).parameters
    x0 = np.array([base_fit[p.name] for p in base_problem.parameters])
    x1 = np.array([fitted[p.name] for p in effect_problem.parameters])
    with base_problem.spec.open() as plant:
        y0 = base_problem.model_signals(plant, x0)  # channel gains fitted on A (or held)
    with effect_problem.spec.open() as plant:
        y1 = effect_problem.model_signals(plant, x1)
    total_w, total_d, signature_d, signature_excess = 0.0, 0.0, 0.0, 0.0
    err0, err1, raw0, raw1 = [], [], [], []
    line_terms: dict[str, tuple[float, float]] = {}
    for i, channel in enumerate(problem.channels):
        _, meas_a, noise_a = measured_a.spectra[channel]
        effect_a = fit_half.spectrum(y1[i], rate)[1]
        raw0.append(spectral_error(fit_half.spectrum(y0[i], rate)[1][bins], meas_a[bins], noise_a))
        raw1.append(spectral_error(effect_a[bins], meas_a[bins], noise_a))
        # scored as well: the lines the fitted effect predicts above the noise where half
        # A has no peak, so an effect that predicts lines the record lacks pays for them
        predicted = (effect_a > measured_a.margin[channel]) & local_maxima(effect_a) & ~bins
        scored = bins | predicted
        mine = np.zeros(all_freqs.size, dtype=bool)
        mine[bins] = claims
        mine[predicted] = claim(predicted)
        _, meas, noise = test_half.spectrum(m.channels[channel], rate)
        _, s0, _ = test_half.spectrum(y0[i], rate)
        _, s1, _ = test_half.spectrum(y1[i], rate)
        sw, terms, excess = held_out_statistic(meas[scored], s0[scored], s1[scored], noise)
        total_w += sw
        total_d += float(np.sum(terms))
        if channel in changed:
            signature_d += float(np.sum(terms[mine[scored]]))
            signature_excess += float(np.sum(excess[mine[scored]]))
            line_terms.update({line_name(channel, fk): (float(d), float(x)) for fk, d, x in
                               zip(all_freqs[scored][mine[scored]], terms[mine[scored]],
                                   excess[mine[scored]])})
        err0.append(noise_corrected_error(s0[bins], meas[bins], noise))
        err1.append(noise_corrected_error(s1[bins], meas[bins], noise))
    z = (total_d + total_w) / (2 * math.sqrt(total_w)) if total_w > 0 else 0.0
    explained = signature_d / signature_excess if signature_excess > 0 else 0.0
    n = int(np.count_nonzero(bins)) * len(problem.channels)
    k = sum(p.name in fitted for p in effect.parameters)  # its hint may leave some out
    ratio = max(np.sum(np.square(raw1)), 1e-24) / max(np.sum(np.square(raw0)), 1e-24)
    return HeldOut(effect.key, float(z), float(norm.ppf(1 - false_alarm_rate)),
                   float(min(explained, 1.0)), float(np.linalg.norm(err0)),
                   float(np.linalg.norm(err1)),
                   {p.name: fitted[p.name] for p in effect.parameters if p.name in fitted},
                   _at_bound(effect, fitted), n_half, float(n * np.log(ratio) + k * np.log(n)),
                   envelope_band_hz=band, claimed=claimed, line_terms=line_terms)


#: Effects whose signature covers less of the unexplained energy than this are not tried,
#: but for two kinds: one scored on an envelope (its score is the spectrum's) and an affine
#: one (``Effect.affine``: fitted from one simulation more than it has parameters, less
#: than the base's own compare costs, so the test rather than the score decides). The
#: pinion shaft's first orders hold 4-10 % of the unexplained peak energy of the shared
#: real records and are confirmed held out on all four (97-99 % of their residual).
MIN_SCORE = 0.1


def validate(problem: FitProblem, comparison: Comparison,
             effect_fmu: Callable[[Effect], str], estimator: FaultEstimator | None = None,
             min_score: float = MIN_SCORE,
             false_alarm_rate: float = FALSE_ALARM_RATE, present: tuple[str, ...] = (),
             progress: Callable[[str], None] | None = None) -> Comparison:
    """The comparison with every suggestion of score >= ``min_score`` tried held out, and
    every effect scored on an envelope or fitted affinely whatever its score (:data:`MIN_SCORE`).

    ``effect_fmu``: the FMU of an effect (the base FMU itself for an ``in_base`` one),
    called only for an effect that is fitted; it raises a :class:`PydiagError` (or a build
    error) when there is none. At most one effect is confident among those that claim the
    same lines, and none that a competitor comes close to (:func:`outcompeted`); the
    others are told which effect beat them. ``present``: effect
    keys the model already has (compare of an effect's model). An FMU that is not a
    GearDiag.GearPair model gets every suggestion "not validated": the effects extend it."""
    model = read_model_description(problem.spec.fmu_path)[0]
    if not GEARPAIR_PARAMETERS <= {v.name for v in model.modelVariables}:
        return not_validated(comparison, f"the catalogue's effects extend GearDiag.GearPair, "
                                         f"and {model.modelName} is not one of its models")
    suggestions = [dataclasses.replace(s) for s in comparison.suggested_effects]
    fits: dict[str, HeldOut] = {}
    for s in suggestions:
        effect = EFFECTS[s.effect]
        if s.score < min_score and not (effect.envelope or effect.affine):  # MIN_SCORE
            s.status = (f"{NOT_TRIED}: its lines hold {100 * s.score:.0f} % of the unexplained "
                        "energy")
            continue
        if s.effect in present or in_model(problem, effect):
            s.status = "already in the model"
            continue
        unknown = effect.unknown_lines(problem.kinematics)
        if unknown:
            s.status = f"{NOT_TRIED}: {unknown}"
            continue
        beside = [k for k in present if not (effect.in_base or EFFECTS[k].in_base)]
        if beside:  # its model extends GearPair, not the model that has them
            s.status = (f"{NOT_VALIDATED}: the model has {', '.join(beside)}, which "
                        f"{effect.model} lacks: trying {s.effect} too needs a Modelica "
                        "model with both")
            continue
        if progress:
            progress(s.effect)
        try:
            fmu = (problem.spec.fmu_path if effect.in_base
                   else functools.partial(effect_fmu, effect))  # built if it is fitted
            h = held_out(problem, comparison, effect, fmu, estimator, false_alarm_rate)
        except (PydiagError, BuildError) as err:
            s.status = f"{NOT_VALIDATED}: {err}"
            continue
        s.held_out = h.to_dict() if h.tried else None
        if h.tried:
            fits[s.effect] = h
        s.status, s.confident = h.verdict, h.confident
    beaten = outcompeted({s.effect: s.held_out["z"] for s in suggestions if s.confident},
                         rivals({s.effect: s.competing for s in suggestions},
                                {s.effect: s.held_out["claimed"] for s in suggestions
                                 if s.held_out}),
                         {s.effect: s.held_out["z"] for s in suggestions
                          if s.held_out and s.held_out["significant"]},
                         float(norm.ppf(1 - false_alarm_rate)), fits)
    for s in suggestions:
        if s.effect in beaten:
            s.confident = False
            s.status = beaten[s.effect]
    return dataclasses.replace(comparison, suggested_effects=suggestions)


def rivals(competing: dict[str, list[str]], claimed: dict[str, tuple[str, ...]]
           ) -> dict[str, list[str]]:
    """Each effect's competitors: those compare found claiming the same peaks of the whole
    record (``competing``), and those whose held-out fit claimed one of the same
    non-synchronous lines of the half (``claimed``: key -> :attr:`HeldOut.claimed`). The
    half's spectrum (and an envelope's) is not the one compare names peaks on: joining
    every other period moves a line that is not synchronous (``joined_freq_hz``), so two
    bearing frequencies a few hertz apart can land on one bin."""
    out = {key: list(keys) for key, keys in competing.items()}
    for key, lines in claimed.items():
        for other, theirs in claimed.items():
            if other != key and set(lines) & set(theirs) and other not in out.setdefault(key, []):
                out[key].append(other)
    return out


def outcompeted(confident_z: dict[str, float], competing: dict[str, list[str]],
                significant_z: dict[str, float] | None = None,
                margin: float = float(norm.ppf(1 - FALSE_ALARM_RATE)),
                fits: dict[str, HeldOut] | None = None) -> dict[str, str]:
    """At most one confident effect among those that claim the same lines, and only one
    the record tells apart from them: of the ``confident_z`` effects (key -> held-out z),
    those a competitor (``competing``) beats, each with the sentence that says so. A
    competitor beats an effect when it is confident with a larger z, or when it beat noise
    held out (``significant_z``: key -> z of every such effect, confident or not) with a z
    within ``margin`` of the effect's: two effects that explain the same lines about as
    well are not told apart by this record, and neither is confident. ``fits`` (key ->
    :class:`HeldOut`, when known): each sentence also gives the share of the residual each
    of the two removes on the lines both claim, and a competitor that is not confident
    and that those lines tell apart from the effect (:func:`_told_apart`) does not come
    close to it: its z was earned on its other lines."""
    kept: list[str] = []
    beaten = {}
    near = significant_z or {}
    for key in sorted(confident_z, key=lambda k: -confident_z[k]):
        rival = next((k for k in kept if k in competing.get(key, ())), None)
        close = next((k for k in sorted(near, key=lambda k: -near[k])
                      if k != key and k in competing.get(key, ())
                      and near[k] > confident_z[key] - margin
                      and not _told_apart(key, k, fits)), None)
        if rival is not None:
            beaten[key] = (f"competes with {rival} for the same lines, which explains them "
                           f"better held out (z {confident_z[rival]:.1f} > "
                           f"{confident_z[key]:.1f}){_on_shared_lines(key, rival, fits)}")
        elif close is not None:
            beaten[key] = (f"competes with {close} for the same lines, which explains them "
                           f"about as well held out (z {near[close]:.1f} against "
                           f"{confident_z[key]:.1f}{_on_shared_lines(key, close, fits)}): "
                           "this record does not tell them apart")
        else:
            kept.append(key)
    return beaten


def _shared_lines(key: str, other: str, fits: dict[str, HeldOut] | None
                  ) -> tuple[int, float, float] | None:
    """(how many lines ``key`` and ``other`` both claim, the share of the residual there
    each removes), or None when not known or neither has residual there."""
    if not fits or key not in fits or other not in fits:
        return None
    shared = set(fits[key].line_terms) & set(fits[other].line_terms)
    mine, theirs = fits[key].explained_on(shared), fits[other].explained_on(shared)
    if not shared or math.isnan(mine) or math.isnan(theirs):
        return None
    return len(shared), mine, theirs


def _told_apart(key: str, other: str, fits: dict[str, HeldOut] | None) -> bool:
    """Whether the lines ``key`` and ``other`` both claim tell them apart: ``key`` removes
    at least MIN_EXPLAINED of the residual there (what a confident effect removes of its
    own lines) and ``other`` less than :data:`TOLD_APART` of what ``key`` removes (a shaft's
    own lines, which a faulty tooth's fit leaves as they were). False when not known."""
    both = _shared_lines(key, other, fits)
    return both is not None and both[1] >= MIN_EXPLAINED and both[2] < TOLD_APART * both[1]


def _on_shared_lines(key: str, other: str, fits: dict[str, HeldOut] | None) -> str:
    """"; on the 9 lines both claim it removes 69 % of the residual, housing 55 %", or ""."""
    both = _shared_lines(key, other, fits)
    if both is None:
        return ""
    n, mine, theirs = both
    lines = f"the {n} lines" if n > 1 else "the one line"
    return (f"; on {lines} both claim it removes {100 * max(mine, 0):.0f} % "
            f"of the residual, {other} {100 * max(theirs, 0):.0f} %")


def not_validated(comparison: Comparison, why: str) -> Comparison:
    """The comparison with every suggestion marked as not validated, and why."""
    return dataclasses.replace(comparison, suggested_effects=[
        dataclasses.replace(s, status=f"{NOT_VALIDATED}: {why}")
        for s in comparison.suggested_effects])
