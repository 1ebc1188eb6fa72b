"""A gear's own sidebands: around the harmonics of its mesh that are none of the other
gear's on its shaft."""

import numpy as np

from pydiag.gear.gear_sidebands import SIDEBANDS, own_sidebands


def test_a_gear_whose_mesh_harmonics_are_all_the_other_gears_has_none_of_its_own():
    """The PHM 2009 spur idler: 96 teeth (stage 1's gear) and 48 (stage 2's pinion):
    every 96-tooth harmonic is a 48-tooth one; the 48's odd harmonics are its own."""
    kept = np.ones(500, dtype=bool)
    assert not own_sidebands(96, 48, kept).any()
    own = np.flatnonzero(own_sidebands(48, 96, kept))
    assert list(own[:2 * SIDEBANDS]) == [46, 47, 49, 50]
    assert not own_sidebands(48, 96, kept)[94:99].any()  # 96's, shared
    assert list(own[2 * SIDEBANDS:4 * SIDEBANDS]) == [142, 143, 145, 146]


def test_the_harmonic_itself_the_other_meshes_sidebands_and_orders_not_kept_are_left_out():
    kept = np.ones(200, dtype=bool)
    kept[1::2] = False  # a faster shaft's lines: every other order
    own = own_sidebands(20, 24, kept)
    assert not own[[20, 40, 60]].any()  # the harmonics
    assert not own[[22, 46, 70, 98]].any()  # within two of 24, 48, 72, 96
    assert list(np.flatnonzero(own[:50])) == [18, 38, 42]
