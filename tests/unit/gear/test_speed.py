"""Speed from a record with a known drift (mesh lines, and a tacho), and order tracking.

The records are written here from the phase of a drifting shaft (not by our model): mesh
harmonics, a once-per-turn modulation, white noise, and a tacho pulse train.
"""

import numpy as np
import pytest

from pydiag.core.errors import MeasurementError
from pydiag.core.measurement import Measurement
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.speed import SpeedSettings, estimate_speed
from pydiag.gear.tracking import order_track
from pydiag.signal.angle import angular_resample
from pydiag.signal.spectra import sync_spectrum

FS, DURATION = 20_000.0, 8.0
NP, NG = 19, 47
START_HZ, DRIFT = 24.7, 0.01  # the speed ramps from 24.7 Hz up by 1 % over the record


def drifting_record(noise=0.5, seed=1, ppr=1):
    n = int(FS * DURATION)
    t = np.arange(n) / FS
    speed = START_HZ * (1 + DRIFT * t / DURATION)
    revs = np.cumsum(speed) / FS
    rng = np.random.default_rng(seed)
    mesh = sum(np.cos(2 * np.pi * h * NP * revs + h) / h for h in range(1, 4))
    acc = mesh * (1 + 0.3 * np.cos(2 * np.pi * revs)) + noise * rng.standard_normal(n)
    tacho = (np.mod(revs * ppr, 1.0) < 0.2).astype(float)
    mean_hz = (revs[-1] - revs[0]) / (t[-1] - t[0])
    return Measurement({"acc": acc, "tacho": tacho}, FS), mean_hz


def mesh_amplitude(m: Measurement, speed_hz: float) -> float:
    kin = GearKinematics(NP, NG, speed_hz)
    spec = sync_spectrum(m.channels["acc"], m.sample_rate_hz, kin.period_s)
    return float(spec.amplitude[np.argmin(np.abs(spec.freq_hz - kin.f_mesh_hz))])


@pytest.mark.parametrize("settings", [SpeedSettings("mesh"), SpeedSettings("auto", tacho="tacho"),
                                      SpeedSettings("tacho", tacho="tacho", pulses_per_rev=3)])
def test_drifting_speed_is_found_far_below_a_bin_and_tracking_restores_the_mesh_line(settings):
    m, mean_hz = drifting_record(ppr=settings.pulses_per_rev)
    nominal = GearKinematics(NP, NG, 25.0)  # 1.2 % above the truth's mean
    found = estimate_speed(m, nominal, settings)
    bin_hz = 1 / DURATION / NP  # one FFT bin at the mesh, in pinion speed
    assert abs(found.speed_hz - mean_hz) < 0.01 * bin_hz, (found.speed_hz, mean_hz)
    assert found.method == ("tacho" if settings.tacho else "mesh harmonic 1")
    assert 0.5 < found.variation_pct < 1.1  # a 1 % ramp, seen over blocks of 10 turns
    tracked = order_track(m, found, drop=("tacho",))
    assert list(tracked.channels) == ["acc"]
    samples_per_rev = tracked.metadata["order_tracking"]["samples_per_rev"]
    assert tracked.sample_rate_hz == pytest.approx(samples_per_rev * found.speed_hz)
    assert tracked.sample_rate_hz >= FS
    # the mesh line (amplitude 1) is whole after tracking, smeared by the drift before
    assert abs(mesh_amplitude(tracked, found.speed_hz) - 1.0) < 0.01
    assert mesh_amplitude(m, found.speed_hz) < 0.5


def test_nominal_method_keeps_the_record():
    m, _ = drifting_record()
    found = estimate_speed(m, GearKinematics(NP, NG, 25.0), SpeedSettings("nominal"))
    assert (found.speed_hz, found.variation_pct, found.method) == (25.0, 0.0, "nominal")
    kept = order_track(m, found, drop=("tacho",))
    assert kept.sample_rate_hz == FS and kept.channels["acc"] is m.channels["acc"]


def test_a_record_without_mesh_lines_is_refused():
    rng = np.random.default_rng(0)
    m = Measurement({"acc": rng.standard_normal(int(FS * 4))}, FS)
    with pytest.raises(MeasurementError, match="no mesh line stands out.*--tacho"):
        estimate_speed(m, GearKinematics(NP, NG, 25.0), SpeedSettings("mesh"))


def test_a_record_sampled_below_the_mesh_search_is_refused_with_the_rate_it_needs():
    """A 32-tooth mesh at 960 Hz sampled at 2 kHz: under Nyquist, but the search reaches
    973.5 Hz and keeps to 0.45 of the rate (the message said the mesh was above Nyquist)."""
    m = Measurement({"acc": np.random.default_rng(0).standard_normal(8000)}, 2000.0)
    with pytest.raises(MeasurementError, match="up to 973.5 Hz, needs a sample rate above "
                       "2163 Hz; the record's is 2000 Hz"):
        estimate_speed(m, GearKinematics(32, 80, 30.0), SpeedSettings("mesh"))


