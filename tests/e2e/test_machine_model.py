"""The machine's own model (:mod:`pydiag.loop.machine_model`): every stage of a machine file
in one Modelica model written by pydiag, built once per content, fitted to a record of
:mod:`truth.gearbox` (written from the shafts' angles, not by the pair model) over the
machine's period; and `pydiag compare --machine` without --fmu, which fits it."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from conftest import inspected, run_cli
from boxes import SHORT_MACHINE
from truth.gearbox import INPUT_HZ, SHORT_BOX, gearbox_record

from pydiag.fit.estimator import FaultEstimator
from pydiag.gear.speed import SpeedSettings
from pydiag.gear.machine_file import load_machine
from pydiag.io.measurements import write_measurement
from pydiag.io.readers import read_measurement
from pydiag.loop.compare import compare
from pydiag.loop.machine_fit import machine_problem
from pydiag.loop.machine_model import machine_fmu, machine_model
from pydiag.diagnose.stages import machine_speed

ROOT = Path(__file__).resolve().parents[2]
MODELICA = ROOT / "modelica"
SMALL = dict(n_particles=8, iterations=4, polish_evaluations=40)
#: The short-period test box's machine file, and the same with a comment of the user's.
BOX = ('name = "short box"\ninput_rpm = 1500\n'
       '[[stages]]\npinion_teeth = 18\ngear_teeth = 36\n'
       '[[stages]]\npinion_teeth = 20\ngear_teeth = 50\n')
COMMENTED_BOX = BOX.replace('"short box"\n', '"short box"  # the test box\n', 1)


def test_the_machine_model_explains_the_second_stages_lines(tmp_path):
    """The same record and bins, fitted by the model of both stages and by the same model
    with the second stage silenced: the first stage alone leaves the second's lines (most
    of the residual); with both, the error falls to well under half and so does what is
    left on those lines."""
    m = gearbox_record(3, box=SHORT_BOX)
    model, built = machine_fmu(SHORT_MACHINE, MODELICA, tmp_path)
    inspected(built.fmu)
    assert machine_fmu(SHORT_MACHINE, MODELICA, tmp_path) == (model, built)  # cached
    speed = machine_speed(m, SHORT_MACHINE, INPUT_HZ, SpeedSettings("mesh"))
    problem = machine_problem(built.fmu, model, m, SHORT_MACHINE, speed)
    assert problem.kinematics.period_s == pytest.approx(10 / speed.speed_hz)
    both = compare(problem, FaultEstimator(**SMALL))
    level = "acc_stage_2_dB"
    first = compare(problem.derive(
        parameters=tuple(p for p in problem.parameters if p.name.startswith("stage_1.")),
        fixed_values={level: -60.0}), FaultEstimator(**SMALL))

    def left(c):  # the residual on the second stage's lines, relative to the measured
        return c.residual_by_family["acc"]["other_stages"]["residual"] * c.error ** 2

    assert first.n_error_bins == both.n_error_bins
    assert first.residual_by_family["acc"]["other_stages"]["residual"] > 0.5
    assert both.error < 0.5 * first.error, (both.error, first.error)
    assert left(both) < 0.2 * left(first), (left(both), left(first))
    assert -40 < both.parameters[level] < 40


def refused(capsys, *argv: str) -> str:
    """The one-line error of the command line ``argv`` (run in this process), exit 2."""
    from pydiag.app.cli import main
    assert main(list(argv)) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    return err


def test_compare_fits_the_machines_model_and_accept_gives_a_stage_an_effect(tmp_path, capsys):
    """The command line: compare --machine without --fmu writes the model's source where it
    says (both stages in it) and fits every stage's parameters; `pydiag accept` adds an
    effect to a stage of the machine file (its comments kept), and compare then fits the
    model with it, the effect after the stages (at this tiny budget the stages' own swarm
    lands a little differently on the model with the effect, so no exact bound). An
    effect a machine's model cannot have on a stage, a stage not named, an effect twice and
    an effect on compare's machine model are each one line, the file untouched."""
    import json
    rec = tmp_path / "box.csv"
    write_measurement(rec, gearbox_record(4, box=SHORT_BOX))
    machine = tmp_path / "box.toml"
    text = COMMENTED_BOX
    machine.write_text(text)
    common = ("-m", "pydiag", "compare", "--measurement", str(rec), "--machine", str(machine),
              "--build-dir", str(tmp_path / "build"), "--history", str(tmp_path / "h.sqlite"),
              "--quiet", "--particles", "6", "--iterations", "2", "--polish", "10",
              "--speed", "mesh", "--force", "--no-validate")
    r = run_cli(*common, "--json", str(tmp_path / "0.json"))
    assert r.returncode == 0, r.stderr
    sources = list((tmp_path / "build" / "machines").glob("Machine_short_box_*/*.mo"))
    assert len(sources) == 1, sources  # named by the machine and a hash of its model
    source = sources[0]
    assert f"model      : {source} (every stage of {machine}, written by pydiag" in r.stdout
    written = source.read_text()
    assert "GearDiag.Components.GearMesh stage_1(Np=18, Ng=36, f_pinion=f_input)" in written
    assert ("GearDiag.Components.GearMesh stage_2(Np=20, Ng=50, f_pinion=f_input*1/2, "
            "t_phase=stage_2_mesh_phase/(20*f_input*1/2))") in written
    assert "stage_2.a_f=" in r.stdout and "acc_stage_2_dB=" in r.stdout
    assert "stage_2_mesh_phase=" in r.stdout
    for args, message in (
            (("housing_sensor", "--stage", "2"), "housing_sensor is not a stage's in a "
             "machine's model yet"),
            (("bearing_outer_race", "--stage", "2"), "bearing_outer_race has nothing to fit "
             "on stage 2: its lines are not known without the bearing's geometry"),
            (("gear_tooth_fault",), "2 stages: give the stage the effect is on (1 or "
             "'stage 1', 2 or 'stage 2')")):
        assert message in refused(capsys, "accept", *args, "--machine", str(machine))
        assert machine.read_text() == text
    r = run_cli("-m", "pydiag", "accept", "gear_tooth_fault", "--machine", str(machine),
                "--stage", "2")
    assert r.returncode == 0 and "gear_tooth_fault on stage 2" in r.stdout, r.stderr
    assert machine.read_text().startswith(text)  # the user's text, comments kept
    assert "gear_tooth_fault is on stage 2 already" in refused(
        capsys, "accept", "gear_tooth_fault", "--machine", str(machine), "--stage", "stage 2")
    # the idler's odd orders on stage 2 (its even ones are the input's): 7 and 9 lie in
    # no feature band but in the compare's bins, on which an effect is fitted: the record
    # lacks them, so they fit to almost nothing (a polish on the bands alone would leave
    # them wherever its steps wandered: lines the record lacks)
    r = run_cli("-m", "pydiag", "accept", "pinion_shaft_orders", "--machine", str(machine),
                "--stage", "2")
    assert r.returncode == 0, r.stderr
    r = run_cli(*common, "--json", str(tmp_path / "1.json"))
    assert r.returncode == 0, r.stderr
    extended = Path(r.stdout.split("model      : ")[1].split(" (")[0])
    assert "GearMeshWithGearToothFaultPinionShaftOrders stage_2(Np=20" in extended.read_text()
    before, after = (json.loads((tmp_path / f"{k}.json").read_text()) for k in "01")
    assert 0 <= after["parameters"]["stage_2.d_g"] <= 0.6
    assert 0 <= after["parameters"]["stage_2.tooth_g"] <= 50  # the stage's gear's teeth
    level = np.std(read_measurement(rec).channels["acc"])
    assert max(after["parameters"][f"stage_2.A_s{k}"] for k in (7, 9)) < 0.01 * level
    assert after["fit_error"] < 1.05 * before["fit_error"]  # fitted from the stages' fit
    assert after["error"] < 1.05 * before["error"]
    assert "--effect fits a pair's effect: give --stage" in refused(
        capsys, *common[2:], "--effect", "gear_eccentricity")
    assert "give --fmu, or --machine FILE" in refused(
        capsys, "compare", "--measurement", str(rec), "--quiet", "--sample-rate", "20000")


