"""Every stage of a two-stage machine judged against its own healthy records: written here
from the shafts' angles (not by the model): each stage's mesh modulated by its two shafts,
and, for a fault, a local tooth defect on one gear: a short dip of its mesh's amplitude
once per turn of that gear's shaft."""

import numpy as np
import pytest

from pydiag.core.errors import MeasurementError
from pydiag.core.measurement import Measurement
from pydiag.gear.machine import machine_from_dict
from pydiag.gear.machine_indicators import judge_stages, machine_record, machine_report
from pydiag.gear.speed import SpeedSettings

FS, DURATION, INPUT_HZ = 20_000.0, 6.0, 25.0
MACHINE = machine_from_dict({"stages": [{"pinion_teeth": 23, "gear_teeth": 61},
                                        {"pinion_teeth": 29, "gear_teeth": 53}]})


def record(seed: int, faulty_shaft: int | None = None, stage: int = 0) -> Measurement:
    rng = np.random.default_rng(seed)
    n = int(FS * DURATION)
    t = np.arange(n) / FS
    speed = INPUT_HZ * 0.99 * (1 + 0.0005 * np.sin(2 * np.pi * 0.2 * t + seed))
    revs = np.cumsum(speed) / FS
    x = np.zeros(n)
    for k in range(len(MACHINE.stages)):
        order = float(MACHINE.mesh_order(k))
        gain = np.ones(n)
        for shaft in (k, k + 1):
            gain += 0.1 * np.cos(2 * np.pi * float(MACHINE.shaft_ratio(shaft)) * revs + shaft)
        if faulty_shaft is not None and k == stage:
            angle = np.mod(float(MACHINE.shaft_ratio(faulty_shaft)) * revs, 1.0)
            gain -= 0.8 * np.exp(-0.5 * ((angle - 0.3) / 0.01) ** 2)  # a broken tooth
        x += gain * sum(np.cos(2 * np.pi * h * order * revs + h) / h for h in (1, 2, 3))
    return Measurement({"acc": x + 0.3 * rng.standard_normal(n)}, FS)


@pytest.fixture(scope="module")
def baseline():
    return machine_record(record(1), MACHINE, SpeedSettings("mesh"), INPUT_HZ)


def test_a_healthy_record_changes_no_stage(baseline):
    healthy = machine_record(record(2), MACHINE, SpeedSettings("mesh"), INPUT_HZ)
    verdicts, spread = judge_stages(MACHINE, healthy, [baseline])
    assert spread > 0
    assert [v.changed for v in verdicts] == [False, False], verdicts


@pytest.mark.parametrize("stage, shaft, suspect", [(0, 0, "pinion"), (1, 2, "gear")])
def test_a_local_tooth_fault_changes_its_stage_and_names_its_shaft(baseline, stage, shaft,
                                                                    suspect):
    faulty = machine_record(record(3, shaft, stage), MACHINE, SpeedSettings("mesh"), INPUT_HZ)
    verdicts, _ = judge_stages(MACHINE, faulty, [baseline])
    assert verdicts[stage].changed and verdicts[stage].suspect == suspect, verdicts[stage]
    other = verdicts[1 - stage]
    assert not (other.changed and other.suspect == ("gear" if stage == 0 else "pinion"))


def test_the_report_judges_nothing_without_a_baseline_and_is_plain_data():
    report = machine_report(record(2), MACHINE, SpeedSettings("mesh"), INPUT_HZ)
    data = report.to_dict()
    assert data["stages"] == [] and data["healthy_spread_db"] is None
    assert [s["teeth"] for s in data["shafts"]] == [[23], [61, 29], [53]]
    assert data["speed_hz"] == pytest.approx(INPUT_HZ * 0.99, rel=1e-3)
    with pytest.raises(MeasurementError, match="needs a baseline"):
        judge_stages(MACHINE, report.record, [])
