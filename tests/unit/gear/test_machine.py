"""The machine description: reading the TOML file (and refusing a bad one with the file and
the key named), the shafts' speeds, and the speed found from every stage's mesh at once.

The two-stage records here are written from a drifting input-shaft angle: each stage's
mesh harmonics amplitude-modulated by both of its shafts (strong, as a chipped tooth or an
eccentric gear makes them), not by the search's own comb of lines.
"""

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from pydiag.core.errors import MachineError, MeasurementError
from pydiag.core.measurement import Measurement
from pydiag.gear.machine_file import load_machine, machine_from_dict
from pydiag.gear.speed import SpeedSettings, estimate_speed

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"

TWO_STAGE = {"name": "test box", "input_rpm": 1800,
             "stages": [{"pinion_teeth": 32, "gear_teeth": 96},
                        {"pinion_teeth": 48, "gear_teeth": 80}]}


def to_toml(data: dict) -> str:
    """The few TOML forms these tests write: scalars, lists of them, tables, arrays of
    tables (top-level keys first, as TOML needs)."""
    def value(v):
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(v).lower() if isinstance(v, bool) else repr(v)

    plain = [f"{k} = {value(v)}" for k, v in data.items()
             if not isinstance(v, dict) and not (isinstance(v, list) and v
                                                  and isinstance(v[0], dict))]
    tables = []
    for k, v in data.items():
        rows = [v] if isinstance(v, dict) else v if isinstance(v, list) and v and \
            isinstance(v[0], dict) else []
        for row in rows:
            tables.append(f"[{k}]" if isinstance(v, dict) else f"[[{k}]]")
            tables += [f"{rk} = {value(rv)}" for rk, rv in row.items()]
    return "\n".join(plain + tables) + "\n"


def test_example_files_read_and_their_shafts_turn_as_the_teeth_say():
    phm = load_machine(EXAMPLES / "phm09_spur.toml")
    assert [s.pinion_teeth for s in phm.stages] == [32, 48]
    assert phm.shafts == ("input", "idler", "output")
    assert phm.shaft_ratio(1) == Fraction(1, 3) and phm.shaft_ratio(2) == Fraction(1, 5)
    assert phm.mesh_order(0) == 32 and phm.mesh_order(1) == 16
    assert phm.tacho.channel == "ch3" and phm.tacho.pulses_per_rev == 10
    kin = phm.stage_kinematics(1, 30.0)
    assert (kin.n_pinion, kin.n_gear, kin.f_pinion_hz) == (48, 80, pytest.approx(10.0))
    gfd = load_machine(EXAMPLES / "gfd_spectraquest.toml")
    assert len(gfd.stages) == 1 and gfd.input_hz == pytest.approx(30.0)
    # the data set's helical set: the spur set's shaft speeds, other meshes
    helical = load_machine(EXAMPLES / "phm09_helical.toml")
    assert [(s.pinion_teeth, s.gear_teeth) for s in helical.stages] == [(16, 48), (24, 40)]
    assert [helical.shaft_ratio(k) for k in range(3)] == [phm.shaft_ratio(k) for k in range(3)]
    assert helical.mesh_order(0) == 16 and helical.mesh_order(1) == 8


