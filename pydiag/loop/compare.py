"""Hold a fitted model against a measurement: residual spectrum, unexplained peaks,
which missing effect they point to.

1. Fit the model (as ``diagnose``), unless its parameters are given.
2. The measurement's spectra, noise and error bins (:mod:`pydiag.loop.residual`), and the
   model's over the same whole periods.
3. A bin is an unexplained peak when the measured amplitude R exceeds the model's S by
   more than sqrt(P ln(N/alpha)) and is a local maximum of the excess: at most alpha of
   false peaks over the N bins (``false_alarm_rate``). The L bins that hold a kinematic
   line are hypotheses the kinematics named before the record was looked at: on those, an
   excess over sqrt(P ln(L/alpha)) is a peak as well (2 alpha in all), so a change the
   model's form spreads thin over many lines of the machine is seen.
4. Peaks are named by the kinematic map (tolerance: one bin); their energy fraction is
   their excess power R^2 - S^2 - P over their channel's measured power on the error
   bins (channels have different units), normalised over all peaks. A peak no line
   explains is named by what it could be (its ratio to each shaft speed, a mains
   multiple).
5. Each catalogue effect scores the peak energy its signature covers
   (:mod:`pydiag.gear.effects`); effects whose signatures claim the same peaks compete. No
   suggestion is confident until held-out validation (:mod:`pydiag.loop.validate`).

The ``error`` is Eq. (12), relative, with the part noise alone produces subtracted
(:func:`pydiag.fit.objective.noise_corrected_error`: ~0 for a perfect model), on the error
bins; ``error_raw`` is the same without the noise correction, which has a noise floor.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.objective import noise_corrected_error, spectral_error
from pydiag.fit.problem import FitProblem
from pydiag.gear.effect import Effect
from pydiag.gear.effects import EFFECTS
from pydiag.gear.kinematic_map import kinematic_map, match_each, with_gear_bearing
from pydiag.gear.peaks import Peak
from pydiag.loop.effect_fit import evidence_channels, fit_effect
from pydiag.loop.residual import (NOT_KINEMATIC, MeasuredSpectra, bin_groups,
                                  describe_non_kinematic, measured_spectra, residual_shares)
from pydiag.loop.results import Comparison, Suggestion
from pydiag.signal.spectra import Spectrum, local_maxima


def compare(problem: FitProblem, estimator: FaultEstimator | None = None,
            false_alarm_rate: float = 0.01,
            max_periods: int | None = None, parameters: dict[str, float] | None = None,
            measured: MeasuredSpectra | None = None,
            effects: Mapping[str, Effect] | None = None) -> Comparison:
    """Fit (unless ``parameters`` are given, by name) and compare; see the module docstring.

    ``measured``: the measurement's spectra when already computed for the same
    false-alarm rate and periods (they depend on the measurement alone); ``effects``: the
    catalogue the residual points into (default :data:`~pydiag.gear.effects.EFFECTS`; a
    machine's model names them for one of its stages)."""
    effects = EFFECTS if effects is None else effects
    measured = measured or measured_spectra(problem, false_alarm_rate, max_periods)
    fit_error = None
    if parameters is None:
        result = (estimator or FaultEstimator()).fit(problem)
        parameters, fit_error = result.parameters, result.error
    featurizer = measured.featurizer
    bins = featurizer.bins
    kin = featurizer.kinematics
    rate = problem.measurement.sample_rate_hz
    x = np.array([parameters[p.name] for p in problem.parameters])
    with problem.spec.open() as plant:
        y = problem.model_signals(plant, x, featurizer.duration_s)
        gains = problem.gains(plant, x) if problem.fit_gain else {}
    lines = kinematic_map(kin, featurizer.max_freq_hz)
    bin_hz = 1.0 / featurizer.duration_s
    candidates, spectra, model_spectra, errors, raw, by_family = [], {}, {}, [], [], {}
    for i, channel in enumerate(problem.channels):
        spectrum = measured.spectra[channel]
        freqs, meas, noise = spectrum.freq_hz, spectrum.amplitude, spectrum.noise_power
        model = featurizer.spectrum(y[i], rate).amplitude
        spectra[channel] = spectrum
        model_spectra[channel] = Spectrum(freqs, model, 0.0)
        groups = bin_groups(freqs, lines, bin_hz, meas, measured.margin[channel])
        by_family[channel] = residual_shares(groups, meas, model, bins, noise)
        errors.append(noise_corrected_error(model[bins], meas[bins], noise))
        raw.append(spectral_error(model[bins], meas[bins], noise))
        excess = meas - model
        channel_power = float(np.sum(meas[bins] ** 2)) or 1.0
        kinematic = ~np.isin(groups, NOT_KINEMATIC)  # a line of the map
        line_margin = np.sqrt(noise * np.log(max(np.count_nonzero(kinematic), 1)
                                             / false_alarm_rate))
        over = (excess > measured.margin[channel]) | (kinematic & (excess > line_margin))
        peaks_at = np.flatnonzero(over & local_maxima(excess))
        # the lines near each peak found by bisection: a record's thousands of peaks
        # against a gearbox's thousands of lines
        for k, line in zip(peaks_at, match_each(freqs[peaks_at], lines, bin_hz)):
            power = max(meas[k] ** 2 - model[k] ** 2 - noise, 0.0) / channel_power
            candidates.append((channel, power, line, freqs[k], meas[k], model[k]))
    candidates.sort(key=lambda c: -c[1])
    total = sum(c[1] for c in candidates) or 1.0
    peaks = [Peak(ch, float(f), float(m - s), float(m), float(s),
                  line.family if line else "unexplained", line.order if line else None,
                  line.label if line else describe_non_kinematic(f, kin, bin_hz), p / total)
             for ch, p, line, f, m, s in candidates]
    suggestions, claims = [], {}
    for effect in effects.values():
        changed = evidence_channels(problem, effect)
        support = [(effect.weight(line, f, kin) * pk.energy_fraction, i, pk)
                   for i, (pk, (_, _, line, f, _, _)) in enumerate(zip(peaks, candidates))
                   if pk.channel in changed]
        support = [(w, i, pk) for w, i, pk in support if w > 0]
        claims[effect.key] = {i for _, i, _ in support}
        score = float(sum(w for w, _, _ in support))
        evidence = [f"{pk.channel} {pk.freq_hz:.2f} Hz ({pk.label or 'no kinematic line'}): "
                    f"{100 * pk.energy_fraction:.0f} % of the unexplained energy"
                    for _, _, pk in sorted(support, key=lambda t: -t[0])[:3]]
        suggestions.append(Suggestion(effect.key, score, evidence))
    for s in suggestions:
        s.competing = [o for o in effects if o != s.effect and claims[o] & claims[s.effect]]
    suggestions.sort(key=lambda s: -s.score)
    # the plots' cursors: every stage's mesh harmonics, low shaft orders and their mesh
    # sidebands, bearings
    orders = with_gear_bearing({"pinion": 3, "gear": 3, "mesh_sb_pinion": 3, "mesh_sb_gear": 3,
                                "bpfo": 5, "bpfi": 5, "bsf": 5, "ftf": 5, "other_shaft": 3,
                                "stage_mesh_sb": 1, "machine_shaft": 3, "machine_bearing": 3})
    markers = [{"freq_hz": ln.freq_hz, "family": ln.family, "label": ln.label} for ln in lines
               if ln.family in ("mesh", "stage_mesh")
               or 0 < abs(ln.order) <= orders.get(ln.family, 0)]
    return Comparison(problem.spec.fmu_path, float(np.sqrt(np.sum(np.square(errors)))),
                      float(np.sqrt(np.sum(np.square(raw)))), dict(parameters),
                      peaks, suggestions, false_alarm_rate, featurizer.n_periods,
                      featurizer.duration_s, bin_hz,
                      int(np.count_nonzero(bins)), fit_error, gains, spectra=spectra,
                      model_spectra=model_spectra, markers=markers, residual_by_family=by_family)


def refit_with_effect(problem: FitProblem, base: Comparison, effect: Effect, effect_fmu: str,
                      estimator: FaultEstimator | None = None) -> Comparison:
    """Fit the effect's parameters on the comparison's bins, the base parameters held at
    their fitted values (freed as well for an effect that reshapes the base's lines:
    :func:`fit_effect`), then compare the effect model on the same footing as ``base``.

    ``problem`` is the base fit's problem (its adapter maps the base parameters to FMU
    variables); ``estimator`` defaults to ``FaultEstimator(**EFFECT_REFIT)``.
    """
    measured = measured_spectra(problem, base.false_alarm_rate, base.n_periods)
    effect_problem, fitted = fit_effect(problem, base, effect, effect_fmu, measured.featurizer,
                                        estimator)
    c = compare(effect_problem, None, base.false_alarm_rate, base.n_periods,
                parameters=fitted, measured=measured)
    return dataclasses.replace(c, parameters={**base.parameters, **fitted})