@pytest.mark.slow
def test_an_effect_the_box_has_lowers_the_error_more_than_one_it_lacks(tmp_path):
    """Every mesh of the box has harmonics 1, 1/2, 1/3 at phases of their own, which the
    pair's stiffness wave cannot make: the even harmonics of the wave (mesh_stiffness_shape)
    on the second stage lower the error; a gear runout (which the box lacks) does not, fitted
    the same way."""
    from pydiag.gear.machine import StageEffect
    from pydiag.loop.machine_fit import fit_machine
    m = gearbox_record(5, faulty_shaft=2, stage=1, box=SHORT_BOX)
    speed = machine_speed(m, SHORT_MACHINE, INPUT_HZ, SpeedSettings("mesh"))
    errors = {}
    for key in (None, "mesh_stiffness_shape", "gear_eccentricity"):
        machine = dataclasses.replace(SHORT_MACHINE, effects=(StageEffect(key, 1),) if key else ())
        model, built = machine_fmu(machine, MODELICA, tmp_path)
        problem = machine_problem(built.fmu, model, m, machine, speed)
        fit = fit_machine(problem, model, FaultEstimator())
        errors[key] = compare(problem, None, parameters=fit.parameters).error
    assert errors["mesh_stiffness_shape"] < 0.9 * errors[None], errors
    assert errors["gear_eccentricity"] > 0.95 * errors[None], errors


