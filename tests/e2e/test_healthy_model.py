"""The model's verdict (`diagnose --machine` with a healthy model and two or more
baselines): the machine file's effects are those `pydiag loop` gave the gearbox
simulator's short box on a healthy record (tests/golden/short_box.loop.toml); each is
refitted held out on a record with a broken output-gear tooth, which the simulator writes
as a dip of the mesh's amplitude once a turn of the output shaft, not as the model's
modulation. The model's verdict then joins the indicators' on every gear its effects size."""

import csv
import json
import time
from pathlib import Path

from conftest import ROOT, run_cli
from truth.gearbox import SHORT_BOX, gearbox_record

from pydiag.io.measurements import write_measurement

HEALTHY_MODEL = ROOT / "tests" / "golden" / "short_box.loop.toml"


def diagnosed(tmp_path, record, *extra: str, run: str = "first"):
    """diagnose --machine (the healthy model) of ``record`` against the short box's healthy
    seeds 1 (the model's own record), 3 and 4 (its repeats), the files written in the
    folder ``run``: (its stdout, its JSON)."""
    folder = tmp_path / run
    folder.mkdir()
    healthy = []
    for seed in (1, 3, 4):
        healthy.append(folder / f"healthy_{seed}.csv")
        write_measurement(healthy[-1], gearbox_record(seed, box=SHORT_BOX))
    measured = folder / "record.csv"
    write_measurement(measured, record)
    out = folder / "out.json"
    r = run_cli("-m", "pydiag", "diagnose", "--machine", str(HEALTHY_MODEL), "--measurement",
                str(measured), *(a for h in healthy for a in ("--baseline", str(h))),
                "--json", str(out), "--build-dir", str(tmp_path / "build"), "--quiet",
                # a small swarm: the healthy fit polishes from the file's [start] too
                "--particles", "8", "--iterations", "4", "--polish", "60", *extra)
    assert r.returncode == 0, r.stderr
    return r.stdout, json.loads(out.read_text())


def test_the_healthy_models_modulation_names_the_broken_output_gear(tmp_path):
    broken = gearbox_record(2, faulty_shaft=2, stage=1, box=SHORT_BOX)
    started = time.perf_counter()
    stdout, report = diagnosed(tmp_path, broken)
    first_s = time.perf_counter() - started
    changes = report["model_changes"]
    own = {("stage 1", "mesh_stiffness_shape"), ("stage 2", "mesh_modulation"),
           ("stage 2", "mesh_stiffness_shape")}
    assert own <= {(c["stage"], c["effect"]) for c in changes}
    # the catalogue's faults the healthy model lacks (the default --lacking) are asked about
    # where the indicators see a change: the broken gear's stage; none names a part (the
    # simulator's dip of the mesh's amplitude is no tooth stiffness the catalogue has)
    lacking = [c for c in changes if (c["stage"], c["effect"]) not in own]
    assert ("stage 2", "gear_tooth_fault") in {(c["stage"], c["effect"]) for c in lacking}
    changed = [c for c in changes if c["changed"]]
    assert len(changed) == 1 and changed[0]["effect"] == "mesh_modulation", changes
    assert changed[0]["part"] == "gear" and changed[0]["components"] == ["50T gear of stage 2"]
    healthy_m_g, fitted_m_g = changed[0]["values"]["stage_2.m_g"]
    assert fitted_m_g > 1.15 * healthy_m_g  # the gear's modulation deepened
    assert all(c["margin"] < 1 for c in changes if not c["changed"])
    assert "mesh_modulation               stage 2         changed" in stdout
    assert ": 50T gear of stage 2" in stdout
    # every gear is covered by an effect of the model; the broken one changed by the model
    # and the indicators both (a modulation does not tell a tooth from a runout), the other
    # three good by both
    gears = {c["name"]: (c["state"], c["judge"]) for c in report["components"]
             if c["kind"] == "gear"}
    assert gears.pop("50T gear of stage 2") == ("changed", "both"), report["components"]
    assert set(gears.values()) == {("good", "both")}, gears
    assert report["components"][0]["name"] == "50T gear of stage 2"  # faulty ones first
    # the healthy model is kept in the history and found again by what it is fitted from
    # (the files' bytes, not their names): the same verdict without fitting it again
    assert "healthy    : the model fitted to " in stdout and "; kept in " in stdout
    started = time.perf_counter()
    again_stdout, again = diagnosed(tmp_path, broken, run="again")
    again_s = time.perf_counter() - started
    assert "; as kept in " in again_stdout
    assert again["model_changes"] == report["model_changes"]
    assert again["components"] == report["components"]
    print(f"first {first_s:.0f} s, with the healthy model kept {again_s:.0f} s")


