"""An independent gear-pair simulator: the "truth" the loop's tests measure, written from the
equations and not from the Modelica model, so that a fit of GearDiag.GearPair to its records
is not an inverse crime.

Where it differs from GearDiag.GearPair (same kinematics and physical defaults):

- two rotating bodies (pinion and gear inertias, the load a dynamometer holding the gear
  speed; optionally a motor's rotor driving the pinion through a flexible coupling)
  instead of one equivalent mass: the speed itself moves when the torque does;
- the mesh stiffness is a sum over the tooth pairs in contact, with a contact ratio of
  1.6 (one pair 40 % of the mesh cycle, two pairs 60 %), each pair's stiffness a parabola
  along its path of contact with tip relief at both ends, in series with the constant
  stiffness of shafts, bearings and bodies, evaluated at the pinion's *angle*, not at
  time; a faulty tooth is a weaker tooth over its whole contact;
- transmission errors are runouts projected on the line of action, in shaft angles, and
  the pitch error one sine at the assembly phase, as the model writes them; with
  :meth:`TruthGear.own_way` they are the simulator's own: a runout is a gear's centre off
  its axis, turning with it, whose offsets set the centre distance, so the operating
  pressure angle, the line of action and the contact ratio; each gear tooth has its pitch
  error (the cutter's passes leave a pattern over every third tooth), shared by the pairs
  in contact by their stiffness (the mesh's error their stiffness-weighted mean, moving as
  one pair loads and the other unloads), sizes and phases not the model's (make test runs
  the first: the second's records take twice as long and its misses are measured in
  bench/CHANGELOG.md);
- each effect of the catalogue is made its own way (see :class:`Effects`): bearing defects
  are pulse trains with random slip through a structural resonance into the accelerometer
  (not a force on the mesh), a torque ripple drives the shafts (and so the speed), the
  housing is a resonance filtered onto the mesh force, backlash is a hard contact loss, a
  misaligned coupling adds the pinion angle's first three orders at the sensor, a misaligned
  motor shaft behind a first stage (29/17 of the pinion's speed) its own, a load heavier
  over half of each gear turn swings the shafts' speed through their inertia.

Integrated with SciPy's LSODA (``odeint``); outputs ``acc`` (the acceleration of the mesh
deflection, plus what the effects add at the sensor) and ``disp`` (the mesh deflection),
like GearPair's channels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import integrate, signal

from pydiag.core.measurement import Measurement

TWO_PI = 2.0 * math.pi
#: The teeth's pressure angle, rad.
PRESSURE_ANGLE_RAD = math.radians(20.0)


@dataclass(frozen=True)
class Effects:
    """The hidden effects; every magnitude 0 is the healthy-but-for-the-pinion-tooth gear."""

    gear_runout_m: float = 0.0  # gear eccentricity, on the line of action
    gear_tooth_loss: float = 0.0  # relative stiffness loss of gear tooth 0
    second_pinion_tooth_loss: float = 0.0  # of pinion tooth 5
    backlash_m: float = 0.0  # a gap opened when the deflection falls below zero
    outer_race_acc: float = 0.0  # peak acceleration of each outer-race pulse response, m/s2
    inner_race_acc: float = 0.0  # the same, inner race (modulated by the load zone)
    # a spalled ball: it strikes the outer race and then the inner (weaker, through the
    # ball's other contact) once each a turn about its axis, the cage carrying it through
    # the load zone once a cage turn; peak of the outer strike's response, m/s2
    ball_acc: float = 0.0
    torque_ripple: float = 0.0  # relative input torque ripple
    ripple_hz: float = 7.3
    housing_hz: float = 0.0  # > 0: the accelerometer sits on a housing mode at this frequency
    housing_zeta: float = 0.05
    # a misaligned coupling on the pinion shaft: its 1x, 2x and 3x (as 1 : 0.6 : 0.35, in
    # the pinion's own angle, phases of their own) at the sensor, beside the mesh, m/s2
    coupling_acc: float = 0.0
    # a misaligned motor shaft behind a first stage (its 17 teeth drive 29 on the pinion's
    # shaft): its 1x, 2x and 3x (as 0.5 : 1 : 0.25, a misalignment's 2x the strongest,
    # phases of their own) in its own angle, at the sensor, m/s2
    other_shaft_acc: float = 0.0
    other_shaft_ratio: float = 29.0 / 17.0
    # a gear tilted on its shaft: the face width in contact, so every tooth pair's
    # stiffness, varies once per gear turn by this share (a load-distribution factor)
    gear_tilt: float = 0.0
    # the load torque heavier over half of each gear turn (a bent output shaft, a coupling
    # to the dynamometer misaligned): its share of the mean load, once a gear turn.
    # Through the shafts' inertia the speed swings once a gear turn (0.004: about 0.7 % of
    # it), and the mesh force by a little
    load_swing: float = 0.0


@dataclass(frozen=True)
class TruthGear:
    n_pinion: int = 14
    n_gear: int = 21
    f_pinion_hz: float = 25.0
    r_pinion_m: float = 0.03
    mass_kg: float = 0.5  # equivalent mass on the line of action, half from each body
    stiffness_n_m: float = 2e8  # mean mesh stiffness
    damping_n_s_m: float = 1000.0
    torque_n_m: float = 50.0
    contact_ratio: float = 1.6
    profile_drop: float = 0.25  # a pair's stiffness at the ends of its path, below its middle
    tip_relief: float = 0.25  # fraction of a pitch over which a pair loads and unloads
    # shafts, bearings and gear bodies in series with the teeth, relative to the teeth's
    # mean stiffness: what makes the variation of the whole mesh smaller than the teeth's
    series_stiffness_ratio: float = 0.45
    pinion_tooth_loss: float = 0.3  # pinion tooth 0 is weaker by this much
    pinion_runout_m: float = 5e-6
    pitch_error_m: float = 0.7e-6  # at the assembly-phase order
    # the simulator's own geometry (own_way): where the pinion's centre points at pinion
    # angle 0 (from the gear's centre), the pressure angle, and the gear teeth's pitch
    # errors, a pattern over `cut_passes` teeth of amplitude pitch_error_m at this phase
    own_geometry: bool = False
    pinion_runout_rad: float = 0.0
    pressure_angle_rad: float = PRESSURE_ANGLE_RAD
    cut_passes: int = 3
    pitch_error_rad: float = 0.0
    load_time_constant_s: float = 0.05  # of the dynamometer holding the speed
    # a motor's rotor driving the pinion through a flexible coupling (0: the input torque
    # acts on the pinion itself): a drive train's inertia, many times the gears', turns a
    # torque ripple into a small swing of the speed
    rotor_inertia_kg_m2: float = 0.0
    coupling_stiffness_n_m_rad: float = 2000.0
    coupling_damping_n_m_s_rad: float = 0.2
    # the geometry of the pinion's bearing (the test's 6205-type bearing)
    n_balls: int = 9
    ball_to_pitch: float = 7.94 / 39.04
    bearing_resonance_hz: float = 2800.0
    slip: float = 0.005  # random spread of the ball-pass intervals
    effects: Effects = field(default_factory=Effects)

    @property
    def r_gear_m(self) -> float:
        return self.r_pinion_m * self.n_gear / self.n_pinion

    @property
    def period_s(self) -> float:
        """The fundamental period: the pinion turns lcm(Np, Ng)/Np times."""
        return math.lcm(self.n_pinion, self.n_gear) / self.n_pinion / self.f_pinion_hz

    @property
    def bpfo_hz(self) -> float:
        return self.n_balls / 2 * self.f_pinion_hz * (1 - self.ball_to_pitch)

    @property
    def bpfi_hz(self) -> float:
        return self.n_balls / 2 * self.f_pinion_hz * (1 + self.ball_to_pitch)

    @property
    def cage_turns_per_turn(self) -> float:
        """The cage's turns a pinion turn: the balls roll between a fixed outer race and
        the turning inner, so their centres go at half the inner contact's speed."""
        return (1 - self.ball_to_pitch) / 2

    @property
    def ball_spin_hz(self) -> float:
        """A ball's turns about its own axis a second: its circumference rolls without
        slip on the fixed outer race, whose surface (radius (D + d)/2) passes the cage at
        the cage's angular speed."""
        r = self.ball_to_pitch
        return self.f_pinion_hz * self.cage_turns_per_turn * (1 + r) / r

    def with_effects(self, **magnitudes) -> "TruthGear":
        return replace(self, effects=replace(self.effects, **magnitudes))

    def own_way(self) -> "TruthGear":
        """This gear with the simulator's own runouts and pitch errors (module docstring):
        the pinion's runout 4 um at 0.9 rad, the pitch pattern 0.6 um at 2.0 rad."""
        return replace(self, own_geometry=True, pinion_runout_m=4e-6, pinion_runout_rad=0.9,
                       pitch_error_m=0.6e-6, pitch_error_rad=2.0)


