"""GearDiag.Effects.ShaftSwing: each shaft's speed swinging once a turn modulates the mesh's
phase at that shaft's speed, as a phase modulation of index Z*s (Z: the wheel's teeth, s:
its speed's swing relative to its mean) says."""

import numpy as np
import pytest
from conftest import ROOT
from scipy.special import jv

from pydiag.fmu.plant import FmuPlant
from pydiag.loop.discover import effect_fmu

F_PINION_HZ, NP, NG = 25.0, 14, 21  # GearPair's defaults
F_MESH_HZ = NP * F_PINION_HZ
RATE_HZ = 10_000.0
# the faulty tooth as the others and no transmission error: the mesh's lines alone
HEALTHY = {"a_f": 0.1, "a0": 0.1, "f_ate": 0.0, "f_dte": 0.0}


def disp_lines(fmu, values):
    """The teeth's deflection's amplitude spectrum over 1.2 s (30 pinion turns, 20 gear
    turns: every line on a bin)."""
    with FmuPlant(str(fmu), ("disp",), sample_rate_hz=RATE_HZ) as plant:
        y = plant.simulate({**HEALTHY, **values}, 1.2, 0.1)[0]
    return np.fft.rfftfreq(len(y), 1 / RATE_HZ), 2 * np.abs(np.fft.rfft(y - y.mean())) / len(y)


@pytest.fixture(scope="module")
def swing_fmu(effects_dir):
    return effect_fmu("shaft_swing", ROOT / "modelica", effects_dir)


@pytest.mark.parametrize("shaft, swing, teeth, f_shaft_hz",
                         [("g", 0.02, NG, F_PINION_HZ * NP / NG), ("p", 0.01, NP, F_PINION_HZ)])
def test_a_swing_puts_its_shafts_sidebands_round_the_mesh_as_a_phase_modulation(
        swing_fmu, shaft, swing, teeth, f_shaft_hz):
    """Far below the mesh's resonance the deflection follows the stiffness, so its first
    sidebands over its mesh line are J1(Z s)/J0(Z s), the same either side, and the
    shaft's own order gets no line."""
    freqs, off = disp_lines(swing_fmu, {})
    _, on = disp_lines(swing_fmu, {f"s_{shaft}": swing, f"psi_{shaft}": 0.7})
    at = lambda f: int(np.argmin(np.abs(freqs - f)))  # noqa: E731
    carrier = on[at(F_MESH_HZ)]
    index = teeth * swing
    for side in (-1, 1):
        assert on[at(F_MESH_HZ + side * f_shaft_hz)] / carrier == pytest.approx(
            jv(1, index) / jv(0, index), rel=0.03)
        assert off[at(F_MESH_HZ + side * f_shaft_hz)] < 1e-3 * carrier
    assert on[at(f_shaft_hz)] < 1e-3 * carrier
    assert carrier / off[at(F_MESH_HZ)] == pytest.approx(jv(0, index), rel=0.01)