def test_the_model_source_names_each_sensors_view_of_each_stage(tmp_path):
    """A sensor near a stage sees it as its own, every other stage through a level of its
    own (a parameter only a fit of that sensor estimates). A copy of the file under another
    name (the loop's) is the same model, built once."""
    model = machine_model(load_machine(ROOT / "examples" / "phm09_spur.toml"))
    copy = tmp_path / "phm09_spur.loop.toml"
    copy.write_text((ROOT / "examples" / "phm09_spur.toml").read_text())
    assert machine_model(load_machine(copy)) == model
    assert model.stages == ("input_stage", "output_stage")
    assert [(o.name, o.near, tuple(o.levels.values())) for o in model.outputs] == [
        ("acc_ch1", 0, ("acc_ch1_output_stage_dB",)), ("acc_ch2", 1, ("acc_ch2_input_stage_dB",))]
    assert ("output Real acc_ch2(unit=\"m/s2\") = output_stage.acc + "
            "exp(acc_ch2_input_stage_dB*log(10)/20)*input_stage.acc") in model.source
    names = [p.name for p in model.parameters(True, {"acc_ch1"})]
    assert names[:5] == ["input_stage.a_f", "input_stage.f_f", "input_stage.f_ate",
                         "input_stage.f_dte", "input_stage.a0"]
    assert names[-1] == "acc_ch1_output_stage_dB" and "acc_ch2_input_stage_dB" not in names
    assert [s.variable for s in model.adapter(["ch2"]).sensors] == ["acc_ch2"]
    with pytest.raises(Exception, match="channel ch9 is none of the machine file's sensors"):
        model.adapter(["ch9"])


def test_a_stage_with_effects_is_their_model_and_fits_their_parameters():
    """Two effects with models of their own on one stage make its mesh their composed
    model, declared inside the machine's; one of the pair's own parameters frees them; a tooth's
    index ranges over the stage's own teeth; an effect with nothing to fit on the stage
    (every one of the first ten orders of a 6-tooth pinion is a mesh harmonic or one of
    their sidebands) is refused; the parameters of an affine effect are known as such."""
    from pydiag.core.errors import UsageError
    from pydiag.gear.machine import StageEffect
    phm = load_machine(ROOT / "examples" / "phm09_spur.toml")
    machine = dataclasses.replace(phm, effects=(
        StageEffect("gear_tooth_fault", 0), StageEffect("gear_eccentricity", 0),
        StageEffect("mesh_stiffness_shape", 1)))
    model = machine_model(machine, MODELICA)
    assert "\n  model GearMeshWithGearEccentricityGearToothFault " in model.source
    assert "  GearMeshWithGearEccentricityGearToothFault input_stage(Np=32" in model.source
    assert "  GearDiag.Components.GearMesh output_stage(Np=48" in model.source
    assert "output_stage_mesh_phase" in {p.name for p in model.parameters(True, {"acc_ch1"})}
    ranges = {p.name: (p.low, p.high) for p in model.parameters(True, {"acc_ch1"})}
    assert ranges["input_stage.tooth_g"] == (0.0, 96.0)
    assert ranges["input_stage.ecc_gear"] == (0.0, 50e-6)
    assert ranges["output_stage.k2"] == (0.0, 0.3) and "input_stage.k2" not in ranges
    small = dataclasses.replace(phm, stages=(dataclasses.replace(phm.stages[0], pinion_teeth=6,
                                                                  gear_teeth=18),
                                             *phm.stages[1:]))
    with pytest.raises(UsageError, match="pinion_shaft_orders has nothing to fit on input"):
        machine_model(dataclasses.replace(small,
                                          effects=(StageEffect("pinion_shaft_orders", 0),)))
    # a 32-tooth pinion driving 96: each of its orders is one of its gear's too; the model
    # has them all (a try fits those whose lines stand out of the gear's comb)
    assert machine_model(dataclasses.replace(
        phm, effects=(StageEffect("pinion_shaft_orders", 0),)), MODELICA).affine_parameters
    # the parameters fit_machine fits affinely: an affine effect's, not another's or a phase
    both = machine_model(dataclasses.replace(phm, effects=(
        StageEffect("pinion_shaft_orders", 1), StageEffect("mesh_modulation", 1))), MODELICA)
    names = {p.name for p in both.effect_parameters}
    assert {"output_stage.A_s1", "output_stage.m_p", "output_stage_mesh_phase"} <= names
    assert both.affine_parameters == {n for n in names if n.startswith("output_stage.A_s")}
    assert not model.affine_parameters
    # the orders an accepted effect holds off (those its try did not fit) are not fitted
    held = machine_model(dataclasses.replace(phm, effects=(
        StageEffect("pinion_shaft_orders", 0, ("A_s5", "A_s6")),)), MODELICA)
    assert held.affine_parameters == {f"input_stage.A_s{k}" for k in (1, 2, 3, 4, 7, 8, 9, 10)}


