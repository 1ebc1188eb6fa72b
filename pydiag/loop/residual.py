"""The residual of a fitted model against a measurement, bin by bin: the measurement's
spectra over whole fundamental periods and their noise, the bins the error is taken on,
and the residual's energy by kinematic family.

- Spectra at full resolution: over M whole fundamental periods of the (order-tracked)
  record, bins every 1/(M T0); noise power per bin P, the median power of the bins between
  synchronous lines over ln 2.
- A bin of the measurement is a significant peak when its amplitude exceeds
  sqrt(P ln(N/alpha)) and is a local maximum: over N bins of complex Gaussian noise, the
  chance of any false peak is at most alpha (Bonferroni).
- The error bins (what the ``error`` of a comparison is taken on) depend on the
  measurement only, so model revisions are compared on the same footing: every
  synchronous line up to the top band edge, and every significant peak; on one stage of
  a machine, none near another stage's lines that is not one of the pair's own (the rule
  of the stage's fit, :func:`pydiag.gear.features.other_stages_lines`): no pair model of
  this stage makes them, and they are named in the peaks and the residual's families.
- Every bin goes to one group of :data:`RESIDUAL_GROUPS`: the kinematic line on it, else a
  significant peak (non-kinematic), else broadband. Each group's share of the measured
  and of the residual energy is over every bin; its share of the error, over the error's
  bins alone, with Eq. 12's weights: where the error lies (bench/RESULTS.md, section 10).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pydiag.core.errors import EstimationError
from pydiag.fit.objective import spectral_residuals
from pydiag.fit.problem import FitProblem
from pydiag.gear.features import FullSpectrumFeaturizer, other_stages_lines
from pydiag.gear.kinematic_map import PRIORITY, with_gear_bearing
from pydiag.signal.spectra import Spectrum, local_maxima, whole_periods

#: Groups of the residual by family, and the kinematic families each gathers.
RESIDUAL_GROUPS = ("mesh_harmonics", "pinion_orders", "gear_orders", "assembly_hunting",
                   "bearing", "other_shaft_orders", "other_stages", "non_kinematic",
                   "broadband")
#: The indices of the groups of bins no kinematic line is on.
NOT_KINEMATIC = (RESIDUAL_GROUPS.index("non_kinematic"), RESIDUAL_GROUPS.index("broadband"))
FAMILY_GROUP = with_gear_bearing({"mesh": "mesh_harmonics", "mesh_sb_pinion": "pinion_orders",
                "pinion": "pinion_orders", "mesh_sb_gear": "gear_orders", "gear": "gear_orders",
                "assembly": "assembly_hunting", "hunting": "assembly_hunting", "bpfo": "bearing",
                "bpfi": "bearing", "bpfi_sb": "bearing", "bsf": "bearing", "ftf": "bearing",
                "other_shaft": "other_shaft_orders", "machine_shaft": "other_shaft_orders",
                "machine_bearing": "bearing", "stage_mesh": "other_stages",
                "stage_mesh_sb": "other_stages", "stage_assembly": "other_stages"})
#: Mains frequencies a non-kinematic line is checked against, Hz.
MAINS_HZ = (50.0, 60.0)


def bin_groups(freqs: np.ndarray, lines: list, bin_hz: float, measured: np.ndarray,
               margin: float) -> np.ndarray:
    """The :data:`RESIDUAL_GROUPS` index of every bin (entry k is frequency (k+1) bin_hz)."""
    groups = np.where((measured > margin) & local_maxima(measured),
                      RESIDUAL_GROUPS.index("non_kinematic"), RESIDUAL_GROUPS.index("broadband"))
    rank = {f: i for i, f in enumerate(PRIORITY)}
    for line in sorted(lines, key=lambda ln: -rank[ln.family]):  # the first family wins
        k = int(round(line.freq_hz / bin_hz)) - 1
        if 0 <= k < freqs.size and abs(freqs[k] - line.freq_hz) <= bin_hz / 2:
            groups[k] = RESIDUAL_GROUPS.index(FAMILY_GROUP[line.family])
    return groups


def residual_shares(groups: np.ndarray, measured: np.ndarray, model: np.ndarray,
                    scored: np.ndarray | None = None,
                    noise_power: float = 0.0) -> dict[str, dict[str, float]]:
    """Each group's share of the measured and of the residual energy; with ``scored`` (the
    error's bins) and the noise power, its share of the squared Eq. 12 error as well."""
    meas_sq, res_sq = measured ** 2, (measured - model) ** 2
    total_meas, total_res = float(meas_sq.sum()) or 1.0, float(res_sq.sum()) or 1.0
    out = {g: {"measured": float(meas_sq[groups == i].sum()) / total_meas,
               "residual": float(res_sq[groups == i].sum()) / total_res}
           for i, g in enumerate(RESIDUAL_GROUPS)}
    if scored is not None and np.any(scored):
        terms = spectral_residuals(model[scored], measured[scored], noise_power) ** 2
        total = float(terms.sum()) or 1.0
        for i, g in enumerate(RESIDUAL_GROUPS):
            out[g]["error"] = float(terms[groups[scored] == i].sum()) / total
    return out


