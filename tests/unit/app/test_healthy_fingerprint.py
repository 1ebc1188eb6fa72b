"""The key a machine's healthy model is kept under (pydiag.app.baselines.healthy_fingerprint):
anything it is fitted from changes it, nothing else does."""

from pathlib import Path

from pydiag.app.baselines import healthy_fingerprint
from pydiag.app.cli import build_parser
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
