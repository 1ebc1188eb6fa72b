"""GearDiag.Effects.PinionShaftOrders: the pinion shaft's own lines at the sensor."""

import numpy as np
import pytest
from conftest import ROOT

from fmu_build import build_fmu
from pydiag.fmu.plant import FmuPlant

F_PINION_HZ = 25.0  # GearPair's default
RATE_HZ = 10_000.0


@pytest.fixture(scope="module")
def shaft_fmu(tmp_path_factory):
    return build_fmu(ROOT / "modelica/GearDiag/Effects/PinionShaftOrders.mo",
                     "GearDiag.Effects.PinionShaftOrders",
                     tmp_path_factory.mktemp("shaft") / "PinionShaftOrders.fmu")


def lines(fmu, values):
    """acc and disp amplitude spectra over 1.2 s (30 pinion turns, 0.8 Hz bins)."""
    with FmuPlant(str(fmu), ("acc", "disp"), sample_rate_hz=RATE_HZ) as plant:
        y = plant.simulate(values, 1.2, 0.1)
    n = y.shape[1]
    return np.fft.rfftfreq(n, 1 / RATE_HZ), 2 * np.abs(np.fft.rfft(y, axis=1)) / n


def test_each_order_adds_its_line_to_acc_and_nothing_to_disp(shaft_fmu):
    freqs, off = lines(shaft_fmu, {})
    _, on = lines(shaft_fmu, {"A_s3": 40.0, "A_s7": 15.0})
    for order, amplitude in ((3, 40.0), (7, 15.0)):
        k = int(np.argmin(np.abs(freqs - order * F_PINION_HZ)))
        assert on[0, k] - off[0, k] == pytest.approx(amplitude, rel=0.02)
    others = [int(np.argmin(np.abs(freqs - o * F_PINION_HZ))) for o in (1, 2, 4, 5, 6, 8, 9, 10)]
    np.testing.assert_allclose(on[0, others], off[0, others], atol=0.05)
    np.testing.assert_allclose(on[1], off[1], rtol=1e-6, atol=1e-15)  # the mesh does not feel it