def _pair_shape(s: float, g: TruthGear) -> float:
    """A tooth pair's stiffness at roll position s (pitches since it came into contact)."""
    eps = g.contact_ratio
    if s <= 0.0 or s >= eps:
        return 0.0
    middle = 2.0 * s / eps - 1.0
    value = 1.0 - g.profile_drop * middle * middle
    for edge in (s, eps - s):  # tip relief: a smooth load-up and load-down
        if edge < g.tip_relief:
            x = edge / g.tip_relief
            value *= x * x * (3.0 - 2.0 * x)
    return value


class _Mesh:
    """The mesh stiffness as a function of the pinion angle."""

    def __init__(self, g: TruthGear) -> None:
        self.g = g
        weights = np.ones(math.lcm(g.n_pinion, g.n_gear))
        n = np.arange(weights.size)
        weights[n % g.n_pinion == 0] *= 1 - g.pinion_tooth_loss
        weights[n % g.n_pinion == 5] *= 1 - g.effects.second_pinion_tooth_loss
        weights[n % g.n_gear == 0] *= 1 - g.effects.gear_tooth_loss
        self.weights = weights
        s = np.linspace(0, 1, 2001)[:-1]  # a healthy mesh cycle
        teeth = np.array([_pair_shape(x, g) + _pair_shape(x + 1, g) for x in s])
        self.series = g.series_stiffness_ratio * np.mean(teeth)
        self.k_pair = g.stiffness_n_m / np.mean(1 / (1 / teeth + 1 / self.series))
        j = np.arange(g.n_gear)  # each gear tooth's pitch error (own_geometry)
        self.gear_errors = g.pitch_error_m * np.cos(TWO_PI * j / g.cut_passes
                                                    + g.pitch_error_rad)

    def stiffness(self, theta_p: float) -> float:
        g = self.g
        u = theta_p * g.n_pinion / TWO_PI  # mesh cycles since the start
        n0 = math.floor(u)
        total = 0.0
        for n in (n0, n0 - 1):  # pairs that came into contact in this cycle and the last
            shape = _pair_shape(u - n, g)
            if shape:
                total += shape * self.weights[n % self.weights.size]
        return self.k_pair / (1 / total + 1 / self.series) if total > 0 else 0.0