def test_each_parameter_of_the_machines_model_is_one_stages_own():
    """What a stage's try frees (stage_view): its fault parameters, its effects', its mesh
    phase and its level at the sensors it is not near; every parameter a fit of both
    sensors estimates is exactly one stage's."""
    from pydiag.gear.machine import StageEffect
    phm = load_machine(ROOT / "examples" / "phm09_spur.toml")
    model = machine_model(dataclasses.replace(phm, effects=(
        StageEffect("mesh_modulation", 1),)), MODELICA)
    own = [model.stage_parameters(k) for k in (0, 1)]
    assert {"input_stage.a_f", "input_stage.a0", "acc_ch2_input_stage_dB"} <= own[0]
    assert {"output_stage.m_p", "output_stage_mesh_phase", "acc_ch1_output_stage_dB"} <= own[1]
    fitted = {p.name for p in model.parameters(True, {"acc_ch1", "acc_ch2"})}
    assert not own[0] & own[1] and fitted <= own[0] | own[1]


def test_the_loop_accepts_an_effect_with_what_its_try_did_not_fit_held_off(tmp_path):
    """The orders a try left unfitted (their lines another shaft's) go into the machine
    file's ``off`` with the effect, the file reads back with them, and the effect is not
    tried on that stage again."""
    from pydiag.loop.machine_loop import held_off
    from pydiag.loop.machine_edits import accept
    path = tmp_path / "phm.toml"
    path.write_text((ROOT / "examples" / "phm09_spur.toml").read_text())
    machine = load_machine(path)
    off = held_off(machine, "pinion_shaft_orders", "input stage",
                   {"input_stage.A_s1": 400.0, "input_stage.A_s2": 200.0})
    assert off == tuple(f"A_s{k}" for k in range(3, 11))
    assert held_off(machine, "mesh_modulation", "output stage",
                    {f"output_stage.{p}": 0.1 for p in ("m_p", "phi_p", "m_g", "phi_g")}) == ()
    edited = accept(path, "pinion_shaft_orders", "input stage", off)
    assert edited.effects[-1].off == off and load_machine(path).effects == edited.effects
    assert 'off = ["A_s3", "A_s4"' in path.read_text()
    # and it is not tried on that stage again for what it holds off
    from pydiag.loop.machine_discover import lacking
    model = machine_model(edited, MODELICA)
    assert "pinion_shaft_orders" not in lacking(edited, model, 0)
    assert "pinion_shaft_orders" in lacking(edited, model, 1)


