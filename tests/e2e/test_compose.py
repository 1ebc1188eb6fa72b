"""Models with several effects (:mod:`pydiag.loop.compose`): written from the effects' own
Modelica files, built once per content, and what they simulate is what each effect adds to
the gear pair, added."""

from pathlib import Path

import numpy as np
import pytest

from pydiag.fmu.plant import FmuPlant
from pydiag.gear.effects import EFFECTS
from pydiag.loop.compose import CompositionError, compose, composed_fmu
from pydiag.loop.discover import effect_fmu

ROOT = Path(__file__).resolve().parents[2]
MODELICA = ROOT / "modelica"
FS, DURATION, WARMUP = 10_000.0, 0.48, 0.05  # 12 pinion turns of GearPair's 14/21 at 25 Hz
RUNOUT = {"ecc_gear": 40e-6, "phase_gear": 0.4}
SHAFTS = {"A_s2": 30.0, "A_s5": 12.0, "A_o1": 20.0, "A_o3": 45.0, "r_other": 0.37}


def acc(fmu: Path, values: dict) -> np.ndarray:
    with FmuPlant(fmu, ("acc",), FS) as plant:
        return plant.simulate({"a_f": 0.3, "f_dte": 0.4, **values}, DURATION, WARMUP)[0]


def test_a_composed_model_adds_what_each_effect_adds(gear_fmu, effects_dir, tmp_path):
    """A gear runout (a transmission error the mesh filters) and both shafts' own orders
    (terms at the sensor): the composed model's acceleration is the pair's plus what each
    effect's own model adds to it, within the integrator's tolerance; the shafts' component
    (``shaft`` in both effects' models) is two components."""
    keys = ("pinion_shaft_orders", "gear_eccentricity", "other_shaft_orders")
    model = compose(keys, MODELICA)
    assert model.keys == ("gear_eccentricity", "pinion_shaft_orders", "other_shaft_orders")
    assert "other_shaft_orders_shaft(f_shaft = r_other*f_pinion" in model.source
    assert '"The other shaft, seen at the sensor"' in model.source  # names in text kept
    fmu = composed_fmu(keys, MODELICA, tmp_path)
    assert (tmp_path / "composed" / model.name / f"{model.name}.mo").read_text() == model.source
    assert composed_fmu(tuple(reversed(keys)), MODELICA, tmp_path) == fmu  # cached
    base = acc(gear_fmu, {})
    each = [acc(effect_fmu(k, MODELICA, effects_dir), values) - base
            for k, values in (("gear_eccentricity", RUNOUT),
                              ("pinion_shaft_orders", {k: v for k, v in SHAFTS.items()
                                                       if k.startswith("A_s")}),
                              ("other_shaft_orders", {k: v for k, v in SHAFTS.items()
                                                      if not k.startswith("A_s")}))]
    together = acc(fmu, {**RUNOUT, **SHAFTS})
    smallest = min(np.max(np.abs(e)) for e in each)  # the runout's: 0.5 m/s2 of 80
    assert smallest > 0.1
    assert np.max(np.abs(together - base - sum(each))) < 0.01 * smallest


def test_effects_that_cannot_share_a_model_are_refused_by_name(modelica_copy):
    with pytest.raises(CompositionError, match="both declare A_b, differently"):
        compose(("bearing_outer_race", "bearing_inner_race"), MODELICA)
    with pytest.raises(CompositionError, match="bearing_ball and gear_bearing_ball are one "
                                               "model .* at two shafts' speeds"):
        compose(("gear_bearing_ball", "bearing_ball"), MODELICA)
    with pytest.raises(CompositionError, match="housing_sensor has no model of its own"):
        compose(("housing_sensor", "gear_eccentricity"), MODELICA)
    runout = modelica_copy / "GearDiag" / "Effects" / "GearEccentricity.mo"
    runout.write_text(runout.read_text().replace("extends GearDiag.GearPair(e_extra =",
                                                 "extends GearDiag.GearPair(contact = "))
    with pytest.raises(CompositionError, match="gear_eccentricity and backlash both set "
                                               "contact"):
        compose(("gear_eccentricity", "backlash"), modelica_copy)
    swing = modelica_copy / "GearDiag" / "Effects" / "ShaftSwing.mo"
    swing.write_text(swing.read_text().replace("t_angle = time +", "t_angle = 2*time +"))
    with pytest.raises(CompositionError, match="ShaftSwing.mo: t_angle = 2.time .*only a term "
                                               "added to time combines"):
        compose(("shaft_swing", "speed_fluctuation"), modelica_copy)