def _centres(g: TruthGear, theta_p: float, theta_g: float, omega_p: float, omega_g: float
             ) -> tuple[float, float, float]:
    """(the transmission error of the two runouts, its rate, the contact ratio) at these
    angles and speeds: each gear's centre off its axis turns with it (the gear's the other
    way); the centres' distance sets the operating pressure angle (the base circles'
    tangent) and so the line of action, on which the offsets' difference is the error,
    and the length of the path of contact. The rate is the offsets' turn projected on
    that line (the line's own turn moves it by the offset over the centre distance
    more, a ten-thousandth: left out)."""
    r_p, r_g = g.r_pinion_m, g.r_gear_m
    a0 = r_p + r_g
    pinion = (g.pinion_runout_m * math.cos(theta_p + g.pinion_runout_rad),
              g.pinion_runout_m * math.sin(theta_p + g.pinion_runout_rad))
    gear = (g.effects.gear_runout_m * math.cos(0.7 - theta_g),
            g.effects.gear_runout_m * math.sin(0.7 - theta_g))
    dx, dy = a0 + gear[0] - pinion[0], gear[1] - pinion[1]
    a = math.hypot(dx, dy)
    base = a0 * math.cos(g.pressure_angle_rad)  # the base circles' radii, summed
    alpha = math.acos(base / a)
    tilt = math.atan2(dy, dx)  # the line of centres' turn
    # the line of action: tangent to both base circles, at alpha from the normal to the
    # line of centres; the pinion's offset along it leads, the gear's lags
    nx, ny = math.sin(alpha - tilt), math.cos(alpha - tilt)
    te = (pinion[0] - gear[0]) * nx + (pinion[1] - gear[1]) * ny
    rate = ((-pinion[1] * omega_p - gear[1] * omega_g) * nx
            + (pinion[0] * omega_p + gear[0] * omega_g) * ny)
    pitch = TWO_PI * r_p * math.cos(g.pressure_angle_rad) / g.n_pinion  # base pitch
    eps = g.contact_ratio - (a * math.sin(alpha) - a0 * math.sin(g.pressure_angle_rad)) / pitch
    return te, rate, eps


