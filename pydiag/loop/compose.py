"""Models with several catalogue effects at once: the Modelica source of GearDiag.GearPair
with every effect's contribution, written from the effects' own files, and its FMU built
once per content.

Every effect of the catalogue with a model of its own extends GearDiag.GearPair and gives
one of its hooks (``GearDiag/Effects/package.mo``). Contributions combine as the physics
does:

- ``k_mod`` (relative stiffness), ``e_extra`` (transmission error), ``F_extra`` (force),
  what ``acc_sensor`` adds to ``der(v)`` (a shaft's or a bearing's own vibration at the
  sensor) and what ``t_angle`` adds to ``time`` (a speed's fluctuation, a shaft's swing:
  angles add) are sums: each effect's term is added;
- ``contact`` (the teeth separate) is the state of the mesh itself: one effect at most
  may set it.

The same effects compose on a stage's mesh between two shafts
(``GearDiag.Components.GearMesh``, :data:`MESH`, a machine's model's stage): its
``acc_sensor`` starts from what the housing sees of the mesh force, its ``t_angle`` from
the stage's own phase, and its ``F_extra`` is a force from outside the mesh that the gear's
shaft takes (a torque ripple of the stage's drive or load).

The effects' declarations (parameters, components) are copied as written; a component
name two effects use is prefixed with the effect's key in the second; a parameter two
effects declare differently cannot be shared, and the composition is refused naming it.
The source is written beside the FMU, readable; the FMU's name carries a hash of the
source and of the library it extends, so an edit of either builds a new one.
"""

from __future__ import annotations

import hashlib
import os
import re
import threading
from dataclasses import dataclass
from pathlib import Path

from pydiag.core.errors import UsageError
from pydiag.fmu.archive import usable_cache
from pydiag.gear.effect import model_file
from pydiag.gear.effects import EFFECTS

#: Hooks whose contributions add.
SUMMED_HOOKS = ("k_mod", "e_extra", "F_extra", "acc_sensor", "t_angle")
#: Hooks one effect at most may set.
SOLE_HOOKS = ("contact",)
#: What an effect's contribution to a hook is added to in its own model, for the hooks
#: that are not 0 without effects: the pair's mesh acceleration, its steady angle.
PAIR_STARTS = {"acc_sensor": "der(v)", "t_angle": "time"}

_EXTENDS = re.compile(r"extends\s+GearDiag\.GearPair\s*\(")
_COMPONENT = re.compile(r"^\s*GearDiag\.[\w.]+\s+(\w+)\s*[(\s\"]", re.M)
_PARAMETER = re.compile(r"^\s*parameter\s+\w+\s+(\w+)", re.M)


@dataclass(frozen=True)
class Base:
    """What composed effects extend: its class, the hooks it has, and what each of
    :data:`PAIR_STARTS`' hooks is without effects."""

    model: str
    hooks: tuple[str, ...]
    starts: dict[str, str]


#: The paper's pair: every effect's own model extends it.
PAIR = Base("GearDiag.GearPair", SUMMED_HOOKS + SOLE_HOOKS, PAIR_STARTS)
#: A stage's mesh between two shafts (a machine's model).
MESH = Base("GearDiag.Components.GearMesh", SUMMED_HOOKS + SOLE_HOOKS,
            {"acc_sensor": "(T/r_p + F_extra - mesh_force)/m_s", "t_angle": "time + t_phase"})


class CompositionError(UsageError):
    """The effects cannot share one model (a hook both set, a parameter both declare)."""


@dataclass(frozen=True)
class EffectSource:
    """One effect's model as written: the hook it gives and the expression, its
    declarations (the lines after the ``extends`` clause), and their names."""

    key: str
    hook: str
    expression: str
    declarations: str
    parameters: dict[str, str]
    components: tuple[str, ...]


