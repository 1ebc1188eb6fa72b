"""A machine's speed is said once, at the input shaft: each stage's fit has the same speed
at its own shaft (a tacho on the input is not the stage's), and leaves it to the machine."""

from types import SimpleNamespace

import numpy as np
import pytest

from pydiag.fit.estimator import FitResult
from pydiag.gear.machine_file import load_machine
from pydiag.gear.speed import SpeedEstimate, SpeedSource
from pydiag.diagnose.diagnosis import Diagnosis, fit_warnings
from pydiag.gear.machine_report import MachineReport, stage_report
from pydiag.diagnose.stages import stage_speed
from conftest import ROOT

MACHINE = load_machine(ROOT / "examples" / "phm09_spur.toml")  # 32/96 then 48/80


def stage_fit_warnings(estimate: SpeedEstimate, k: int, **kwargs) -> list[str]:
    """fit_warnings of stage ``k``'s fit, its problem's speed the stage's own."""
    problem = SimpleNamespace(parameters=(), channels=("ch1",), measurement=SimpleNamespace(
        metadata={}), speed=stage_speed(estimate, MACHINE, k))
    return fit_warnings(problem, 0.5, **kwargs)


def machine_diagnosis(speed: SpeedEstimate) -> MachineReport:
    stages = []
    for k, stage in enumerate(MACHINE.stages):
        own = stage_speed(speed, MACHINE, k)
        said = stage_fit_warnings(speed, k, speed=False) + ["a fit's own warning"]
        fit = Diagnosis(FitResult({}, 0.5, 1, 0.0, [0.5]), "healthy", "none", "none", "none",
                        warnings=said)
        stages.append(stage_report(stage.name, stage.pinion_teeth, stage.gear_teeth,
                                   own.speed_hz, None, fit))
    return MachineReport(MACHINE, speed, tuple(stages))


@pytest.mark.parametrize("speed, said", [
    (SpeedEstimate(30.0, 0.1, "tacho", 30.0, np.zeros(3), source=SpeedSource.TACHO,
                   mesh_speed_hz=30.3, band_pct=0.52), "30.30000 Hz, +1.000 % from the tacho's 30.00000"),
    (SpeedEstimate(30.0, 0.8, "mesh harmonic 1", 30.0, np.zeros(3), band_pct=0.52),
     "swings by +-0.4 %"),
])
def test_the_speed_is_said_once_at_the_input_shaft(speed, said):
    # a stage's own fit would say it at its shaft's speed (the output stage's: 10 Hz)
    assert any("%" in w for w in stage_fit_warnings(speed, 1))
    warnings = machine_diagnosis(speed).warnings
    assert said in warnings[0]
    assert warnings[1:] == ["input stage: a fit's own warning", "output stage: a fit's own warning"]