def _dynamics_of(g: TruthGear, mesh: _Mesh, inertia_p: float, inertia_g: float,
                 omega_g0: float, load_damping: float):
    """The mesh's dynamics, a function (y, t) -> (the state's derivatives, the mesh force);
    the state: the pinion's angle and speed, the mesh deflection and its rate, and with a
    rotor the coupling's twist and the rotor's speed. Every constant is looked up once
    here: the integrator calls it some 25 times a sample."""
    e = g.effects
    r_p, r_g = g.r_pinion_m, g.r_gear_m
    n_p = g.n_pinion
    assembly = g.n_pinion / (math.lcm(g.n_pinion, g.n_gear) / g.n_pinion)
    runout_p, pitch, runout_g = g.pinion_runout_m, g.pitch_error_m, e.gear_runout_m
    tilt, backlash, damping = e.gear_tilt, e.backlash_m, g.damping_n_s_m
    torque, ripple, ripple_w = g.torque_n_m, e.torque_ripple, TWO_PI * e.ripple_hz
    load_torque, swing = g.torque_n_m * g.n_gear / g.n_pinion, e.load_swing
    rotor_inertia = g.rotor_inertia_kg_m2
    k_coupling, c_coupling = g.coupling_stiffness_n_m_rad, g.coupling_damping_n_m_s_rad
    eps, drop, relief = g.contact_ratio, g.profile_drop, g.tip_relief
    weights, n_weights, errors = mesh.weights, mesh.weights.size, mesh.gear_errors.tolist()
    n_g = g.n_gear
    k_pair, series = mesh.k_pair, mesh.series
    sin, cos, floor = math.sin, math.cos, math.floor

    def shaped(s: float, eps: float) -> tuple[float, float]:
        """_pair_shape, inline, over a path of ``eps`` pitches, and its slope in ``s``
        (own_geometry's pitch errors move with it)."""
        if s <= 0.0 or s >= eps:
            return 0.0, 0.0
        middle = 2.0 * s / eps - 1.0
        value = 1.0 - drop * middle * middle
        slope = -drop * 2.0 * middle * 2.0 / eps
        for edge, sign in ((s, 1.0), (eps - s, -1.0)):
            if edge < relief:
                x = edge / relief
                ease = x * x * (3.0 - 2.0 * x)
                slope = slope * ease + value * sign * 6.0 * x * (1.0 - x) / relief
                value *= ease
        return value, slope

    def sine_errors(theta_p, theta_g, omega_p, omega_g):
        """(the mesh stiffness, the transmission error, its rate): runouts and the pitch
        error as sines of the shaft angles."""
        te = (runout_p * sin(theta_p) + pitch * sin(assembly * theta_p)
              + runout_g * sin(theta_g + 0.7))
        te_rate = (runout_p * cos(theta_p) * omega_p
                   + pitch * assembly * cos(assembly * theta_p) * omega_p
                   + runout_g * cos(theta_g + 0.7) * omega_g)
        u = theta_p * n_p / TWO_PI  # _Mesh.stiffness, inline
        n0 = floor(u)
        total = 0.0
        for n in (n0, n0 - 1):
            pair = shaped(u - n, eps)[0]
            if pair:
                total += pair * weights[n % n_weights]
        return (k_pair / (1 / total + 1 / series) if total > 0 else 0.0), te, te_rate

    def own_errors(theta_p, theta_g, omega_p, omega_g):
        """The same, the simulator's own way: the centres' geometry, each tooth's pitch
        error shared by the pairs in contact by their stiffness."""
        runout, runout_rate, eps = _centres(g, theta_p, theta_g, omega_p, omega_g)
        u = theta_p * n_p / TWO_PI  # mesh cycles since the start
        n0 = floor(u)
        total = moment = slope_total = slope_moment = 0.0
        for n in (n0, n0 - 1):  # pairs that came into contact in this cycle and the last
            pair, slope = shaped(u - n, eps)
            if pair:
                w = weights[n % n_weights]
                error = errors[n % n_g]  # the gear tooth of the n-th engagement
                total += pair * w
                moment += pair * w * error
                slope_total += slope * w
                slope_moment += slope * w * error
        if total <= 0:
            return 0.0, runout, runout_rate
        # the pairs' errors weighted by their stiffness, and the rate of that mean as they
        # load and unload (the mesh cycles' rate times the shares' slope)
        shared = moment / total
        rate = (slope_moment - shared * slope_total) / total * omega_p * n_p / TWO_PI
        return k_pair / (1 / total + 1 / series), runout + shared, runout_rate + rate

    errors_of = own_errors if g.own_geometry else sine_errors

    def dynamics(y, t):
        y = y.tolist()  # Python floats: the same IEEE arithmetic as numpy's scalars, faster
        theta_p, omega_p, d, dv = y[:4]
        theta_g = (r_p * theta_p - d) / r_g
        omega_g = (r_p * omega_p - dv) / r_g
        k_mesh, te, te_rate = errors_of(theta_p, theta_g, omega_p, omega_g)
        stretch = d - te
        k = k_mesh * (1.0 + tilt * cos(theta_g + 1.9))
        if backlash > 0.0 and stretch < 0.0:  # the teeth separate: no force across the gap
            stretch = min(stretch + backlash, 0.0)
            force = k * stretch + (damping * (dv - te_rate) if stretch < 0.0 else 0.0)
        else:
            force = k * stretch + damping * (dv - te_rate)
        t_in = torque * (1.0 + ripple * sin(ripple_w * t))
        t_load = (load_torque * (1.0 + swing * cos(theta_g + 2.6))
                  + load_damping * (omega_g - omega_g0))
        rotor = []
        if rotor_inertia > 0.0:  # the ripple drives the rotor, the coupling the pinion
            twist, omega_r = y[4], y[5]
            t_coupling = k_coupling * twist + c_coupling * (omega_r - omega_p)
            rotor = [omega_r - omega_p, (t_in - t_coupling) / rotor_inertia]
            t_in = t_coupling
        acc_p = (t_in - r_p * force) / inertia_p
        acc_g = (r_g * force - t_load) / inertia_g
        return [omega_p, acc_p, dv, r_p * acc_p - r_g * acc_g] + rotor, force

    return dynamics


