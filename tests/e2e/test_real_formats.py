"""diagnose and compare on records in MATLAB and WAV files, channels mapped and the
operating point given on the command line, the speed found in the record.

The records come from our FMU at a pinion speed 0.6 % off the nominal one given to
diagnose (as a loaded motor slips), stored the way a data recorder would: a MAT file with
a channel named otherwise and its rate in a variable, in g; a WAV file of 16-bit PCM,
whose level is lost (the channel gain is fitted).
"""

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.io.wavfile
from conftest import run_cli

from pydiag.core.measurement import Measurement
from pydiag.fmu.plant import FmuPlant
from pydiag.gear.kinematics import GearKinematics
from pydiag.signal.noise import add_white_noise

TRUE_SPEED_HZ = 24.85  # the nominal 1500 rpm is 25 Hz
FS = 10_000.0
CASE = {"a_f": 0.3, "f_f": 0.6}  # a tooth fault (Table 1 case 3)
FAST = ["--particles", "8", "--iterations", "8", "--polish", "60", "--quiet"]


@pytest.fixture(scope="module")
def slipped_record(gear_fmu) -> Measurement:
    kin = GearKinematics(14, 21, TRUE_SPEED_HZ)
    with FmuPlant(gear_fmu, ("acc",), FS, fixed_values={"f_pinion": TRUE_SPEED_HZ}) as plant:
        clean = plant.simulate(CASE, 20 * kin.period_s, 0.05)[0]
    return Measurement({"acc": add_white_noise(clean, 10.0, np.random.default_rng(5))}, FS)


def _diagnose(fmu, path, extra, tmp_path, command="diagnose"):
    out = tmp_path / f"{command}.json"
    res = run_cli("-m", "pydiag", command, "--fmu", str(fmu), "--measurement",
                  str(path), "--rpm", "1500", "--teeth", "14,21", "--json", str(out), *extra,
                  *FAST, cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    return json.loads(out.read_text()), res.stdout


def test_mat_record_in_g_with_a_renamed_channel(gear_fmu, slipped_record, tmp_path):
    path = tmp_path / "rig.mat"
    scipy.io.savemat(path, {"Fs": FS, "ch_housing": slipped_record.channels["acc"] / 9.80665})
    result, text = _diagnose(gear_fmu, path, ["--channel", "ch_housing=acc", "--unit", "g",
                                              "--gain", "fixed"], tmp_path)
    assert abs(result["speed_hz"] - TRUE_SPEED_HZ) < 1e-4 * TRUE_SPEED_HZ
    assert result["speed_method"].startswith("mesh harmonic") and result["nominal_speed_hz"] == 25.0
    # the ends where the phase is not measured are cut: 16 of the 20 periods remain
    assert result["n_periods"] >= 15 and result["duration_s"] > 15 * 3 / TRUE_SPEED_HZ
    assert result["channels"] == ["acc"]
    for name, value in CASE.items():
        assert abs(result["parameters"][name] - value) < 0.05, result["parameters"]
    assert "speed      : 24.85" in text


def test_wav_record_level_lost_the_gain_is_fitted(gear_fmu, slipped_record, tmp_path):
    x = slipped_record.channels["acc"]
    pcm = np.round(x / np.max(np.abs(x)) * 20000).astype(np.int16)
    path = tmp_path / "rig.wav"
    scipy.io.wavfile.write(path, int(FS), pcm)
    result, _ = _diagnose(gear_fmu, path, ["--channel", "ch1=acc"], tmp_path)
    assert abs(result["speed_hz"] - TRUE_SPEED_HZ) < 1e-4 * TRUE_SPEED_HZ
    assert result["gains"]["acc"] == pytest.approx(20000 / 32768 / np.max(np.abs(x)), rel=0.1)
    assert abs(result["parameters"]["a_f"] - CASE["a_f"]) < 0.05, result["parameters"]
    assert result["fault_mode"] == "tooth_fault"

    compared, _ = _diagnose(gear_fmu, path, ["--channel", "ch1=acc", "--history",
                                             str(tmp_path / "h.sqlite")], tmp_path, "compare")
    assert compared["speed_method"].startswith("mesh harmonic")
    assert compared["n_periods"] >= 15  # the whole record, not the first 10 periods only
    assert compared["error"] < 0.5
    assert (tmp_path / "h.sqlite").is_file()  # the history went where it was told


def test_compare_history_defaults_to_the_user_data_folder_not_the_current_one(gear_fmu,
                                                                          slipped_record,
                                                                          tmp_path):
    import os
    path = tmp_path / "rig.mat"
    scipy.io.savemat(path, {"Fs": FS, "acc": slipped_record.channels["acc"]})
    _diagnose(gear_fmu, path, [], tmp_path, "compare")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["compare.json", "rig.mat"]
    assert (Path(os.environ["XDG_DATA_HOME"]) / "pydiag" / "history.sqlite").is_file()
    # the effect FMUs its validation built are in the per-user cache
    assert list((Path(os.environ["XDG_CACHE_HOME"]) / "pydiag" / "effects").glob("*/*.fmu"))
