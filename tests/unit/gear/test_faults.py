"""The words a component's state is said in, and who says it: the rules that name a fault
from what changed (pydiag.gear.faults) and the healthy model's verdict laid over the
indicators' (pydiag.gear.component.judged_by_model)."""

import dataclasses
import math

import pytest

from pydiag.gear.component import (ASK_MODEL, BY_BOTH, BY_INDICATORS, BY_MODEL, Component,
                                   ComponentVerdict, ModelChange, asked_of_model,
                                   judged_by_model)
from pydiag.gear.effects import EFFECTS
from pydiag.gear.faults import model_shaft_state, shaft_state, tooth_state


@pytest.mark.parametrize("rises, state", [([], "good"), ([1], "imbalance"), ([1, 2], "bent"),
                                          ([1, 2, 3], "looseness"), ([2], "changed"),
                                          ([2, 4], "changed")])
def test_a_shafts_risen_orders_name_its_fault(rises, state):
    assert shaft_state(rises) == state


def test_a_models_shaft_orders_rise_where_they_grew_by_half_the_largest_growth():
    assert model_shaft_state((100, 50, 20), (300, 60, 20)) == "imbalance"
    assert model_shaft_state((100, 50, 20), (300, 160, 20)) == "bent"
    assert model_shaft_state((100, 50, 20), (90, 40, 20)) == "changed"  # none grew


def test_a_tooth_is_broken_once_it_lost_half_its_stiffness():
    assert tooth_state((0.0,), (0.2,)) == "chipped"
    assert tooth_state((0.1,), (0.55,)) == "broken"


def test_each_catalogue_effect_names_its_fault_from_its_own_parameters():
    assert EFFECTS["gear_tooth_fault"].fault_of({"d_g": (0.0, 0.58)}) == "broken"
    assert EFFECTS["bearing_inner_race"].fault_of({"A_b": (0.0, 3.0)}) == "inner"
    assert EFFECTS["gear_eccentricity"].fault_of({"ecc_gear": (0.0, 1e-5)}) == "eccentric"
    assert EFFECTS["pinion_shaft_orders"].fault_of(
        {"A_s1": (1.0, 9.0), "A_s2": (1.0, 1.5)}) == "imbalance"
    assert EFFECTS["mesh_modulation"].fault_of({"m_g": (0.1, 0.3)}) == "changed"
    # an order held off keeps its place: a risen 2x with the 1x held off is no imbalance
    assert EFFECTS["pinion_shaft_orders"].fault_of({"A_s2": (1.0, 9.0),
                                                    "A_s3": (1.0, 1.2)}) == "changed"
    assert EFFECTS["pinion_shaft_orders"].fault_of({"A_s2": (1.0, 9.0), "A_s3": (1.0, 8.0),
                                                    "A_s4": (1.0, 7.0)}) == "looseness"


GEAR = Component("gear", "80T gear of output", "output", 80, "output", "gear")
PINION = Component("gear", "48T pinion of output", "idler", 48, "output", "pinion")
BEARING = Component("bearing", "OS:OS", "output")


def change(margin, components, covers, fault="changed", effect="mesh_modulation"):
    return ModelChange("output", effect, 10.0, 0.0, 1.0, margin, {"m_g": (0.1, 0.3)}, "gear",
                       components, fault, covers)


def test_the_model_names_what_it_covers_and_the_indicators_keep_the_rest():
    indicators = (ComponentVerdict(PINION, "changed", {"sidebands": 3.0}, 6.0, 1.4, "rose"),
                  ComponentVerdict(GEAR, "good", {}, 6.0, 0.3),
                  ComponentVerdict(BEARING, "outer", {"outer": 9.0}, 6.0, 2.0, "its BPFO"))
    covers = (PINION.name, GEAR.name)
    judged = {v.component.name: v for v in judged_by_model(
        indicators, [change(2.5, (GEAR.name,), covers)])}
    gear, pinion, bearing = judged[GEAR.name], judged[PINION.name], judged[BEARING.name]
    # named by the model where the indicators saw nothing
    assert (gear.state, gear.judge, gear.margin) == ("changed", BY_MODEL, 2.5)
    assert "0.1 -> 0.3" in gear.reason and gear.evidence["model output mesh_modulation"] == 2.5
    # covered, not named, and faulty by the indicators: theirs stands, the model's word added
    assert (pinion.state, pinion.judge, pinion.margin) == ("changed", BY_INDICATORS, 1.4)
    assert pinion.reason == "rose; the healthy model's mesh_modulation on output names " \
        "80T gear of output" and pinion.evidence["sidebands"] == 3
    assert bearing == indicators[2]  # not covered
    assert [v.faulty for v in judged_by_model(indicators, [change(2.5, (GEAR.name,), covers)])
            ] == [True, True, True]


