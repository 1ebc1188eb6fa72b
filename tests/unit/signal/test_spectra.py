"""Synchronous spectra, noise floors and synthetic noise, on synthetic signals."""

import numpy as np
import pytest

from pydiag.core.errors import MeasurementError, UsageError
from pydiag.gear.kinematics import GearKinematics
from pydiag.signal.noise import add_white_noise
from pydiag.signal.spectra import (amplitude_spectrum, band_envelope, local_maxima, noise_power,
                                    sync_spectrum, whole_periods, without_synchronous)

KIN = GearKinematics(14, 21, 25.0)  # mesh 350 Hz, fundamental period 0.12 s
FS = 10_000.0


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












@pytest.mark.parametrize("window", ["boxcar", "hann"])
def test_amplitude_spectrum_reads_a_tone_on_a_bin(window):
    n, fs = 4000, 1000.0
    t = np.arange(n) / fs
    freqs, amp = amplitude_spectrum(2.5 * np.sin(2 * np.pi * 50.0 * t) + 4.0, fs, window)
    assert freqs[np.argmax(amp)] == 50.0
    assert amp.max() == pytest.approx(2.5, rel=1e-6)  # Hann: symmetric window, gain divided out
    assert amp[0] < 1e-6 * 4.0  # mean removed
    with pytest.raises(ValueError, match="window"):
        amplitude_spectrum(t, fs, "flattop")


def test_noise_power_mean_and_robust_estimates():
    rng = np.random.default_rng(4)
    noise = np.abs(rng.normal(size=20_000) + 1j * rng.normal(size=20_000))  # E|z|^2 = 2
    assert noise_power(noise) == pytest.approx(2.0, rel=0.03)
    assert noise_power(noise, robust=True) == pytest.approx(2.0, rel=0.03)
    spiked = np.concatenate([noise, np.full(50, 100.0)])  # a few non-synchronous lines
    assert noise_power(spiked) > 1.2 * 2.0
    assert noise_power(spiked, robust=True) == pytest.approx(2.0, rel=0.04)
    assert noise_power(noise[:5], min_bins=9) == 0.0 and noise_power(np.array([])) == 0.0


def test_local_maxima_include_edges_and_plateaus():
    v = np.array([3.0, 1.0, 2.0, 2.0, 0.5, 4.0])
    assert local_maxima(v).tolist() == [True, False, True, True, False, True]


def test_a_period_that_is_not_whole_samples_is_still_one_period_and_reads_exactly():
    """A 33.333333 Hz shaft at 25.6 kHz: a 0.06 s record rounds to 1536 samples, a hair
    short of 0.06 s; it was judged shorter than one period, and every particle failed."""
    from pydiag.signal.spectra import sync_spectrum
    fs, period = 25_600.0, 2 / 33.333333
    n = int(round(period * fs))
    assert n < period * fs  # the record is a fraction of a sample short
    t = np.arange(n) / fs
    spec = sync_spectrum(np.cos(2 * np.pi * 5 / period * t), fs, period)
    assert spec.n_periods == 1
    assert spec.amplitude[5] == pytest.approx(1.0, abs=2e-3)
    long = np.arange(int(37.5 * period * fs)) / fs  # 37 whole periods and a half
    spec = sync_spectrum(0.5 * np.cos(2 * np.pi * 12 / period * long), fs, period)
    assert spec.n_periods == 37 and spec.amplitude[12] == pytest.approx(0.5, rel=1e-3)
    assert np.max(np.delete(spec.amplitude, 12)) < 1e-3


def test_band_envelope_beats_at_the_strike_rate_of_a_ringing_mode():
    """Strikes at 89.6 Hz ring a 3 kHz mode: the spectrum has no line at 89.6 Hz, the
    envelope of the band around the mode has it; the band must fit under Nyquist."""
    t = np.arange(int(FS * 2.0)) / FS
    since = np.mod(t, 1 / 89.6)
    x = np.exp(-900.0 * since) * np.sin(2 * np.pi * 3000.0 * since)
    freqs, amp = amplitude_spectrum(x, FS, "hann")
    env_freqs, env = amplitude_spectrum(band_envelope(x, FS, (1575.0, 4500.0)), FS, "hann")
    line = np.argmin(np.abs(freqs - 89.6))
    assert env[line] > 10 * amp[line]  # 20 dB
    assert env[line] == pytest.approx(env[(env_freqs > 50) & (env_freqs < 1000)].max())
    with pytest.raises(ValueError, match="band"):
        band_envelope(x, FS, (1575.0, 6000.0))


def test_without_synchronous_keeps_what_does_not_repeat_every_period():
    """A gear's lines (every harmonic of the period) go; a bearing's line between them
    stays, at its amplitude."""
    periods, n_per = 8, 1200
    t = np.arange(periods * n_per) / FS  # 8 periods of 0.12 s
    gear = 3.0 * np.cos(2 * np.pi * t / 0.12 * 42) + np.cos(2 * np.pi * t / 0.12 * 5) + 0.7
    bearing = 0.5 * np.cos(2 * np.pi * 89.62 * t)
    left = without_synchronous(gear + bearing, periods)
    assert np.max(np.abs(without_synchronous(gear, periods))) < 1e-9
    freqs, amp = amplitude_spectrum(left, FS)
    line = np.argmin(np.abs(freqs - 89.62))
    assert np.max(amp[line - 2:line + 3]) == pytest.approx(
        np.max(amplitude_spectrum(bearing, FS)[1][line - 2:line + 3]), rel=0.05)
