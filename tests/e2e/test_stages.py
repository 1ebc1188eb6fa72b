"""diagnose of a two-stage machine, stage by stage (:mod:`pydiag.diagnose.stages`), on records
of :mod:`truth.gearbox` (written from the shafts' angles, not by the pair model fitted):
each stage fitted at its own shafts on its own lines, and judged against a healthy
baseline."""

import numpy as np
import pytest
from boxes import MACHINE
from truth.gearbox import INPUT_HZ, gearbox_record

from pydiag.fit.estimator import FaultEstimator
from pydiag.fit.build import ProblemSettings
from pydiag.gear.features import KinematicFeaturizer
from pydiag.gear.machine_indicators import machine_record
from pydiag.gear.speed import SpeedSettings
from pydiag.diagnose.stages import diagnose_machine, stage_problem

SMALL = dict(n_particles=8, iterations=6, polish_evaluations=60)


def test_a_stage_is_fitted_at_its_own_shafts_without_the_other_stages_lines(gear_fmu):
    from pydiag.gear.speed import estimate_speed
    m = gearbox_record(2)
    speed = estimate_speed(m, MACHINE.stage_kinematics(0, INPUT_HZ), SpeedSettings("mesh"),
                           machine=MACHINE)
    problem = stage_problem(str(gear_fmu), m, MACHINE, 1, speed)
    kin = problem.kinematics
    assert (kin.n_pinion, kin.n_gear) == (24, 54)
    assert kin.f_pinion_hz == pytest.approx(speed.speed_hz * 20 / 64)
    lines = problem.reference["acc"].freq_hz
    first_mesh = 20 * speed.speed_hz  # stage 1's mesh lies in stage 2's third mesh band
    assert 2.5 * kin.f_mesh_hz < first_mesh < 3.5 * kin.f_mesh_hz
    assert np.min(np.abs(lines - first_mesh)) > 0.4 * kin.f_hunting_hz
    whole = KinematicFeaturizer(kin)(problem.measurement.channels["acc"],
                                     problem.measurement.sample_rate_hz).freq_hz
    assert np.min(np.abs(whole - first_mesh)) < 1e-6 * first_mesh  # there without exclusion


def test_every_stage_diagnosed_and_the_broken_one_judged_changed(gear_fmu):
    result = diagnose_machine(str(gear_fmu), gearbox_record(3, faulty_shaft=2, stage=1),
                              MACHINE, INPUT_HZ, ProblemSettings(speed=SpeedSettings("mesh")),
                              FaultEstimator(**SMALL),
                              baselines=[machine_record(gearbox_record(1), MACHINE,
                                                        SpeedSettings("mesh"), INPUT_HZ)])
    first, second = result.stages
    assert first.fault_mode == "healthy" and first.severity == "none"
    assert second.verdict.changed and second.suspect == "gear"
    assert second.fault_mode != "healthy"
    data = result.to_dict()
    assert [s["mesh_hz"] for s in data["stages"]] == pytest.approx(
        [20 * result.speed.speed_hz, 20 / 64 * 24 * result.speed.speed_hz])
    assert data["speed_hz"] == pytest.approx(INPUT_HZ * 0.99, rel=1e-3)
    assert "baselines" in data["severity_scale"] and data["healthy_spread_db"] > 0