def read_effect(key: str, modelica_root: Path) -> EffectSource:
    """The effect ``key``'s Modelica source, taken apart (module docstring)."""
    effect = EFFECTS[key]
    if not effect.own_fmu:
        raise CompositionError(f"{key} has no model of its own (it is fitted on the base "
                               "model or applied to its output)")
    path = model_file(effect, modelica_root)
    text = re.sub(r"//[^\n]*", "", path.read_text())
    found = _EXTENDS.search(text)
    if found is None:
        raise CompositionError(f"{path}: does not extend GearDiag.GearPair")
    depth, end = 1, found.end()
    while depth:
        if end >= len(text):
            raise CompositionError(f"{path}: the extends clause is not closed")
        depth += {"(": 1, ")": -1}.get(text[end], 0)
        end += 1
    hook, sep, expression = text[found.end():end - 1].partition("=")
    hook = hook.strip()
    if not sep or hook not in SUMMED_HOOKS + SOLE_HOOKS or "," in _top_level(expression):
        raise CompositionError(f"{path}: gives {hook or 'nothing'}; an effect gives one of "
                               f"the hooks {', '.join(SUMMED_HOOKS + SOLE_HOOKS)}")
    expression = " ".join(expression.split())
    if hook in PAIR_STARTS:
        start = PAIR_STARTS[hook]
        if not expression.startswith(start + " +"):
            raise CompositionError(f"{path}: {hook} = {expression[:40]}...: only a term "
                                   f"added to {start} combines with other effects")
        expression = expression[len(start) + 2:].strip()
    body = text[text.index(";", end) + 1:]
    closing = re.search(rf"^\s*end\s+{path.stem}\s*;", body, re.M)
    if closing is None:
        raise CompositionError(f"{path}: no 'end {path.stem};' closes the model")
    body = _without_annotation(body[:closing.start()])
    parameters = {}
    for statement in _statements(body):
        name = _PARAMETER.match(statement)
        if name:
            parameters[name.group(1)] = " ".join(statement.split())
    return EffectSource(key, hook, expression, body.rstrip(), parameters,
                        tuple(_COMPONENT.findall(body)))


def _without_annotation(body: str) -> str:
    """A model body without its class annotation (the documentation: the composed model
    is documented by its own description, and a model takes one annotation)."""
    found = re.search(r"^\s*annotation\s*\(", body, re.M)
    if found is None:
        return body
    depth, quoted, end = 1, False, found.end()
    while depth and end < len(body):
        ch = body[end]
        if ch == '"' and body[end - 1] != "\\":
            quoted = not quoted
        elif not quoted:
            depth += {"(": 1, ")": -1}.get(ch, 0)
        end += 1
    rest = body[end:].lstrip()
    return body[:found.start()] + (rest[1:] if rest.startswith(";") else rest)


def _rename(text: str, old: str, new: str) -> str:
    """``text`` with the name ``old`` replaced by ``new`` outside string literals."""
    parts = text.split('"')
    return '"'.join(re.sub(rf"\b{old}\b", new, p) if i % 2 == 0 else p
                    for i, p in enumerate(parts))


def _top_level(expression: str) -> str:
    """``expression`` with everything inside parentheses removed."""
    out, depth = [], 0
    for ch in expression:
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if depth == 0 and ch not in "()":
            out.append(ch)
    return "".join(out)


def _statements(body: str) -> list[str]:
    """The declarations of a model body, one a ``;`` outside strings and parentheses."""
    out, current, depth, quoted = [], [], 0, False
    for ch in body:
        current.append(ch)
        if ch == '"':
            quoted = not quoted
        elif not quoted:
            depth += {"(": 1, ")": -1}.get(ch, 0)
            if ch == ";" and depth == 0:
                out.append("".join(current).strip())
                current = []
    return out


@dataclass(frozen=True)
class ComposedModel:
    """A base (the pair, a stage's mesh) with the effects ``keys``: the model's name and
    its source."""

    keys: tuple[str, ...]
    name: str
    source: str


