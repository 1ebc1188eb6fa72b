"""Held-out validation of an effect: does adding it predict data it was not fitted to?

The record (order-tracked, whole fundamental periods) is cut into alternating periods:
half A (0, 2, 4, ...) and half B (1, 3, 5, ...), two records of the same machine with
independent noise (:class:`pydiag.gear.features.FullSpectrumFeaturizer`, ``half``). The
effect's parameters (and the channel gains) are fitted on A with the base parameters held
at the whole record's fit (:func:`pydiag.loop.effect_fit.fit_effect`; freed as well for an
effect that reshapes the base's own lines, and the base then gets the same polish on A),
then base and effect are scored on B, on the bins A's measurement chose and on those where
the fitted effect predicts a line above the noise that A lacks (an effect that predicts
lines the record lacks pays for them). Joining every other period keeps a synchronous
line on its bin and moves one that is not (``joined_freq_hz``): lines are named where the
halves show them.

**The test.** On B, each compared bin holds a measured amplitude R, Rician around the
true line with noise power P per bin. With mu0, mu1 the Rician means of the base and
effect lines (:func:`pydiag.fit.objective.rician_mean`), V0 the Rician variance around the
base line, w = 1/V0 and d = mu1 - mu0, the held-out improvement is

    D = sum w [(R - mu0)^2 - (R - mu1)^2] = sum w d (2R - mu0 - mu1).

If the base is right and the effect only fits A's noise, D is close to normal with mean
-sum w d^2 and variance 4 sum w d^2, so

    z = (D + sum w d^2) / (2 sqrt(sum w d^2))

is standard normal: the effect lowers the held-out error by more than noise would when z
exceeds the (1 - alpha) quantile (:data:`FALSE_ALARM_RATE`). A misfit of the base's form
is in both halves, so a confident effect must also **explain its lines**: on B, the part
of the residual above noise on the lines its signature claims, sum w [(R - mu0)^2 - V0],
must fall by at least :data:`pydiag.loop.results.MIN_EXPLAINED`; no fitted parameter
may sit at a bound of its range (an angle has none); and the model with it must predict B
better than the base: its held-out error (noise-corrected Eq. 12 on the bins A chose)
falls. z tests only that the change is more than A's noise: a change the right way that
overshoots, or bends lines the effect does not claim, passes it and predicts B worse.

An effect whose lines are in the envelope of a band above the gear's (``Effect.envelope``:
a bearing's strikes ringing a structural mode) is fitted and scored the same way on the
envelope's spectrum of each channel, its gear lines removed first (every line that
repeats each fundamental period), the channel gains held at the base fit's. An effect
none of whose lines is among the scored bins has no residual to explain: it is not fitted
("not tried"). ``delta_bic`` is the Bayesian information criterion on half A, reported
beside z: it takes any systematic misfit as evidence, so z is the ranking.

The same test asks of an effect the model has (``own``) whether the record wants other
values of it: its parameters polished on A from the base fit's values, everything else
held, and scored on B against those values (a healthy model's gear modulation on a
record of a broken tooth: :func:`pydiag.loop.machine_discover.refit_own_effects`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from statistics import NormalDist
from typing import Callable

import numpy as np

from pydiag.core.errors import EstimationError
from pydiag.core.parameters import Parameter
from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.objective import noise_corrected_error, rician_mean, spectral_error
from pydiag.fit.problem import FitProblem, ProblemObjective
from pydiag.gear.effect import Effect
from pydiag.gear.features import FullSpectrumFeaturizer
from pydiag.gear.kinematic_map import KinematicLine, coinciding, kinematic_map, match_each
from pydiag.loop.effect_fit import (EFFECT_REFIT, effect_parameters, evidence_channels,
                                    fit_effect, free_polish, refit_own)
from pydiag.loop.residual import MeasuredSpectra, measured_spectra
from pydiag.loop.results import Comparison, HeldOut
from pydiag.signal.spectra import ENVELOPE_TOP, local_maxima

#: Chance that an effect which only fits noise passes the held-out test.
FALSE_ALARM_RATE = 0.01
#: A parameter closer to a bound than this share of its range is at the bound ...
AT_BOUND = 0.01
#: ... and the fit presses against it when a step of BOUND_PROBE of its range inward
#: raises the fitted half's error by more than BOUND_PRESSURE of it.
BOUND_PROBE = 0.1
BOUND_PRESSURE = 0.01


@dataclass
class Halves:
    """What held-out validation takes from the record and the base fit alone, the same for
    every effect scored on one band (the spectrum's, or an envelope's): half A's spectra,
    peak margins and the bins scored, the kinematic lines where the joined halves show
    them, and the base model's signals at its fit (for the effects that hold the base)."""

    problem: FitProblem  # the base problem, its gains held on an envelope
    base_problem: FitProblem  # the same on half A's bins
    measured: MeasuredSpectra
    lines: list[KinematicLine]
    base_signals: np.ndarray | None = None
    freed_base: dict[str, float] | None = None  # the base polished free on A (one estimator)

    def free_base(self, estimator: FaultEstimator, parameters: dict[str, float]
                  ) -> dict[str, float]:
        """The base fit ``parameters`` polished with every base parameter free on half A
        (:func:`~pydiag.loop.effect_fit.free_polish`): what every effect that frees the
        base is scored against, made once for all of them."""
        if self.freed_base is None:
            self.freed_base = free_polish(estimator, len(self.base_problem.parameters)).refine(
                self.base_problem, parameters).parameters
        return self.freed_base


