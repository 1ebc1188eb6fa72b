"""The held-out test's statistic: its false-alarm rate under noise alone, its power when
the effect is real; the half featurizer's two halves."""

import math

import numpy as np
import pytest
from scipy.stats import norm

from pydiag.gear.features import FullSpectrumFeaturizer
from pydiag.gear.kinematics import GearKinematics
from pydiag.loop.competition import deferred, outcompeted, rivals, settle
from pydiag.loop.effect_fit import in_model
from pydiag.core.parameters import Parameter
from pydiag.loop.held_out import FALSE_ALARM_RATE, held_out_statistic, pressed_bounds
from pydiag.loop.results import HeldOut, Status


def rician(amplitude, noise_power, rng, size):
    """|A + n| with n complex Gaussian of power noise_power (per bin)."""
    n = rng.normal(0, np.sqrt(noise_power / 2), (size, amplitude.size, 2))
    return np.hypot(amplitude + n[..., 0], n[..., 1])


def z_of(measured, base, effect, noise):
    total_w, terms, _ = held_out_statistic(measured, base, effect, noise)
    return (terms.sum() + total_w) / (2 * np.sqrt(total_w))


def test_false_alarm_rate_when_the_effect_only_fits_noise():
    """Base lines right; the 'effect' moved the lines by what a fit to other noise would:
    z exceeds its threshold in about alpha of the trials (2000 trials, 300 bins)."""
    rng = np.random.default_rng(1)
    base = np.concatenate([rng.uniform(0.5, 5, 60), np.zeros(240)])  # lines and empty bins
    noise = 0.3
    threshold = norm.ppf(1 - FALSE_ALARM_RATE)
    held = rician(base, noise, rng, 2000)
    fitted_to = rician(base, noise, rng, 2000)  # the other half's noise, which the effect fits
    z = np.array([z_of(r, base, base + 0.3 * (f - base), noise)
                  for r, f in zip(held, fitted_to)])
    rate = np.mean(z > threshold)
    assert 0.002 < rate < 0.025, rate  # 0.01 +- 3.5 binomial standard deviations
    assert abs(np.mean(z)) < 0.15 and 0.85 < np.std(z) < 1.15  # standard normal


def test_a_real_effect_passes_and_a_wrong_one_does_not():
    rng = np.random.default_rng(2)
    base = rng.uniform(0.5, 5, 80)
    truth = base.copy()
    truth[::8] += 1.0  # the lines a missing effect raises
    measured = rician(truth, 0.3, rng, 1)[0]
    threshold = norm.ppf(1 - FALSE_ALARM_RATE)
    assert z_of(measured, base, truth, 0.3) > 3 * threshold
    wrong = base.copy()
    wrong[4::8] += 1.0  # raises other lines: as noise alone, z is about standard normal
    assert z_of(measured, base, wrong, 0.3) < threshold