def test_a_fit_written_as_the_machine_files_start_is_where_compare_starts(tmp_path, capsys):
    """record_start (the loop's, at every step) writes a fit as the file's [start] table,
    in place of the one before and after the user's text; compare --machine then polishes
    from it as well, so its fit is no worse than the one written, at a budget whose own
    swarm lands far from it (bench/RESULTS.md section 13). A [start] that is not a table of
    numbers is one line."""
    import json

    from pydiag.loop.machine_edits import START_NOTE, record_start
    rec, machine = tmp_path / "box.csv", tmp_path / "box.toml"
    write_measurement(rec, gearbox_record(4, box=SHORT_BOX))
    text = COMMENTED_BOX
    machine.write_text(text)
    common = ("-m", "pydiag", "compare", "--measurement", str(rec), "--machine", str(machine),
              "--build-dir", str(tmp_path / "build"), "--history", str(tmp_path / "h.sqlite"),
              "--quiet", "--speed", "mesh", "--no-validate", "--force", "--polish", "10")
    r = run_cli(*common, "--particles", "10", "--iterations", "6", "--json",
                str(tmp_path / "fit.json"))
    assert r.returncode == 0, r.stderr
    fit = json.loads((tmp_path / "fit.json").read_text())
    record_start(machine, {"stage_1.a0": 0.5})
    edited = record_start(machine, fit["parameters"])  # the one before replaced
    written = machine.read_text()
    assert written.startswith(text) and written.count("[start]") == 1
    assert written.count(START_NOTE) == 1 and '"stage_1.a0" = 0.5\n' not in written
    assert dict(load_machine(machine).start) == dict(edited.start) == pytest.approx(
        fit["parameters"])
    r = run_cli(*common, "--particles", "4", "--iterations", "1", "--json",
                str(tmp_path / "again.json"))
    assert r.returncode == 0, r.stderr
    again = json.loads((tmp_path / "again.json").read_text())
    assert again["fit_error"] <= fit["fit_error"] and again["warnings"] == []
    # a name the model does not fit (an effect taken out of the file) is said, not used
    record_start(machine, {**fit["parameters"], "stage_1.m_p": 0.2})
    r = run_cli(*common, "--particles", "4", "--iterations", "1", "--json",
                str(tmp_path / "again.json"))
    assert r.returncode == 0, r.stderr
    said = "[start] names what its model does not fit, not used: stage_1.m_p"
    assert said in r.stderr and said in json.loads((tmp_path / "again.json").read_text())[
        "warnings"][-1]
    machine.write_text(text + '[start]\n"stage_1.a0" = "high"\n')
    assert "start: a table of parameter names and finite numbers" in refused(
        capsys, *common[2:])


def test_each_stage_sees_the_machines_lines_from_its_own_shafts():
    """Seen from the output stage, its mesh is "mesh" and the input stage's a stage_mesh
    line; the catalogue named for it fits ``output_stage.<name>``, its hint's ranges named
    so too, and an effect on the acceleration changes every sensor's acceleration."""
    from pydiag.gear.effects import EFFECTS
    from pydiag.gear.kinematic_map import kinematic_map, match
    from pydiag.loop.stage_catalogue import stage_effect
    phm = load_machine(ROOT / "examples" / "phm09_spur.toml")
    model = machine_model(phm)
    views = [phm.model_kinematics(30.0, k) for k in (0, 1)]
    assert views[0].period_s == pytest.approx(views[1].period_s) == pytest.approx(0.5)
    lines = [kinematic_map(v, 2000.0) for v in views]
    bin_hz = 1 / views[0].period_s
    assert [match(480.0, ln, bin_hz).family for ln in lines] == ["stage_mesh", "mesh"]
    assert [match(960.0, ln, bin_hz).family for ln in lines] == ["mesh", "mesh"]  # shared
    effects = model.stage_effects(1)
    assert "housing_sensor" not in effects  # a sensor's path, not a stage's
    # a bearing's effect on a stage is the first bearing on its pinion's shaft (the idler's
    # ID:IS, an ER-10K): its geometry from the machine file, named for the stage; the last
    # stage's gear bearing the output's, at the output's speed (48/80 of the idler's)
    outer = effects["bearing_outer_race"]
    assert outer.values_from(views[1]) == {
        "output_stage.n_balls": 8.0, "output_stage.d_ball": pytest.approx(7.9375e-3),
        "output_stage.d_pitch": pytest.approx(33.5026e-3), "output_stage.alpha_contact": 0.0,
        "output_stage.r_shaft": 1.0}
    gear_outer = effects["gear_bearing_outer_race"].values_from(views[1])
    assert gear_outer["output_stage.r_shaft"] == pytest.approx(48 / 80)
    tooth = effects["gear_tooth_fault"]
    assert [p.name for p in tooth.parameters] == ["output_stage.d_g", "output_stage.tooth_g"]
    assert tooth.hint([], 0.0, views[1]) == {"output_stage.tooth_g": (0.0, 80.0)}
    shafts = stage_effect(EFFECTS["pinion_shaft_orders"], "output_stage", model.quantities)
    assert shafts.outputs == ("acc_ch1", "acc_ch2")
    assert dataclasses.replace(shafts, outputs=None).changes("acc_ch1")
    # a torque ripple is read from periods on any stage (the meshes are not coupled), a
    # speed ripple only on a stage alone in its machine (else its model ripples that stage)
    load = effects["load_fluctuation"].ripple
    assert load.variables == ("output_stage.dT", "output_stage.f_load", "output_stage.T")
    assert load.accelerations == ("acc_ch1", "acc_ch2")
    assert effects["speed_fluctuation"].ripple is None
    alone = stage_effect(EFFECTS["speed_fluctuation"], "stage", model.quantities, alone=True)
    assert alone.ripple.variables == ("stage.ds", "stage.f_speed")


