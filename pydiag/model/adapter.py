"""Adapter files: describe any FMU to pydiag, without Python.

An adapter (TOML) says which FMU variables are the fault parameters, which outputs are
the sensor channels, where the gear kinematics come from, which start values to set
and how to simulate. Example (see README, "Bring your own FMU")::

    [simulation]
    relative_tolerance = 1e-8      # optional
    engine = "auto"                # auto | native | fmpy
    warmup_s = 0.05                # start-up discarded before the analysed window (<= 100 s)
    cs_step_s = 1e-5               # Co-Simulation communication step (default: 1/(20 f_top))
    eval_timeout_s = 60.0          # wall time one simulation may take (--eval-timeout wins)

    [kinematics]                   # gear models: lines at the kinematic frequencies
    n_pinion = 14                  # a number, or {parameter = "z1"}
    n_gear = {parameter = "z2"}
    f_pinion_hz = {parameter = "n_rpm", scale = 0.016666666666666666}

    [spectrum]                     # other models (no [kinematics]): windowed FFT
    window_s = 2.0
    max_freq_hz = 50.0

    [start_values]
    "load.T" = 50.0

    [[sensor]]
    channel = "acc"                # the measurement column
    variable = "housing.a"         # the FMU output
    scale = 1.0                    # channel = scale * output

    [[fault_parameter]]
    variable = "tooth.stiffnessAmp"   # the FMU variable to set
    role = "a_f"                      # a_f, f_f, f_ate, f_dte feed the classification;
    low = 0.1                         #   any other name is estimated and reported only
    high = 0.9
    scale = 1.0                       # FMU value = scale * estimated value

Every mistake is reported as ``AdapterError`` naming the file, the table and the key.
A fault parameter becomes a :class:`~pydiag.core.parameters.Parameter` named by its role.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from pydiag.core.errors import AdapterError, UsageError
from pydiag.core.measurement import Measurement
from pydiag.core.parameters import Parameter
from pydiag.fmu.description import FmuVariable, require_settable
from pydiag.fmu.plant import DEFAULT_WARMUP_S, ENGINES, PlantSpec
from pydiag.gear.conventions import GEAR_FAULT_PARAMETERS, KINEMATIC_PARAMETERS
from pydiag.gear.kinematics import GearKinematics
from pydiag.io.units import dimension

#: Longest start-up an adapter may ask for, simulated seconds: it is simulated before every
#: evaluation (a warm-up of 1e6 s made each evaluation run until its timeout).
MAX_WARMUP_S = 100.0


@dataclass(frozen=True)
class SensorMap:
    channel: str
    variable: str
    scale: float = 1.0


@dataclass(frozen=True)
class Quantity:
    """A number, or an FMU parameter times a scale."""

    value: float | None = None
    parameter: str | None = None
    scale: float = 1.0

    def resolve(self, parameters: dict[str, float], what: str) -> float:
        if self.parameter is None:
            return float(self.value)
        if self.parameter not in parameters:
            raise AdapterError(f"[kinematics] {what}: the FMU has no parameter "
                               f"'{self.parameter}' with a start value")
        return self.scale * float(parameters[self.parameter])


@dataclass(frozen=True)
class Adapter:
    sensors: tuple[SensorMap, ...]
    fault_parameters: tuple[Parameter, ...]
    kinematics: dict[str, Quantity] | None = None
    window_s: float | None = None
    max_freq_hz: float | None = None
    start_values: dict = field(default_factory=dict)
    relative_tolerance: float | None = None
    engine: str = "auto"
    warmup_s: float = DEFAULT_WARMUP_S
    source: str = "<built-in>"
    cs_step_s: float | None = None
    eval_timeout_s: float | None = None

    def resolve_kinematics(self, parameters: dict[str, float]) -> GearKinematics | None:
        """The kinematics at FMU ``parameters`` (the values a run sets: they win over the
        adapter's start values); None for a model without [kinematics]."""
        if self.kinematics is None:
            return None
        values = {**self.start_values, **parameters}
        teeth = {}
        for name in ("n_pinion", "n_gear"):
            count = self.kinematics[name].resolve(values, name)
            if abs(count - round(count)) > 1e-9:
                raise AdapterError(f"{self.source}: [kinematics] {name} is {count:g}: a number "
                                   "of teeth must be whole")
            teeth[name] = int(round(count))
        try:
            return GearKinematics(teeth["n_pinion"], teeth["n_gear"],
                                  self.kinematics["f_pinion_hz"].resolve(values, "f_pinion_hz"))
        except UsageError as err:
            raise AdapterError(f"{self.source}: [kinematics] {err}") from err

    def kinematic_values(self, kinematics: GearKinematics) -> dict[str, float]:
        """FMU parameter values that put the model at ``kinematics``: one per kinematic
        quantity the adapter reads from a parameter (value / scale); a quantity given as a
        number is the model's fixed and cannot be set."""
        if self.kinematics is None:
            return {}
        wanted = {"n_pinion": kinematics.n_pinion, "n_gear": kinematics.n_gear,
                  "f_pinion_hz": kinematics.f_pinion_hz}
        for name in ("n_pinion", "n_gear"):
            fixed = self.kinematics[name]
            if fixed.parameter is None and round(fixed.value) != wanted[name]:
                raise UsageError(f"{self.source}: [kinematics] fixes {name} = {fixed.value:g} "
                                 "(the FMU's teeth cannot be set), but the operating point "
                                 f"asks for {wanted[name]} (--teeth, or the record's own)")
        return {q.parameter: float(wanted[name]) / q.scale
                for name, q in self.kinematics.items() if q.parameter is not None}

    def channel_names(self) -> list[str]:
        return [s.channel for s in self.sensors]

    def plant_spec(self, fmu_path: str | Path, sample_rate_hz: float,
                   sensors: tuple[SensorMap, ...] | None = None,
                   fixed_values: dict[str, float] | None = None,
                   relative_tolerance: float | None = None,
                   engine: str | None = None) -> PlantSpec:
        """How to run the FMU for ``sensors`` (default: all): the adapter's start values and
        simulation settings, overridden by the arguments that are given."""
        return PlantSpec(str(fmu_path), tuple(s.variable for s in (sensors or self.sensors)),
                         sample_rate_hz, {**self.start_values, **(fixed_values or {})},
                         relative_tolerance or self.relative_tolerance, engine or self.engine,
                         self.cs_step_s)


def gear_default(channels: list[str]) -> Adapter:
    """The conventions of the GearDiag models (:mod:`pydiag.gear.conventions`): paper
    parameter names, channel = output name, kinematics from Np, Ng, f_pinion."""
    return Adapter(
        sensors=tuple(SensorMap(c, c) for c in channels),
        fault_parameters=GEAR_FAULT_PARAMETERS,
        kinematics={field: Quantity(parameter=name) for field, name in KINEMATIC_PARAMETERS.items()})


# ---------------------------------------------------------------------- loading
def _number(table: dict, key: str, where: str, default=None, positive=False) -> float | None:
    if key not in table:
        if default is None:
            raise AdapterError(f"{where}: '{key}' is required")
        return default
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise AdapterError(f"{where}: '{key}' must be a number, got {value!r}")
    if not math.isfinite(value):
        raise AdapterError(f"{where}: '{key}' must be a finite number, got {value}")
    if positive and not value > 0:
        raise AdapterError(f"{where}: '{key}' must be positive, got {value}")
    return float(value)


def _string(table: dict, key: str, where: str) -> str:
    value = table.get(key)
    if not isinstance(value, str) or not value:
        raise AdapterError(f"{where}: '{key}' must be a non-empty string")
    return value


def _quantity(value, where: str) -> Quantity:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return Quantity(value=float(value))
    if isinstance(value, dict):
        unknown = set(value) - {"parameter", "scale"}
        if unknown:
            raise AdapterError(f"{where}: unknown key(s) {sorted(unknown)}")
        return Quantity(parameter=_string(value, "parameter", where),
                        scale=_number(value, "scale", where, default=1.0))
    raise AdapterError(f"{where}: must be a number or {{parameter = \"name\", scale = ...}}")


def _check_keys(table: dict, allowed: set[str], where: str) -> None:
    unknown = set(table) - allowed
    if unknown:
        raise AdapterError(f"{where}: unknown key(s) {sorted(unknown)}; allowed: {sorted(allowed)}")


def _tables(data: dict, key: str, allowed: set[str], source: str):
    """(where, table) for each [[key]] table; at least one is required."""
    tables = data.get(key)
    if not isinstance(tables, list) or not tables:
        raise AdapterError(f"{source}: at least one [[{key}]] table is required")
    for i, table in enumerate(tables):
        where = f"{source} [[{key}]] #{i + 1}"
        _check_keys(table, allowed, where)
        yield where, table


def parse_adapter(data: dict, source: str = "<adapter>") -> Adapter:
    _check_keys(data, {"simulation", "kinematics", "spectrum", "start_values", "sensor",
                       "fault_parameter"}, source)
    sim = data.get("simulation", {})
    _check_keys(sim, {"relative_tolerance", "engine", "warmup_s", "cs_step_s", "eval_timeout_s"},
                f"{source} [simulation]")
    cs_step = None
    if "cs_step_s" in sim:
        cs_step = _number(sim, "cs_step_s", f"{source} [simulation]", positive=True)
    engine = sim.get("engine", "auto")
    if engine not in ENGINES:
        raise AdapterError(f"{source} [simulation]: engine must be one of {ENGINES}, got {engine!r}")
    tolerance = sim.get("relative_tolerance")
    if tolerance is not None:
        tolerance = _number(sim, "relative_tolerance", f"{source} [simulation]", positive=True)
    warmup = _number(sim, "warmup_s", f"{source} [simulation]", default=DEFAULT_WARMUP_S)
    if not 0 <= warmup <= MAX_WARMUP_S:
        raise AdapterError(f"{source} [simulation]: 'warmup_s' must lie in [0, {MAX_WARMUP_S:g}] "
                           f"s (it is simulated before every evaluation), got {warmup:g}")
    timeout = None
    if "eval_timeout_s" in sim:
        timeout = _number(sim, "eval_timeout_s", f"{source} [simulation]", positive=True)

    sensor_maps = []
    for where, s in _tables(data, "sensor", {"channel", "variable", "scale"}, source):
        variable = _string(s, "variable", where)
        sensor_maps.append(SensorMap(s.get("channel", variable) or variable, variable,
                                     _number(s, "scale", where, default=1.0)))
    channels = [s.channel for s in sensor_maps]
    if len(set(channels)) != len(channels):
        raise AdapterError(f"{source}: [[sensor]] channels must be unique, got {channels}")

    param_maps = []
    for where, p in _tables(data, "fault_parameter", {"variable", "role", "low", "high", "scale"},
                            source):
        variable = _string(p, "variable", where)
        low, high = _number(p, "low", where), _number(p, "high", where)
        if not low < high:
            raise AdapterError(f"{where}: need low < high, got [{low}, {high}]")
        scale = _number(p, "scale", where, default=1.0)
        if scale == 0:
            raise AdapterError(f"{where}: 'scale' must not be 0")
        try:
            param_maps.append(Parameter(p.get("role", variable), low, high, variable, scale))
        except UsageError as err:
            raise AdapterError(f"{where}: {err}") from err
    roles = [p.name for p in param_maps]
    if len(set(roles)) != len(roles):
        raise AdapterError(f"{source}: [[fault_parameter]] roles must be unique, got {roles}")

    kin = None
    if "kinematics" in data:
        k = data["kinematics"]
        _check_keys(k, {"n_pinion", "n_gear", "f_pinion_hz"}, f"{source} [kinematics]")
        missing = {"n_pinion", "n_gear", "f_pinion_hz"} - set(k)
        if missing:
            raise AdapterError(f"{source} [kinematics]: missing {sorted(missing)}")
        kin = {name: _quantity(k[name], f"{source} [kinematics] {name}") for name in k}
    window = max_freq = None
    if "spectrum" in data:
        s = data["spectrum"]
        _check_keys(s, {"window_s", "max_freq_hz"}, f"{source} [spectrum]")
        window = _number(s, "window_s", f"{source} [spectrum]", positive=True)
        max_freq = _number(s, "max_freq_hz", f"{source} [spectrum]", positive=True)
    if kin is None and window is None:
        raise AdapterError(f"{source}: give [kinematics] (gear models) or [spectrum] (others)")
    if kin is not None and window is not None:
        raise AdapterError(f"{source}: give either [kinematics] or [spectrum], not both")

    starts = data.get("start_values", {})
    for name, value in starts.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                not math.isfinite(value):
            raise AdapterError(f"{source} [start_values]: '{name}' must be a finite number")
    return Adapter(tuple(sensor_maps), tuple(param_maps), kin, window, max_freq,
                   {k: float(v) for k, v in starts.items()}, tolerance, engine, warmup, source,
                   cs_step, timeout)


def load_adapter(path: str | Path) -> Adapter:
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except OSError as err:
        raise AdapterError(f"cannot read adapter {path}: {err.strerror or err}") from err
    except UnicodeDecodeError as err:
        raise AdapterError(f"{path}: not UTF-8 text (TOML files are UTF-8): {err}") from err
    except tomllib.TOMLDecodeError as err:
        raise AdapterError(f"{path}: not valid TOML: {err}") from err
    return parse_adapter(data, str(path))


def check_against_fmu(adapter: Adapter, variables: dict[str, FmuVariable]) -> None:
    """Every name the adapter uses exists in the FMU, and what it sets can be set."""
    src = adapter.source
    for s in adapter.sensors:
        if s.variable not in variables:
            raise AdapterError(f"{src}: sensor variable '{s.variable}' is not in the FMU")
    for p in adapter.fault_parameters:
        require_settable(variables, p.fmu_variable, f"{src}: fault parameter", AdapterError)
    for name in adapter.start_values:
        require_settable(variables, name, f"{src}: start value", AdapterError)


def check_units(measurement: Measurement, maps: tuple[SensorMap, ...],
                variables: dict[str, FmuVariable]) -> None:
    """UsageError where a channel's unit (converted with --unit) measures another quantity
    than the model output it is compared with (a length read onto an acceleration)."""
    given = measurement.metadata.get("si_units", {})
    for s in maps:
        si = given.get(s.channel)
        model_unit = getattr(variables.get(s.variable), "unit", None)
        expected = dimension(model_unit) if model_unit else None
        if si and expected and si != expected:
            words = {"m/s2": "an acceleration", "m/s": "a velocity", "m": "a displacement"}
            raise UsageError(f"channel {s.channel} was given in {words[si]} unit ("
                             f"{measurement.metadata.get('units', {}).get(s.channel, si)}), but "
                             f"the model's output {s.variable} is {words[expected]} "
                             f"({model_unit}): check --unit")
