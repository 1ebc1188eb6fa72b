"""The effect catalogue: each candidate missing effect (:class:`~pydiag.gear.effect.Effect`),
its Modelica model and its parameters, declared here once, its signature and hint named
from :mod:`pydiag.gear.signatures`; docs/effects.md tells how to add one.
"""

from __future__ import annotations

import dataclasses
import math

from pydiag.core.parameters import Parameter
from pydiag.gear.effect import (GEAR, GEAR_BEARING, GEAR_SHAFT, MESH, OTHER_SHAFT, PINION,
                               PINION_BEARING, PINION_SHAFT, Effect)
from pydiag.gear.bearing_signatures import (MAX_STRIKE_M_S2, ball_defect, bearing_missing,
                                            bearing_values, family, gear_ball_defect,
                                            gear_bearing_missing, gear_bearing_values,
                                            shared_family)
from pydiag.gear.signatures import (GEAR_PAIR_FAMILIES, MAX_HOUSING_HZ, MAX_RIPPLE_HZ,
                                    MAX_SHAFT_ORDER_M_S2, MAX_SWING, backlash,
                                    gear_eccentricity, gear_tooth_fault, housing_hint,
                                    housing_start, load_fluctuation, mesh_modulation,
                                    other_shaft, other_shaft_hint, other_shaft_missing,
                                    other_shaft_values, pinion_eccentricity, pinion_shaft,
                                    pinion_shaft_hint, ripple_hint, second_pinion_tooth,
                                    shaft_swing, stiffness_shape, tooth_hint)
from pydiag.gear.faults import BALL, ECCENTRIC, INNER, OUTER, model_shaft_state, tooth_state
from pydiag.gear.kinematic_map import SHAFT_ORDERS
from pydiag.signal.ripple import LoadRipple, SpeedRipple
from pydiag.signal.transfer import HousingMode


_OUTER = Effect(
    "bearing_outer_race", "GearDiag.Effects.BearingOuterRace",
    "outer-race defect, pinion bearing (strikes ringing a structural mode)",
    (Parameter("A_b", 0.0, MAX_STRIKE_M_S2),), family(("bpfo",)), synchronous=False,
    outputs=("acc",), envelope=True, affine=True, machine_values=bearing_values,
    missing=bearing_missing, parts=(("A_b", PINION_BEARING),), fault=OUTER)
_INNER = Effect(
    "bearing_inner_race", "GearDiag.Effects.BearingInnerRace",
    "inner-race defect, pinion bearing (strikes ringing a structural mode)",
    (Parameter("A_b", 0.0, MAX_STRIKE_M_S2),
     Parameter("phi_zone", -math.pi, math.pi, periodic=True)),
    family(("bpfi", "bpfi_sb")), synchronous=False, outputs=("acc",), envelope=True,
    affine=True, machine_values=bearing_values, missing=bearing_missing,
    parts=(("A_b", PINION_BEARING),), fault=INNER)
# a spalled ball strikes both races once each a turn about its axis (2 x BSF, the
# kinematic map's even BSF lines), the cage carrying it through the load zone
_BALL = Effect(
    "bearing_ball", "GearDiag.Effects.BearingBall",
    "rolling-element defect, pinion bearing (strikes twice a ball turn ringing a "
    "structural mode)",
    (Parameter("A_b", 0.0, MAX_STRIKE_M_S2),
     Parameter("phi_cage", -math.pi, math.pi, periodic=True)),
    ball_defect, synchronous=False, outputs=("acc",), envelope=True, affine=True,
    machine_values=bearing_values, missing=bearing_missing,
    parts=(("A_b", PINION_BEARING),), fault=BALL)


def _on_gear_shaft(effect: Effect, weight) -> Effect:
    """A bearing effect of the bearing on the gear's shaft (``GearKinematics.gear_bearing``,
    the kinematic map's ``gear_`` families): the same model, its strikes at that shaft's
    speed (``r_shaft``). In a machine only the shaft no stage's pinion turns has one: every
    other shaft's bearings are a pinion's."""
    return dataclasses.replace(
        effect, key=f"gear_{effect.key}",
        description=effect.description.replace("pinion bearing", "gear bearing"),
        weight=weight, machine_values=gear_bearing_values, missing=gear_bearing_missing,
        parts=(("A_b", GEAR_BEARING),))


