"""The keys a machine's healthy model and its --baseline files' records are kept under in
the history (pydiag.app.baselines): anything they are made from changes them, nothing
else does."""

from pathlib import Path

from pydiag.app.baselines import healthy_fingerprint
from pydiag.app.cli import build_parser
from pydiag.gear.speed import SpeedSettings
from pydiag.loop.compose import BuiltModel
from pydiag.loop.stage_catalogue import FAULT_EFFECTS

ROOT = Path(__file__).resolve().parents[3]


def test_the_healthy_models_key_follows_what_it_is_fitted_from(tmp_path):
    first, repeat, fmu = (tmp_path / name for name in ("run2.csv", "run1.csv", "m.fmu"))
    first.write_text("t,acc\n0,1\n")
    repeat.write_text("t,acc\n0,2\n")
    fmu.write_bytes(b"an FMU")
    built = BuiltModel(fmu, tmp_path / "m.mo")

    def key(*extra: str) -> str:
        args = build_parser().parse_args([
            "diagnose", "--machine", str(ROOT / "examples" / "phm09_spur.toml"),
            "--measurement", "record.csv", "--baseline", str(first), "--baseline",
            str(repeat), *extra])
        return healthy_fingerprint(args, built, [str(first), str(repeat)])

    plain = key()
    assert key() == plain
    # outputs, what is said, how the work is spread and the record judged: the same model
    assert key("--json", "out.json", "--quiet", "--workers", "1", "--force") == plain
    # the fit's settings, the reading of the records: another model
    assert key("--particles", "8") != plain
    # the effects a record may be asked about: the fit does not depend on them (each is
    # tried on the healthy records when a record first asks for it)
    assert key("--lacking", "bearing_outer_race") == key("--lacking", "none") == plain
    assert key("--sample-rate", "66666.67") != plain
    repeat.write_text("t,acc\n0,3\n")  # the repeat's bytes
    assert key() != plain
    repeat.write_text("t,acc\n0,2\n")
    fmu.write_bytes(b"another FMU")  # the model built
    assert key() != plain


def test_a_healthy_model_is_asked_about_every_component_fault_of_the_catalogue():
    """The default --lacking: each effect that names a gear's, bearing's or shaft's fault,
    none that says only "changed", refines the pair's own pinion tooth or reshapes the
    base's own lines."""
    assert {"gear_tooth_fault", "gear_eccentricity", "pinion_eccentricity",
            "bearing_outer_race", "bearing_inner_race",
            "bearing_ball", "gear_bearing_outer_race", "pinion_shaft_orders",
            "other_shaft_orders"} <= set(FAULT_EFFECTS)
    assert not {"mesh_modulation", "mesh_stiffness_shape", "backlash", "pinion_tooth_softening",
                "second_pinion_tooth_fault", "housing_sensor"} & set(FAULT_EFFECTS)


def test_a_baseline_files_record_is_made_once_and_found_again(tmp_path, monkeypatch):
    """The --baseline files' records as the machine sees them, kept in the history the
    healthy model is kept in: made on the first call, found on the next (the same
    record), made again when the file's bytes or how it is read change."""
    import json

    from truth.gearbox import SHORT_BOX, gearbox_record

    import pydiag.app.baselines as baselines
    from pydiag.app.machine_options import apply_machine
    from pydiag.io.measurements import write_measurement
    machine_file = tmp_path / "box.toml"
    machine_file.write_text((ROOT / "tests" / "golden" / "short_box.loop.toml").read_text())
    files = [tmp_path / f"healthy_{seed}.csv" for seed in (1, 3)]
    for seed, path in zip((1, 3), files):
        write_measurement(path, gearbox_record(seed, box=SHORT_BOX))
    made = []
    real = baselines.machine_record
    monkeypatch.setattr(baselines, "machine_record",
                        lambda m, *a, **k: made.append(m.metadata["file"]) or real(m, *a, **k))

    def records(*extra: str) -> list:
        args = build_parser().parse_args([
            "diagnose", "--machine", str(machine_file), "--measurement", "record.csv",
            "--history", str(tmp_path / "h.sqlite"),
            *(a for f in files for a in ("--baseline", str(f))), *extra])
        args.machine_description = apply_machine(args)
        machine = args.machine_description
        healthy = baselines.healthy_measurements(args)
        return [json.dumps(r.to_dict()) for r in baselines.baseline_records(
            args, machine, SpeedSettings("mesh"), healthy,
            baselines.records_kept_in(args, machine, healthy))]  # NaN != NaN, not in JSON

    first = records()
    assert made == [str(f) for f in files]
    assert records() == first and len(made) == 2  # found, not made again
    assert records("--quiet", "--workers", "1") == first and len(made) == 2
    write_measurement(files[1], gearbox_record(4, box=SHORT_BOX), overwrite=True)  # its bytes
    assert records()[1] != first[1] and made[2:] == [str(files[1])]
    records("--rpm", "1490")  # read at another speed: both made again
    assert len(made) == 5