def test_batch_diagnoses_every_stage_of_every_record(gear_fmu, tmp_path):
    import pandas as pd
    from conftest import run_cli

    from pydiag.io.measurements import write_measurement
    folder = tmp_path / "records"
    folder.mkdir()
    write_measurement(folder / "healthy.csv", gearbox_record(2))
    write_measurement(folder / "broken.csv", gearbox_record(3, faulty_shaft=0, stage=0))
    write_measurement(tmp_path / "baseline.csv", gearbox_record(1))
    machine = tmp_path / "box.toml"
    machine.write_text(f'name = "{MACHINE.name}"\ninput_rpm = {60 * INPUT_HZ}\n'
                       + "".join(f"[[stages]]\npinion_teeth = {s.pinion_teeth}\n"
                                 f"gear_teeth = {s.gear_teeth}\n" for s in MACHINE.stages))
    out = tmp_path / "rows.csv"
    # the verdicts are the baseline's: the smallest fit will do
    res = run_cli("-m", "pydiag", "batch", "--fmu", str(gear_fmu), "--machine", str(machine),
                  "--measurements", str(folder), "--baseline", str(tmp_path / "baseline.csv"),
                  "--out", str(out), "--speed", "mesh", "--particles", "4", "--iterations",
                  "2", "--polish", "0", "--workers", "2", "--quiet")
    assert res.returncode == 0, res.stderr
    rows = pd.read_csv(out).set_index("measurement")
    # the baseline is read once, before any record: one that is not there stops the batch
    res = run_cli("-m", "pydiag", "batch", "--fmu", str(gear_fmu), "--machine", str(machine),
                  "--measurements", str(folder), "--baseline", str(tmp_path / "none.csv"),
                  "--out", str(tmp_path / "none_rows.csv"), "--speed", "mesh", "--quiet")
    assert res.returncode == 2 and "none.csv" in res.stderr, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and not (tmp_path / "none_rows.csv").exists()
    broken = rows.loc[str(folder / "broken.csv")]
    healthy = rows.loc[str(folder / "healthy.csv")]
    assert (broken["status"], healthy["status"]) == ("ok", "ok"), rows["message"]
    assert broken["stage 1:suspect"] == "pinion" and broken["fault_mode"] != "healthy"
    assert (healthy["stage 1:fault_mode"], healthy["stage 2:fault_mode"]) == ("healthy",
                                                                              "healthy")
    assert healthy["fault_mode"] == "healthy" and healthy["severity"] == "none"
    assert broken["stage 1:change_db"] > healthy["stage 1:change_db"]
    # every component judged against the baseline, a column each, the faulty in one
    pinion = f"{MACHINE.stages[0].pinion_teeth}T pinion of stage 1"
    assert broken[f"{pinion}:state"] == "changed" and pinion in broken["faulty"], broken
    assert healthy[f"{pinion}:state"] == "good" and pd.isna(healthy["faulty"]), healthy


def test_compare_of_one_stage_names_the_other_stages_lines(gear_fmu):
    """Stage 2 compared on a two-stage record: stage 1's mesh and its sidebands, which no
    pair model of stage 2 makes, are the other stage's lines in the peaks and the residual
    families, not unexplained, and not in the error (as in the stage's fit); the cursors
    mark both stages' meshes."""
    from pydiag.gear.speed import estimate_speed
    from pydiag.loop.compare import compare
    m = gearbox_record(4)
    speed = estimate_speed(m, MACHINE.stage_kinematics(0, INPUT_HZ), SpeedSettings("mesh"),
                           machine=MACHINE)
    problem = stage_problem(str(gear_fmu), m, MACHINE, 1, speed)
    c = compare(problem, FaultEstimator(n_particles=4, iterations=2, polish_evaluations=20))
    first_mesh = 20 * speed.speed_hz
    near = [p for p in c.peaks if abs(p.freq_hz - first_mesh) < 1.5 * c.bin_hz]
    assert near and {p.family for p in near} == {"stage_mesh"}, near
    assert any(p.family == "stage_mesh_sb" for p in c.peaks)
    assert not [p for p in c.peaks if p.family == "unexplained"
                and p.energy_fraction > 0.01], c.peaks[:5]
    shares = c.residual_by_family["acc"]
    assert shares["other_stages"]["measured"] > 0.2, shares
    from pydiag.loop.residual import measured_spectra
    scored = measured_spectra(problem, c.false_alarm_rate).featurizer.bins
    freqs = np.asarray(c.spectra["acc"].freq_hz)
    assert not scored[np.abs(freqs - first_mesh) < 1.5 * c.bin_hz].any()
    assert scored[np.abs(freqs - problem.kinematics.f_mesh_hz) < 0.5 * c.bin_hz].all()
    assert c.n_error_bins == np.count_nonzero(scored)
    assert {"mesh", "stage_mesh"} <= {mk["family"] for mk in c.markers}
