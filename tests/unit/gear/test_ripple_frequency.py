"""The torque-ripple frequency read from the spacing of unexplained peaks."""

from types import SimpleNamespace

from pydiag.gear.signatures import ripple_frequency

F_MESH, BIN = 350.0, 1 / 2.4


def peak(freq_hz, energy, family="unexplained"):
    return SimpleNamespace(freq_hz=freq_hz, energy_fraction=energy, family=family)


def test_the_spacing_every_mesh_harmonic_repeats_beats_its_multiples():
    # a 7.3 Hz ripple moving the speed: sidebands at k x 7.3 Hz, the second ones strongest
    peaks = [peak(h * F_MESH + s * k * 7.3, e) for h in (2, 4) for s in (-1, 1)
             for k, e in ((1, 0.03), (2, 0.08), (3, 0.02))]
    assert abs(ripple_frequency(peaks, BIN, F_MESH) - 7.3) <= BIN


def test_a_lone_line_near_a_shaft_order_loses_to_the_sidebands():
    peaks = [peak(17.7, 0.2)] + [peak(h * F_MESH + s * 7.3, 0.1) for h in (1, 2, 3)
                                 for s in (-1, 1)]
    assert abs(ripple_frequency(peaks, BIN, F_MESH) - 7.3) <= BIN


def test_explained_peaks_and_far_offsets_propose_nothing():
    assert ripple_frequency([peak(357.3, 0.5, family="mesh_sb_pinion"),
                             peak(400.0, 0.5)], BIN, F_MESH) is None