def compose(keys: tuple[str, ...], modelica_root: Path, base: Base = PAIR) -> ComposedModel:
    """``base`` with every effect of ``keys`` (module docstring), in a canonical order (the
    catalogue's), so that the same set makes the same model. One effect on the pair is its
    own model: the pair takes two or more."""
    keys = tuple(k for k in EFFECTS if k in set(keys))
    if len(keys) < (2 if base == PAIR else 1):
        raise CompositionError(f"a composed model of {base.model} takes "
                               f"{'two effects' if base == PAIR else 'an effect'} or more")
    models: dict[str, str] = {}
    for k in keys:  # a gear bearing's effect is its pinion bearing's model at another speed
        if (other := models.setdefault(EFFECTS[k].model, k)) != k:
            raise CompositionError(f"{other} and {k} are one model ({EFFECTS[k].model}) at "
                                   "two shafts' speeds: one model cannot have both yet")
    sources = [read_effect(k, modelica_root) for k in keys]
    for src in sources:
        if src.hook not in base.hooks:
            raise CompositionError(f"{src.key} gives {src.hook}, which {base.model} has not")
    terms: dict[str, list[str]] = {}
    setters: dict[str, str] = {}
    declared: dict[str, tuple[str, str]] = {}
    components: set[str] = set()
    bodies = []
    for src in sources:
        if src.hook in SOLE_HOOKS and src.hook in setters:
            raise CompositionError(f"{setters[src.hook]} and {src.key} both set {src.hook}: "
                                   "one model cannot have both")
        setters.setdefault(src.hook, src.key)
        body, expression = src.declarations, src.expression
        for name in src.components:
            if name in components:  # the second one's renamed, in its expression too
                new = f"{src.key}_{name}"
                body, expression = _rename(body, name, new), _rename(expression, name, new)
                name = new
            components.add(name)
        for name, text in src.parameters.items():
            if name in declared:
                other, first = declared[name]
                if first != text:
                    raise CompositionError(f"{other} and {src.key} both declare {name}, "
                                           "differently: one model cannot have both")
                body = "\n".join(line for line in body.splitlines()
                                 if " ".join(line.split()) != text)
            declared.setdefault(name, (src.key, text))
        terms.setdefault(src.hook, []).append(expression)
        bodies.append(f"  // {src.key} ({EFFECTS[src.key].model})\n{body.strip(chr(10))}")
    modifiers = []
    for hook in SUMMED_HOOKS + SOLE_HOOKS:
        if hook in terms:
            added = " + ".join(f"({t})" for t in terms[hook])
            modifiers.append(f"{hook} = {base.starts[hook]} + {added}" if hook in base.starts
                             else f"{hook} = {added}")
    name = base.model.rsplit(".", 1)[1] + "With" + "".join(
        EFFECTS[k].model.rsplit(".", 1)[1] for k in keys)
    description = f"{base.model} with " + ", ".join(keys)
    source = ("within GearDiag;  // its effects' models are GearDiag's, and see what it declares\n"
              f"model {name} \"{description}\"\n"
              "  // Written by pydiag from the effects' models (pydiag/loop/compose.py).\n"
              f"  extends {base.model}(\n    " + ",\n    ".join(modifiers) + ");\n"
              + "\n".join(bodies) + f"\nend {name};\n")
    return ComposedModel(keys, name, source)


def library_hash(modelica_root: Path) -> str:
    """A hash of every Modelica file of the library (paths and contents)."""
    digest = hashlib.sha256()
    for path in sorted(Path(modelica_root).rglob("*.mo")):
        digest.update(str(path.relative_to(modelica_root)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def composed_fmu(keys: tuple[str, ...], modelica_root: Path, build_dir: Path) -> Path:
    """The FMU of :func:`compose`'s model, built unless one of the same source and library
    exists; its source is ``<build_dir>/composed/<name>.mo``."""
    model = compose(keys, modelica_root)
    return built_fmu(model.name, model.source, modelica_root, Path(build_dir) / "composed").fmu


@dataclass(frozen=True)
class BuiltModel:
    """A model pydiag wrote and built: its FMU, its source file, and whether that source
    is the user's edit of what pydiag wrote (then the FMU is built from the edit)."""

    fmu: Path
    source: Path
    edited: bool = False


def built_fmu(name: str, source: str, modelica_root: Path, folder: Path) -> BuiltModel:
    """The FMU of the model ``GearDiag.<name>`` written as ``source`` (it uses the library
    at ``modelica_root``), built unless one of the same source and library exists in
    ``folder``. The source is kept as ``<name>/<name>.mo`` there (a folder a model, so
    that a model is built from its own file and the library alone), readable and
    editable: an edit of it is the user's and wins (the FMU is built from it; ``edited``;
    one that does not build is the user's error, naming the file), told from pydiag's own
    earlier text by the hash of what pydiag last wrote (``.<name>.mo.written``), so a
    source pydiag writes differently replaces only its own (and one without that record,
    from before edits were kept)."""
    from fmu_build import ModelicaBuildError, build_fmu

    folder = Path(folder) / name  # a source root of its own: no other file is read with it
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.mo"
    written = folder / f".{name}.mo.written"
    text = path.read_text() if path.exists() else None
    # without a record of what pydiag wrote, the file is pydiag's own (from before edits
    # were kept)
    edited = (text is not None and text != source and written.exists()
              and written.read_text() != _digest(text))
    if edited:
        source = text
    elif text != source:
        path.write_text(source)
        written.write_text(_digest(source))
    tag = _digest(source + library_hash(modelica_root))[:12]
    out = folder / f"{name}_{tag}.fmu"
    if not usable_cache(out):  # built beside, then renamed: a failed build leaves no FMU
        partial = folder / f".{out.stem}.{os.getpid()}.{threading.get_ident()}.fmu"
        try:
            build_fmu(path, f"GearDiag.{name}", partial, library_roots=(Path(modelica_root),))
            os.replace(partial, out)
        except ModelicaBuildError as err:
            if not edited:  # pydiag's own source: a bug of pydiag's
                raise
            raise UsageError(f"{path} (your edit of the model pydiag wrote) does not build: "
                             f"{err}; mend it, or delete it for pydiag's own") from err
        finally:
            partial.unlink(missing_ok=True)
    return BuiltModel(out, path, edited)


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()
