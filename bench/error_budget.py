"""Where a real record's error lies, and what two other noise models would make of it.

For each record of a labelled set in the layout of ``../shared/data/gfd`` (channel a1 in g,
no time column): GearPair with the channel gain and ``a0`` fitted, the speed found and the
record order-tracked, compared on the whole record (``pydiag compare``'s error:
noise-corrected Eq. 12 on every synchronous line and every significant peak). With
``--phm09 FOLDER``, the PHM 2009 spur records named there instead, each stage of
``examples/phm09_spur.toml`` on its own (the pair model of the stage, the other stage's
lines left out, the speed from the meshes). Printed:

- the share of the weighted squared residual of Eq. 12 on each group of bins (the
  kinematic families, the non-kinematic peaks) and the bins that hold the most;
- the error with a noise floor that follows the spectrum (each bin's noise power the
  median power / ln 2 of the bins between lines within +-1/6 octave, the peaks judged
  against it) instead of one floor for the whole band;
- an upper bound for a comb of lines of random amplitude (every tooth of a gear a little
  different): on the bins of the gear's orders and the hunting/assembly lines (and the
  pinion's orders), the expected power taken from the measurement itself (its local
  median / ln 2 within +-1/6 octave) and added to the noise power, as a stochastic line
  model would predict it at best;
- how much each group's lines repeat: the complex spectra of the even and of the odd
  periods' averages, ``sum |A - B|^2 / sum (|A|^2 + |B|^2)`` on the group's lines (0: the
  same line in both halves, a deterministic source; 1: random phases);
- the share of the error's square on the sidebands within K orders of either shaft round
  the first five mesh harmonics, and the error a model that made those lines exactly
  would leave (``sqrt(1 - share)`` times the error): the bound of any modulation of the
  mesh by the shafts (amplitude, phase, tooth errors that repeat each turn);
- the share of the error's square below half the mesh frequency (the shafts' low orders,
  far from any mesh harmonic), by group.

With ``--bounds`` (no fit, a few seconds a record), what a model could reach held out, as
the loop scores it (half A of the periods fitted, noise-corrected Eq. 12 on half B at
the bins A chose): half A's lines, their noise taken out (``sqrt(max(A^2 - P, 0))``),
put exactly where A has them and nothing elsewhere, on

- every synchronous line (the best any model synchronous with the pair can do);
- the lines within K orders of either shaft of every mesh harmonic, the zeroth too (a
  shaft's own orders, any modulation or transmission error of either shaft by its angle,
  any shape, amplitude and phase free on every line);
- the combination lines of both shafts within K orders of each (the pair's tooth-pair
  pattern, its hunting/assembly lines, that no one shaft's form makes);
- each gear's tooth-by-tooth error sequence (Z values a turn, of any shape: a pitch,
  profile or runout error of every tooth) through a smooth transfer path: the line at
  m f_mesh + k f_s (m >= 1) is ``H(f) |E_s(k mod Z_s)|``, one amplitude for each of the
  sequence's orders at every mesh harmonic, the same for k and -k (a real sequence), the
  shafts' own orders (m = 0) free as the shaft-order effects make them, H piecewise
  linear in frequency with a node at every mesh harmonic (the gain curve as it is) or
  NODES nodes a mesh harmonic (a transfer path resolved finer); fitted on A by
  alternating least squares in amplitude (a bound's fit, not Eq. 12's).

Usage:
    .venv/bin/python bench/error_budget.py [--data ../shared/data/gfd] [--records b30hz90,...]
        [--bounds]
    .venv/bin/python bench/error_budget.py --phm09 ../shared/data/phm09 \
        [--records "spur 1_30hz_High_1,spur 2_30hz_High_1"]
"""

from __future__ import annotations

import argparse
import platform
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydiag.fit.build import ProblemSettings  # noqa: E402
from pydiag.fit.estimator import FaultEstimator  # noqa: E402
from pydiag.fit.gain import curve_basis, curve_nodes, fitted_curve  # noqa: E402
from pydiag.fit.objective import noise_corrected_error, spectral_residuals  # noqa: E402
from pydiag.fit.build import build_problem  # noqa: E402
from pydiag.gear.features import FullSpectrumFeaturizer, other_stages_lines  # noqa: E402
from pydiag.gear.kinematic_map import kinematic_map  # noqa: E402
from pydiag.gear.machine_file import load_machine  # noqa: E402
from pydiag.gear.speed import SpeedSettings  # noqa: E402
from pydiag.io.readers import read_measurement  # noqa: E402
from pydiag.loop.compare import compare  # noqa: E402
from pydiag.loop.residual import RESIDUAL_GROUPS, bin_groups, measured_spectra  # noqa: E402
from pydiag.diagnose.stages import machine_speed, stage_problem  # noqa: E402
from pydiag.signal.spectra import Spectrum, local_maxima, whole_periods  # noqa: E402

