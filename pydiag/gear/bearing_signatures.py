"""The signatures and machine values of the bearing effects (:mod:`pydiag.gear.effects`):
which lines of the kinematic map a bearing's strikes make, the geometry and shaft speed its
model takes from the kinematics, and what the kinematics must say for it to have lines.
The pair's bearing (``GearKinematics.bearing``) has the map's ``bpfo`` ... ``ftf`` families;
the bearing on the gear's shaft (``GearKinematics.gear_bearing``) the ``gear_`` ones."""

from __future__ import annotations

from pydiag.gear.kinematic_map import GEAR_BEARING_PREFIX, PAIR_BEARING_FAMILIES

#: The families of another bearing's lines than the gear's.
OTHER_BEARINGS = PAIR_BEARING_FAMILIES + ("machine_bearing",)


def family(name):
    """The weight of a line of one of the families ``name``: 1, else 0."""
    def weight(line, freq, kin):
        return 1.0 if line is not None and line.family in name else 0.0
    return weight


def shared_family(name):
    """:func:`family` of the bearing on the gear's shaft, and a line another bearing's comb
    has too, named for that one (the pair's own bearing's, or the machine's: on a box of
    one geometry the output's 5th BPFO is the intermediate's 2nd and the input's 1st)."""
    def weight(line, freq, kin):
        if line is None:
            return 0.0
        return 1.0 if line.family in name or (line.family in OTHER_BEARINGS
                                              and set(line.also) & set(name)) else 0.0
    return weight


def _ball_defect(prefix: str):
    # a spalled ball strikes both races once each a turn about its axis: 2 x BSF and its
    # harmonics (the BSF lines of even order); the two strikes differ (the races' curvature
    # and load), which makes the odd ones, and the cage's turn through the load zone
    # modulates them (FTF)
    bsf, ftf = prefix + "bsf", prefix + "ftf"

    def weight(line, freq, kin):
        if line is not None and prefix and line.family in OTHER_BEARINGS \
                and set(line.also) & {bsf, ftf}:
            return 0.5  # shared with another bearing's comb (shared_family)
        if line is None or line.family not in (bsf, ftf):
            return 0.0
        return 1.0 if line.family == bsf and line.order % 2 == 0 else 0.5
    return weight


ball_defect = _ball_defect("")
#: The same of the bearing on the gear's shaft (``GearKinematics.gear_bearing``).
gear_ball_defect = _ball_defect(GEAR_BEARING_PREFIX)


def _values(kin, bearing) -> dict[str, float]:
    """A bearing's geometry and its shaft's speed over the pinion's, as the bearing effects'
    models name them."""
    return {} if bearing is None else {
        "n_balls": float(bearing.n_balls), "d_ball": bearing.ball_diameter_m,
        "d_pitch": bearing.pitch_diameter_m, "alpha_contact": bearing.contact_angle_rad,
        "r_shaft": kin.shaft_hz(bearing.shaft) / kin.f_pinion_hz}


def bearing_values(kin) -> dict[str, float]:  # the pair's bearing (GearKinematics.bearing)
    return _values(kin, None if kin is None else kin.bearing)


def bearing_missing(kin) -> str:
    return ("the bearing's geometry (--bearing, or a machine file's [[bearings]] on the pinion's "
            "shaft)" if kin is None or kin.bearing is None else "")


def gear_bearing_values(kin) -> dict[str, float]:  # GearKinematics.gear_bearing
    return _values(kin, None if kin is None else kin.gear_bearing)


def gear_bearing_missing(kin) -> str:
    return ("a bearing on the gear's shaft that no stage's pinion turns (a machine file's "
            "[[bearings]] on its output shaft)" if kin is None or kin.gear_bearing is None else "")


#: The largest bearing strike the bearing effects fit, m/s2 at the model's sensor (500 g):
#: a fitted channel gain scales it to the measurement's, and real records fit gains down
#: to about 0.01.
MAX_STRIKE_M_S2 = 5000.0