def test_an_effect_the_healthy_model_lacks_names_the_input_bearings_outer_race(tmp_path):
    """The first question (--lacking): the outer race, which the healthy model has not,
    tried on both stages; the input bearing's strikes make every other line of the
    intermediate bearing's (half its speed), so stage 2's outer race rises too, and the
    larger change names the lines."""
    _, report = diagnosed(tmp_path, gearbox_record(2, box=SHORT_BOX,
                                                   bearing=((0, "outer", 6.0),)),
                          "--lacking", "bearing_outer_race")
    races = {c["stage"]: c for c in report["model_changes"]
             if c["effect"] == "bearing_outer_race"}
    assert races["stage 1"]["changed"] and races["stage 1"]["fault"] == "outer"
    assert races["stage 1"]["components"] == ["input bearing"]
    assert races["stage 1"]["values"]["stage_1.A_b"][0] == 0  # from off: the model lacks it
    assert not races["stage 2"]["changed"], races
    assert races["stage 2"]["beaten_by"] == "bearing_outer_race on stage 1"
    states = {c["name"]: (c["state"], c["judge"]) for c in report["components"]}
    assert states["input bearing"] == ("outer", "both")  # the envelope's line says so too
    assert states["intermediate bearing"] == ("good", "both")
    assert all(s == ("good", "both") for n, s in states.items() if "T " in n), states


def test_the_output_shafts_bearing_is_named_by_the_last_stages_gear_bearing(tmp_path):
    """The output shaft carries no stage's pinion: its bearing is the last stage's gear
    bearing. Its outer race's strikes (a fifth of the input's rate on the box's one
    geometry: every fifth line is the input bearing's, every other fifth the intermediate
    one's) are tried with the pinion bearings' races; no healthy record shows them, so
    they were not tried there (a z of 0), and the output bearing's change, the largest,
    claims the shared lines."""
    _, report = diagnosed(tmp_path, gearbox_record(2, box=SHORT_BOX,
                                                   bearing=((2, "outer", 6.0),)),
                          "--lacking", "bearing_outer_race,gear_bearing_outer_race")
    changed = [c for c in report["model_changes"] if c["changed"]]
    assert [(c["stage"], c["effect"], c["fault"], c["components"]) for c in changed] == [
        ("stage 2", "gear_bearing_outer_race", "outer", ["output bearing"])], changed
    races = {c["stage"]: c for c in report["model_changes"]
             if c["effect"] == "bearing_outer_race"}
    assert races["stage 1"]["beaten_by"] == "gear_bearing_outer_race on stage 2"
    states = {c["name"]: (c["state"], c["judge"]) for c in report["components"]}
    assert states["output bearing"] == ("outer", "both")
    assert all(s[0] == "good" for n, s in states.items() if n != "output bearing"), states


