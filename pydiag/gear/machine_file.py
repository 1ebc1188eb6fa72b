"""The machine file read and checked: a TOML file (its format: docs/machine-file.md) in, a
:class:`~pydiag.gear.machine.Machine` out, every mistake a
:class:`~pydiag.core.errors.MachineError` naming the file, the table and the key."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

from pydiag.core.errors import MachineError
from pydiag.gear.effects import EFFECTS
from pydiag.gear.kinematics import Bearing, crowded
from pydiag.gear.machine import (LATER_TYPES, PARALLEL_TYPES, Machine, Sensor,
                                 Stage, StageEffect, Tacho)

_TOP_KEYS = {"name", "input_rpm", "shafts", "stages", "bearings", "sensors", "tacho",
             "effects", "start"}
_STAGE_KEYS = {"name", "type", "pinion_teeth", "gear_teeth"}
_BEARING_KEYS = {"name", "shaft", "n_balls", "ball_diameter_mm", "pitch_diameter_mm",
                 "contact_angle_deg"}
_SENSOR_KEYS = {"channel", "unit", "sensitivity", "near_stage", "output"}
_TACHO_KEYS = {"channel", "pulses_per_rev", "shaft"}
_EFFECT_KEYS = {"key", "stage", "off"}


# ---------------------------------------------------------------------- reading
def _where(source: str, table: str, key: str) -> str:
    return f"{source}: {table}{'.' if table and key else ''}{key}"


def _check_keys(data: dict, allowed: set[str], source: str, table: str) -> None:
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise MachineError(f"{_where(source, table, unknown[0])}: unknown key (known: "
                           f"{', '.join(sorted(allowed))})")


def _require(table: dict, key: str, source: str, where: str) -> None:
    """A :class:`MachineError` naming the file and the key unless ``table`` has ``key``."""
    if key not in table:
        raise MachineError(f"{_where(source, where, key)}: missing")


def _teeth(value, source: str, table: str, key: str, least: int = 1) -> int:
    """A count (teeth, balls, pulses) of at least ``least``: a whole number, not inf or
    nan."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value) or value != int(value) or value < least:
        what = ("a whole number of at least 2 (a gear of one tooth meshes once a turn: "
                "no mesh to tell from its shaft)" if least == 2 else "a positive whole number")
        raise MachineError(f"{_where(source, table, key)}: {what}, got {value!r}")
    return int(value)


def _positive(value, source: str, table: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value) or value <= 0:
        raise MachineError(f"{_where(source, table, key)}: must be a positive number, "
                           f"got {value!r}")
    return float(value)


