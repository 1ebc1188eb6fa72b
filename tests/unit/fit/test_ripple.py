"""A speed or torque ripple read from the model's periodic response is the Modelica model
with the ripple inside it (GearDiag.Effects.SpeedFluctuation, LoadFluctuation) integrated
over the whole record: two implementations, one of a modulated angle or a force in the
equations, one of periodic signals read along the angle or weighted by the force
(pydiag.signal.ripple)."""

import dataclasses

import numpy as np
import pytest

from pydiag.core.measurement import Measurement
from pydiag.core.parameters import Parameter
from pydiag.fit.build import build_problem
from pydiag.fmu.periodic import simulate_period
from pydiag.fmu.plant import FmuPlant
from pydiag.signal.ripple import (OVERSAMPLE, LoadRipple, SpeedRipple, along_angle,
                                  modulated_angle)

RATE_HZ = 10_000.0
PERIOD_S = 0.12  # GearPair's fundamental period by default: 3 pinion turns at 25 Hz
WARMUP_S, DURATION_S = 0.4, 2.0
FAULT = {"a_f": 0.3, "f_ate": 0.2, "f_dte": 0.3}  # a faulty tooth and errors: many lines


def effect_fmu(effects_dir, name: str):
    fmu = effects_dir / f"{name}.fmu"
    if not fmu.exists():
        from fmu_build import build_fmu
        from tests.conftest import ROOT
        build_fmu(ROOT / "modelica" / "GearDiag" / "Effects" / f"{name}.mo",
                  f"GearDiag.Effects.{name}", fmu)
    return fmu


@pytest.fixture(scope="module")
def ripple_fmu(effects_dir):
    return effect_fmu(effects_dir, "SpeedFluctuation")


def spectrum(y: np.ndarray) -> np.ndarray:
    """Of the signal's variation (a displacement's static deflection left out)."""
    return np.abs(np.fft.rfft((y - y.mean()) * np.hanning(y.size))) / y.size


def band_error(a: np.ndarray, b: np.ndarray, top_hz: float) -> float:
    """Relative error of the spectrum ``a`` against ``b`` from the first mesh harmonic
    (350 Hz) to ``top_hz``, where a ripple's sidebands are (a ripple of 0.2 % moves the
    pinion's own line at 25 Hz by 1 %)."""
    f = np.fft.rfftfreq(2 * (a.size - 1), 1 / RATE_HZ)
    band = (f >= 300.0) & (f <= top_hz)
    return float(np.linalg.norm(a[band] - b[band]) / np.linalg.norm(b[band]))


@pytest.mark.parametrize("model,ripple,values,tolerance", [
    ("SpeedFluctuation", SpeedRipple(), {"ds": 0.002, "f_speed": 7.3}, 0.03),
    ("SpeedFluctuation", SpeedRipple(), {"ds": 0.01, "f_speed": 3.1}, 0.06),  # near the mode
    ("LoadFluctuation", LoadRipple(), {"dT": 5.0, "f_load": 7.3}, 0.01),
    ("LoadFluctuation", LoadRipple(), {"dT": 20.0, "f_load": 3.1}, 0.01)])
def test_the_ripple_read_from_periods_is_the_modelica_model_integrated_whole(
        effects_dir, model, ripple, values, tolerance):
    outputs = ("acc", "disp")
    with FmuPlant(str(effect_fmu(effects_dir, model)), outputs, RATE_HZ) as plant:
        inside = plant.simulate({**FAULT, **values}, DURATION_S, WARMUP_S)
        steady = plant.simulate({**FAULT, ripple.variables[0]: 0.0}, DURATION_S, WARMUP_S)
        read = ripple.read(lambda changes: simulate_period(plant, {**FAULT, **changes}, WARMUP_S,
                                                           PERIOD_S, OVERSAMPLE),
                           {"T": 50.0, **values}, outputs, inside.shape[1], RATE_HZ, WARMUP_S)
    assert read is not None  # the model without the ripple repeats
    for i in range(2):
        b = spectrum(inside[i])
        error = band_error(spectrum(read[i]), b, 4000.0)
        assert error < tolerance
        # and the ripple changed them: a copy of the steady response is far further off
        assert band_error(spectrum(steady[i]), b, 4000.0) > 10 * error


def test_the_angle_read_without_a_ripple_gives_the_period_back_at_its_samples():
    rng = np.random.default_rng(0)
    period = rng.standard_normal(40)
    angle, pace = modulated_angle(100, 1000.0, 0.3, 0.0, 7.0)
    np.testing.assert_allclose(along_angle(period, 1000.0, angle, pace, 2),
                               np.tile(period, 3)[:100], atol=1e-12)


def test_a_problem_with_the_ripple_reads_it_from_one_period_of_its_model(ripple_fmu,
                                                                         monkeypatch):
    """The values the ripple is read with are the fitted ones, else the fixed ones, else
    the FMU's; its model is integrated over one period at the finer rate, the ripple off."""
    with FmuPlant(str(ripple_fmu), ("acc",), RATE_HZ) as plant:
        record = plant.simulate({**FAULT, "ds": 0.004, "f_speed": 5.0}, DURATION_S, WARMUP_S)
    measurement = Measurement({"acc": record[0]}, RATE_HZ)
    problem = build_problem(str(ripple_fmu), measurement, fixed_values={**FAULT, "f_speed": 5.0},
                            parameters=(Parameter("ds", 0.0, 0.05),), warmup_s=WARMUP_S)
    rippled = dataclasses.replace(problem, ripple=SpeedRipple())
    with FmuPlant(str(ripple_fmu), ("acc",), RATE_HZ, fixed_values=problem.spec.fixed_values
                  ) as plant:
        runs = []
        integrate = plant._simulate
        monkeypatch.setattr(plant, "_simulate", lambda *a: runs.append(a) or integrate(*a))
        whole = problem.simulate(plant, np.array([0.004]))[0]
        read = rippled.simulate(plant, np.array([0.004]))[0]
        assert runs[-1][0]["ds"] == 0.0 and runs[-1][4] == RATE_HZ * OVERSAMPLE
        assert runs[-1][2] <= 2 * PERIOD_S * RATE_HZ * OVERSAMPLE
        rippled.simulate(plant, np.array([0.008]))  # the period again: no integration
        assert len(runs) == 2
    assert band_error(spectrum(read), spectrum(whole), 4000.0) < 0.03
    np.testing.assert_allclose(whole, record[0][:whole.size], rtol=1e-6,
                               atol=1e-6 * np.abs(whole).max())
