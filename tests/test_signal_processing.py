"""Kinematics, synchronous spectra, features, Eq. (12) and noise: on synthetic signals."""

import numpy as np
import pytest

from pydiag.core.errors import MeasurementError, UsageError

from pydiag.gear.features import features_from_spectrum, paper_bands, signal_features
from pydiag.gear.kinematics import GearKinematics
from pydiag.signal.noise import add_white_noise
from pydiag.fit.objective import spectral_error
from pydiag.signal.spectra import sync_spectrum, whole_periods

KIN = GearKinematics(14, 21, 25.0)
FS = 10_000.0


def test_kinematics_of_the_default_gear():
    assert KIN.f_mesh_hz == 350.0
    assert KIN.n_assembly_phases == 3  # lcm(14, 21) / 14
    assert KIN.f_assembly_hz == pytest.approx(350.0 / 3)
    assert KIN.f_gear_hz == pytest.approx(350.0 / 21)
    assert KIN.period_s == pytest.approx(0.12)  # 3 pinion turns = 2 gear turns
    hunting = GearKinematics(14, 29, 25.0)  # coprime: every pair meets once per 29 turns
    assert hunting.n_assembly_phases == 29 and hunting.period_s == pytest.approx(29 / 25)
    with pytest.raises(UsageError, match="teeth counts"):
        GearKinematics(0, 21, 25.0)


def test_sync_spectrum_reads_exact_line_amplitudes():
    t = np.arange(int(5 * KIN.period_s * FS)) / FS
    x = 3.0 * np.sin(2 * np.pi * 350 * t + 0.3) + 0.5 * np.cos(2 * np.pi * 25 * t) + 7.0
    spec = sync_spectrum(x, FS, KIN.period_s, max_freq_hz=2000)
    assert spec.n_periods == 5
    amp = dict(zip(np.round(spec.freq_hz, 6), spec.amplitude))
    assert amp[350.0] == pytest.approx(3.0, rel=1e-9)
    assert amp[25.0] == pytest.approx(0.5, rel=1e-9)
    assert amp[0.0] == 0.0  # the mean is not a line
    others = [a for f, a in amp.items() if f not in (350.0, 25.0)]
    assert max(others) < 1e-9
    assert spec.noise_power < 1e-20


def test_sync_spectrum_cuts_to_whole_periods_and_rejects_short_records():
    n = int(2.5 * KIN.period_s * FS)
    assert whole_periods(n, FS, KIN.period_s) == (2, 2400)
    with pytest.raises(MeasurementError, match="shorter than one fundamental period"):
        sync_spectrum(np.zeros(100), FS, KIN.period_s)


def test_sync_spectrum_off_grid_period_uses_exact_frequencies():
    fs = 9_999.0  # a period is not a whole number of samples
    t = np.arange(int(20 * KIN.period_s * fs)) / fs
    spec = sync_spectrum(2.0 * np.sin(2 * np.pi * 700 * t), fs, KIN.period_s, 1000)
    assert spec.amplitude[np.argmin(abs(spec.freq_hz - 700))] == pytest.approx(2.0, rel=2e-3)


def test_noise_floor_matches_white_noise_power():
    rng = np.random.default_rng(0)
    sigma = 0.7
    x = rng.normal(0, sigma, int(20 * KIN.period_s * FS))
    spec = sync_spectrum(x, FS, KIN.period_s)
    # a bin of white noise: E|2X/N|^2 = 4 sigma^2 / N
    assert spec.noise_power == pytest.approx(4 * sigma ** 2 / x.size, rel=0.05)


def test_snr_is_a_power_ratio():
    rng = np.random.default_rng(1)
    t = np.arange(200_000) / FS
    clean = 2.0 * np.sin(2 * np.pi * 350 * t)
    noisy = add_white_noise(clean, 10.0, rng)
    assert np.var(clean) / np.var(noisy - clean) == pytest.approx(10.0, rel=0.02)
    with pytest.raises(UsageError, match="SNR must be positive"):
        add_white_noise(clean, 0.0, rng)