def _text(value, source: str, table: str, key: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise MachineError(f"{_where(source, table, key)}: must be a non-empty string, "
                           f"got {value!r}")
    return value.strip()


def _tables(data: dict, key: str, source: str) -> list[dict]:
    value = data.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise MachineError(f"{source}: {key}: must be an array of tables ([[{key}]])")
    return value


def _default_shafts(n_stages: int) -> tuple[str, ...]:
    if n_stages == 1:
        return ("input", "output")
    middle = ["intermediate"] if n_stages == 2 else [f"intermediate {k}"
                                                     for k in range(1, n_stages)]
    return ("input", *middle, "output")


def _stage(table: dict, k: int, source: str) -> Stage:
    where = f"stages[{k}]"
    _check_keys(table, _STAGE_KEYS, source, where)
    kind = _text(table.get("type", "spur"), source, where, "type")
    if kind in LATER_TYPES:
        raise MachineError(f"{_where(source, where, 'type')}: {kind} stages are not supported "
                           "yet (parallel-axis stages only: spur, helical)")
    if kind not in PARALLEL_TYPES:
        raise MachineError(f"{_where(source, where, 'type')}: unknown stage type '{kind}' "
                           f"(known: {', '.join(PARALLEL_TYPES + LATER_TYPES)})")
    for key in ("pinion_teeth", "gear_teeth"):
        _require(table, key, source, where)
    return Stage(_teeth(table["pinion_teeth"], source, where, "pinion_teeth", 2),
                 _teeth(table["gear_teeth"], source, where, "gear_teeth", 2),
                 _text(table.get("name", f"stage {k + 1}"), source, where, "name"), kind)


def machine_from_dict(data: dict, source: str = "(in memory)") -> Machine:
    """A :class:`Machine` from the parsed TOML ``data`` (``source`` names it in errors)."""
    _check_keys(data, _TOP_KEYS, source, "")
    stages = tuple(_stage(t, k, source) for k, t in enumerate(_tables(data, "stages", source)))
    if not stages:
        raise MachineError(f"{source}: stages: a machine needs at least one [[stages]] table")
    names = [s.name for s in stages]
    if len(set(names)) != len(names):
        raise MachineError(f"{source}: stages: two stages are called the same")
    shafts = data.get("shafts")
    if shafts is None:
        shafts = _default_shafts(len(stages))
    else:
        if not isinstance(shafts, list) or len(shafts) != len(stages) + 1:
            raise MachineError(f"{source}: shafts: {len(stages)} stage(s) need a list of "
                               f"{len(stages) + 1} shaft names (input first)")
        shafts = tuple(_text(s, source, "", f"shafts[{i}]") for i, s in enumerate(shafts))
        if len(set(shafts)) != len(shafts):
            raise MachineError(f"{source}: shafts: two shafts are called the same")
    machine = Machine(_text(data.get("name", Path(source).stem), source, "", "name"),
                      stages, tuple(shafts),
                      _positive(data["input_rpm"], source, "", "input_rpm") / 60.0
                      if "input_rpm" in data else None, source=source)

    def shaft_of(table: dict, where: str, default: int | None = None) -> int:
        if "shaft" not in table:
            if default is None:
                raise MachineError(f"{_where(source, where, 'shaft')}: missing")
            return default
        name = table["shaft"]
        if not isinstance(name, str) or name not in machine.shafts:
            raise MachineError(f"{_where(source, where, 'shaft')}: no shaft called {name!r}; "
                               f"the shafts are {', '.join(machine.shafts)}")
        return machine.shafts.index(name)

    bearings = []
    for i, t in enumerate(_tables(data, "bearings", source)):
        where = f"bearings[{i}]"
        _check_keys(t, _BEARING_KEYS, source, where)
        for key in ("n_balls", "ball_diameter_mm", "pitch_diameter_mm"):
            _require(t, key, source, where)
        n = _teeth(t["n_balls"], source, where, "n_balls")
        d = _positive(t["ball_diameter_mm"], source, where, "ball_diameter_mm")
        pitch = _positive(t["pitch_diameter_mm"], source, where, "pitch_diameter_mm")
        if d >= pitch:
            raise MachineError(f"{_where(source, where, 'ball_diameter_mm')}: must be below "
                               f"pitch_diameter_mm ({d:g} >= {pitch:g})")
        if why := crowded(n, d, pitch):
            raise MachineError(f"{_where(source, where, 'n_balls')}: {why}")
        angle = t.get("contact_angle_deg", 0.0)
        if isinstance(angle, bool) or not isinstance(angle, (int, float)) \
                or not 0 <= angle < 90:
            raise MachineError(f"{_where(source, where, 'contact_angle_deg')}: must lie in "
                               f"[0, 90), got {angle!r}")
        bearings.append(Bearing(n, d * 1e-3, pitch * 1e-3, math.radians(angle),
                                machine.shafts[shaft_of(t, where)],
                                _text(t.get("name", f"bearing {i + 1}"), source, where, "name")))
        if bearings[-1].name in [b.name for b in bearings[:-1]]:  # each is judged by name
            raise MachineError(f"{_where(source, where, 'name')}: another bearing is called "
                               f"{bearings[-1].name!r}: give each a name of its own")
    sensors = []
    for i, t in enumerate(_tables(data, "sensors", source)):
        where = f"sensors[{i}]"
        _check_keys(t, _SENSOR_KEYS, source, where)
        _require(t, "channel", source, where)
        near = None
        if "near_stage" in t:
            if t["near_stage"] not in names:
                raise MachineError(f"{_where(source, where, 'near_stage')}: no stage called "
                                   f"{t['near_stage']!r}; the stages are {', '.join(names)}")
            near = names.index(t["near_stage"])
        sensors.append(Sensor(
            _text(t["channel"], source, where, "channel"),
            _text(t["unit"], source, where, "unit") if "unit" in t else None,
            _text(t["sensitivity"], source, where, "sensitivity") if "sensitivity" in t
            else None, near, _text(t.get("output", "acc"), source, where, "output")))
    channels = [s.channel for s in sensors]
    if len(set(channels)) != len(channels):
        raise MachineError(f"{source}: sensors: a channel is described twice")
    tacho = None
    if "tacho" in data:
        t = data["tacho"]
        if not isinstance(t, dict):
            raise MachineError(f"{source}: tacho: must be a table ([tacho])")
        _check_keys(t, _TACHO_KEYS, source, "tacho")
        _require(t, "channel", source, "tacho")
        tacho = Tacho(_text(t["channel"], source, "tacho", "channel"),
                      _teeth(t.get("pulses_per_rev", 1), source, "tacho", "pulses_per_rev"),
                      shaft_of(t, "tacho", 0))
        if tacho.channel in channels:
            raise MachineError(f"{_where(source, 'tacho', 'channel')}: '{tacho.channel}' is "
                               "also a vibration sensor")
    effects = []
    for i, t in enumerate(_tables(data, "effects", source)):
        where = f"effects[{i}]"
        _check_keys(t, _EFFECT_KEYS, source, where)
        _require(t, "key", source, where)
        key = _text(t["key"], source, where, "key")
        if key not in EFFECTS:
            raise MachineError(f"{_where(source, where, 'key')}: no effect {key!r} in the "
                               f"catalogue ({', '.join(EFFECTS)})")
        if "stage" not in t and len(stages) > 1:
            raise MachineError(f"{_where(source, where, 'stage')}: missing (the machine has "
                               f"{len(stages)} stages)")
        stage = t.get("stage", names[0])
        if stage not in names:
            raise MachineError(f"{_where(source, where, 'stage')}: no stage called {stage!r}; "
                               f"the stages are {', '.join(names)}")
        if any((e.key, e.stage) == (key, names.index(stage)) for e in effects):
            raise MachineError(f"{_where(source, where, 'key')}: {key} is on {stage} twice")
        off = t.get("off", [])
        known = [p.name for p in EFFECTS[key].parameters]
        if not isinstance(off, list) or any(name not in known for name in off):
            raise MachineError(f"{_where(source, where, 'off')}: a list of {key}'s parameters "
                               f"({', '.join(known)}), got {off!r}")
        effects.append(StageEffect(key, names.index(stage), tuple(off)))
    start = data.get("start", {})
    if not isinstance(start, dict) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in start.values()):
        raise MachineError(f"{source}: start: a table of parameter names and finite numbers "
                           "([start])")
    return Machine(machine.name, stages, machine.shafts, machine.input_hz, tuple(bearings),
                   tuple(sensors), tacho, source, tuple(effects),
                   tuple((str(k), float(v)) for k, v in start.items()))


def load_machine(path: str | Path) -> Machine:
    """The machine described by the TOML file ``path`` (module docstring)."""
    path = Path(path)
    try:  # utf-8-sig: a byte-order mark, as some editors write, is no statement
        data = tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except FileNotFoundError as err:
        raise MachineError(f"machine file {path} not found") from err
    except (OSError, UnicodeDecodeError) as err:
        raise MachineError(f"machine file {path} cannot be read: {err}") from err
    except tomllib.TOMLDecodeError as err:
        raise MachineError(f"{path}: not valid TOML: {err}") from err
    except RecursionError as err:
        raise MachineError(f"{path}: arrays or tables nested too deeply to be a machine "
                           "file") from err
    return machine_from_dict(data, str(path))