def test_where_both_say_good_the_judge_is_both():
    indicators = (ComponentVerdict(GEAR, "good", {}, 6.0, 0.3),)
    v, = judged_by_model(indicators, [change(0.4, (GEAR.name,), (GEAR.name,))])
    assert (v.state, v.judge, v.margin) == ("good", BY_BOTH, 0.4)
    assert "within the healthy repeats (0.40 x)" in v.reason


def test_a_change_without_healthy_repeats_judges_nothing():
    indicators = (ComponentVerdict(GEAR, "changed", {}, 6.0, 1.4, "rose"),)
    assert judged_by_model(indicators, [change(math.nan, (GEAR.name,), (GEAR.name,))]
                           ) == indicators


def test_of_two_changes_that_name_a_component_the_larger_margin_says_its_fault():
    indicators = (ComponentVerdict(GEAR, "good", {}, 6.0, 0.2),)
    v, = judged_by_model(indicators, [
        change(1.5, (GEAR.name,), (GEAR.name,)),
        change(3.0, (GEAR.name,), (GEAR.name,), "broken", "gear_tooth_fault")])
    assert (v.state, v.margin, v.judge) == ("broken", 3.0, BY_MODEL)
    assert "gear_tooth_fault" in v.reason


def test_the_indicators_word_is_said_where_the_model_only_says_changed():
    """The model's modulation says the pinion changed; its shaft's swing says eccentric."""
    indicators = (ComponentVerdict(PINION, "eccentric", {}, 6.0, 10.2, "its shaft's swing"),)
    v, = judged_by_model(indicators, [change(3.3, (PINION.name,), (PINION.name, GEAR.name))])
    assert (v.state, v.judge, v.margin) == ("eccentric", BY_BOTH, 3.3)
    assert v.reason.endswith("; the indicators: eccentric (its shaft's swing)")
    # a word of the model's own wins
    v, = judged_by_model(indicators, [change(3.3, (PINION.name,), (PINION.name,), "chipped")])
    assert (v.state, v.judge) == ("chipped", BY_BOTH)


def test_a_change_that_names_no_part_names_nothing():
    """A shaft's orders that all fell: the record differs, and no fault grew."""
    shaft = Component("shaft", "input", "input")
    indicators = (ComponentVerdict(shaft, "good", {}, 6.0, 0.4),)
    v, = judged_by_model(indicators, [change(1.5, (), ("input",), effect="pinion_shaft_orders")])
    assert (v.state, v.judge, v.margin) == ("good", BY_BOTH, None) and "names no part" in v.reason


def test_a_bearing_fault_whose_lines_another_bearing_claims_is_good():
    """The indicators read the input bearing's ball from lines the output ball's comb
    shares; the model's ball effect on the input bearing, held out, has its lines claimed
    by the output bearing's ball: the model's good stands. Where it is not that fault's
    effect (the outer race's), or the component is a gear, the indicators' word stands."""
    inner = Component("bearing", "IS:IS", "input")
    output = Component("bearing", "OS:OS", "output")
    indicators = (ComponentVerdict(inner, "ball", {"ball_db": 6.0}, 6.0, 1.9, "its 2xBSF"),
                  ComponentVerdict(output, "ball", {"ball_db": 9.0}, 6.0, 3.0, "its 2xBSF"))
    ball = ModelChange("input", "bearing_ball", 12.0, 0.0, 2.0, 1.5, {"A_b": (0.0, 9.0)},
                       "pinion bearing", (inner.name,), "ball", (inner.name,),
                       beaten_by="gear_bearing_ball on output")
    winner = ModelChange("output", "gear_bearing_ball", 30.0, 0.0, 2.0, 7.3,
                         {"A_b": (0.0, 8.9)}, "gear bearing", (output.name,), "ball",
                         (output.name,))
    v, w = judged_by_model(indicators, [winner, ball])
    assert (v.state, v.judge, v.margin) == ("ball", BY_BOTH, 7.3)  # the output's
    assert (w.state, w.judge, w.margin) == ("good", BY_MODEL, 1.5)
    assert "has its lines claimed by gear_bearing_ball on output" in w.reason
    assert w.reason.endswith("; the indicators: ball (its 2xBSF)") and w.evidence["ball_db"] == 6
    outer = ModelChange("input", "bearing_outer_race", 1.0, 0.0, 2.0, 0.3, {"A_b": (0.0, 1.0)},
                        "pinion bearing", (), "outer", (inner.name,))
    assert judged_by_model(indicators[:1], [outer])[0].state == "ball"
    # beside a larger change of another fault, the evidence is the tested fault's
    v = judged_by_model(indicators, [dataclasses.replace(outer, margin=4.0), winner, ball])[1]
    assert v.state == "good" and v.evidence["model input bearing_ball"] == 1.5
    assert "model input bearing_outer_race" not in v.evidence
    eccentric = (ComponentVerdict(PINION, "eccentric", {}, 6.0, 10.2, "its shaft's swing"),)
    assert judged_by_model(eccentric, [change(0.2, (), (PINION.name,), "eccentric",
                                              "gear_eccentricity")])[0].state == "eccentric"


