"""Gear kinematics, the paper's bands and the feature vector, on synthetic signals."""

import numpy as np
import pytest

from pydiag.core.errors import UsageError
from pydiag.gear.features import features_from_spectrum, paper_bands, signal_features
from pydiag.gear.kinematics import GearKinematics
from pydiag.signal.spectra import sync_spectrum

KIN = GearKinematics(14, 21, 25.0)
FS = 10_000.0


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