def _pulse_train(rate_hz: float, t: np.ndarray, spread: float, rng: np.random.Generator,
                 width_s: float, sizes: tuple[float, ...] = (1.0,)
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Gaussian pulses at intervals 1/rate_hz (each interval spread by ``spread``), on t,
    their heights ``sizes`` in turn; returns (pulses, pulse times)."""
    n = int(np.ceil(t[-1] * rate_hz)) + 2
    times = np.cumsum(np.full(n, 1.0 / rate_hz) * (1 + spread * rng.standard_normal(n)))
    pulses = np.zeros_like(t)
    dt = t[1] - t[0]
    half = int(np.ceil(5 * width_s / dt))
    for i, tk in enumerate(times):
        k = int(round(tk / dt))
        lo, hi = max(k - half, 0), min(k + half + 1, t.size)
        if lo < hi:
            pulses[lo:hi] += (sizes[i % len(sizes)]
                              * np.exp(-0.5 * ((t[lo:hi] - tk) / width_s) ** 2))
    return pulses, times


def _resonance(x: np.ndarray, fs: float, f_hz: float, zeta: float, acceleration: bool):
    """x through one structural mode (unit static gain; acceleration: its second derivative
    scaled to unit gain far above the mode)."""
    w = TWO_PI * f_hz
    num = [1.0, 0.0, 0.0] if acceleration else [w * w]
    b, a = signal.bilinear(num, [1.0, 2 * zeta * w, w * w], fs)
    return signal.lfilter(b, a, x)


#: The effects only the sensor sees: the mesh's dynamics are the same without them.
SENSOR_ONLY = ("outer_race_acc", "inner_race_acc", "ball_acc", "housing_hz", "housing_zeta",
               "coupling_acc", "other_shaft_acc", "other_shaft_ratio")


def dynamics_of(g: TruthGear) -> TruthGear:
    """``g`` without the effects only the sensor sees: gears with one ``dynamics_of`` share
    one integration (:func:`simulate_many`)."""
    return replace(g, effects=replace(g.effects, **{name: getattr(Effects(), name)
                                                     for name in SENSOR_ONLY}))


def simulate(g: TruthGear, duration_s: float, sample_rate_hz: float,
             warmup_s: float = 0.3, effect_seed: int = 0) -> dict[str, np.ndarray]:
    """The noise-free channels ``acc`` (m/s2) and ``disp`` (m) over ``duration_s`` after
    ``warmup_s``; ``effect_seed`` draws the bearing's slip."""
    return simulate_many([g], duration_s, sample_rate_hz, warmup_s, effect_seed)[0]


def simulate_many(gears: list[TruthGear], duration_s: float, sample_rate_hz: float,
                  warmup_s: float = 0.3, effect_seed: int = 0) -> list[dict[str, np.ndarray]]:
    """:func:`simulate` of each of ``gears``, which differ only in what the sensor sees
    (one :func:`dynamics_of`): the mesh is integrated once."""
    if len({dynamics_of(g) for g in gears}) != 1:
        raise ValueError("the gears differ in more than what the sensor sees")
    t, y, out = _integrate(gears[0], duration_s, sample_rate_hz, warmup_s)
    return [_observe(g, t, y, out, duration_s, sample_rate_hz, warmup_s, effect_seed)
            for g in gears]


def _integrate(g: TruthGear, duration_s: float, sample_rate_hz: float, warmup_s: float):
    """(times, states, each sample's (derivatives, mesh force)) of the mesh's dynamics."""
    mesh = _Mesh(g)
    r_p, r_g = g.r_pinion_m, g.r_gear_m
    inertia_p = 2 * g.mass_kg * r_p ** 2  # each body contributes 1/(2 m) of 1/m_eq
    inertia_g = 2 * g.mass_kg * r_g ** 2
    omega_p0 = TWO_PI * g.f_pinion_hz
    omega_g0 = omega_p0 * g.n_pinion / g.n_gear
    # every body, seen at the gear
    j_gear = inertia_g + (inertia_p + g.rotor_inertia_kg_m2) * (g.n_gear / g.n_pinion) ** 2
    load_damping = j_gear / g.load_time_constant_s
    d0 = g.torque_n_m / r_p / mesh.stiffness(0.0)
    n = int(round((warmup_s + duration_s) * sample_rate_hz))
    t = np.arange(n + 1) / sample_rate_hz
    dynamics = _dynamics_of(g, mesh, inertia_p, inertia_g, omega_g0, load_damping)
    y0, atol = [0.0, omega_p0, d0, 0.0], [1e-9, 1e-6, 1e-13, 1e-9]
    if g.rotor_inertia_kg_m2 > 0.0:  # the coupling twisted by the mean torque
        y0 = y0 + [g.torque_n_m / g.coupling_stiffness_n_m_rad, omega_p0]
        atol = atol + [1e-9, 1e-6]
    y = integrate.odeint(lambda yk, tk: dynamics(yk, tk)[0], y0, t, rtol=1e-9, atol=atol,
                         hmax=0.25 / sample_rate_hz, mxstep=100_000)
    return t, y, [dynamics(yk, tk) for yk, tk in zip(y, t)]


def pinion_speed_hz(g: TruthGear, duration_s: float, sample_rate_hz: float,
                    warmup_s: float = 0.3) -> np.ndarray:
    """The pinion's speed, Hz, at each sample :func:`simulate` keeps."""
    t, y, _ = _integrate(g, duration_s, sample_rate_hz, warmup_s)
    return y[_kept(t, duration_s, sample_rate_hz, warmup_s), 1] / TWO_PI


def _kept(t: np.ndarray, duration_s: float, sample_rate_hz: float, warmup_s: float
          ) -> np.ndarray:
    """Which samples of the integration's times ``t`` a record keeps: ``duration_s`` after
    the warm-up."""
    keep = t >= warmup_s - 1e-12
    keep[np.flatnonzero(keep)[int(round(duration_s * sample_rate_hz)):]] = False
    return keep


def _observe(g: TruthGear, t: np.ndarray, y: np.ndarray, out: list, duration_s: float,
             sample_rate_hz: float, warmup_s: float, effect_seed: int) -> dict[str, np.ndarray]:
    """What the sensors see of the integrated dynamics, with ``g``'s sensor effects."""
    acc = np.array([d[3] for d, _ in out])
    e = g.effects
    if e.housing_hz > 0:  # the sensor sees the housing's response to the mesh force
        force = np.array([f for _, f in out])
        acc = _resonance(force / g.mass_kg, sample_rate_hz, e.housing_hz, e.housing_zeta, True)
    if e.coupling_acc > 0:
        theta = y[:, 0]
        acc = acc + e.coupling_acc * (np.cos(theta + 0.3) + 0.6 * np.cos(2 * theta + 1.9)
                                      + 0.35 * np.cos(3 * theta - 0.8))
    if e.other_shaft_acc > 0:
        theta = e.other_shaft_ratio * y[:, 0]  # the rigid chain: the motor's angle
        acc = acc + e.other_shaft_acc * (0.5 * np.cos(theta + 1.1) + np.cos(2 * theta - 0.4)
                                         + 0.25 * np.cos(3 * theta + 2.2))
    rng = np.random.default_rng(effect_seed)
    if e.outer_race_acc > 0:
        pulses, _ = _pulse_train(g.bpfo_hz, t, g.slip, rng, 0.1e-3)
        acc = acc + e.outer_race_acc * _unit_peak(
            _resonance(pulses, sample_rate_hz, g.bearing_resonance_hz, 0.05, True))
    if e.inner_race_acc > 0:
        pulses, _ = _pulse_train(g.bpfi_hz, t, g.slip, rng, 0.1e-3)
        zone = 0.5 * (1 + np.cos(y[:, 0]))  # the defect passes the load zone once a turn
        acc = acc + e.inner_race_acc * _unit_peak(
            _resonance(pulses * zone, sample_rate_hz, g.bearing_resonance_hz, 0.05, True))
    if e.ball_acc > 0:  # an outer strike, then an inner one, each spin of the ball
        pulses, _ = _pulse_train(2 * g.ball_spin_hz, t, g.slip, rng, 0.1e-3, (1.0, 0.6))
        zone = 0.5 * (1 + np.cos(g.cage_turns_per_turn * y[:, 0] + 0.4))
        acc = acc + e.ball_acc * _unit_peak(
            _resonance(pulses * zone, sample_rate_hz, g.bearing_resonance_hz, 0.05, True))
    keep = _kept(t, duration_s, sample_rate_hz, warmup_s)
    return {"acc": acc[keep], "disp": y[keep, 2]}


def _unit_peak(x: np.ndarray) -> np.ndarray:
    return x / (np.max(np.abs(x)) or 1.0)


def record(g: TruthGear, periods: int, seed: int, sample_rate_hz: float = 10_000.0,
           snr: float = 10.0, clean: dict[str, np.ndarray] | None = None) -> Measurement:
    """A noisy measurement (white noise at ``snr`` per channel) of ``periods`` fundamental
    periods; ``clean``: the noise-free channels when already simulated."""
    clean = clean or simulate(g, periods * g.period_s, sample_rate_hz)
    rng = np.random.default_rng(seed)
    return Measurement({k: _noisy(v, snr, rng) for k, v in clean.items()}, sample_rate_hz)


def _noisy(x: np.ndarray, snr: float, rng: np.random.Generator) -> np.ndarray:
    """``x`` with Gaussian white noise of 1/``snr`` its variance (a power ratio)."""
    return x + rng.normal(0.0, np.sqrt(np.var(x) / snr), x.shape)