def test_halves_hold_the_same_lines_and_independent_noise():
    kin = GearKinematics(14, 21, 25.0)
    rate = 10_000.0
    n = int(round(8 * kin.period_s * rate))
    t = np.arange(n) / rate
    rng = np.random.default_rng(3)
    x = 2.0 * np.sin(2 * np.pi * kin.f_mesh_hz * t) + rng.normal(0, 1, n)
    halves = [FullSpectrumFeaturizer(kin, 4, 1000.0, half=h) for h in (0, 1)]
    assert halves[0].duration_s == 8 * kin.period_s
    spectra = [h.spectrum(x, rate) for h in halves]
    k = int(round(kin.f_mesh_hz * 4 * kin.period_s)) - 1  # the mesh line's bin
    for s in spectra:
        assert abs(s.freq_hz[k] - kin.f_mesh_hz) < 1e-9 and abs(s.amplitude[k] - 2.0) < 0.1
    noise = [np.delete(s.amplitude, k) for s in spectra]
    assert abs(np.corrcoef(noise[0], noise[1])[0, 1]) < 0.1  # other periods, other noise
    whole = FullSpectrumFeaturizer(kin, 4, 1000.0).spectrum(x[:n // 2], rate).amplitude
    assert not np.allclose(whole, spectra[0].amplitude)  # half 0 is not the first half


def test_halves_of_periods_of_no_whole_number_of_samples_have_the_same_bins():
    """A period of 660.8 samples (227 Hz pinion, 14/21 teeth, at 50 kHz): the halves' periods
    are not all of one length, and the test compares them bin by bin."""
    kin = GearKinematics(14, 21, 227.0)
    rate = 50_000.0
    n = int(np.ceil(6 * kin.period_s * rate))  # 3 periods each: 1982 and 1983 samples
    x = np.sin(2 * np.pi * kin.f_mesh_hz * np.arange(n) / rate)
    halves = [FullSpectrumFeaturizer(kin, 3, 10_000.0, half=h) for h in (0, 1)]
    (f0, a0), (f1, a1) = ((s.freq_hz, s.amplitude) for s in (h.spectrum(x, rate) for h in halves))
    assert f0.shape == f1.shape and np.array_equal(f0, f1)
    k = int(np.argmax(a0))
    assert abs(f0[k] - kin.f_mesh_hz) < 0.5 * (f0[1] - f0[0]) and a0[k] > 0.95 and a1[k] > 0.95


def test_halves_of_many_periods_of_no_whole_number_of_samples_keep_lines_on_their_bins():
    """75 periods a half of 660.8 samples: the mesh and its 4th harmonic (12.7 kHz) on the
    bin at their frequency, whole (periods cut to 660 samples put them 0.12 % high, 4 bins
    off at 1x mesh)."""
    kin = GearKinematics(14, 21, 227.0)
    rate = 50_000.0
    n = int(np.ceil(150 * kin.period_s * rate))
    t = np.arange(n) / rate
    x = np.sin(2 * np.pi * kin.f_mesh_hz * t) + 0.5 * np.sin(2 * np.pi * 4 * kin.f_mesh_hz * t)
    for half in (0, 1):
        s = FullSpectrumFeaturizer(kin, 75, 15_000.0, half=half).spectrum(x, rate)
        freqs, amp = s.freq_hz, s.amplitude
        bin_hz = freqs[1] - freqs[0]
        assert abs(bin_hz * 75 * kin.period_s - 1) < 1e-6
        for harmonic, amplitude in ((1, 1.0), (4, 0.5)):
            k = int(np.argmin(abs(freqs - harmonic * kin.f_mesh_hz)))
            assert abs(freqs[k] - harmonic * kin.f_mesh_hz) < 1e-6 * freqs[k]
            assert abs(amp[k] - amplitude) < 0.02 * amplitude


def test_one_confident_effect_per_set_of_competing_lines():
    competing = {"shape": ["backlash", "housing"], "backlash": ["shape", "housing"],
                 "housing": ["shape", "backlash"], "runout": ["tooth"], "tooth": ["runout"]}
    beaten = outcompeted({"shape": 120.0, "housing": 80.0, "runout": 600.0, "backlash": 3.0},
                         competing)
    # the runout claims other lines than the shape: both stay; housing and backlash lose
    assert set(beaten) == {"housing", "backlash"}
    assert beaten["housing"].startswith("competes with shape") and "120.0 > 80.0" in beaten["housing"]
    assert outcompeted({"tooth": 5.0}, competing) == {}


def test_a_confident_effect_whose_absence_bends_the_base_defers_the_weaker_ones():
    """As on the torque ripple's record of the independent simulator: the ripple's
    sidebands, not synchronous, leak into the swing's bins of the joined halves, and the
    swing, fitted with the base free, takes them up (bench/RESULTS.md changelog)."""
    confident = {"ripple": 121.1, "swing": 16.1, "runout": 594.0}
    waiting = deferred(confident, bending={"ripple", "swing"})
    assert set(waiting) == {"swing"}  # the runout, stronger than the ripple, stands
    assert "ripple's absence bends" in waiting["swing"] and "z 121.1" in waiting["swing"]
    assert deferred(confident, bending=()) == {}
    assert deferred({"runout": 594.0, "swing": 16.1}, bending={"swing"}) == {}  # weakest
    # settle: outcompeted first, then deferred among those left
    held = {k: HeldOut(k, z, 2.3, 0.9, 0.8, 0.5, {}) for k, z in confident.items()}
    verdicts = settle(held, {"runout": [], "ripple": [], "swing": []}, {"ripple", "swing"})
    assert {k: status for k, (status, _) in verdicts.items()} == {"swing": Status.DEFERRED}


def test_a_line_between_the_synchronous_ones_moves_where_the_half_joins_periods():
    """A half joins every other period: a synchronous line stays on its bin; one that is
    not (a bearing's) jumps in phase at every joint and shows where ``joined_freq_hz``
    says, with most of its power."""
    kin = GearKinematics(14, 21, 25.0)  # fundamental period 0.12 s
    rate = 10_000.0
    t = np.arange(int(round(20 * kin.period_s * rate))) / rate
    half = FullSpectrumFeaturizer(kin, 10, 1575.0, half=0)
    assert FullSpectrumFeaturizer(kin, 10, 1575.0).joined_freq_hz(89.62) == 89.62
    for f in (89.62, 135.38, 357.3, 200.4, 75.0, kin.f_mesh_hz):
        s = half.spectrum(np.cos(2 * np.pi * f * t + 0.3), rate)
        freqs, amp = s.freq_hz, s.amplitude
        k = int(np.argmax(amp))
        assert abs(freqs[k] - half.joined_freq_hz(f)) <= 1 / (10 * kin.period_s), f
        assert amp[k] ** 2 / np.sum(amp ** 2) >= 0.4
    assert half.joined_freq_hz(75.0) == 75.0 and abs(half.joined_freq_hz(89.62) - 87.57) < 0.01


def test_effects_that_claim_one_line_of_a_half_compete():
    competing = {"shape": ["backlash"], "backlash": ["shape"], "outer": [], "inner": []}
    claimed = {"outer": ("acc envelope 87.50 Hz", "acc envelope 270.83 Hz"),
               "inner": ("acc envelope 87.50 Hz",), "shape": ()}
    out = rivals(competing, claimed)
    assert out["outer"] == ["inner"] and out["inner"] == ["outer"]
    assert out["shape"] == ["backlash"] and competing["outer"] == []  # not changed in place
    assert set(outcompeted({"outer": 65.8, "inner": 10.1}, out)) == {"inner"}


def test_competing_effects_the_record_does_not_tell_apart_are_neither_confident():
    """A confident effect whose competitor beat noise with about its z (within the test's
    threshold) is not confident: the record does not tell them apart. A competitor far
    below, or one claiming other lines, changes nothing."""
    competing = {"second_tooth": ["softening"], "softening": ["second_tooth"], "runout": []}
    significant = {"second_tooth": 37.7, "softening": 36.5, "runout": 594.0}
    beaten = outcompeted({"second_tooth": 37.7, "runout": 594.0}, competing, significant)
    assert set(beaten) == {"second_tooth"}
    assert "does not tell them apart" in beaten["second_tooth"] and "36.5" in beaten["second_tooth"]
    assert outcompeted({"second_tooth": 37.7}, competing, {**significant, "softening": 20.0}) == {}
    assert outcompeted({"second_tooth": 37.7}, competing) == {}  # no others known
    # one with a far larger z (not confident: its own lines' form wrong) is not "about as well"
    said = outcompeted({"second_tooth": 37.7}, competing, {**significant, "softening": 90.0})
    assert "explains them at least as well held out (z 90.0 against 37.7" in \
        said["second_tooth"]


def test_competitors_are_set_side_by_side_on_the_lines_both_claim():
    """The sentence of an effect the record does not tell apart from a competitor gives
    what each removes of the residual on the lines both claim, from their terms there."""
    def fit(key, z, terms):
        return HeldOut(key, z, 2.3, 0.6, 1.0, 0.5, {}, line_terms=terms)
    housing = fit("housing", 208.9, {"acc 1266.67 Hz": (6.0, 10.0), "acc 1300.00 Hz": (1.0, 0.0)})
    tooth = fit("tooth", 221.5, {"acc 1266.67 Hz": (4.0, 10.0), "acc 100.00 Hz": (9.0, 9.0)})
    assert tooth.explained_on(["acc 1266.67 Hz", "acc 1300.00 Hz"]) == pytest.approx(0.4)
    assert math.isnan(tooth.explained_on(["acc 5.00 Hz"]))
    assert "line_terms" not in housing.to_dict()
    competing = {"housing": ["tooth"], "tooth": ["housing"]}
    beaten = outcompeted({"housing": 208.9}, competing, {"housing": 208.9, "tooth": 221.5},
                         fits={"housing": housing, "tooth": tooth})
    assert "on the one line both claim it removes 60 % of the residual, tooth 40 %" in \
        beaten["housing"], beaten
    assert "both claim" not in outcompeted({"housing": 208.9}, competing,
                                           {"housing": 208.9, "tooth": 221.5})["housing"]


def test_a_competitor_the_shared_lines_tell_apart_does_not_beat_an_effect():
    """An effect that removes most of the residual on the lines it shares with a competitor
    which removes next to nothing there is told apart from it, whatever that competitor's
    z (earned on its other lines); one that removes half as much or more is not, and one
    that is confident with a larger z still wins."""
    def fit(key, z, terms):
        return HeldOut(key, z, 2.3, 0.6, 1.0, 0.5, {}, line_terms=terms)
    low = {"acc 89.53 Hz": 10.0, "acc 179.05 Hz": 5.0}
    shaft = fit("shaft", 176.1, {k: (0.97 * x, x) for k, x in low.items()})
    tooth = fit("tooth", 221.5, {**{k: (0.0, x) for k, x in low.items()},
                                 "acc 925.11 Hz": (40.0, 50.0)})
    competing = {"shaft": ["tooth"], "tooth": ["shaft"]}
    significant = {"shaft": 176.1, "tooth": 221.5}
    assert outcompeted({"shaft": 176.1}, competing, significant,
                       fits={"shaft": shaft, "tooth": tooth}) == {}
    assert set(outcompeted({"shaft": 176.1}, competing, significant)) == {"shaft"}  # unknown
    half = fit("tooth", 221.5, {k: (0.5 * x, x) for k, x in low.items()})
    assert set(outcompeted({"shaft": 176.1}, competing, significant,
                           fits={"shaft": shaft, "tooth": half})) == {"shaft"}
    # confident and ahead by z, a competitor wins all the same: one confident effect
    assert set(outcompeted({"shaft": 176.1, "tooth": 221.5}, competing,
                           fits={"shaft": shaft, "tooth": tooth})) == {"shaft"}


def test_an_effect_is_in_the_model_when_every_parameter_it_fits_on_this_pair_is():
    """The pinion shaft's even orders are gear orders on 14/21 teeth and never fitted: a
    model fitting its odd ones has it; one fitting some of them does not."""
    from types import SimpleNamespace

    from pydiag.core.parameters import Parameter
    from pydiag.gear.effects import EFFECTS
    shaft = EFFECTS["pinion_shaft_orders"]
    def problem(names):
        return SimpleNamespace(parameters=tuple(Parameter(n, 0.0, 1.0) for n in names),
                               kinematics=GearKinematics(14, 21, 25.0))
    assert in_model(problem(["a0", "A_s1", "A_s3", "A_s5", "A_s7"]), shaft)
    assert not in_model(problem(["a0", "A_s1", "A_s3"]), shaft)
    assert not in_model(problem(["a0"]), EFFECTS["housing_sensor"])
    assert in_model(problem(["a0", "f_housing", "zeta_housing"]), EFFECTS["housing_sensor"])
    # another shaft's orders are fitted where the record has lines: a model with some of
    # them has it, one with none does not (nor, without its ratio, has anything to fit)
    other = EFFECTS["other_shaft_orders"]
    assert in_model(problem(["a0", "A_o2"]), other)
    assert not in_model(problem(["a0"]), other)


def test_a_bound_saturates_only_where_the_fit_presses_against_it():
    """A parameter at a bound saturates when the error rises stepping inward from it (the
    record asks for more than the range allows); one the error hardly depends on there
    (a housing mode's damping, with every line below the mode) does not, so the verdict
    does not hang on where rounding stopped its fit. A bound of 0 (the effect off), an
    angle, a tooth's index and a parameter not the effect's are never saturated."""
    params = (Parameter("runout", 0.0, 50e-6), Parameter("zeta", 0.005, 0.5),
              Parameter("phase", 0.0, 6.3, periodic=True), Parameter("a0", 0.01, 0.9))
    names = {"runout", "zeta", "phase"}

    def error(x):  # falls towards the runout's top; nearly flat in zeta; a0 pressed too
        return 1.0 - 1e4 * x[0] + 1e-4 * x[1] + 0.3 * x[3]

    at = np.array([50e-6, 0.005, 0.0, 0.01])
    assert pressed_bounds(params, at, error, names) == ["runout"]
    assert pressed_bounds(params, at, error, names | {"a0"}) == ["runout", "a0"]
    assert pressed_bounds(params, np.array([25e-6, 0.005, 6.3, 0.5]), error, names) == []

    def steep(x):  # the error falls towards the damping's lower bound
        return 1.0 + 2.0 * x[1]

    assert pressed_bounds(params, at, steep, names) == ["zeta"]
    zero = (Parameter("runout", 0.0, 50e-6),)
    assert pressed_bounds(zero, np.array([0.0]), lambda x: 1.0 + 1e4 * x[0], {"runout"}) == []
    tooth = (Parameter("tooth", 0.5, 13.5, step=1.0),)
    assert pressed_bounds(tooth, np.array([13.5]), lambda x: 2.0 - x[0], {"tooth"}) == []


def test_an_effect_that_predicts_the_other_half_worse_is_not_confident():
    """z, the share explained and the bounds all pass; the held-out error rises: "worse
    held out", not confident, and the sentence gives both errors."""
    better = HeldOut("wave", 11.4, 2.3, 0.51, 0.699, 0.690, {})
    worse = HeldOut("wave", 11.4, 2.3, 0.51, 0.699, 0.721, {})
    assert better.confirmed and better.status is Status.CONFIRMED
    assert not worse.confirmed and worse.status is Status.WORSE
    assert "0.699 -> 0.721" in worse.message
    assert worse.to_dict()["status"] == "worse held out"


def test_an_envelope_spectrum_is_the_modulus_of_an_analytic_signal_linear_in_the_record():
    """What a fit of a model affine in its parameters combines (``analytic``) gives the
    featurizer's envelope spectrum (``of_analytic``), and is linear: two records' analytic
    signals add to their sum's."""
    kin = GearKinematics(14, 21, 25.0)
    rate = 20_000.0
    n = int(np.ceil(8 * kin.period_s * rate))
    t = np.arange(n) / rate
    rng = np.random.default_rng(5)
    strikes = np.sin(2 * np.pi * 3000 * t) * (1 + np.cos(2 * np.pi * 87.0 * t))
    x, other = strikes + rng.normal(0, 0.3, n), rng.normal(0, 1, n)
    for half in (None, 0):
        f = FullSpectrumFeaturizer(kin, 4, 500.0, half=half, envelope_band_hz=(2000.0, 4000.0))
        z = f.analytic(x, rate)
        assert f.of_analytic(z, rate).amplitude == pytest.approx(f(x, rate).amplitude,
                                                                 rel=1e-9, abs=1e-12)
        assert f.analytic(x + 2 * other, rate) == pytest.approx(
            z + 2 * f.analytic(other, rate), abs=1e-9)
    assert FullSpectrumFeaturizer(kin, 4, 500.0).analytic(x, rate) is None