def test_batch_judges_every_record_by_the_healthy_model_fitted_once(tmp_path):
    """batch --machine with the healthy model: fitted (or found kept) once before the
    records, grown once by the lacking effects any record asks for, each record's changes
    a column and its components' states the joined ones: what diagnose says of the
    record."""
    folder, records = tmp_path / "baselines", tmp_path / "records"
    folder.mkdir()
    records.mkdir()
    healthy = []
    for seed in (1, 3, 4):
        healthy.append(folder / f"healthy_{seed}.csv")
        write_measurement(healthy[-1], gearbox_record(seed, box=SHORT_BOX))
    broken = gearbox_record(2, faulty_shaft=2, stage=1, box=SHORT_BOX)
    write_measurement(records / "broken.csv", broken)
    write_measurement(records / "healthy_5.csv", gearbox_record(5, box=SHORT_BOX))
    out = tmp_path / "rows.csv"
    r = run_cli("-m", "pydiag", "batch", "--machine", str(HEALTHY_MODEL), "--measurements",
                str(records), "--out", str(out), "--build-dir", str(tmp_path / "build"),
                *(a for h in healthy for a in ("--baseline", str(h))), "--quiet",
                "--particles", "8", "--iterations", "4", "--polish", "60")
    assert r.returncode == 0, r.stderr
    assert r.stdout.count("healthy    : the model fitted to ") == 1, r.stdout
    assert "more of its lacking effects tried on them, kept again" in r.stdout, r.stdout
    rows = {Path(row["measurement"]).name: row for row in csv.DictReader(out.open())}
    assert rows["broken.csv"]["model"].startswith(
        "mesh_modulation on stage 2: changed"), rows["broken.csv"]["model"]
    assert rows["broken.csv"]["50T gear of stage 2:state"] == "changed"
    assert rows["healthy_5.csv"]["model"] == "", rows["healthy_5.csv"]["model"]
    assert rows["healthy_5.csv"]["faulty"] == ""
    # one path: diagnose asks the record the same lacking effects of the same model
    _, alone = diagnosed(tmp_path, broken, run="alone")
    asked = {(c["stage"], c["effect"]) for c in alone["model_changes"]}
    assert ("stage 2", "gear_tooth_fault") in asked  # a lacking effect, tried in the batch too
    assert {c["name"]: c["state"] for c in alone["components"]} == {
        k.removesuffix(":state"): v for k, v in rows["broken.csv"].items()
        if k.endswith(":state")}
    assert rows["broken.csv"]["model"] == "; ".join(
        f"{c['effect']} on {c['stage']}: {c['fault']} ({c['margin']:.2f} x)"
        + (f", {', '.join(c['components'])}" if c["components"] else "")
        for c in alone["model_changes"] if c["changed"])


def test_of_one_baseline_file_the_healthy_fit_is_kept_and_each_record_polishes_it(tmp_path):
    """One --baseline file (the README's command): no healthy repeat, so the model judges no
    component (said, and a warning); but its fit to the baseline is kept in the history and
    each record's fit is that fit polished (at most the polish's budget and one more), not
    a swarm from nothing, record after record."""
    baseline, history = tmp_path / "healthy_1.csv", tmp_path / "h.sqlite"
    write_measurement(baseline, gearbox_record(1, box=SHORT_BOX))
    runs = []
    for name, record in (("broken", gearbox_record(2, faulty_shaft=2, stage=1, box=SHORT_BOX)),
                         ("healthy", gearbox_record(5, box=SHORT_BOX))):
        measured, out = tmp_path / f"{name}.csv", tmp_path / f"{name}.json"
        write_measurement(measured, record)
        r = run_cli("-m", "pydiag", "diagnose", "--machine", str(HEALTHY_MODEL),
                    "--measurement", str(measured), "--baseline", str(baseline),
                    "--json", str(out), "--build-dir", str(tmp_path / "build"), "--quiet",
                    "--history", str(history), "--particles", "8", "--iterations", "4",
                    "--polish", "60")
        assert r.returncode == 0, r.stderr
        runs.append((r, json.loads(out.read_text())))
    for (r, report), kept in zip(runs, ("; kept in ", "; as kept in ")):
        assert "no healthy repeat to hold a record to" in r.stdout and kept in r.stdout
        assert "needs two --baseline files" in r.stderr and "1 given" in r.stderr
        assert report["model_changes"] == []
        assert {c["judge"] for c in report["components"]} == {"indicators"}
        assert all(1 < s["model"]["evaluations"] <= 61 for s in report["stages"])
    broken = {c["name"]: c["state"] for c in runs[0][1]["components"]}
    assert broken["50T gear of stage 2"] == "changed"  # the indicators' word


