"""rumoca front end: compile a Modelica model and return its flat equations with roles.

Variable roles (state, algebraic, output, parameter) come from rumoca's DAE stage
(``Model.states``, ``Model.algebraics``...). Expressions come from its ``flat`` stage,
whose equations are residual trees with source spans; the DAE stage stores the same
expressions in a compact arena that is harder to walk and carries no extra information
for the models this bridge supports.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import rumoca

from fmu_build.errors import ModelicaBuildError

Tree = dict[str, Any]


@dataclass
class SourceMap:
    """Turns rumoca's (source id, byte offset) spans into ``file:line`` strings."""

    files: dict[int, tuple[str, str]] = field(default_factory=dict)

    def locate(self, span: dict | None) -> str | None:
        if not span or span.get("source") not in self.files:
            return None
        name, text = self.files[span["source"]]
        line = text.count("\n", 0, span.get("start", 0)) + 1
        return f"{name}:{line}"


@dataclass
class Variable:
    name: str
    role: str  # "parameter" | "state" | "algebraic" | "output"
    type_name: str  # "Real" | "Integer" | "Boolean"
    unit: str | None
    description: str | None
    start: Tree | None
    binding: Tree | None
    fixed: bool | None
    location: str | None
    nominal: Tree | None = None


@dataclass
class Equation:
    residual: Tree
    location: str | None


@dataclass
class FlatModel:
    name: str
    variables: dict[str, Variable]
    equations: list[Equation]
    functions: dict[str, Tree]
    sources: SourceMap

    def names(self, role: str) -> list[str]:
        return [v.name for v in self.variables.values() if v.role == role]


def find_library_root(model_file: Path) -> Path:
    """The folder holding the top-level package of ``model_file`` (walk up through package.mo)."""
    folder = model_file.resolve().parent
    while (folder / "package.mo").exists() and (folder.parent / "package.mo").exists():
        folder = folder.parent
    return folder.parent if (folder / "package.mo").exists() else folder


def _diagnostics_text(err: rumoca.RumocaError) -> str:
    lines = []
    for diag in getattr(err, "diagnostics", None) or []:
        where = f"{diag.file}:{diag.line}: " if diag.file and diag.line else ""
        lines.append(f"{where}{diag.message}")
    return "; ".join(lines) or str(err).splitlines()[0]


def _literal_value(tree: Tree | None) -> float | None:
    if tree and "Literal" in tree:
        (kind, value), = tree["Literal"]["value"].items()
        return float(value)
    return None