OPERATING_POINT = {"n_pinion": 32, "n_gear": 80, "f_pinion_hz": 30.0}  # README of gfd
SAMPLE_RATE_HZ = 12_900.0  # inferred in that README, not documented
PHM09_RATE_HZ = 66_666.67  # the challenge's documentation (../shared/data/phm09/README.md)
#: The half-width of the window a local floor or a comb's expected power is taken over.
OCTAVE = 1 / 6
#: How far from a mesh harmonic (shaft orders) the sidebands a modulation could make reach.
SIDEBAND_ORDERS = (1, 3, 6, 10, 16)
#: The groups of bins a comb of random line amplitudes is put on.
COMBS = (("gear_orders", "assembly_hunting"),
         ("gear_orders", "assembly_hunting", "pinion_orders"))
#: The false-alarm rate of the peaks a half's bins are chosen by (compare's default).
FALSE_ALARM_RATE = 0.01
#: Orders of either shaft round each mesh harmonic a bound's lines reach (``--bounds``) ...
BOUND_ORDERS = (10, 20, 40)
#: ... and of both shafts at once, for the pair's combination lines.
PAIR_ORDERS = 10
#: Nodes a mesh harmonic of the finer transfer curve a tooth sequence is seen through.
NODES = 8


def local_power(freqs: np.ndarray, amplitude: np.ndarray, among: np.ndarray,
                octave: float = OCTAVE) -> np.ndarray:
    """At every bin, the median power / ln 2 of the bins ``among`` within +-``octave``."""
    idx = np.flatnonzero(among)
    f = freqs[idx]
    out = np.zeros(freqs.size)
    for i in range(freqs.size):
        a, b = np.searchsorted(f, [freqs[i] * 2 ** -octave, freqs[i] * 2 ** octave])
        if b > a:
            out[i] = np.median(amplitude[idx[a:b]] ** 2) / np.log(2)
    return out