def test_angles_add(effects_dir, tmp_path):
    """A speed's fluctuation and a shaft's swing each lead the mesh's angle by a term of
    their own: composed, each does what its own model does while the other is off, and
    both together lead it by their sum."""
    fluctuation, swing = {"ds": 0.01, "f_speed": 5.0}, {"s_g": 0.02, "psi_g": 0.7}
    keys = ("shaft_swing", "speed_fluctuation")
    assert "t_angle = time + (ds/(2*pi*f_speed)" in compose(keys, MODELICA).source
    fmu = composed_fmu(keys, MODELICA, tmp_path)
    off = {**EFFECTS["speed_fluctuation"].neutral_values(),
           **EFFECTS["shaft_swing"].neutral_values()}
    for key, values in (("speed_fluctuation", fluctuation), ("shaft_swing", swing)):
        own = acc(effect_fmu(key, MODELICA, effects_dir), values)
        np.testing.assert_allclose(acc(fmu, {**off, **values}), own,
                                   atol=1e-3 * np.max(np.abs(own)))
    both = acc(fmu, {**fluctuation, **swing})
    assert np.max(np.abs(both - acc(fmu, {**off, **swing}))) > 0.1 * np.max(np.abs(both))


def test_an_edit_of_a_written_model_is_the_users_and_is_built(tmp_path):
    """The source pydiag writes beside an FMU is the user's to edit: an edit is built and
    kept (not written over), and said to be an edit; removed, pydiag's is written again."""
    from pydiag.loop.compose import built_fmu
    source = ("within GearDiag;\nmodel Tiny \"a pair at 30 Hz\"\n"
              "  GearDiag.GearPair pair(f_pinion=30);\n"
              "  output Real acc(unit=\"m/s2\") = pair.acc \"the mesh\";\nend Tiny;\n")
    first = built_fmu("Tiny", source, MODELICA, tmp_path)
    assert not first.edited and first.source.read_text() == source
    edit = source.replace("f_pinion=30", "f_pinion=35")
    first.source.write_text(edit)
    second = built_fmu("Tiny", source, MODELICA, tmp_path)
    assert second.edited and second.fmu != first.fmu and second.source.read_text() == edit
    with FmuPlant(second.fmu, ("acc",), FS) as plant:
        assert plant.parameters()["pair.f_pinion"] == 35
    first.source.unlink()
    third = built_fmu("Tiny", source, MODELICA, tmp_path)
    assert not third.edited and third.fmu == first.fmu and third.source.read_text() == source


def test_an_edit_that_does_not_build_is_the_users_error_and_breaks_no_other_model(tmp_path):
    """A syntax error in an edited source is one line naming that file (the user's to
    mend), not an internal error; a stray file beside it (a backup copy of a broken edit)
    breaks no other model's build: each model is built from a folder of its own."""
    from pydiag.core.errors import UsageError
    from pydiag.loop.compose import built_fmu
    source = ("within GearDiag;\nmodel Tiny \"a pair at 30 Hz\"\n"
              "  GearDiag.GearPair pair(f_pinion=30);\n"
              "  output Real acc(unit=\"m/s2\") = pair.acc \"the mesh\";\nend Tiny;\n")
    first = built_fmu("Tiny", source, MODELICA, tmp_path)
    broken = source.replace("pair.acc", "pair.acc +")
    first.source.write_text(broken)
    (tmp_path / "Tiny.orig.mo").write_text(broken)  # beside every model's folder
    with pytest.raises(UsageError, match=r"Tiny\.mo \(your edit of the model pydiag "
                                         r"wrote\) does not build"):
        built_fmu("Tiny", source.replace("30 Hz", "31 Hz"), MODELICA, tmp_path)
    other = built_fmu("Other", source.replace("Tiny", "Other"), MODELICA, tmp_path)
    assert other.fmu.exists() and not other.edited