def envelope_band(problem: FitProblem, effect: Effect) -> tuple[float, float] | None:
    """The band whose envelope ``effect`` is scored on, or None: its spectrum."""
    if not effect.envelope:
        return None
    top, rate = problem.featurizer.max_freq_hz, problem.measurement.sample_rate_hz
    band = (top, ENVELOPE_TOP * rate)
    if not band[0] < band[1]:
        raise EstimationError(f"{effect.key} is scored on the envelope above the gear's bands "
                              f"({top:g} Hz), and a sample rate of {rate:g} Hz leaves none")
    return band


def halves(problem: FitProblem, base: Comparison, band: tuple[float, float] | None,
           with_base_signals: bool = False) -> Halves:
    """The :class:`Halves` of the record of ``problem`` and the fit ``base``, on ``band``."""
    kin = problem.kinematics
    n_half = base.n_periods // 2
    if kin is None or n_half < 1:
        raise EstimationError("held-out validation needs a gear model and a record of at "
                              "least two fundamental periods")
    if band is not None:  # the gear's lines removed, no line left to tell a gain by
        problem = problem.derive(fixed_gains=base.gains)
    half_a = FullSpectrumFeaturizer(kin, n_half, problem.featurizer.max_freq_hz, half=0,
                                    envelope_band_hz=band)
    measured = measured_spectra(problem, base.false_alarm_rate, featurizer=half_a)
    fit_half = measured.featurizer
    bin_hz = 1.0 / (n_half * kin.period_s)
    lines = coinciding([dataclasses.replace(line, freq_hz=fit_half.joined_freq_hz(line.freq_hz))
                        for line in kinematic_map(kin, fit_half.max_freq_hz)], 0.5 * bin_hz)
    out = Halves(problem, problem.derive(featurizer=fit_half), measured, lines)
    if with_base_signals:
        out.base_signals = _signals(out.base_problem, base.parameters)
    return out


def _signals(problem: FitProblem, parameters: dict[str, float]) -> np.ndarray:
    """The model's channel signals at ``parameters`` (by name), gains as ``problem`` has them."""
    with problem.spec.open() as plant:
        return problem.model_signals(plant, np.array([parameters[p.name]
                                                      for p in problem.parameters]))


def threshold(false_alarm_rate: float = FALSE_ALARM_RATE) -> float:
    """The z above which an effect lowers the held-out error by more than noise would."""
    return NormalDist().inv_cdf(1 - false_alarm_rate)


