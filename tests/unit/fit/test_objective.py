"""The weighted spectral error of Eq. (12), its noise awareness and noise correction."""

import numpy as np
import pytest

from pydiag.fit.objective import spectral_error


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


def test_a_floor_that_is_not_flat_is_one_noise_power_per_bin():
    """A real spectrum's floor rises at a resonance: per-bin noise powers give what each
    bin's own scalar gives, and a flat per-bin floor gives the scalar's error exactly; a
    model right on bins of a 10x floor is judged by that floor, not the flat one."""
    from pydiag.fit.objective import noise_corrected_error, rician_mean
    rng = np.random.default_rng(5)
    a = np.array([0.0, 0.3, 1.0, 5.0])
    p = np.array([0.0, 0.01, 0.04, 1.0])
    assert np.allclose(rician_mean(a, p), [rician_mean(a[i:i + 1], p[i])[0] for i in range(4)])
    s = np.concatenate([np.linspace(0.2, 3, 40), np.zeros(400)])
    floor = np.full(s.size, 0.04)
    floor[200:] = 0.4  # the upper half of the bins sits on a resonance's floor
    n = rng.normal(0, np.sqrt(floor / 2)[:, None], (s.size, 2)) @ np.array([1, 1j])
    measured = np.abs(s + n)
    assert noise_corrected_error(s, measured, np.full(s.size, 0.04)) == \
        noise_corrected_error(s, measured, 0.04)
    assert spectral_error(s, measured, np.full(s.size, 0.04)) == spectral_error(s, measured, 0.04)
    assert noise_corrected_error(s, measured, floor) < 0.2 < 0.4 < noise_corrected_error(
        s, measured, 0.04)
