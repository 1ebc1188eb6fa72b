"""The housing transfer path applied to the base model's output is the Modelica model with
the mode inside it (GearDiag.Effects.HousingSensor), in its periodic steady state: two
implementations, one integrated with the mesh, one a product of spectra."""

import numpy as np
import pytest

from pydiag.fmu.plant import FmuPlant
from pydiag.signal.transfer import HousingMode, mode_accelerance

#: Fast enough that the mesh's lines above the band compared (10 kHz) do not alias into it:
#: the path weighs a line where it is, a sampled output where its alias is.
RATE_HZ = 200_000.0
BAND_HZ = 10_000.0
PERIOD_S = 0.12  # GearPair's fundamental period by default: 3 pinion turns at 25 Hz

FAULT = {"a_f": 0.4, "f_ate": 0.4, "f_dte": 0.4}  # a faulty tooth and errors: many lines


def spectrum(y: np.ndarray) -> np.ndarray:
    return np.abs(np.fft.rfft(y)) / y.size


@pytest.mark.parametrize("f_n_hz,zeta", [(2500.0, 0.05), (900.0, 0.02), (6000.0, 0.2)])
def test_the_housing_path_is_the_modelica_housing_mode_in_steady_state(gear_fmu, housing_fmu,
                                                                      f_n_hz, zeta):
    # a warm-up long enough for the lightest mode's transient to die (1/(zeta w_n) = 9 ms)
    warmup_s, n = 0.3, int(round(PERIOD_S * RATE_HZ))
    with FmuPlant(str(gear_fmu), ["acc"], RATE_HZ) as base:
        mesh = base.simulate(FAULT, PERIOD_S, warmup_s)[0]
    with FmuPlant(str(housing_fmu), ["acc"], RATE_HZ) as plant:
        inside = plant.simulate({**FAULT, "f_housing": f_n_hz, "zeta_housing": zeta},
                                PERIOD_S, warmup_s)[0]
    applied = HousingMode("acc").apply(mesh[:n], RATE_HZ, {"f_housing": f_n_hz,
                                                           "zeta_housing": zeta})
    a, b = spectrum(inside[:n]), spectrum(applied)
    band = np.fft.rfftfreq(n, 1 / RATE_HZ) <= BAND_HZ
    lines = band & (a > 1e-3 * a.max())  # the lines that matter, 60 dB under the strongest
    assert np.count_nonzero(lines) > 20
    np.testing.assert_allclose(b[lines], a[lines], rtol=0.02, atol=1e-4 * a.max())
    # and the path changed them: the mode weighs the lines near it, not a copy of the mesh
    assert np.max(np.abs(spectrum(mesh[:n])[lines] - a[lines])) > 0.1 * a.max()


def test_the_accelerance_is_one_far_above_the_mode_and_one_over_two_zeta_at_it():
    f = np.array([25.0, 2500.0, 250_000.0])
    h = np.abs(mode_accelerance(f, 2500.0, 0.05))
    assert h[0] == pytest.approx((25.0 / 2500.0) ** 2, rel=1e-3)
    assert h[1] == pytest.approx(1 / (2 * 0.05), rel=1e-9)
    assert h[2] == pytest.approx(1.0, rel=1e-3)


def test_a_fit_of_the_path_alone_simulates_the_model_once(gear_fmu, monkeypatch):
    """The plant gives the last run's signals again for the same values, a copy each time:
    varying only the housing costs one integration, and a caller's edit changes nothing."""
    runs = []
    with FmuPlant(str(gear_fmu), ["acc"], 10_000.0) as plant:
        integrate = plant._simulate
        monkeypatch.setattr(plant, "_simulate", lambda *a: runs.append(a) or integrate(*a))
        path = HousingMode("acc")
        outs = []
        for f_n in (800.0, 1600.0, 3200.0):
            y = plant.simulate(FAULT, PERIOD_S, 0.05)
            outs.append(path.apply(y[0], 10_000.0, {"f_housing": f_n, "zeta_housing": 0.05}))
            y[0] = 0.0  # a caller's edit
        assert len(runs) == 1
        assert not np.allclose(outs[0], outs[1]) and not np.allclose(outs[1], outs[2])
        assert np.array_equal(plant.simulate(FAULT, PERIOD_S, 0.05)[0],
                              integrate(*runs[0])[0])
        plant.simulate({**FAULT, "a_f": 0.2}, PERIOD_S, 0.05)
        assert len(runs) == 2
