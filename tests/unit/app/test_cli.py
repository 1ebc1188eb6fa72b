"""The command line's contract: user errors exit 2 with one line, bugs exit 3 and say so,
every number is checked before any work."""

import pytest

from pydiag.app import arguments, cli
from pydiag.core.errors import MeasurementError


def run(argv, capsys):
    try:
        code = cli.main(argv)
    except SystemExit as stop:
        code = stop.code
    err = capsys.readouterr().err
    return code, err


def test_a_pydiag_error_is_the_users_to_fix(monkeypatch, capsys):
    def fails(args):
        raise MeasurementError("m.csv: column 'acc' contains NaN values")
    monkeypatch.setattr(cli, "cmd_inspect", fails)
    code, err = run(["inspect", "x.fmu"], capsys)
    assert code == 2 and err == "pydiag inspect: error: m.csv: column 'acc' contains NaN values\n"


@pytest.mark.parametrize("bug", [ValueError("operands could not be broadcast together"),
                                 OSError("disk on fire"), ZeroDivisionError("division by zero")])
def test_anything_else_is_an_internal_error_never_the_users(monkeypatch, capsys, bug):
    def fails(args):
        raise bug
    monkeypatch.setattr(cli, "cmd_inspect", fails)
    monkeypatch.delenv("PYDIAG_DEBUG", raising=False)
    code, err = run(["inspect", "x.fmu"], capsys)
    assert code == 3 and "internal error" in err and "a bug in pydiag" in err
    assert len(err.strip().splitlines()) == 1
    monkeypatch.setenv("PYDIAG_DEBUG", "1")
    with pytest.raises(type(bug)):
        cli.main(["inspect", "x.fmu"])


@pytest.mark.parametrize("argv,message", [
    (["diagnose", "--workers", "0"], "--workers: 0 must be >= 1"),
    (["diagnose", "--polish", "-5"], "--polish: -5 must be >= 0"),
    (["diagnose", "--seed", "-1"], "--seed: -1 must be >= 0"),
    (["diagnose", "--particles", "many"], "--particles: 'many' is not an integer"),
    (["diagnose", "--eval-timeout", "0"], "--eval-timeout: 0 must be > 0"),
    (["compare", "--false-alarm-rate", "0"], "--false-alarm-rate: 0 must be > 0"),
    (["compare", "--false-alarm-rate", "-1"], "--false-alarm-rate: -1 must be > 0"),
    (["compare", "--bearing", "9,40,39.04"], "ball diameter < pitch diameter"),
    (["compare", "--bearing", "9.5,7.94,39.04"], "positive integer"),
    (["compare", "--effect", "gremlins"], "invalid choice: 'gremlins'"),
    (["discover", "--effects", "backlash,gremlins"], "unknown effect(s) gremlins"),
    (["compare", "--other-shaft", "29/0"], "positive speed ratio"),
    (["discover", "--other-shaft", "-1.7"], "positive speed ratio"),
    (["compare", "--other-shaft", "fast"], "got 'fast'"),
    (["regress", "--rtol", "nan"], "--rtol: 'nan' is not a finite number"),
    (["simulate", "--snr", "0"], "--snr: 0 must be > 0"),
    (["simulate", "--set", "f_pinion"], "--set: takes NAME=VALUE"),
])
def test_numbers_are_checked_at_parse_time(capsys, argv, message):
    base = {"diagnose": ["--fmu", "f.fmu", "--measurement", "m.csv"],
            "compare": ["--fmu", "f.fmu", "--measurement", "m.csv"],
            "discover": ["--fmu", "f.fmu", "--measurement", "m.csv"],
            "regress": ["--fmu", "f.fmu", "--golden", "g.json"],
            "simulate": ["--fmu", "f.fmu", "--out", "o.csv"]}[argv[0]]
    code, err = run([argv[0], *base, *argv[1:]], capsys)
    assert code == 2 and message in err, err
    assert len(err.strip().splitlines()) == 1


def test_more_workers_than_cores_is_refused_unless_asked(capsys, monkeypatch, tmp_path):
    """--workers 1000 started 1085 processes (4 GB, 20 times slower)."""
    monkeypatch.setattr(cli.os, "cpu_count", lambda: 2)
    base = ["diagnose", "--fmu", str(tmp_path / "f.fmu"), "--measurement", str(tmp_path / "m.csv")]
    code, err = run([*base, "--workers", "1000"], capsys)
    assert code == 2 and "--workers: 1000 is more than the 2 cores" in err, err
    code, err = run([*base, "--workers", "3", "--oversubscribe"], capsys)
    assert code == 2 and "--workers" not in err and "m.csv" in err, err  # got past the check


@pytest.mark.parametrize("text,ratio", [("1.706", 1.706), ("29/17", 29 / 17),
                                        ("14/21*19/47", 14 / 21 * 19 / 47), ("2*0.5", 1.0)])
