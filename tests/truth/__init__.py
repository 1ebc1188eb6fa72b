"""The independent gear simulator (:mod:`truth.gear_sim`) and the base model the loop's
tests and bench fit to its records."""

from pydiag.core.parameters import Parameter
from pydiag.gear.conventions import HEALTHY_TOOTH
from pydiag.gear.effects import EFFECTS
from pydiag.model.adapter import gear_default
from truth.gear_sim import Effects

#: GearPair's paper parameters, the healthy teeth's level a0, the stiffness wave's shape and
#: the faulty tooth's softening and its form. The paper's faulty-tooth amplitude a_f may
#: fall below its 0.1 here: a weaker tooth's form is d_f's, and a_f only trims it.
BASE_PARAMETERS = (tuple(Parameter("a_f", 0.0, 0.9) if p.name == "a_f" else p
                         for p in gear_default(["acc", "disp"]).fault_parameters)
                   + (HEALTHY_TOOTH,) + EFFECTS["mesh_stiffness_shape"].parameters
                   + EFFECTS["pinion_tooth_softening"].parameters)
#: What the engineer knows of the simulator's machine beyond the gear pair, given with every
#: record whether or not a shaft is faulty: the motor shaft's speed ratio (29/17), so its
#: orders are kinematic lines.
OPERATING_POINT = {"other_shaft_ratio": Effects().other_shaft_ratio}