def held_out_statistic(measured: np.ndarray, base: np.ndarray, effect: np.ndarray,
                       noise_power: float | np.ndarray
                       ) -> tuple[float, np.ndarray, np.ndarray]:
    """The parts of the test (module docstring) on some bins: sum w d^2, each bin's term
    of D, and each bin's base excess w [(R - mu0)^2 - V0]; ``noise_power``: one for all
    bins, or each bin's."""
    mu0, mu1 = rician_mean(base, noise_power), rician_mean(effect, noise_power)
    var0 = np.maximum(base ** 2 + noise_power - mu0 ** 2, 1e-300)
    w, d = 1.0 / var0, mu1 - mu0
    terms = w * d * (2 * measured - mu0 - mu1)
    excess = w * ((measured - mu0) ** 2 - var0)
    return float(np.sum(w * d * d)), terms, excess


def pressed_bounds(parameters: tuple[Parameter, ...], x: np.ndarray,
                   error: Callable[[np.ndarray], float], names: set[str]) -> list[str]:
    """Those of ``names`` among ``parameters`` (at ``x``, the fit) at a bound of their range
    that the fit presses against: within AT_BOUND of it (a low of 0, the effect off, an
    angle and a tooth's index do not count), and a step of BOUND_PROBE of the range
    inward raises ``error`` by more than BOUND_PRESSURE of it. A parameter the error hardly
    depends on there is undetermined, not saturated: where its fit stops is the rounding's
    (a housing mode's damping above the band's lines), and a verdict must not hang on it."""
    x = np.asarray(x, dtype=float)
    at_fit = None
    out = []
    for i, p in enumerate(parameters):
        if p.periodic or p.step is not None or p.name not in names:
            continue
        margin = AT_BOUND * (p.high - p.low)
        if x[i] >= p.high - margin:
            inward = -BOUND_PROBE * (p.high - p.low)
        elif x[i] <= p.low + margin and p.low > 0:
            inward = BOUND_PROBE * (p.high - p.low)
        else:
            continue
        at_fit = error(x) if at_fit is None else at_fit
        probe = x.copy()
        probe[i] += inward
        if error(probe) > at_fit * (1 + BOUND_PRESSURE):
            out.append(p.name)
    return out


def _at_bound(problem: FitProblem, effect: Effect, fitted: dict[str, float]) -> list[str]:
    """The effect's parameters the fit on ``problem`` presses against a bound of
    (:func:`pressed_bounds`, on the fitted half's error)."""
    x = np.array([fitted[p.name] for p in problem.parameters])
    with ProblemObjective(problem) as objective:
        return pressed_bounds(problem.parameters, x, objective,
                              {p.name for p in effect.parameters})