@pytest.mark.parametrize("change, key", [
    ({"stages": [{"pinion_teeth": 0, "gear_teeth": 96}]}, "stages[0].pinion_teeth"),
    ({"stages": [{"pinion_teeth": 32, "gear_teeth": 96.5}]}, "stages[0].gear_teeth"),
    ({"stages": [{"pinion_teeth": 32, "gear_teeth": 96, "teeth": 3}]}, "stages[0].teeth"),
    ({"stages": [{"pinion_teeth": 32, "gear_teeth": 96, "type": "planetary"}]},
     "stages[0].type"),
    ({"stages": []}, "stages"),
    ({"input_rpm": -5}, "input_rpm"),
    ({"gears": 2}, "gears"),
    ({"bearings": [{"shaft": "layshaft", "n_balls": 9, "ball_diameter_mm": 8,
                    "pitch_diameter_mm": 39}]}, "bearings[0].shaft"),
    ({"bearings": [{"shaft": "input", "n_balls": 9, "ball_diameter_mm": 40,
                    "pitch_diameter_mm": 39}]}, "bearings[0].ball_diameter_mm"),
    ({"sensors": [{"channel": "ch1", "near_stage": "third"}]}, "sensors[0].near_stage"),
    ({"shafts": ["a", "b"]}, "shafts"),
    ({"tacho": {"channel": "ch3", "pulses_per_rev": 0}}, "tacho.pulses_per_rev"),
    ({"effects": [{"key": "gear_wobble", "stage": "stage 1"}]}, "effects[0].key"),
    ({"effects": [{"key": "backlash"}]}, "effects[0].stage"),
    ({"effects": [{"key": "backlash", "stage": "third"}]}, "effects[0].stage"),
    ({"effects": [{"key": "backlash", "stage": "stage 2"}] * 2}, "effects[1].key"),
    ({"effects": [{"key": "backlash", "stage": "stage 2", "off": ["A_s1"]}]}, "effects[0].off"),
    ({"effects": [{"key": "pinion_shaft_orders", "stage": "stage 2", "off": "A_s1"}]},
     "effects[0].off"),
    ({"start": {"input_stage.a0": "high"}}, "start"),
])
def test_a_bad_machine_file_is_refused_naming_the_file_and_the_key(tmp_path, change, key):
    path = tmp_path / "box.toml"
    path.write_text(to_toml({**TWO_STAGE, **change}))
    with pytest.raises(MachineError) as err:
        load_machine(path)
    message = str(err.value)
    assert str(path) in message and key in message, message
    assert "\n" not in message


def test_a_start_table_is_what_a_fit_polishes_from_and_none_is_none(tmp_path):
    path = tmp_path / "box.toml"
    path.write_text(to_toml(TWO_STAGE))
    assert load_machine(path).fit_start() is None
    path.write_text(to_toml(TWO_STAGE) + '[start]\n"stage_1.a0" = 0.25\ngain_dB = -3\n')
    assert load_machine(path).fit_start() == {"stage_1.a0": 0.25, "gain_dB": -3.0}


