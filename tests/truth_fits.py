"""What the tests and the bench fit to the independent simulator's records
(:mod:`truth.gear_sim`): the base model's parameters, the machine beyond the pair that the
engineer knows, the operating points they share, and the measures of how far an effect
stands out of a record."""

import numpy as np

from pydiag.core.parameters import Parameter
from pydiag.fit.build import build_problem
from pydiag.fit.problem import FitProblem
from pydiag.gear.conventions import HEALTHY_TOOTH
from pydiag.gear.effects import EFFECTS
from pydiag.gear.kinematics import Bearing
from pydiag.model.adapter import gear_default
from truth.gear_sim import Effects, TruthGear, record, simulate

#: GearPair's paper parameters, the healthy teeth's level a0, the stiffness wave's shape and
#: the faulty tooth's softening and its form. The paper's faulty-tooth amplitude a_f may
#: fall below its 0.1 here: a weaker tooth's form is d_f's, and a_f only trims it.
BASE_PARAMETERS = (tuple(Parameter("a_f", 0.0, 0.9) if p.name == "a_f" else p
                         for p in gear_default(["acc", "disp"]).fault_parameters)
                   + (HEALTHY_TOOTH,) + EFFECTS["mesh_stiffness_shape"].parameters
                   + EFFECTS["pinion_tooth_softening"].parameters)
#: The simulator's pinion bearing: a 6205 (9 balls of 7.94 mm on a 39.04 mm pitch circle).
BEARING = Bearing(9, 7.94e-3, 39.04e-3)
#: What the engineer knows of the simulator's machine beyond the gear pair, given with every
#: record whether or not a shaft is faulty: the pinion bearing's geometry and the motor
#: shaft's speed ratio (29/17), so their lines are kinematic.
OPERATING_POINT = {"other_shaft_ratio": Effects().other_shaft_ratio, "bearing": BEARING}

#: Where the simulator's teeth do separate: the mesh (14 x 227 Hz = 3178 Hz) at the mesh
#: resonance, sqrt(K/m)/(2 pi) = 3183 Hz; at 25 Hz the contact force never falls to zero,
#: even at 1 N.m.
RESONANCE = TruthGear(f_pinion_hz=227.0)
#: 4.5 mesh harmonics (the analysed band, 14.3 kHz) need more than 28.6 kHz.
RESONANCE_RATE_HZ = 50_000.0
RESONANCE_TOP_HZ = 4.5 * RESONANCE.n_pinion * RESONANCE.f_pinion_hz
#: 150 periods of 13.2 ms: a 2 s record. With 20 (0.26 s) the change a gap makes, once the
#: base has bent to it, was within what the halves' noise lets the held-out test see.
RESONANCE_PERIODS = 150


def resonance_clean(backlash_m: float = 0.0) -> dict:
    """The noise-free channels of :data:`RESONANCE_PERIODS` periods at :data:`RESONANCE`,
    the teeth's gap ``backlash_m`` (0: none)."""
    g = RESONANCE.with_effects(backlash_m=backlash_m)
    return simulate(g, RESONANCE_PERIODS * g.period_s, RESONANCE_RATE_HZ, warmup_s=0.1)


def resonance_problem(gear_fmu: str, clean: dict, seed: int) -> FitProblem:
    """The base model's problem on a noisy record (SNR 10, ``seed``) of ``clean``."""
    m = record(RESONANCE, RESONANCE_PERIODS, seed, RESONANCE_RATE_HZ, clean=clean)
    return build_problem(str(gear_fmu), m, parameters=BASE_PARAMETERS,
                         operating_point={"f_pinion_hz": RESONANCE.f_pinion_hz,
                                          "bearing": BEARING},
                         fixed_values={"T": RESONANCE.torque_n_m})


def line_margin_db(with_effect: np.ndarray, without: np.ndarray, snr: float,
                   sample_rate_hz: float, max_freq_hz: float) -> tuple[float, float]:
    """(frequency, margin in dB) of the strongest spectral line an effect changes below
    ``max_freq_hz``, over the mean amplitude of a noise bin at ``snr`` (noise-free inputs
    of equal length)."""
    n = with_effect.size
    freqs = np.fft.rfftfreq(n, 1 / sample_rate_hz)
    change = 2 * np.abs(np.fft.rfft(with_effect - np.mean(with_effect))
                        - np.fft.rfft(without - np.mean(without))) / n
    keep = (freqs > 0) & (freqs <= max_freq_hz)
    k = np.argmax(np.where(keep, change, 0))
    sigma = np.sqrt(np.var(with_effect) / snr)
    noise_bin = sigma * np.sqrt(np.pi / n)  # mean amplitude of a white-noise bin
    return float(freqs[k]), float(20 * np.log10(max(change[k], 1e-300) / noise_bin))


def envelope_margin_db(noisy: np.ndarray, sample_rate_hz: float, band_hz: tuple[float, float],
                       lines_hz: list[float]) -> tuple[float, float]:
    """(frequency, margin in dB) of the strongest of ``lines_hz`` in the envelope spectrum
    of a noisy record (the band ``band_hz``, Hann window), over that spectrum's noise
    floor (median power / ln 2: robust to the lines)."""
    from pydiag.signal.spectra import amplitude_spectrum, band_envelope, noise_power

    freqs, amp = amplitude_spectrum(band_envelope(noisy, sample_rate_hz, band_hz),
                                    sample_rate_hz, "hann")
    keep = (freqs > 1.0) & (freqs < 2000.0)
    floor = np.sqrt(noise_power(amp[keep], robust=True))
    peaks = [(f, amp[np.abs(freqs - f) <= 1.5 * (freqs[1] - freqs[0])].max()) for f in lines_hz]
    f, a = max(peaks, key=lambda p: p[1])
    return float(f), float(20 * np.log10(a / floor))