def repeatability(signal: np.ndarray, samples: int, orders: np.ndarray) -> float:
    """``sum |A - B|^2 / sum (|A|^2 + |B|^2)`` at ``orders`` of the period of ``samples``:
    A, B the spectra of the average of the even and of the odd periods of ``signal``."""
    periods = signal[:signal.size // samples * samples].reshape(-1, samples)
    a = np.fft.rfft(periods[0::2].mean(axis=0))[orders]
    b = np.fft.rfft(periods[1::2].mean(axis=0))[orders]
    return float(np.sum(np.abs(a - b) ** 2) / np.sum(np.abs(a) ** 2 + np.abs(b) ** 2))


def gfd_problems(path: Path, gain_curve: bool = False) -> dict:
    """The record's problem (GearPair, the channel gain or with ``gain_curve`` the gain
    curve fitted), by the record's name."""
    m = read_measurement(path, SAMPLE_RATE_HZ, ["a1=acc"], ["g"])
    return {path.name: build_problem(str(ROOT / "build" / "GearPair.fmu"), m,
                                     operating_point=OPERATING_POINT,
                                     speed=SpeedSettings("auto"), fit_gain=True,
                                     gain_curve=gain_curve)}


def phm09_problems(path: Path, gain_curve: bool = False) -> dict:
    """Each stage's problem (its channel as ``acc``, the tacho left out, the speed from
    every mesh) of a 30 Hz PHM09 record, by the record's and the stage's names."""
    machine = load_machine(ROOT / "examples" / "phm09_spur.toml")
    m = read_measurement(path, PHM09_RATE_HZ)
    speed = SpeedSettings("mesh", tacho="ch3")
    found = machine_speed(m, machine, 30.0, speed)
    settings = ProblemSettings(fit_gain=True, gain_curve=gain_curve, speed=speed)
    return {f"{path.name} {stage.name}": stage_problem(
        str(ROOT / "build" / "GearPair.fmu"), m, machine, k, found, settings)
        for k, stage in enumerate(machine.stages)}


def budget(name: str, problem) -> None:
    c = compare(problem, FaultEstimator(seed=0))
    s = c.spectra[problem.channels[0]]
    freqs, meas, model = s.freq_hz, s.amplitude, c.model_spectra[problem.channels[0]].amplitude
    noise, rate = s.noise_power, c.false_alarm_rate
    margin = np.sqrt(noise * np.log(meas.size / rate))
    bins = measured_spectra(problem, rate).featurizer.bins  # the error's (compare's) bins
    groups = bin_groups(freqs, kinematic_map(problem.kinematics, problem.featurizer.max_freq_hz),
                        c.bin_hz, meas, margin)
    term = np.zeros(meas.size)  # each scored bin's part of the squared error
    term[bins] = spectral_residuals(model[bins], meas[bins], noise) ** 2
    total = float(term.sum())
    shares = c.residual_by_family[problem.channels[0]]
    between = (np.arange(meas.size) + 1) % c.n_periods != 0  # not on a synchronous line
    print(f"\n{name}: error {c.error:.3f} on {bins.sum()} bins ({c.n_periods} periods)")
    tracked = problem.measurement
    samples = int(round(problem.kinematics.period_s * tracked.sample_rate_hz))
    print("| group | bins | share of the measured (the error's bins) | share of the error's "
          "square | repeats |")
    print("|---|---|---|---|---|")
    for i, group in enumerate(RESIDUAL_GROUPS):
        on = bins & (groups == i)
        if on.any():
            lines = (np.flatnonzero(on & ~between) + 1) // c.n_periods  # orders of the period
            again = (f"{repeatability(tracked.channels[problem.channels[0]], samples, lines):.2f}"
                     if lines.size else "-")
            print(f"| {group} | {on.sum()} | {np.sum(meas[on] ** 2) / np.sum(meas[bins] ** 2):.2f}"
                  f" | {shares[group]['error']:.2f} | {again} |")
    top = np.flatnonzero(bins)[np.argsort(-term[bins])[:6]]
    print("largest bins: " + "; ".join(
        f"{freqs[k]:.1f} Hz {RESIDUAL_GROUPS[groups[k]]} measured {meas[k]:.3g} model "
        f"{model[k]:.3g} ({100 * term[k] / total:.1f} %)" for k in top))
    floor = local_power(freqs, meas, between)
    own = ~between | ((meas > np.sqrt(floor * np.log(meas.size / rate))) & local_maxima(meas))
    exclude = getattr(problem.featurizer, "exclude_hz", ())  # a stage: as compare leaves out
    if exclude:
        own &= ~other_stages_lines(freqs, problem.kinematics, exclude,
                                   problem.featurizer.max_freq_hz)
    print(f"local floor ({floor[bins].min() / noise:.3g}-{floor[bins].max() / noise:.3g} x the "
          f"flat one): error {noise_corrected_error(model[bins], meas[bins], floor[bins]):.3f} "
          f"on the same bins, {noise_corrected_error(model[own], meas[own], floor[own]):.3f} "
          f"on its own {own.sum()}")
    bounds, kin = [], problem.kinematics
    for k_max in SIDEBAND_ORDERS:
        near = np.zeros(meas.size, dtype=bool)
        for f_shaft in (kin.f_pinion_hz, kin.f_gear_hz):
            for h in range(1, 6):
                for k in range(1, k_max + 1):
                    for f in (h * kin.f_mesh_hz - k * f_shaft, h * kin.f_mesh_hz + k * f_shaft):
                        near |= np.abs(freqs - f) < 0.5 * c.bin_hz + 1e-9
        share = float(term[near & bins].sum() / total)
        bounds.append(f"K {k_max}: {share:.2f} -> {c.error * np.sqrt(1 - share):.3f}")
    print("sidebands within K shaft orders of mesh harmonics 1-5, share of the error's square "
          "-> the error with them exact: " + "; ".join(bounds))
    low = bins & (freqs < kin.f_mesh_hz / 2)
    print(f"below half the mesh: {term[low].sum() / total:.2f} of the error's square (" + ", ".join(
        f"{group} {term[low & (groups == i)].sum() / total:.2f}"
        for i, group in enumerate(RESIDUAL_GROUPS) if term[low & (groups == i)].any()) + ")")
    for comb in COMBS:
        on = np.isin(groups, [RESIDUAL_GROUPS.index(g) for g in comb])
        power = noise + np.where(on, local_power(freqs, meas, on), 0.0)
        print(f"comb of random lines on {' + '.join(comb)} at the measured power (a bound): "
              f"error {noise_corrected_error(model[bins], meas[bins], power[bins]):.3f}")


def lines_near(freqs: np.ndarray, bin_hz: float, f_mesh_hz: float,
                shafts_hz: tuple[float, ...], k_max: int, together: bool = False
                ) -> dict[int, tuple[int, int, int]]:
    """The bins (index into ``freqs``, entry k at (k+1) ``bin_hz``) of the lines m f_mesh +
    k f_s, |k| <= ``k_max``, m >= 0, above 0 Hz, each with its shaft's index, k and m (the
    first shaft's where two coincide); ``together``: m f_mesh + k1 f_1 + k2 f_2 instead,
    shaft index -1 and k 0."""
    k = np.arange(-k_max, k_max + 1)
    if together:
        combos = [(-1, 0, float(a * shafts_hz[0] + b * shafts_hz[1]))
                  for a in k for b in k]
    else:
        combos = [(s, int(kk), float(kk * f)) for s, f in enumerate(shafts_hz) for kk in k]
    out: dict[int, tuple[int, int, int]] = {}
    for m in range(int(freqs[-1] / f_mesh_hz) + 2):
        for s, kk, offset in combos:
            f = m * f_mesh_hz + offset
            j = int(round(f / bin_hz)) - 1
            if f > 0 and 0 <= j < freqs.size and j not in out:
                out[j] = (s, kk, m)
    return out


def sequence_lines(freqs: np.ndarray, bin_hz: float, f_mesh_hz: float,
                   shafts: tuple[tuple[float, int], ...], own_orders_free: bool = True
                   ) -> dict[int, tuple[int, int]]:
    """The bins of every line m f_mesh + k f_s of each shaft s (speed, teeth Z), |k| <=
    Z/2, each with a key: the shaft's index and the order of its tooth sequence the line
    shows, ``min(k mod Z, Z - k mod Z)``; with ``own_orders_free`` a shaft's own order
    (m = 0: its unbalance, misalignment, ..., no tooth's) a key of its own, ``(S + s, k)``
    for S shafts (the first shaft's where two coincide)."""
    out: dict[int, tuple[int, int]] = {}
    for s, (f_shaft, teeth) in enumerate(shafts):
        found = lines_near(freqs, bin_hz, f_mesh_hz, (f_shaft,), teeth // 2)
        for j, (_, k, m) in found.items():
            out.setdefault(j, (len(shafts) + s, k) if m == 0 and own_orders_free
                           else (s, min(k % teeth, teeth - k % teeth)))
    return out


def sequence_fit(freqs: np.ndarray, amplitude: np.ndarray, lines: dict[int, tuple[int, int]],
                 nodes_hz: np.ndarray, iterations: int = 150) -> np.ndarray:
    """Line amplitudes ``H(f) e_key`` fitted to ``amplitude`` on ``lines`` (each bin's key:
    the sequence and its order), H piecewise linear between ``nodes_hz``, both
    non-negative, by alternating (non-negative) least squares; zero off the lines."""
    js = np.array(sorted(lines))
    _, which = np.unique(np.array([lines[j] for j in js]), axis=0, return_inverse=True)
    which = which.ravel()
    y = amplitude[js]
    hat = curve_basis(freqs[js], nodes_hz)
    h, e = np.ones(nodes_hz.size), np.zeros(which.max() + 1)
    for _ in range(iterations):
        transfer = hat @ h
        e = np.maximum(np.bincount(which, transfer * y, e.size)
                       / np.maximum(np.bincount(which, transfer ** 2, e.size), 1e-300), 0.0)
        h = fitted_curve(e[which], y, hat)
    out = np.zeros(amplitude.size)
    out[js] = (hat @ h) * e[which]
    return out


@dataclass
class HalfLines:
    """Half A's spectrum, its lines with the noise taken out and the bins it chose, and
    half B's spectrum: what a bound is fitted on and scored on."""

    a: Spectrum
    b: Spectrum
    bins: np.ndarray
    lines_a: np.ndarray
    n_half: int  # fundamental periods a half holds

    def on_b(self, model: np.ndarray) -> float:
        """Noise-corrected Eq. 12 of ``model`` (amplitude at every bin) on B, at A's bins."""
        return noise_corrected_error(model[self.bins], self.b.amplitude[self.bins],
                                     self.b.noise_power)

    def on_a(self, model: np.ndarray) -> float:
        return noise_corrected_error(model[self.bins], self.a.amplitude[self.bins],
                                     self.a.noise_power)


def half_lines(problem) -> HalfLines | None:
    """The :class:`HalfLines` of ``problem``'s record (None: under two periods)."""
    kin, m = problem.kinematics, problem.measurement
    channel, top = problem.channels[0], problem.featurizer.max_freq_hz
    n_half = whole_periods(m.n_samples, m.sample_rate_hz, kin.period_s)[0] // 2
    if n_half < 1:
        return None
    measured = measured_spectra(problem, FALSE_ALARM_RATE, featurizer=FullSpectrumFeaturizer(
        kin, n_half, top, half=0))
    a = measured.spectra[channel]
    b = FullSpectrumFeaturizer(kin, n_half, top, half=1).spectrum(m.channels[channel],
                                                                  m.sample_rate_hz)
    synchronous = (np.arange(a.amplitude.size) + 1) % n_half == 0
    lines_a = np.where(synchronous, np.sqrt(np.maximum(a.amplitude ** 2 - a.noise_power, 0.0)),
                       0.0)
    return HalfLines(a, b, measured.featurizer.bins, lines_a, n_half)


def sequence_bound(problem, halves: HalfLines, nodes_hz: np.ndarray,
                   own_orders_free: bool = True) -> np.ndarray:
    """The tooth sequences' model (:func:`sequence_fit`) of ``problem``'s pair on half A."""
    kin = problem.kinematics
    lines = sequence_lines(halves.a.freq_hz, float(halves.a.freq_hz[0]), kin.f_mesh_hz,
                           ((kin.f_pinion_hz, kin.n_pinion), (kin.f_gear_hz, kin.n_gear)),
                           own_orders_free)
    return sequence_fit(halves.a.freq_hz, halves.lines_a, lines, nodes_hz)


def held_out_bounds(name: str, problem) -> None:
    """Print what the model forms of the module docstring (``--bounds``) could reach held
    out: half A's lines predicting half B, on the bins A chose."""
    kin, top = problem.kinematics, problem.featurizer.max_freq_hz
    halves = half_lines(problem)
    if halves is None:
        print(f"\n{name}: fewer than two fundamental periods, no halves")
        return
    freqs, lines_a = halves.a.freq_hz, halves.lines_a
    bin_hz = float(freqs[0])
    shafts = (kin.f_pinion_hz, kin.f_gear_hz)

    def only(lines: dict) -> np.ndarray:
        mask = np.zeros(lines_a.size, dtype=bool)
        mask[list(lines)] = True
        return np.where(mask, lines_a, 0.0)

    row = [f"{halves.on_b(np.zeros(lines_a.size)):.3f}", f"{halves.on_b(lines_a):.3f}"]
    row += [f"{halves.on_b(only(lines_near(freqs, bin_hz, kin.f_mesh_hz, shafts, k))):.3f}"
            for k in BOUND_ORDERS]
    row.append(f"{halves.on_b(only(lines_near(freqs, bin_hz, kin.f_mesh_hz, shafts, PAIR_ORDERS, together=True))):.3f}")
    harmonics = curve_nodes(kin, top)
    finer = np.arange(0.0, harmonics[-1] + 1e-9, kin.f_mesh_hz / NODES)
    for nodes in (harmonics, finer):
        model = sequence_bound(problem, halves, nodes)
        row.append(f"{halves.on_b(model):.3f} (A {halves.on_a(model):.3f})")
    print(f"| {name} ({kin.n_pinion}/{kin.n_gear}) | {halves.n_half} | " + " | ".join(row) + " |",
          flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data" / "gfd")
    ap.add_argument("--phm09", type=Path, help="the PHM09 folder (its zips) instead")
    ap.add_argument("--bounds", action="store_true",
                    help="only what model forms could reach held out (no fit)")
    ap.add_argument("--records", help="names without their extension (default: the GFD four; "
                    "with --phm09 spur 1_30hz_High_1 and spur 2_30hz_High_1)")
    args = ap.parse_args()
    if args.phm09:
        names = args.records or "spur 1_30hz_High_1,spur 2_30hz_High_1"
        paths = [args.phm09 / f"{name}.zip" for name in names.split(",")]
    else:
        names = args.records or "b30hz0,b30hz90,h30hz0,h30hz90"
        paths = [args.data / f"{name}.csv.gz" for name in names.split(",")]
    missing = [str(p) for p in paths if not p.exists()]
    if missing:
        print(f"error_budget: no record {', '.join(missing)}", file=sys.stderr)
        return 2
    print(f"{platform.machine()}, Python {platform.python_version()}")
    if args.bounds:
        print("\nHeld-out error (half A's lines predict half B) of a model that has exactly:\n\n"
              "| record | periods a half | nothing | every synchronous line | "
              + " | ".join(f"either shaft's orders within {k} of each mesh harmonic"
                           for k in BOUND_ORDERS)
              + f" | both shafts' combinations within {PAIR_ORDERS} | each gear's tooth "
              f"sequence, the gain curve | the same, {NODES} nodes a mesh harmonic |\n"
              + "|---" * (6 + len(BOUND_ORDERS)) + "|")
    for path in paths:
        for name, problem in (phm09_problems if args.phm09 else gfd_problems)(path).items():
            (held_out_bounds if args.bounds else budget)(name, problem)
    return 0


if __name__ == "__main__":
    sys.exit(main())