def flatten(model_file: str | Path, model: str,
            library_roots: tuple[Path, ...] = ()) -> FlatModel:
    """Compile ``model`` from ``model_file`` with rumoca (its library's root, and
    ``library_roots`` besides); raise ModelicaBuildError on any failure."""
    path = Path(model_file)
    if not path.is_file():
        raise ModelicaBuildError(f"no such Modelica file: {path}")
    roots = [str(find_library_root(path))] + [str(Path(r).resolve()) for r in library_roots]
    session = rumoca.Session(roots=list(dict.fromkeys(roots)))
    try:
        compiled = session.load(str(path), model=model)
        dae = compiled.to_dict("dae")
        flat = compiled.to_dict("flat")
    except rumoca.RumocaError as err:
        raise ModelicaBuildError(f"rumoca could not compile {model}: {_diagnostics_text(err)}") from err

    sources = SourceMap({sid: (name, text) for sid, name, text in dae["source_map"]["files"]})
    if len(compiled.inputs):
        raise ModelicaBuildError(
            f"top-level inputs are not supported ({', '.join(compiled.inputs.names)}); "
            "make them parameters")
    roles = {name: "state" for name in compiled.states.names}
    roles.update({name: "algebraic" for name in compiled.algebraics.names})
    roles.update({name: "output" for name in compiled.outputs.names})
    roles.update({name: "parameter" for name in compiled.parameters.names})

    variables: dict[str, Variable] = {}
    for name, var in flat["variables"].items():
        if name not in roles:
            continue  # constants, folded into literals by rumoca
        location = sources.locate(var.get("source_span"))
        type_name = flat["variable_type_names"].get(name, "Real") if isinstance(
            flat.get("variable_type_names"), dict) else "Real"
        fixed = var.get("fixed")  # rumoca gives [bool] or null
        if isinstance(fixed, list):
            fixed = fixed[0] if fixed else None
        common = dict(role=roles[name], type_name=type_name, unit=var.get("unit"),
                      description=var.get("description"),
                      fixed=None if fixed is None else bool(fixed), location=location,
                      nominal=var.get("nominal"))
        dims = var.get("dims") or []
        if not dims:
            variables[name] = Variable(name=name, start=var.get("start"),
                                       binding=var.get("binding"), **common)
            continue
        if roles[name] != "parameter" or len(dims) != 1:
            raise ModelicaBuildError(f"array variable '{name}' is not supported (only "
                                     "one-dimensional parameters are)", location)
        starts = element_trees(name, var.get("start"), dims[0], location)
        bindings = element_trees(name, var.get("binding"), dims[0], location)
        for i in range(dims[0]):
            element = f"{name}[{i + 1}]"
            variables[element] = Variable(name=element, start=starts[i], binding=bindings[i],
                                          **common)
    missing = {name for name in roles if not any(
        v == name or v.startswith(f"{name}[") for v in variables)}
    if missing:
        raise ModelicaBuildError(f"rumoca's flat model lacks variables {sorted(missing)}")

    for key in ("algorithms", "when_chains", "initial_equations", "initial_algorithms",
                "structured_equations", "assert_equations"):
        if flat.get(key):
            raise ModelicaBuildError(f"{key.replace('_', ' ')} are not supported")

    equations = []
    for eq in flat["equations"]:
        if "residual" not in eq:
            raise ModelicaBuildError(f"equation form {next(iter(eq))} is not supported")
        equations.append(Equation(eq["residual"], sources.locate(_first_span(eq["residual"]))))
    return FlatModel(model, variables, equations, flat["functions"], sources)


def element_name(name: str, subscripts: list[Tree]) -> str:
    """The scalar name of ``name`` at literal ``subscripts`` (``a[2]``): how a one-dimensional
    array parameter is named once expanded (:func:`element_trees`)."""
    indices = []
    for sub in subscripts:
        if "Index" not in sub:
            raise ValueError(f"a subscript of '{name}' is not a literal index")
        indices.append(str(int(sub["Index"]["value"])))
    return f"{name}[{','.join(indices)}]"


def element_trees(name: str, tree: Tree | None, size: int,
                  location: str | None) -> list[Tree | None]:
    """The ``size`` element expressions of an array parameter's value ``tree``: an array
    literal's elements, another array parameter's elements (``c = a`` in a modification),
    ``fill(v, n)``, ``zeros(n)``, ``ones(n)``, or one scalar for every element."""
    if tree is None:
        return [None] * size
    (kind, node), = tree.items()
    if kind == "Array" and len(node["elements"]) == size:
        return list(node["elements"])
    if kind == "VarRef" and not node.get("subscripts"):
        return [{"VarRef": {**node, "subscripts": [{"Index": {"value": i + 1}}]}}
                for i in range(size)]
    if kind == "BuiltinCall" and node["function"] in ("Fill", "Zeros", "Ones"):
        value = {"Fill": node["args"][0] if node["args"] else None,
                 "Zeros": {"Literal": {"value": {"Real": 0.0}}},
                 "Ones": {"Literal": {"value": {"Real": 1.0}}}}[node["function"]]
        if value is not None:
            return [value] * size
    if kind == "Literal":
        return [tree] * size
    raise ModelicaBuildError(f"the value of array parameter '{name}' is not supported (an "
                             f"array literal of {size} elements, another array parameter, "
                             "fill(), zeros() or ones() are)", location)


def _first_span(tree: Any) -> dict | None:
    """The first source span found in a tree (depth first), for error messages."""
    if isinstance(tree, dict):
        if "span" in tree and isinstance(tree["span"], dict) and "source" in tree["span"]:
            return tree["span"]
        for value in tree.values():
            span = _first_span(value)
            if span:
                return span
    elif isinstance(tree, list):
        for value in tree:
            span = _first_span(value)
            if span:
                return span
    return None