def test_a_record_is_fitted_from_the_healthy_fit_without_a_swarm(tmp_path):
    """refit_machine: the short box's model with the loop's effects, its fit on healthy
    seed 1 (the file's [start]) polished on a record with a broken output-gear tooth, no
    swarm: one simulation at the start, at most the polish's budget more, the error below
    the start's, every parameter of the model given a value, and the output gear's
    modulation deeper than the healthy fit's."""
    from pydiag.diagnose.stages import machine_speed
    from pydiag.fit.estimator import FaultEstimator
    from pydiag.gear.machine_file import load_machine
    from pydiag.gear.speed import SpeedSettings
    from pydiag.loop.machine_fit import machine_problem, refit_machine
    from pydiag.loop.machine_model import machine_fmu
    from truth.gearbox import INPUT_HZ

    machine = load_machine(HEALTHY_MODEL)
    model, built = machine_fmu(machine, ROOT / "modelica", tmp_path)
    record = gearbox_record(2, faulty_shaft=2, stage=1, box=SHORT_BOX)
    problem = machine_problem(built.fmu, model, record, machine,
                              machine_speed(record, machine, INPUT_HZ, SpeedSettings("mesh")))
    start = machine.fit_start()
    at_start = refit_machine(problem, model, FaultEstimator(polish_evaluations=0), start)
    fit = refit_machine(problem, model, FaultEstimator(polish_evaluations=100), start)
    assert at_start.evaluations == 1 and 1 < fit.evaluations <= 101
    assert fit.error < at_start.error
    assert set(fit.parameters) == {p.name for p in problem.parameters}
    assert fit.parameters["stage_2.m_g"] > start["stage_2.m_g"]  # the gear's modulation deepens


def test_a_healthy_model_grown_record_by_record_holds_what_one_grown_at_once_does(tmp_path):
    """with_lacking: the rows of the lacking effects a record first asks for, tried on the
    healthy model's own records. Asked one stage at a time (two records, each asking about
    one bearing), the model holds the same rows as asked both at once, so a record's
    verdict does not depend on which records came before it; asked again, nothing is
    tried."""
    from pydiag.diagnose.stages import healthy_problems
    from pydiag.gear.machine_file import load_machine
    from pydiag.loop.machine_model import machine_fmu
    from pydiag.loop.own_changes import HealthyModel, with_lacking
    from truth.gearbox import INPUT_HZ

    machine = load_machine(HEALTHY_MODEL)
    model, built = machine_fmu(machine, ROOT / "modelica", tmp_path)
    first, *repeats = healthy_problems(str(built.fmu), model, machine,
                                       [gearbox_record(s, box=SHORT_BOX) for s in (1, 3, 4)],
                                       INPUT_HZ)
    start = machine.fit_start()
    healthy = HealthyModel({p.name: start.get(p.name, p.off) for p in first.parameters}, 0.01,
                           {}, ({}, {}), ("bearing_outer_race",))

    def effect_model(with_one):
        return str(machine_fmu(with_one, ROOT / "modelica", tmp_path)[1].fmu)
    one, two = ("stage 1", "bearing_outer_race"), ("stage 2", "bearing_outer_race")
    stepwise = with_lacking(healthy, machine, model, first, repeats, {one}, effect_model)
    assert stepwise.held == (one,)
    stepwise = with_lacking(stepwise, machine, model, first, repeats, {one, two}, effect_model)
    at_once = with_lacking(healthy, machine, model, first, repeats, {one, two}, effect_model)
    assert stepwise.held == at_once.held == (one, two)
    assert set(at_once.baseline_z) == {one, two}  # tried there: lines of theirs stood out
    assert stepwise.baseline_z == at_once.baseline_z and stepwise.repeat_z == at_once.repeat_z
    assert with_lacking(at_once, machine, model, first, repeats, {two}, effect_model) is at_once