def test_a_torque_ripple_on_one_stage_is_read_from_periods_of_the_machines_model(tmp_path):
    """A torque ripple on the second of two stages, read from two periods of the machine's
    model without it (the stage's torque stepped: its load follows, the other stage's mesh
    does not see it), is the machine's model with the ripple integrated whole."""
    from pydiag.fmu.periodic import simulate_period
    from pydiag.fmu.plant import FmuPlant
    from pydiag.gear.machine import StageEffect
    from pydiag.signal.ripple import OVERSAMPLE
    machine = dataclasses.replace(SHORT_MACHINE,
                                  effects=(StageEffect("load_fluctuation", 1),))
    model, built = machine_fmu(machine, MODELICA, tmp_path)
    ripple = model.ripple
    assert ripple.torque_variable == f"{model.stages[1]}.T"
    outputs, rate_hz, warmup_s = tuple(o.name for o in model.outputs), 20_000.0, 0.3
    period_s = machine.model_kinematics(INPUT_HZ).period_s
    values = {ripple.amplitude_variable: 10.0, ripple.freq_variable: 4.0}
    with FmuPlant(str(built.fmu), outputs, rate_hz) as plant:
        torque = float(plant.variables[ripple.torque_variable].start)
        whole = plant.simulate(values, 1.0, warmup_s)
        steady = plant.simulate({ripple.amplitude_variable: 0.0}, 1.0, warmup_s)
        read = ripple.read(lambda changes: simulate_period(
            plant, {**values, **changes}, warmup_s, period_s, OVERSAMPLE),
            {**values, ripple.torque_variable: torque}, outputs, whole.shape[1], rate_hz,
            warmup_s)

    def spectrum(y):
        return np.abs(np.fft.rfft((y - y.mean()) * np.hanning(y.size)))
    for i in range(len(outputs)):
        b = spectrum(whole[i])
        error = np.linalg.norm(spectrum(read[i]) - b) / np.linalg.norm(b)
        assert error < 0.01
        assert np.linalg.norm(spectrum(steady[i]) - b) / np.linalg.norm(b) > 10 * error


@pytest.mark.slow
def test_the_effect_the_box_has_is_confirmed_held_out_on_each_stage(tmp_path):
    """compare --machine tries what the residual points to on each stage held out: the
    stiffness wave's even harmonics (the box's meshes have harmonics 1, 1/2, 1/3 at phases
    of their own) confirmed on both stages, nothing else confident."""
    import json
    rec, machine = tmp_path / "box.csv", tmp_path / "box.toml"
    write_measurement(rec, gearbox_record(5, faulty_shaft=2, stage=1, box=SHORT_BOX))
    machine.write_text('name = "short box"\ninput_rpm = 1500\n'
                       '[[stages]]\npinion_teeth = 18\ngear_teeth = 36\n'
                       '[[stages]]\npinion_teeth = 20\ngear_teeth = 50\n')
    r = run_cli("-m", "pydiag", "compare", "--measurement", str(rec), "--machine", str(machine),
                "--build-dir", str(tmp_path / "build"), "--history", str(tmp_path / "h.sqlite"),
                "--quiet", "--speed", "mesh", "--particles", "10", "--iterations", "8",
                "--polish", "100", "--json", str(tmp_path / "c.json"))
    assert r.returncode == 0, r.stderr
    found = json.loads((tmp_path / "c.json").read_text())["suggested_effects"]
    assert sorted((s["effect"], s["stage"]) for s in found if s["confident"]) == [
        ("mesh_stiffness_shape", "stage 1"), ("mesh_stiffness_shape", "stage 2")]
    assert "mesh_stiffness_shape on stage 2" in r.stdout


