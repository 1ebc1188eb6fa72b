"""What pydiag writes into a machine file: an effect accepted on a stage, a fit of the
machine's model to start the next fit from. The user's file is edited where it is
(:func:`~pydiag.io.outputs.edit_in_place`), the rest of it as it was, and each edit is
checked as the file would be read before it is written."""

from __future__ import annotations

import json
import math
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path

from pydiag.core.errors import UsageError
from pydiag.gear.effects import EFFECTS
from pydiag.gear.machine import Machine
from pydiag.gear.machine_file import load_machine, machine_from_dict
from pydiag.io.outputs import edit_in_place
from pydiag.loop.stage_catalogue import not_on_a_stage, nothing_to_fit, on_a_stage


def accept(path: str | Path, key: str, stage: str | None = None,
           off: tuple[str, ...] = ()) -> Machine:
    """Give the machine of the file ``path`` the effect ``key`` on ``stage`` (its name or
    number; may be left out for a machine of one stage), with its parameters ``off`` held
    at their neutral value: an ``[[effects]]`` table appended to the file, in its own line
    ends, the rest of it as it was. The file is checked as it would be read first, then
    appended to where it is (:func:`~pydiag.io.outputs.edit_in_place`: a link still names
    it, its mode stays, a read-only file is refused, another process's lines are kept), so
    a refused edit leaves it as it was. Returns the machine it now describes."""
    path = Path(path)
    machine = load_machine(path)
    if key not in EFFECTS:
        raise UsageError(f"no effect {key!r} in the catalogue ({', '.join(EFFECTS)})")
    if not on_a_stage(EFFECTS[key]):
        raise UsageError(not_on_a_stage(key))
    if stage is None and len(machine.stages) > 1:
        raise UsageError(f"{path}: {len(machine.stages)} stages: give the stage the effect "
                         f"is on ({machine.stage_choices()})")
    index = 0 if stage is None else machine.stage_index(stage)
    name = machine.stages[index].name
    if key in machine.effect_keys(index):
        raise UsageError(f"{path}: {key} is on {name} already")
    if why := nothing_to_fit(machine, index, key):  # the model would refuse it
        raise UsageError(f"{path}: {why}")
    edited: list[Machine] = []

    def added(text: str) -> str:  # the table, in the file's own line ends
        nl = "\r\n" if "\r\n" in text else "\n"
        text += ("" if text.endswith("\n") or not text else nl) + \
            f"{nl}[[effects]]{nl}key = \"{key}\"{nl}stage = {_toml_string(name)}{nl}"
        if off:
            text += f"off = [{', '.join(_toml_string(o) for o in off)}]{nl}"
        edited.append(_read_back(text, path))
        return text

    edit_in_place(path, added)
    return edited[0]


def _toml_string(text: str) -> str:
    """``text`` as a TOML basic string: any character as it is, but quotes, backslashes and
    control characters escaped (JSON's escapes of those are TOML's)."""
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def _read_back(text: str, path: Path) -> Machine:
    """The machine the edited ``text`` of ``path`` describes: an edit that would leave the
    file unreadable is refused before it is written."""
    try:
        return machine_from_dict(tomllib.loads(text), str(path))
    except tomllib.TOMLDecodeError as err:  # a bug of the edit, not the user's file
        raise RuntimeError(f"the edit of {path} would not be valid TOML: {err}") from err


#: The line the loop writes above a machine file's [start] table.
START_NOTE = ("# a fit of this machine's model (pydiag loop's last): every fit of it "
              "also polishes from here")


#: A TOML table's header line, ``[name]`` or ``[[name]]``, with any spacing TOML allows
#: and a comment.
_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\[\]]*?)\s*\]\]?\s*(#.*)?$")


def record_start(path: str | Path, values: Mapping[str, float]) -> Machine:
    """Write ``values`` (a fit of the machine's model, by parameter name) as the file's
    ``[start]`` table, in place of the one it had, at its end; the rest of the file
    (comments too, its line ends) as it was. Checked as it would be read, then written
    where the file is (:func:`~pydiag.io.outputs.edit_in_place`). Returns the machine it
    now describes."""
    path = Path(path)
    edited: list[Machine] = []

    def rewritten(text: str) -> str:
        nl = "\r\n" if "\r\n" in text else "\n"
        kept, inside = [], False
        for line in text.splitlines():
            header = _HEADER.match(line)
            if header:
                inside = header.group(1) == "[" and header.group(2) == "start"
            if not inside and line != START_NOTE:
                kept.append(line)
        rows = "".join(f"{_toml_string(name)} = {float(value)!r}{nl}"
                       for name, value in sorted(values.items()) if math.isfinite(value))
        text = nl.join(kept).rstrip("\r\n") + f"{nl}{nl}{START_NOTE}{nl}[start]{nl}{rows}"
        edited.append(_read_back(text, path))
        return text

    edit_in_place(path, rewritten)
    return edited[0]