def test_a_sideband_comb_is_not_taken_for_the_mesh():
    """A strong faulty-tooth modulation puts lines at h f_mesh - h f_pinion; a search wider
    than half a pinion order at the mesh finds that comb at a lower speed (it did)."""
    n = int(FS * 4)
    revs = np.arange(n) / FS * 25.0
    tooth = np.exp(-0.5 * ((np.mod(revs, 1.0) - 0.5) / 0.02) ** 2)  # one tooth per turn
    acc = sum(np.cos(2 * np.pi * h * NP * revs) for h in range(1, 4)) * (0.2 + 3 * tooth)
    found = estimate_speed(Measurement({"acc": acc}, FS), GearKinematics(NP, NG, 25.5),
                           SpeedSettings("mesh"))
    assert found.speed_hz == pytest.approx(25.0, rel=1e-6)


def test_tacho_with_missing_pulses_is_refused():
    m, _ = drifting_record()
    pulses = m.channels["tacho"].copy()
    starts = np.flatnonzero(np.diff(pulses) > 0)
    pulses[starts[10]:starts[10] + 200] = 0.0  # one pulse lost
    m.channels["tacho"] = pulses
    with pytest.raises(MeasurementError, match="misses pulses"):
        estimate_speed(m, GearKinematics(NP, NG, 25.0), SpeedSettings("tacho", tacho="tacho"))


@pytest.mark.parametrize("cycles_per_sample", [0.05, 0.2, 0.4])
def test_angular_resampling_keeps_tone_amplitudes(cycles_per_sample):
    """The resampler's claim (signal/angle.py): < 0.1 % amplitude error up to 0.4 fs."""
    n = 40_000
    revs = np.arange(n) / 97.3 + 1e-3 * np.sin(np.arange(n) / 5000)  # 97.3 samples a turn, wobbling
    order = round(cycles_per_sample * 97.3)  # a whole order: one bin of 300 turns
    x = np.cos(2 * np.pi * order * revs)  # a tone locked to the angle
    (y,) = angular_resample([x], revs, 98, 1.0, 300)
    k = np.arange(y.size)
    amp = 2 * abs(np.sum(y * np.exp(-2j * np.pi * order * k / 98))) / y.size
    assert abs(amp - 1.0) < 1e-3


def swinging_record(swing: float, cycles: int = 1, seed: int = 0):
    """30 s of a 32-tooth mesh whose speed swings by +-``swing`` around 29.9 Hz, ``cycles``
    times, with a once-per-turn tacho."""
    fs, duration, mean_hz = 12_800.0, 30.0, 29.9
    t = np.arange(int(fs * duration)) / fs
    revs = np.cumsum(mean_hz * (1 + swing * np.sin(2 * np.pi * cycles * t / duration))) / fs
    mesh = sum(np.cos(2 * np.pi * h * 32 * revs + h) / h for h in range(1, 5))
    rng = np.random.default_rng(seed)
    tacho = (np.mod(revs, 1.0) < 0.2).astype(float)
    return Measurement({"a1": mesh + rng.standard_normal(t.size), "tacho": tacho}, fs), mean_hz


def test_a_speed_that_swings_once_over_the_record_is_found_at_its_mean_not_at_an_end():
    """A mesh line whose frequency swings +-0.4 % once over the record peaks near the ends
    of its swing, where it dwells longest; the demodulation is centred on the line's
    power centroid, its mean frequency (a band centred on the peak lost the far end of the
    swing: 0.25 % off)."""
    m, mean_hz = swinging_record(0.004)
    found = estimate_speed(m, GearKinematics(32, 80, 30.0), SpeedSettings("mesh", "a1"))
    assert found.speed_hz == pytest.approx(mean_hz, rel=1e-4)
    assert found.variation_pct == pytest.approx(0.8, abs=0.05)


def test_a_swing_near_the_edge_of_the_demodulation_band_is_said():
    """32/80 teeth: the mesh phase is followed within +-0.625 % (half the gear's speed); a
    swing of +-0.55 % leaves it and the speed comes out off: a warning says so, and the
    tacho is not blamed for the mesh's miss. A swing of +-0.2 % is followed exactly."""
    kin = GearKinematics(32, 80, 30.0)
    calm, mean_hz = swinging_record(0.002)
    found = estimate_speed(calm, kin, SpeedSettings("mesh", "a1"))
    assert found.speed_hz == pytest.approx(mean_hz, rel=1e-5) and found.warning() is None
    assert found.band_pct == pytest.approx(100 * 0.5 * 32 / 80 / 32)
    wide, _ = swinging_record(0.0055)
    off = estimate_speed(wide, kin, SpeedSettings("mesh", "a1"))
    assert abs(off.speed_hz / mean_hz - 1) > 5e-4  # the miss the warning is for
    assert "near the +-0.625 % the mesh line's phase is followed in" in off.warning()
    tacho = estimate_speed(wide, kin, SpeedSettings("auto", "a1", tacho="tacho"))
    assert tacho.speed_hz == pytest.approx(mean_hz, rel=1e-4)
    assert abs(tacho.tacho_disagreement_pct) > 0.1 and tacho.warning() is None