def test_discover_tries_an_effect_on_every_stage_of_the_machines_model(tmp_path, capsys):
    """discover --machine without --fmu: the effect asked for, tried held out on each stage
    of the machine's own model (a row a stage, named for it, in the text and the JSON; every
    order of the 18-tooth pinion driving 36 is also one of its gear's and an output order,
    so it is fitted only where its line stands out of those shafts' orders around it: not
    where the output's broken tooth strikes). An effect no stage can have, and --stage
    without --fmu, are one line each."""
    import json
    rec, machine = tmp_path / "box.csv", tmp_path / "box.toml"
    write_measurement(rec, gearbox_record(5, faulty_shaft=2, stage=1, box=SHORT_BOX))
    machine.write_text(BOX)
    common = ("discover", "--measurement", str(rec), "--machine", str(machine), "--speed",
              "mesh", "--build-dir", str(tmp_path / "build"), "--quiet")
    from pydiag.app.cli import main
    assert main([*common, "--effects", "pinion_shaft_orders", "--particles", "6", "--iterations",
                 "2", "--polish", "10", "--json", str(tmp_path / "d.json")]) == 0
    out = capsys.readouterr().out
    rows = json.loads((tmp_path / "d.json").read_text())["ranking"]
    tried = {d["stage"]: d for d in rows if d["effect"] == "pinion_shaft_orders"}
    assert sorted(tried) == ["stage 1", "stage 2"] and tried["stage 2"]["z"] is not None
    # the output's broken tooth strikes at every output order, and each input order is
    # the 5th of those: none stands out of the output's orders around it
    assert tried["stage 1"]["status"] == "not tried", tried["stage 1"]
    assert "another shaft's orders" in tried["stage 1"]["message"]
    assert "pinion_shaft_orders on stage 1" in out and "pinion_shaft_orders on stage 2" in out
    assert "not an effect a stage of a machine's model can have: housing_sensor" in refused(
        capsys, *common, "--effects", "housing_sensor")
    assert "--stage 2: discover fits that stage's pair model: give it with --fmu" in refused(
        capsys, *common, "--stage", "2")


@pytest.mark.slow
def test_discover_finds_the_boxs_effect_on_each_stage(tmp_path):
    """discover on the machine's own model, every effect the stages can have: the box's
    two effects on both stages confident (an effect on one stage does not compete with
    itself on the other): the stiffness wave's even harmonics (its meshes have harmonics 1,
    1/2, 1/3 at phases of their own) and the mesh's modulation once per turn of each shaft
    (10 % by each of its two shafts); nothing else confident (a swing of the shafts, whose
    first sidebands are the modulation's, ranks high but is outcompeted by it): what
    compare and the loop find, without the residual's pointing.

    The box also has a broken tooth on the output gear (stage 2's gear): it should be found
    as that gear's tooth fault. It is a known miss, said as such: the box writes it as a
    short dip of the mesh's amplitude once a turn, which the catalogue's forms (a stiffness
    loss while the tooth is alone in contact) fit only in part (bench/RESULTS.md 13)."""
    from pydiag.loop.effect_fit import EFFECT_REFIT
    from pydiag.loop.machine_discover import discover_machine
    from pydiag.loop.machine_fit import compare_machine
    m = gearbox_record(5, faulty_shaft=2, stage=1, box=SHORT_BOX)
    speed = machine_speed(m, SHORT_MACHINE, INPUT_HZ, SpeedSettings("mesh"))
    model, built = machine_fmu(SHORT_MACHINE, MODELICA, tmp_path)
    problem = machine_problem(built.fmu, model, m, SHORT_MACHINE, speed)
    base = compare_machine(problem, model, FaultEstimator(), FaultEstimator(**EFFECT_REFIT))
    found = discover_machine(problem, SHORT_MACHINE, model, base,
                             lambda machine: str(machine_fmu(machine, MODELICA, tmp_path)[1].fmu))
    confident = {(d.effect, d.stage) for d in found if d.confident}
    box = {(effect, stage) for effect in ("mesh_stiffness_shape", "mesh_modulation")
           for stage in ("stage 1", "stage 2")}
    tooth = ("gear_tooth_fault", "stage 2")
    assert box <= confident <= box | {tooth}, [(d.effect, d.stage, d.message) for d in found]
    if tooth not in confident:
        pytest.xfail("known miss: the box's broken output-gear tooth (a dip of the mesh's "
                     "amplitude once a turn) is fitted by the catalogue's tooth fault in part "
                     "only: " + next((d.message for d in found
                                      if (d.effect, d.stage) == tooth), "not tried"))