def test_bands_follow_kinematics():
    bands = {b.name: b for b in paper_bands(KIN)}
    assert len(bands) == 10
    assert (bands["mesh1"].low_hz, bands["mesh1"].high_hz) == (175.0, 525.0)
    assert bands["mesh4"].high_hz == 4.5 * 350
    assert bands["shaft3"].low_hz < 75 < bands["shaft3"].high_hz
    assert bands["assembly"].low_hz < 350 / 3 < bands["assembly"].high_hz
    faster = {b.name: b for b in paper_bands(GearKinematics(14, 21, 50.0))}
    assert faster["mesh2"].low_hz == 2 * bands["mesh2"].low_hz


def test_paper_features_are_band_maxima_and_lines_keep_sidebands():
    t = np.arange(int(KIN.period_s * FS)) / FS
    x = np.sin(2 * np.pi * 350 * t) + 0.2 * np.sin(2 * np.pi * 375 * t)  # mesh + sideband
    paper = signal_features(x, FS, KIN, "paper")
    lines = signal_features(x, FS, KIN, "lines")
    assert paper.amplitude.size == 10
    assert paper.amplitude[0] == pytest.approx(1.0) and paper.freq_hz[0] == pytest.approx(350)
    assert 375.0 in np.round(lines.freq_hz, 6)
    assert lines.amplitude[np.argmin(abs(lines.freq_hz - 375))] == pytest.approx(0.2)
    with pytest.raises(UsageError, match="feature mode"):
        features_from_spectrum(sync_spectrum(x, FS, KIN.period_s), KIN, "bogus")


def test_spectral_error_eq12():
    r = np.array([1.0, 0.5, 0.1])
    assert spectral_error(r, r) == 0.0
    s = np.array([1.0, 0.5, 0.2])
    # weight (0.2/1 + 1)^2 on the only differing line; normalised by |r|
    expected = np.sqrt((0.2 + 1) ** 2 * 0.1 ** 2) / np.sqrt(np.sum(r ** 2))
    assert spectral_error(s, r) == pytest.approx(expected)
    with pytest.raises(ValueError, match="shapes differ"):
        spectral_error(s, r[:2])


def test_noise_aware_error_prefers_the_true_line_over_the_noise_floor():
    """A zero line measured in noise reads about sqrt(P); the noise-aware error is lowest
    for the true (zero) model line, the plain Eq. (12) prefers a fake line at the floor."""
    p = 0.01
    measured = np.array([1.0, np.sqrt(p)])
    true_model, fake_model = np.array([1.0, 0.0]), np.array([1.0, np.sqrt(p)])
    assert spectral_error(true_model, measured, p) < spectral_error(fake_model, measured, p)
    assert spectral_error(fake_model, measured) < spectral_error(true_model, measured)


def test_rician_mean_and_noise_corrected_error():
    from pydiag.fit.objective import noise_corrected_error, rician_mean
    rng = np.random.default_rng(4)
    p = 0.04
    for a in (0.0, 0.1, 1.0, 30.0):  # from pure noise to a line far above it
        n = rng.normal(0, np.sqrt(p / 2), (200_000, 2)) @ np.array([1, 1j])
        assert rician_mean(np.array([a]), p)[0] == pytest.approx(np.mean(np.abs(a + n)), rel=5e-3)
    # over many noise draws: a perfect model's corrected error is ~0 while the raw one is
    # not, and for a model that misses a line (2.3, ten noise sigmas) it estimates the
    # noise-free error
    s = np.concatenate([np.linspace(0.2, 3, 40), np.zeros(400)])
    wrong = s.copy()
    wrong[30] = 0.0
    raw, perfect, missing = [], [], []
    for _ in range(20):
        n = rng.normal(0, np.sqrt(p / 2), (s.size, 2)) @ np.array([1, 1j])
        measured = np.abs(s + n)
        raw.append(spectral_error(s, measured, p))
        perfect.append(noise_corrected_error(s, measured, p))
        missing.append(noise_corrected_error(wrong, measured, p))
    assert np.mean(raw) > 0.15 and np.mean(perfect) < 0.25 * np.mean(raw)
    assert np.mean(missing) == pytest.approx(spectral_error(wrong, s), rel=0.1)
