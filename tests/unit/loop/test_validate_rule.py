"""Which of compare's suggestions validation tries held out: by the share of the
unexplained energy its lines hold, and in the loop every synchronous one."""

from types import SimpleNamespace

from pydiag.gear.effects import EFFECTS
from pydiag.gear.kinematics import GearKinematics
from pydiag.loop.results import Status, Suggestion
from pydiag.loop.validate import MIN_SCORE, _not_fitted

PROBLEM = SimpleNamespace(parameters=(), kinematics=GearKinematics(14, 21, 25.0))


def why(key: str, score: float, every_synchronous: bool = False):
    s = Suggestion(key, score, [])
    return _not_fitted(PROBLEM, s, EFFECTS[key], MIN_SCORE, (), None, every_synchronous)


def test_an_effect_is_tried_when_its_lines_hold_enough_of_the_unexplained_energy():
    assert why("mesh_modulation", 2 * MIN_SCORE) is None
    status, message = why("mesh_modulation", 0.03)
    assert status is Status.NOT_TRIED
    assert message == "not tried: its lines hold 3 % of the unexplained energy"
    assert why("pinion_shaft_orders", 0.0) is None  # affine: one simulation a parameter


def test_the_loop_tries_every_synchronous_effect_but_those_that_free_the_base():
    assert why("mesh_modulation", 0.0, every_synchronous=True) is None
    assert why("gear_tooth_fault", 0.01, every_synchronous=True) is None
    # a ripple's model is simulated whole, backlash's fit frees the base: only evidence
    # makes them worth their fits
    assert why("load_fluctuation", 0.01, every_synchronous=True)[0] is Status.NOT_TRIED
    assert why("backlash", 0.01, every_synchronous=True)[0] is Status.NOT_TRIED