EFFECTS = {e.key: e for e in (
    Effect("mesh_stiffness_shape", "GearDiag.GearPair",
           "even harmonics of the mesh stiffness wave (contact ratio, tip relief)",
           (Parameter("k2", 0.0, 0.3), Parameter("phi2", -math.pi, math.pi, periodic=True),
            Parameter("k4", 0.0, 0.1), Parameter("phi4", -math.pi, math.pi, periodic=True)),
           stiffness_shape, in_base=True, parts=(("k2", MESH), ("k4", MESH))),
    Effect("pinion_tooth_softening", "GearDiag.GearPair",
           "the faulty pinion tooth is also softer over its contact, most while alone in it "
           "(a crack, a chip)",
           (Parameter("d_f", 0.0, 0.6), Parameter("eps_c", 1.1, 1.9),
            Parameter("q_c", 1.0, 5.0), Parameter("r_c", 0.02, 0.5)),
           second_pinion_tooth, in_base=True, parts=(("d_f", PINION),), fault=tooth_state),
    # a runout is a transmission error, which the mesh's linear contact passes on
    # linearly: the outputs are affine in its amplitude's two phase components
    Effect("gear_eccentricity", "GearDiag.Effects.GearEccentricity", "driven-gear runout",
           (Parameter("ecc_gear", 0.0, 50e-6),
            Parameter("phase_gear", -math.pi, math.pi, periodic=True)), gear_eccentricity,
           affine=True, parts=(("ecc_gear", GEAR),), fault=ECCENTRIC),
    Effect("pinion_eccentricity", "GearDiag.Effects.PinionEccentricity", "pinion runout",
           (Parameter("ecc_pinion", 0.0, 50e-6),
            Parameter("phase_pinion", -math.pi, math.pi, periodic=True)), pinion_eccentricity,
           affine=True, parts=(("ecc_pinion", PINION),), fault=ECCENTRIC),
    # an eccentric or tilted gear: the load along the face varies around the turn
    Effect("mesh_modulation", "GearDiag.Effects.MeshModulation",
           "the mesh stiffness modulated once per turn of each shaft (a gear mounted tilted "
           "or eccentric: the face width in contact varies around its turn)",
           (Parameter("m_p", 0.0, 0.5), Parameter("phi_p", -math.pi, math.pi, periodic=True),
            Parameter("m_g", 0.0, 0.5), Parameter("phi_g", -math.pi, math.pi, periodic=True)),
           mesh_modulation, parts=(("m_p", PINION), ("m_g", GEAR))),
    # a softer tooth over its contact; which tooth is unknown (one turn of the index, the
    # bump moving smoothly with it; the hint sets the turn from the wheel's teeth)
    Effect("gear_tooth_fault", "GearDiag.Effects.GearToothFault", "faulty tooth on the driven gear",
           (Parameter("d_g", 0.0, 0.6), Parameter("tooth_g", 0.0, 21.0, periodic=True)),
           gear_tooth_fault, tooth_hint("tooth_g", "n_gear"), parts=(("d_g", GEAR),), fault=tooth_state),
    # a second tooth is not tooth 0; its index is a whole tooth (step 1: each tooth is
    # searched by particles of its own; a smooth index stopped between teeth), counted the
    # shorter way from tooth 0 (the hint: tooth k and N - k are one pattern, reversed)
    Effect("second_pinion_tooth_fault", "GearDiag.Effects.SecondPinionToothFault",
           "a second faulty pinion tooth",
           (Parameter("d_f2", 0.0, 0.6), Parameter("tooth2", 0.5, 13.5, step=1.0)),
           second_pinion_tooth, tooth_hint("tooth2", "n_pinion", other_than_zero=True),
           reshapes_base=True, parts=(("d_f2", PINION),), fault=tooth_state),
    # the teeth separate only where the dynamic deflection outgrows the static one (the mesh
    # at a resonance): the loss then reshapes the lines the base makes, which a base fit
    # without it bends to. Its transition is the teeth's surfaces coming into contact: from
    # a hard contact to the roughness of ground teeth (Ra 0.3 um). Wider, the factor is a
    # softening stiffness law over the whole deflection instead (RESULTS.md, changelog).
    Effect("backlash", "GearDiag.Effects.Backlash", "contact loss between the teeth",
           (Parameter("delta_c", 0.01e-6, 0.3e-6),), backlash, reshapes_base=True,
           parts=(("delta_c", MESH),)),
    _OUTER, _INNER, _BALL,
    *(_on_gear_shaft(e, weight) for e, weight in (
        (_OUTER, shared_family(("gear_bpfo",))),
        (_INNER, shared_family(("gear_bpfi", "gear_bpfi_sb"))),
        (_BALL, gear_ball_defect))),
    Effect("load_fluctuation", "GearDiag.Effects.LoadFluctuation", "torque ripple",
           (Parameter("dT", 0.0, 20.0), Parameter("f_load", 0.5, MAX_RIPPLE_HZ)), load_fluctuation,
           ripple_hint("f_load"), synchronous=False,
           ripple=LoadRipple("dT", "f_load", "T")),
    # the same lines as a torque ripple (they compete): a ripple the shafts' inertia turns
    # into a speed fluctuation modulates the mesh's phase rather than its force
    Effect("speed_fluctuation", "GearDiag.Effects.SpeedFluctuation",
           "the shafts' speed fluctuates (phase modulation of every line)",
           (Parameter("ds", 0.0, 0.05), Parameter("f_speed", 0.5, MAX_RIPPLE_HZ)),
           load_fluctuation, ripple_hint("f_speed"), synchronous=False, reshapes_base=True,
           ripple=SpeedRipple("ds", "f_speed")),
    # a torsional swing at each shaft's own speed (a misaligned coupling, a bent shaft): the
    # mesh's phase modulated once a turn of either shaft, synchronous with the pair. Deep
    # (the gear's swing is Ng times deeper in the mesh's phase), so far from affine, and it
    # takes energy from the mesh harmonics into their sidebands: fitted with the base free.
    # On a record tracked by a tacho the swing the tacho sees, of its shaft and of those it
    # turns rigidly, is out of the record: what it fits there is the mesh's angle against
    # the tacho's (a transmission error once a turn, a shaft's torsion; RESULTS 13)
    Effect("shaft_swing", "GearDiag.Effects.ShaftSwing",
           "each shaft's speed swings once a turn (phase modulation of the mesh at each "
           "shaft's speed)",
           (Parameter("s_p", 0.0, MAX_SWING), Parameter("psi_p", -math.pi, math.pi, periodic=True),
            Parameter("s_g", 0.0, MAX_SWING), Parameter("psi_g", -math.pi, math.pi, periodic=True)),
           shaft_swing, reshapes_base=True, parts=(("s_p", PINION_SHAFT), ("s_g", GEAR_SHAFT))),
    # a shaft's unbalance, misalignment or looseness, seen at the sensor through its
    # bearings: one amplitude an order (the outputs are affine in all of them)
    Effect("pinion_shaft_orders", "GearDiag.Effects.PinionShaftOrders",
           "the pinion shaft's own vibration at its first orders (unbalance, misalignment, "
           "looseness)",
           tuple(Parameter(f"A_s{k}", 0.0, MAX_SHAFT_ORDER_M_S2)
                 for k in range(1, SHAFT_ORDERS + 1)),
           pinion_shaft, pinion_shaft_hint, outputs=("acc",), affine=True,
           parts=tuple((f"A_s{k}", PINION_SHAFT) for k in range(1, SHAFT_ORDERS + 1)),
           fault=model_shaft_state),
    # the same, of a shaft beyond the pair at a speed ratio the kinematics give: not
    # synchronous with the pair's period in general (a motor shaft at 29/17 of the pinion's)
    Effect("other_shaft_orders", "GearDiag.Effects.OtherShaftOrders",
           "another shaft's own vibration at its first orders (a second stage, a motor shaft)",
           tuple(Parameter(f"A_o{k}", 0.0, MAX_SHAFT_ORDER_M_S2)
                 for k in range(1, SHAFT_ORDERS + 1)),
           other_shaft, other_shaft_hint, synchronous=False, outputs=("acc",), affine=True,
           machine_values=other_shaft_values, missing=other_shaft_missing,
           parts=tuple((f"A_o{k}", OTHER_SHAFT) for k in range(1, SHAFT_ORDERS + 1)),
           fault=model_shaft_state),
    # the mode reweights every line the gear pair makes on its way to the sensor (its
    # signature: all of them); its frequency is fitted in the band where the residual of
    # those lines bunches (the hint), or above the band, where it shows only as a tilt
    # (the free start); damping from a sharp structural mode to a heavily damped one.
    # Lower bounds: a mode below every line passes the force as a mass (accelerance 1/m),
    # the channel gain takes the rest
    Effect("housing_sensor", "GearDiag.Effects.HousingSensor",
           "accelerometer on the housing, behind one housing mode",
           (Parameter("f_housing", 20.0, MAX_HOUSING_HZ), Parameter("zeta_housing", 0.005, 0.5)),
           family(GEAR_PAIR_FAMILIES), housing_hint, outputs=("acc",), reshapes_base=True,
           free_start=housing_start, transfer=HousingMode("acc")),
)}