def test_unreadable_machine_files_are_the_users_to_fix(tmp_path):
    with pytest.raises(MachineError, match="not found"):
        load_machine(tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[[stages]\npinion_teeth = 3\n")
    with pytest.raises(MachineError, match="not valid TOML"):
        load_machine(bad)


# ---------------------------------------------------------------------- speed of a machine
FS, DURATION = 25_000.0, 4.0
MACHINE = machine_from_dict(TWO_STAGE)


def two_stage_record(true_hz: float, seed: int = 3,
                     noise: float = 0.3) -> tuple[Measurement, np.ndarray]:
    """Both stages' meshes, each modulated by its two shafts so strongly that the first
    sidebands stand almost as high as the mesh; the input speed drifts by 0.05 %."""
    n = int(FS * DURATION)
    t = np.arange(n) / FS
    speed = true_hz * (1 + 0.0005 * np.sin(2 * np.pi * 0.3 * t))
    revs = np.cumsum(speed) / FS
    rng = np.random.default_rng(seed)
    x = np.zeros(n)
    for k in range(len(MACHINE.stages)):
        shafts = [float(MACHINE.shaft_ratio(k)), float(MACHINE.shaft_ratio(k + 1))]
        modulation = 1 + sum(0.8 / j * np.cos(2 * np.pi * j * r * revs + j)
                             for r in shafts for j in (1, 2))
        mesh = sum(np.cos(2 * np.pi * h * float(MACHINE.mesh_order(k)) * revs + h) / h
                   for h in (1, 2, 3))
        x += mesh * modulation
    x += noise * rng.standard_normal(n)
    return Measurement({"acc": x}, FS), revs


def mean_hz(revs: np.ndarray, valid: tuple[int, int] = (0, -1)) -> float:
    """The true mean speed over the samples ``valid`` (where an estimate measured it)."""
    a, b = valid[0], valid[1] % revs.size
    return float((revs[b] - revs[a]) / ((b - a) / FS))


@pytest.mark.parametrize("slip", [0.0, 0.02, 0.035])
def test_one_speed_for_every_mesh_finds_a_slipping_machine_within_a_hundredth_percent(slip):
    record, revs = two_stage_record(30.0 * (1 - slip))
    kin = MACHINE.stage_kinematics(0, 30.0)
    found = estimate_speed(record, kin, SpeedSettings("mesh"), machine=MACHINE)
    truth = mean_hz(revs, found.valid)
    assert abs(found.speed_hz / truth - 1) < 1e-4, (found.speed_hz, truth)
    assert found.confidence_db > 1, found.confidence_db
    assert found.to_dict()["speed_confidence_db"] == found.confidence_db
    if slip > 0.015:  # beyond the one-stage search's window (0.45 pinion orders)
        try:
            pair = estimate_speed(record, kin, SpeedSettings("mesh"))
        except MeasurementError:
            return  # refused: no mesh line stands out in its window
        assert abs(pair.speed_hz / truth - 1) > 1e-3


def test_a_tacho_estimate_carries_the_mesh_speed_to_check_it_by():
    record, revs = two_stage_record(29.5)
    # the tacho gives 11 pulses a turn and the user says 10: it reads 1.1 times the speed
    record.channels["tacho"] = (np.mod(revs * 11, 1.0) < 0.2).astype(float)
    kin = MACHINE.stage_kinematics(0, 30.0)
    found = estimate_speed(record, kin, SpeedSettings("tacho", tacho="tacho",
                                                      pulses_per_rev=10), machine=MACHINE)
    assert found.speed_hz == pytest.approx(1.1 * mean_hz(revs), rel=1e-3)
    assert found.mesh_speed_hz == pytest.approx(mean_hz(revs), rel=1e-3)
    assert found.tacho_disagreement_pct == pytest.approx(-100 / 11, abs=0.1)
    assert "--pulses-per-rev" in found.warning()
    # 2 pulses a turn read as 1: twice the nominal, the meshes at the nominal: refused,
    # with the count the tacho gives
    record.channels["tacho"] = (np.mod(revs * 2, 1.0) < 0.2).astype(float)
    with pytest.raises(MeasurementError, match="about 2 pulses a turn"):
        estimate_speed(record, kin, SpeedSettings("tacho", tacho="tacho"), machine=MACHINE)


def test_a_stage_is_found_by_name_or_number_and_a_wrong_one_is_named():
    machine = machine_from_dict({**TWO_STAGE, "stages": [
        {**TWO_STAGE["stages"][0], "name": "input stage"}, TWO_STAGE["stages"][1]]})
    assert machine.stage_index("input stage") == 0 and machine.stage_index("2") == 1
    for wrong in ("3", "0", "output"):
        with pytest.raises(MachineError, match="the stages are 1 \\(input stage\\), 2"):
            machine.stage_index(wrong)


@pytest.mark.parametrize("stages, turns", [
    ([(32, 96), (48, 80)], 15),  # PHM09: 3 input turns, then 5 idler turns (15 input)
    ([(18, 36), (20, 50)], 10),  # 1 gear turn (2 input), then 5 turns of 2 input turns
    ([(20, 64), (24, 54)], 144),  # hunting teeth: 16 input turns, then 9 x 64/20 = 28.8
])
def test_a_model_of_every_stage_repeats_when_every_stage_does(stages, turns):
    """The machine's period is the shortest whole number of every stage's hunting-tooth
    periods, counted in input turns; its kinematics analyse every stage's bands."""
    machine = machine_from_dict({"name": "box", "stages": [
        {"pinion_teeth": p, "gear_teeth": g} for p, g in stages]})
    assert machine.fundamental_order() == Fraction(1, turns)
    kin = machine.model_kinematics(25.0)
    assert kin.period_s == pytest.approx(turns / 25.0)
    assert machine.stage_kinematics(0, 25.0).period_s < kin.period_s
    from pydiag.gear.features import paper_bands
    bands = paper_bands(kin)
    assert len(bands) == 10 * len(stages)
    second = machine.stage_kinematics(1, 25.0)
    assert any(b.low_hz < second.f_mesh_hz < b.high_hz and b.name == "stage2:mesh1"
               for b in bands)