def test_a_speed_ratio_is_a_number_a_fraction_or_a_product_of_them(text, ratio):
    assert arguments.speed_ratio(text) == pytest.approx(ratio, rel=1e-12)


@pytest.mark.parametrize("extra, message", [
    ([], "2 stages; compare fits one stage's pair model: give --stage (1 or 'input stage', "
         "2 or 'output stage')"),
    (["--stage", "3"], "no stage '3'; the stages are 1 (input stage), 2 (output stage)"),
    (["--stage", "1", "--other-shaft", "0.2"], "describes the machine's: give them there"),
])
def test_compare_on_a_machine_of_several_stages_fits_the_stage_named(capsys, extra, message):
    from pathlib import Path
    machine = Path(__file__).resolve().parents[3] / "examples" / "phm09_spur.toml"
    code, err = run(["compare", "--fmu", "x.fmu", "--measurement", "m.csv", "--machine",
                     str(machine), *extra], capsys)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("command", ["compare", "loop"])
def test_a_stage_without_its_fmu_is_refused_not_ignored(capsys, command):
    """--stage names a stage's pair fit; without --fmu the machine's own model of every
    stage would be fitted instead, and the --stage given ignored."""
    from pathlib import Path
    machine = Path(__file__).resolve().parents[3] / "examples" / "phm09_spur.toml"
    code, err = run([command, "--measurement", "m.csv", "--machine", str(machine),
                     "--stage", "2"], capsys)
    assert code == 2 and "--stage 2: " + command + " fits that stage's pair model: give it " \
        "with --fmu" in err and len(err.strip().splitlines()) == 1, err


def test_a_machine_files_sensors_apply_to_the_channels_chosen_only():
    """--channel ch1 on a machine file that gives ch1 and ch2 in volts: ch1's unit is
    taken, ch2's is not (a unit for a channel not read was refused as if the user had
    given --unit for it)."""
    from pathlib import Path

    from pydiag.app.machine_options import apply_machine
    machine = Path(__file__).resolve().parents[3] / "examples" / "phm09_spur.toml"
    args = cli.build_parser().parse_args(["compare", "--fmu", "x.fmu", "--measurement", "m.csv",
                                          "--machine", str(machine), "--stage", "1",
                                          "--channel", "ch1=acc"])
    apply_machine(args)
    assert args.unit == ["ch1=V"] and args.channel == ["ch1=acc"]
    args = cli.build_parser().parse_args(["compare", "--fmu", "x.fmu", "--measurement", "m.csv",
                                          "--machine", str(machine), "--stage", "1"])
    apply_machine(args)
    assert args.unit == ["ch1=V", "ch2=V"]


@pytest.mark.parametrize("command", ["diagnose", "compare", "discover", "loop"])
def test_a_one_stage_machine_files_sensor_keeps_its_name_for_the_machines_model(command):
    """A one-stage machine file's sensor a1: a pair's FMU (--fmu) reads it as the output it
    measures (a1=acc); the machine's own model maps the file's channels itself and reads it
    as a1 (read as acc, it was "channel acc is none of the machine file's sensors")."""
    from pathlib import Path

    from pydiag.app.machine_options import apply_machine
    machine = str(Path(__file__).resolve().parents[3] / "examples" / "gfd_spectraquest.toml")
    common = [command, "--measurement", "m.csv", "--machine", machine]
    args = cli.build_parser().parse_args(common)
    apply_machine(args)
    assert args.channel == ["a1"]
    args = cli.build_parser().parse_args(common + ["--fmu", "x.fmu"])
    apply_machine(args)
    assert args.channel == ["a1=acc"]


@pytest.mark.parametrize("command", [["diagnose", "--measurement", "m.csv"],
                                     ["batch", "--measurements", "m.csv", "--out", "o.csv"]])
@pytest.mark.parametrize("extra", [
    [],  # no baseline: no healthy model
    ["--baseline", "a.csv", "--baseline", "kept"],  # kept baselines hold no record
])
def test_lacking_effects_need_the_healthy_model_and_its_repeat(capsys, tmp_path, extra,
                                                                command):
    from pathlib import Path
    machine = Path(__file__).resolve().parents[3] / "examples" / "phm09_spur.toml"
    if extra:  # a machine file with an effect
        machine = tmp_path / "with_effect.toml"
        machine.write_text(Path(__file__).resolve().parents[3].joinpath(
            "examples", "phm09_spur.toml").read_text()
            + '\n[[effects]]\nkey = "mesh_modulation"\nstage = "output stage"\n')
    code, err = run([*command, "--machine", str(machine), "--lacking", "bearing_outer_race",
                     *extra], capsys)
    assert code == 2 and "--lacking tries effects against the machine's healthy model" in err \
        and len(err.strip().splitlines()) == 1, err