def held_out(problem: FitProblem, base: Comparison, effect: Effect,
             effect_fmu: str | Callable[[], str], estimator: FaultEstimator | None = None,
             false_alarm_rate: float = FALSE_ALARM_RATE,
             memo: dict | None = None, own: bool = False) -> HeldOut:
    """Fit ``effect`` on half A, score it against the base model on half B.

    ``problem`` is the base fit's problem and ``base`` its comparison (parameters, peaks
    for the effect's bounds); ``effect_fmu`` the effect's FMU, or what builds it (called
    only when the effect is fitted: not for one with nothing to explain); ``estimator``
    defaults to ``FaultEstimator(**EFFECT_REFIT)``; ``memo``: band -> :class:`Halves` of
    this record and fit, filled as effects need them (what every effect shares). ``own``:
    ``effect`` is one the model has, and the question is whether the record asks for
    other values of it than ``base``'s (:func:`~pydiag.loop.effect_fit.refit_own`, the
    base held; ``effect_fmu`` unused), not whether the model lacks it."""
    kin = problem.kinematics
    n_half = base.n_periods // 2
    if kin is None or n_half < 1:
        raise EstimationError("held-out validation needs a gear model and a record of at "
                              "least two fundamental periods")
    m = problem.measurement
    rate = m.sample_rate_hz
    band = envelope_band(problem, effect)
    def untried(why_not: str = "") -> HeldOut:  # nothing to explain (module docstring)
        return HeldOut(effect.key, math.nan, threshold(false_alarm_rate), 0.0,
                       math.nan, math.nan, {}, n_periods=n_half, delta_bic=math.nan,
                       tried=False, envelope_band_hz=band, why_not=why_not)
    # before any spectrum: its lines unknown, or none it could fit stands above the noise
    if why_not := effect.unknown_lines(kin):
        return untried(why_not)
    if not own and not effect_parameters(problem, base, effect):
        return untried("no line of it stands out (of the noise, or of another shaft's orders "
                       "around it) where it can be told from the pair's")
    memo = {} if memo is None else memo
    if band not in memo:
        memo[band] = halves(problem, base, band)
    shared = memo[band]
    problem = shared.problem  # its gains held on an envelope
    measured_a = shared.measured
    fit_half = measured_a.featurizer
    bins = fit_half.bins
    test_half = fit_half.other_half()
    bin_hz = 1.0 / (n_half * kin.period_s)
    lines = shared.lines  # where the halves' spectra show them (a non-synchronous one moves)
    changed = evidence_channels(problem, effect)  # on the others, none of its evidence
    all_freqs = next(iter(measured_a.spectra.values())).freq_hz
    def claim(mask: np.ndarray) -> np.ndarray:  # whether its signature claims each bin
        chosen = all_freqs[mask]
        return np.array([effect.weight(line, fk, kin) > 0 for line, fk
                         in zip(match_each(chosen, lines, bin_hz), chosen)], dtype=bool)
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
    base_problem = shared.base_problem
    base_fit = dict(base.parameters)
    if own:
        effect_problem, fitted = refit_own(problem, base, effect, fit_half, estimator)
    else:
        if callable(effect_fmu):
            effect_fmu = effect_fmu()
        effect_problem, fitted = fit_effect(problem, base, effect, effect_fmu, fit_half,
                                            estimator)
    if effect.reshapes_base and not own:  # its fit freed the base: the base model gets
        base_fit = shared.free_base(estimator, base_fit)  # the same polish, gains on A
        y0 = _signals(base_problem, base_fit)
    else:
        if shared.base_signals is None:
            shared.base_signals = _signals(base_problem, base_fit)
        y0 = shared.base_signals
    y1 = _signals(effect_problem, fitted)
    total_w, total_d, signature_d, signature_excess = 0.0, 0.0, 0.0, 0.0
    err0, err1, raw0, raw1 = [], [], [], []
    line_terms: dict[str, tuple[float, float]] = {}
    for i, channel in enumerate(problem.channels):
        meas_a, noise_a = (measured_a.spectra[channel].amplitude,
                           measured_a.spectra[channel].noise_power)
        effect_a = fit_half.spectrum(y1[i], rate).amplitude
        raw0.append(spectral_error(fit_half.spectrum(y0[i], rate).amplitude[bins], meas_a[bins],
                                   noise_a))
        raw1.append(spectral_error(effect_a[bins], meas_a[bins], noise_a))
        # scored as well: the lines the fitted effect predicts above the noise where half
        # A has no peak, so an effect that predicts lines the record lacks pays for them
        predicted = (effect_a > measured_a.margin[channel]) & local_maxima(effect_a) & ~bins
        scored = bins | predicted
        mine = np.zeros(all_freqs.size, dtype=bool)
        mine[bins] = claims
        mine[predicted] = claim(predicted)
        measured_b = test_half.spectrum(m.channels[channel], rate)
        meas, noise = measured_b.amplitude, measured_b.noise_power
        s0 = test_half.spectrum(y0[i], rate).amplitude
        s1 = test_half.spectrum(y1[i], rate).amplitude
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
    return HeldOut(effect.key, float(z), threshold(false_alarm_rate),
                   float(min(explained, 1.0)), float(np.linalg.norm(err0)),
                   float(np.linalg.norm(err1)),
                   {p.name: fitted[p.name] for p in effect.parameters if p.name in fitted},
                   _at_bound(effect_problem, effect, fitted), n_half, float(n * np.log(ratio) + k * np.log(n)),
                   envelope_band_hz=band, claimed=claimed, line_terms=line_terms)
