"""Condition indicators of a record whose speed drifts, written here from the shaft angles
(not by our model): a gear pair whose pinion or gear has one weak tooth."""

import json

import numpy as np
import pytest
from conftest import run_cli, write_csv

from pydiag.core.errors import MeasurementError
from pydiag.core.measurement import Measurement
from pydiag.gear.indicators import INDICATORS, condition_indicators
from pydiag.gear.kinematics import GearKinematics
from pydiag.gear.speed import SpeedSettings

FS, DURATION = 20_000.0, 6.0
NP, NG = 19, 47
NOMINAL = GearKinematics(NP, NG, 25.0)


def gear_record(weak: str | None = None, noise: float = 0.3, seed: int = 1) -> Measurement:
    """Mesh harmonics; a ``weak`` ("pinion" or "gear") tooth meshes at half the amplitude
    once per turn of its shaft; the speed ramps 1 % from 24.7 Hz; white noise."""
    n = int(FS * DURATION)
    t = np.arange(n) / FS
    revs = np.cumsum(24.7 * (1 + 0.01 * t / DURATION)) / FS
    mesh_phase = NP * revs
    amplitude = np.ones(n)
    if weak is not None:
        teeth = NP if weak == "pinion" else NG
        tooth = np.floor(np.mod(mesh_phase, teeth))  # the tooth of that shaft in mesh
        amplitude = np.where(tooth == 3, 0.5, 1.0)
    signal = sum(amplitude * np.cos(2 * np.pi * h * mesh_phase) / h for h in (1, 2, 3))
    rng = np.random.default_rng(seed)
    return Measurement({"acc": signal + noise * rng.standard_normal(n),
                        "acc2": 0.5 * signal + noise * rng.standard_normal(n)}, FS,
                       {"file": f"{weak or 'healthy'}.csv"})


@pytest.mark.parametrize("shaft", ["pinion", "gear"])
def test_the_weak_tooth_shows_on_its_own_shaft(shaft):
    healthy = condition_indicators(gear_record(None), NOMINAL, SpeedSettings("mesh"), shaft)
    weak = condition_indicators(gear_record(shaft), NOMINAL, SpeedSettings("mesh"), shaft)
    for report in (healthy, weak):
        assert report.mesh_order == (NP if shaft == "pinion" else NG)
        assert set(report.indicators) == {"acc", "acc2"}
        assert list(report.indicators["acc"]) == list(INDICATORS)
        assert abs(report.speed.speed_hz - np.mean(24.7 * (1 + 0.005))) < 1e-3
    assert healthy.indicators["acc"]["fm4"] == pytest.approx(3.0, abs=0.6)
    assert weak.indicators["acc"]["fm4"] > 5.0
    assert weak.indicators["acc"]["ser"] > 3 * healthy.indicators["acc"]["ser"]
    assert "this record" in healthy.reference


def test_a_baseline_sets_the_trend_reference_and_is_checked():
    base = gear_record(None, seed=2)
    report = condition_indicators(gear_record("pinion"), NOMINAL, SpeedSettings("mesh"),
                                  baseline=base)
    own = condition_indicators(gear_record("pinion"), NOMINAL, SpeedSettings("mesh"))
    assert report.reference == "baseline healthy.csv"
    # the weak tooth's residual carries more variance than the healthy baseline's
    assert report.indicators["acc"]["na4"] > own.indicators["acc"]["na4"]
    assert report.indicators["acc"]["fm4"] == own.indicators["acc"]["fm4"]
    with pytest.raises(MeasurementError, match="the baseline has no channel acc2"):
        condition_indicators(gear_record("pinion"), NOMINAL, SpeedSettings("mesh"),
                             baseline=Measurement({"acc": base.channels["acc"]}, FS))


def test_the_cli_writes_one_table_per_channel_or_one_table(tmp_path):
    m = gear_record("pinion")
    t = np.arange(m.n_samples) / FS
    rows = zip(t, m.channels["acc"], m.channels["acc2"])
    path = write_csv(tmp_path / "weak.csv", ["time_s", "acc", "acc2"], rows)
    out = tmp_path / "ind.json"
    res = run_cli("-m", "pydiag", "indicators", "--measurement", str(path), "--rpm", "1500",
                  "--teeth", f"{NP},{NG}", "--json", str(out))
    assert res.returncode == 0, res.stderr
    data = json.loads(out.read_text())
    assert set(data["indicators"]) == {"acc", "acc2"} and data["mesh_order"] == NP
    assert data["indicators"]["acc"]["fm4"] > 5.0
    assert "fm4" in res.stdout and "NA4, NB4   : relative to this record" in res.stdout
    one = tmp_path / "one.json"
    res = run_cli("-m", "pydiag", "indicators", "--measurement", str(path), "--channel", "acc",
                  "--rpm", "1500", "--teeth", f"{NP},{NG}", "--json", str(one))
    assert res.returncode == 0, res.stderr
    assert json.loads(one.read_text())["indicators"]["fm4"] == data["indicators"]["acc"]["fm4"]
    res = run_cli("-m", "pydiag", "indicators", "--measurement", str(path), "--rpm", "1500")
    assert res.returncode == 2 and "give the teeth (--teeth NP,NG)" in res.stderr