def test_a_bearing_fault_the_model_does_not_see_keeps_the_indicators_word():
    """The model's try of the very fault the indicators read in the envelope within the
    healthy repeats, or its lines claimed by a gear's change (which repeats with the
    machine and makes no envelope line): the indicators' word stands, the model's said."""
    inner = Component("bearing", "IS:IS", "input")
    indicators = (ComponentVerdict(inner, "inner", {"inner_db": 13.4}, 6.9, 1.9, "its BPFI"),)
    race = ModelChange("input", "bearing_inner_race", 2.0, 0.0, 2.0, 0.4, {"A_b": (0.0, 1.0)},
                       "pinion bearing", (), "inner", (inner.name,))
    v, = judged_by_model(indicators, [race])
    assert (v.state, v.judge, v.margin) == ("inner", BY_INDICATORS, 1.9)
    assert v.reason == ("its BPFI; the healthy model's bearing_inner_race on input is within "
                        "the healthy repeats (0.40 x)")
    assert v.evidence == {"inner_db": 13.4, "model input bearing_inner_race": 0.4}
    runout = ModelChange("input", "gear_eccentricity", 60.0, 0.0, 2.0, 7.8,
                         {"ecc_gear": (0.0, 5e-5)}, "gear", (GEAR.name,), "eccentric",
                         (GEAR.name,))
    claimed = dataclasses.replace(race, margin=1.6, beaten_by="gear_eccentricity on input")
    v, = judged_by_model(indicators, [runout, claimed])
    assert (v.state, v.judge) == ("inner", BY_INDICATORS)
    assert "has its lines claimed by gear_eccentricity on input (1.60 x)" in v.reason


def test_the_model_is_asked_about_what_the_indicators_find_faulty_or_near_it():
    shaft = Component("shaft", "input", "input")
    verdicts = (ComponentVerdict(PINION, "changed", {}, 6.0, 1.4),
                ComponentVerdict(GEAR, "good", {}, 6.0, ASK_MODEL),  # half its threshold
                ComponentVerdict(BEARING, "good", {}, 6.0, 0.9 * ASK_MODEL),
                ComponentVerdict(shaft, "not judged", {}, None, None, "no baseline"))
    assert asked_of_model(verdicts) == {PINION.name, GEAR.name}
    # a fault the indicators name is asked about whatever its margin (a swing's own rule)
    assert asked_of_model((ComponentVerdict(BEARING, "outer", {}, 6.0, None),)) == {BEARING.name}


def test_a_gear_the_model_alone_names_beside_its_shafts_faulty_gear_stays_good():
    """An idler's 48T pinion eccentric (the indicators, by its shaft's swing, and the
    model's runout): its shaft's 96T gear of the other stage, good by the indicators, is
    fitted by the model's tooth fault (the eccentric pinion moves the shaft, and with it the
    other mesh, which the model's uncoupled stages give to that mesh's own gear): the
    indicators' good stands. With the pinion good by the indicators, the model's word on
    the gear stands."""
    idler_gear = Component("gear", "96T gear of input", "idler", 96, "input", "gear")
    eccentric = ModelChange("output", "pinion_eccentricity", 90.0, 0.0, 1.0, 13.5,
                            {"ecc_pinion": (0.0, 5e-5)}, "pinion", (PINION.name,),
                            "eccentric", (PINION.name,))
    tooth = ModelChange("input", "gear_tooth_fault", 80.0, 0.0, 1.0, 12.3,
                        {"d_g": (0.0, 0.6)}, "gear", (idler_gear.name,), "broken",
                        (idler_gear.name,))
    indicators = (ComponentVerdict(PINION, "eccentric", {}, 6.0, 7.8, "its shaft's swing"),
                  ComponentVerdict(idler_gear, "good", {"sidebands": 0.2}, 6.0, 0.3))
    judged = {v.component.name: v for v in judged_by_model(indicators, [eccentric, tooth])}
    assert (judged[PINION.name].state, judged[PINION.name].judge) == ("eccentric", BY_BOTH)
    gear = judged[idler_gear.name]
    assert (gear.state, gear.judge, gear.margin) == ("good", BY_INDICATORS, 0.3)
    assert "gear_tooth_fault" in gear.reason
    assert f"the indicators find {PINION.name} on its shaft faulty" in gear.reason
    assert gear.evidence["model input gear_tooth_fault"] == 12.3
    calm = (dataclasses.replace(indicators[0], state="good", margin=0.4), indicators[1])
    judged = {v.component.name: v for v in judged_by_model(calm, [tooth])}
    assert (judged[idler_gear.name].state, judged[idler_gear.name].judge) == ("broken",
                                                                              BY_MODEL)
