"""Condition indicators against their definitions, on signals whose values are known."""

import numpy as np
import pytest

from pydiag.signal.condition import (TrendReference, normalized_moment, raw_indicators,
                                     synchronous_average, tsa_indicators, tsa_signals)

N = 512  # samples per revolution
TEETH = 32
ANGLE = np.arange(N) / N


def mesh_tone(amplitude: float = 1.0) -> np.ndarray:
    return amplitude * np.cos(2 * np.pi * TEETH * ANGLE)


def record(revolution: np.ndarray, n_revs: int, noise: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.tile(revolution, n_revs) + rng.normal(0, noise, n_revs * N)


def test_a_pure_mesh_tone():
    x = mesh_tone(2.5)
    raw = raw_indicators(np.tile(x, 10))
    assert raw["kurtosis"] == pytest.approx(1.5, rel=1e-9)
    assert raw["crest_factor"] == pytest.approx(np.sqrt(2), rel=1e-9)
    assert raw["rms"] == pytest.approx(2.5 / np.sqrt(2), rel=1e-9)
    ind = tsa_indicators(tsa_signals(x, TEETH))
    assert ind["fm0"] == pytest.approx(2.0, rel=1e-9)  # peak-to-peak 2A over the line A
    # nothing but the mesh: no difference signal, no envelope variation, no sidebands
    assert np.isnan(ind["fm4"]) and np.isnan(ind["nb4"])
    assert ind["er"] < 1e-12 and ind["ser"] < 1e-12


def test_tones_in_gaussian_noise_have_the_gaussian_moments():
    """The difference signal is the averaged noise: FM4 near 3, M6A near 15, M8A near 105."""
    values = {k: [] for k in ("fm4", "na4", "m6a", "m8a")}
    revolution = mesh_tone() + 0.3 * np.sin(2 * np.pi * 2 * TEETH * ANGLE)
    for seed in range(30):
        tsa = synchronous_average(record(revolution, 100, 1.0, seed), N)
        ind = tsa_indicators(tsa_signals(tsa, TEETH))
        for k in values:
            values[k].append(ind[k])
    assert np.mean(values["fm4"]) == pytest.approx(3.0, abs=0.15)
    assert np.mean(values["na4"]) == pytest.approx(3.0, abs=0.15)
    assert np.mean(values["m6a"]) == pytest.approx(15.0, rel=0.15)
    assert np.mean(values["m8a"]) == pytest.approx(105.0, rel=0.3)


def test_one_weak_tooth_per_revolution_raises_fm4_and_the_sidebands():
    healthy = mesh_tone()
    weak = healthy.copy()
    tooth = slice(5 * N // TEETH, 6 * N // TEETH)
    weak[tooth] *= 0.5  # one tooth meshes with half the amplitude
    fm4, ser, er = [], [], []
    for revolution in (healthy, weak):
        tsa = synchronous_average(record(revolution, 100, 0.5, 1), N)
        ind = tsa_indicators(tsa_signals(tsa, TEETH))
        fm4.append(ind["fm4"])
        ser.append(ind["ser"])
        er.append(ind["er"])
    assert fm4[0] == pytest.approx(3.0, abs=0.6)
    assert fm4[1] > 5.0, fm4
    # the weak tooth's sidebands (about 0.5/32 each) against the averaged noise's
    assert ser[1] > 3 * ser[0] and er[1] > 1.3 * er[0], (ser, er)


def test_the_signals_split_the_spectrum_as_defined():
    """Shaft orders 1-2, mesh harmonics, first sidebands and other orders, each put on one
    order, land where the definitions say."""
    parts = {1: 0.7, 2: 0.2, TEETH: 1.0, 2 * TEETH: 0.4, TEETH - 1: 0.3, TEETH + 1: 0.25,
             TEETH + 3: 0.1, 7: 0.05}
    tsa = sum(a * np.cos(2 * np.pi * k * ANGLE) for k, a in parts.items())
    s = tsa_signals(tsa, TEETH)

    def amplitudes(x):
        return np.round(2 * np.abs(np.fft.rfft(x)) / N, 9)

    regular, difference, residual = (amplitudes(x) for x in (s.regular, s.difference, s.residual))
    for k, a in parts.items():
        in_regular = k in (1, 2, TEETH, 2 * TEETH, TEETH - 1, TEETH + 1)
        assert regular[k] == pytest.approx(a if in_regular else 0.0)
        assert difference[k] == pytest.approx(0.0 if in_regular else a)
        assert residual[k] == pytest.approx(0.0 if k in (1, 2, TEETH, 2 * TEETH) else a)
    np.testing.assert_allclose(s.regular + s.difference, s.tsa, atol=1e-12)
    ser = (0.3 + 0.25 + 0.1) / 1.0
    assert tsa_indicators(s)["ser"] == pytest.approx(ser)


def test_na4_against_a_baseline_is_the_fourth_moment_over_the_baseline_variance():
    rng = np.random.default_rng(5)
    base = tsa_signals(mesh_tone() + 0.1 * rng.normal(size=N), TEETH)
    worse = tsa_signals(mesh_tone() + 0.3 * rng.normal(size=N), TEETH)
    own = tsa_indicators(worse)
    trended = tsa_indicators(worse, TrendReference.of(base))
    assert own["na4"] == pytest.approx(normalized_moment(worse.residual, 4))
    ratio = np.var(worse.residual) / np.var(base.residual)
    assert trended["na4"] == pytest.approx(own["na4"] * ratio ** 2)
    assert trended["na4"] > 20 * own["na4"]  # three times the noise: nine times the variance


def test_a_tsa_needs_a_whole_revolution():
    with pytest.raises(ValueError, match="hold no revolution"):
        synchronous_average(np.zeros(N - 1), N)


def test_a_faster_shafts_lines_are_left_out_of_the_residual_and_difference():
    # a shaft turning 3 times a turn of this one: orders 3, 6, 9, ... are its lines
    parts = {6: 0.5, 7: 0.2, TEETH + 3: 0.1, 11: 0.3}
    tsa = sum(a * np.cos(2 * np.pi * k * ANGLE) for k, a in parts.items())
    s = tsa_signals(tsa, TEETH, faster_shafts=(3,))
    residual, difference = (np.round(2 * np.abs(np.fft.rfft(x)) / N, 9)
                            for x in (s.residual, s.difference))
    for k, a in parts.items():
        assert residual[k] == pytest.approx(0.0 if k % 3 == 0 else a)
        assert difference[k] == pytest.approx(0.0 if k % 3 == 0 else a)
    with pytest.raises(ValueError, match="whole number"):
        tsa_signals(tsa, TEETH, faster_shafts=(1,))