def describe_non_kinematic(freq_hz: float, kin, bin_hz: float) -> str:
    """What a line no kinematic frequency explains could be."""
    text = (f"not kinematic: {freq_hz / kin.f_pinion_hz:.3g}x pinion, "
            f"{freq_hz / kin.f_gear_hz:.3g}x gear")
    if kin.surroundings is not None:
        for shaft in kin.surroundings.shafts:
            text += f", {freq_hz / (shaft.ratio * kin.f_pinion_hz):.3g}x {shaft.name}"
    elif kin.f_other_shaft_hz is not None:
        text += f", {freq_hz / kin.f_other_shaft_hz:.3g}x other shaft"
    for mains in MAINS_HZ:
        n = round(freq_hz / mains)
        if n >= 1 and abs(freq_hz - n * mains) <= bin_hz:
            text += f", {n}x {mains:g} Hz mains"
    return text + (" (a shaft or stage the machine file lacks, the mains, or a resonance)"
                   if kin.surroundings is not None else
                   " (another shaft or stage, the mains, or a resonance)")


def error_bins(measured: np.ndarray, margin: float, n_periods: int) -> np.ndarray:
    """Synchronous line bins and the measurement's own significant local maxima."""
    k = np.arange(measured.size)
    on_line = (k + 1) % n_periods == 0  # entry k holds frequency (k + 1)/(M T0)
    return on_line | ((measured > margin) & local_maxima(measured))


@dataclass
class MeasuredSpectra:
    """What a comparison fixes from the measurement alone: the featurizer with the bins
    scored, each channel's spectrum and noise power, and the peak margins."""

    featurizer: FullSpectrumFeaturizer
    spectra: dict[str, Spectrum]
    margin: dict[str, float]


def measured_spectra(problem: FitProblem, false_alarm_rate: float,
                     max_periods: int | None = None,
                     featurizer: FullSpectrumFeaturizer | None = None) -> MeasuredSpectra:
    """The measurement's spectra on ``featurizer`` (default: all the record's whole
    periods, at most ``max_periods``), its peak margins, and the bins scored."""
    kin = problem.kinematics
    if kin is None:
        raise EstimationError("compare names peaks by gear kinematics: give the FMU's Np, Ng, "
                              "f_pinion, or an adapter with [kinematics]")
    if not 0 < false_alarm_rate < 1:
        raise EstimationError(f"the false-alarm rate must lie strictly between 0 and 1, got "
                              f"{false_alarm_rate}")
    m = problem.measurement
    n_periods, _ = whole_periods(m.n_samples, m.sample_rate_hz, kin.period_s)
    if n_periods < 1:
        raise EstimationError(f"record of {m.duration_s:.4g} s is shorter than one fundamental "
                              f"period ({kin.period_s:.4g} s)")
    featurizer = featurizer or FullSpectrumFeaturizer(
        kin, min(n_periods, max_periods or n_periods), problem.featurizer.max_freq_hz)
    spectra, margin, bins = {}, {}, None
    for channel in problem.channels:
        spectra[channel] = spectrum = featurizer.spectrum(m.channels[channel], m.sample_rate_hz)
        freqs, amp, noise = spectrum.freq_hz, spectrum.amplitude, spectrum.noise_power
        margin[channel] = np.sqrt(noise * np.log(freqs.size / false_alarm_rate))
        mask = error_bins(amp, margin[channel], featurizer.n_periods)
        bins = mask if bins is None else bins | mask
    exclude = getattr(problem.featurizer, "exclude_hz", ())  # another stage's lines
    if exclude and featurizer.envelope_band_hz is None:  # every channel has these bins
        bins &= ~other_stages_lines(freqs, kin, exclude, featurizer.max_freq_hz)
    return MeasuredSpectra(featurizer.with_bins(bins), spectra, margin)
