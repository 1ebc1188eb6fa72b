"""The housing mode's signature (every line of the gear pair) and its frequency's bounds (the
band where the gear pair's unexplained lines bunch)."""

import dataclasses

import pytest

from pydiag.gear.effects import EFFECTS
from pydiag.gear.signatures import MODE_BAND, resonance_band
from pydiag.gear.features import max_band_freq_hz
from pydiag.gear.kinematic_map import KinematicLine
from pydiag.gear.kinematics import GearKinematics

KIN = GearKinematics(32, 80, 29.84)


@dataclasses.dataclass
class Peak:  # the fields of pydiag.loop.compare.Peak the signatures read
    freq_hz: float
    family: str
    energy_fraction: float


def comb(center_hz, n, energy, family="pinion"):
    """n lines a pinion order apart around ``center_hz``, ``energy`` in all."""
    f0 = round(center_hz / KIN.f_pinion_hz) - n // 2
    return [Peak((f0 + i) * KIN.f_pinion_hz, family, energy / n) for i in range(n)]


def test_the_band_is_where_the_gear_pairs_lines_bunch_not_the_strongest_line():
    # one strong line at 300 Hz, a comb of weaker pinion orders around 1.3 kHz that holds
    # more energy in all, and a strong line no gear-pair family makes at 2 kHz
    peaks = ([Peak(300.0, "mesh_sb_pinion", 0.2)] + comb(1300.0, 9, 0.5)
             + [Peak(2000.0, "gear", 0.3)])
    low, high = resonance_band(peaks)
    centre = (low + high) / 2
    assert centre == pytest.approx(1300.0, rel=0.02)
    assert high / low == pytest.approx((1 + MODE_BAND) / (1 - MODE_BAND))
    hint = EFFECTS["housing_sensor"].bounds(peaks, 0.1, KIN)
    f_housing = next(p for p in hint if p.name == "f_housing")
    assert (f_housing.low, f_housing.high) == (low, high)


def test_the_housing_claims_every_line_the_gear_pair_makes():
    """A housing mode reweights every line on its way to the sensor: its signature is all
    of the gear pair's lines, wherever the residual bunches; the band only bounds its
    frequency."""
    weight = EFFECTS["housing_sensor"].weight
    inside = KinematicLine(1290.0, "pinion", 43, "43x pinion")
    assert weight(inside, inside.freq_hz, KIN) == 1.0
    assert weight(KinematicLine(800.0, "pinion", 27, ""), 800.0, KIN) == 1.0
    assert weight(KinematicLine(KIN.f_mesh_hz, "mesh", 1, ""), KIN.f_mesh_hz, KIN) == 1.0
    # a gear order: the base gear pair does not make it, no mode reshapes it into being
    assert weight(KinematicLine(1300.0, "gear", 109, ""), 1300.0, KIN) == 0.0
    assert weight(None, 1300.0, KIN) == 0.0


def test_no_peaks_of_the_gear_pair_no_band_no_bounds():
    peaks = [Peak(2000.0, "gear", 1.0), Peak(123.4, "unexplained", 0.5)]
    assert resonance_band(peaks) is None
    assert EFFECTS["housing_sensor"].bounds(peaks, 0.1, KIN) == EFFECTS["housing_sensor"].parameters


def test_the_housing_is_polished_from_above_the_band_too():
    start = EFFECTS["housing_sensor"].free_start(max_band_freq_hz(KIN))
    assert start["f_housing"] > max_band_freq_hz(KIN)
    f_housing, zeta = EFFECTS["housing_sensor"].parameters
    assert f_housing.low < start["f_housing"] < f_housing.high
    assert zeta.low < start["zeta_housing"] < zeta.high


def test_a_bunch_at_the_top_of_the_analysed_range_leaves_the_mode_free_above_it():
    top = max_band_freq_hz(KIN)
    peaks = comb(0.97 * top, 7, 1.0)
    low, _ = resonance_band(peaks)
    f_housing = next(p for p in EFFECTS["housing_sensor"].bounds(peaks, 0.1, KIN)
                     if p.name == "f_housing")
    assert f_housing.low == low < top and f_housing.high == EFFECTS["housing_sensor"].parameters[0].high


def test_the_housing_looks_for_its_band_on_the_channels_it_changes_only():
    """A housing mode rings the acceleration, not the mesh's displacement: a bunch of disp
    lines is no band of it. Yet they are its evidence: its absence bent the base parameters
    both channels share (effect_fit.evidence_channels)."""
    from types import SimpleNamespace

    from pydiag.gear.peaks import Peak as ComparePeak
    from pydiag.loop.effect_fit import effect_peaks, evidence_channels

    def on(channel, peaks):
        return [ComparePeak(channel, p.freq_hz, 0.0, 0.0, 0.0, p.family, 1, "", p.energy_fraction)
                for p in peaks]
    peaks = on("disp", comb(600.0, 9, 0.7)) + on("acc", comb(1300.0, 5, 0.3))
    problem = SimpleNamespace(channels=("acc", "disp"), spec=SimpleNamespace(sensors=("acc", "disp")))
    housing = EFFECTS["housing_sensor"]
    own = effect_peaks(problem, housing, peaks)
    assert {p.channel for p in own} == {"acc"} and len(own) == 5
    low, high = resonance_band(own)
    assert low < 1300.0 < high  # all peaks together: the disp bunch at 600 Hz
    assert resonance_band(peaks)[0] < 600.0 < resonance_band(peaks)[1]
    assert effect_peaks(problem, EFFECTS["gear_eccentricity"], peaks) == peaks
    assert not housing.changes("disp") and housing.changes("acc")
    assert EFFECTS["gear_tooth_fault"].changes("disp")
    assert evidence_channels(problem, housing) == {"acc", "disp"}
    assert evidence_channels(problem, EFFECTS["bearing_outer_race"]) == {"acc"}
