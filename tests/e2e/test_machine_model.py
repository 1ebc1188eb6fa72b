"""The machine's own model (:mod:`pydiag.loop.machine_model`): every stage of a machine file
in one Modelica model written by pydiag, built once per content, fitted to a record of
:mod:`truth.gearbox` (written from the shafts' angles, not by the pair model) over the
machine's period; and `pydiag compare --machine` without --fmu, which fits it."""

from pathlib import Path

import pytest
from conftest import inspected, run_cli
from truth.gearbox import INPUT_HZ, SHORT_MACHINE, gearbox_record

from pydiag.fit.estimator import FaultEstimator
from pydiag.gear.speed import SpeedSettings
from pydiag.io.measurements import write_measurement
from pydiag.loop.compare import compare
from pydiag.loop.machine_model import machine_fmu, machine_model, machine_problem
from pydiag.loop.stages import machine_speed

ROOT = Path(__file__).resolve().parents[2]
MODELICA = ROOT / "modelica"
SMALL = dict(n_particles=8, iterations=4, polish_evaluations=40)


def test_the_machine_model_explains_the_second_stages_lines(tmp_path):
    """The same record and bins, fitted by the model of both stages and by the same model
    with the second stage silenced: the first stage alone leaves the second's lines (most
    of the residual); with both, the error falls to well under half and so does what is
    left on those lines."""
    m = gearbox_record(3, machine=SHORT_MACHINE)
    model, fmu = machine_fmu(SHORT_MACHINE, MODELICA, tmp_path)
    inspected(fmu)
    assert machine_fmu(SHORT_MACHINE, MODELICA, tmp_path) == (model, fmu)  # cached
    speed = machine_speed(m, SHORT_MACHINE, INPUT_HZ, SpeedSettings("mesh"))
    problem = machine_problem(fmu, model, m, SHORT_MACHINE, speed)
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


def test_compare_without_an_fmu_writes_and_fits_the_machines_model(tmp_path):
    """The command line: the model's source is written where it says, readable (both
    stages in it), and the fit names every stage's parameters; an effect needs a stage."""
    rec = tmp_path / "box.csv"
    write_measurement(rec, gearbox_record(4, machine=SHORT_MACHINE))
    machine = tmp_path / "box.toml"
    machine.write_text('name = "short box"\ninput_rpm = 1500\n'
                       '[[stages]]\npinion_teeth = 18\ngear_teeth = 36\n'
                       '[[stages]]\npinion_teeth = 20\ngear_teeth = 50\n')
    common = ("-m", "pydiag", "compare", "--measurement", str(rec), "--machine", str(machine),
              "--build-dir", str(tmp_path / "build"), "--history", str(tmp_path / "h.sqlite"),
              "--quiet")
    r = run_cli(*common, "--particles", "6", "--iterations", "2", "--polish", "10",
                "--speed", "mesh")
    assert r.returncode == 0, r.stderr
    source = tmp_path / "build" / "machines" / "Machine_short_box.mo"
    assert f"model      : {source}" in r.stdout
    text = source.read_text()
    assert "GearDiag.GearPair stage_1(Np=18, Ng=36, f_pinion=f_input)" in text
    assert "GearDiag.GearPair stage_2(Np=20, Ng=50, f_pinion=f_input*1/2)" in text
    assert "stage_2.a_f=" in r.stdout and "acc_stage_2_dB=" in r.stdout
    r = run_cli(*common, "--effect", "gear_eccentricity")
    assert r.returncode == 2 and "--effect fits a pair's effect: give --stage" in r.stderr
    r = run_cli("-m", "pydiag", "compare", "--measurement", str(rec), "--quiet",
                "--sample-rate", "20000")
    assert r.returncode == 2 and "give --fmu, or --machine FILE" in r.stderr


def test_the_model_source_names_each_sensors_view_of_each_stage():
    """A sensor near a stage sees it as its own, every other stage through a level of its
    own (a parameter only a fit of that sensor estimates)."""
    from pydiag.gear.machine import load_machine
    model = machine_model(load_machine(ROOT / "examples" / "phm09_spur.toml"))
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