@pytest.mark.slow
def test_the_loop_on_the_machines_model_accepts_effect_after_effect(tmp_path):
    """pydiag loop --machine without --fmu: the box's effects accepted one step at a time
    (the mesh's modulation by its shafts and the stiffness wave's even harmonics), each
    confirmed held out, the error falling at every step, then nothing confident; nothing
    the box lacks is accepted; what is accepted is written into the copy of the machine
    file, the file given unchanged (the measured sequence: bench/RESULTS.md section 13).
    At least three of the four: the last, stage 1's modulation, is not told apart from a
    swing of its shafts held out (their first sidebands are the same), and then neither is
    accepted."""
    import json
    rec, machine = tmp_path / "box.csv", tmp_path / "box.toml"
    write_measurement(rec, gearbox_record(5, faulty_shaft=2, stage=1, box=SHORT_BOX))
    text = ('name = "short box"\ninput_rpm = 1500\n[[stages]]\npinion_teeth = 18\n'
            'gear_teeth = 36\n[[stages]]\npinion_teeth = 20\ngear_teeth = 50\n')
    machine.write_text(text)
    r = run_cli("-m", "pydiag", "loop", "--measurement", str(rec), "--machine", str(machine),
                "--build-dir", str(tmp_path / "build"), "--history", str(tmp_path / "h.sqlite"),
                "--quiet", "--speed", "mesh", "--max-steps", "5", "--json",
                str(tmp_path / "loop.json"))
    assert r.returncode == 0, r.stderr
    steps = json.loads((tmp_path / "loop.json").read_text())["steps"]
    box = {f"{effect} on stage {k}" for effect in ("mesh_modulation", "mesh_stiffness_shape")
           for k in (1, 2)}
    accepted = [s["effect"] for s in steps[:-1]]
    assert len(accepted) >= 3 and set(accepted) <= box and steps[-1]["effect"] is None, accepted
    assert not any(s["confident"] for s in steps[-1]["suggested_effects"])
    errors = [s["error"] for s in steps]
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    assert all(s["held_out_error_with"] < s["held_out_error_base"] for s in steps[:-1])
    assert machine.read_text() == text
    copy = load_machine(tmp_path / "box.loop.toml")
    assert [f"{e.key} on stage {e.stage + 1}" for e in copy.effects] == accepted


def test_any_machine_name_builds_and_two_machines_of_one_name_are_two_models(tmp_path):
    """A machine named as people name things (spaces, parentheses, quotes, a backslash,
    an accent) with an effect accepted builds an FMU (CasADi takes a letter, then letters,
    digits and single underscores); its name is kept for people in the model's
    description. Two machine files of one name with other teeth are two models, each
    with a source of its own: an edit of one's is never fitted for the other."""
    from pydiag.gear.machine import StageEffect
    one = load_machine(ROOT / "examples" / "gfd_spectraquest.toml")
    named = dataclasses.replace(one, name='SpectraQuest GFD (inferred teeth) "b\\ox" né',
                                effects=(StageEffect("gear_tooth_fault", 0),))
    model, built = machine_fmu(named, MODELICA, tmp_path)
    assert "__" not in model.name and model.name[0].isalpha()
    assert "SpectraQuest GFD (inferred teeth) 'b/ox' né: every stage" in model.source
    assert inspected(built.fmu)
    other = dataclasses.replace(named, stages=(dataclasses.replace(one.stages[0],
                                                                    gear_teeth=81),))
    assert machine_model(other, MODELICA).name != model.name


def test_a_pairs_outputs_are_its_channels_and_only_a_housing_accelerometer_gets_a_curve(
        tmp_path):
    """A machine file without sensors reads a record's `disp` channel as the mesh's
    deflection and every other as `acc` (a pair's outputs, as `pydiag simulate` names
    them), one gain each; one that places an accelerometer and a deflection sensor fits
    a gain curve on the accelerometer only (the housing is between it and the mesh, not
    between the mesh and its own deflection)."""
    from truth.gear_sim import TruthGear, record

    from pydiag.gear.machine_file import machine_from_dict
    m = record(TruthGear(), 4, 5)
    pair = {"name": "pair", "input_rpm": 1500,
            "stages": [{"pinion_teeth": 14, "gear_teeth": 21}]}
    placed = {**pair, "sensors": [{"channel": "acc", "output": "acc"},
                                  {"channel": "disp", "output": "disp"}]}
    for description, outputs, curved in ((pair, ["acc", "disp"], set()),
                                         (placed, ["acc_acc", "disp_disp"], {"acc"})):
        machine = machine_from_dict(description, "pair.toml")
        model, built = machine_fmu(machine, MODELICA, tmp_path)
        speed = machine_speed(m, machine, 25.0)
        problem = machine_problem(built.fmu, model, m, machine, speed)
        assert problem.channels == ("acc", "disp")
        assert list(problem.spec.sensors) == outputs
        assert problem.gain_curve == curved
