"""Translate rumoca's flat expression trees into CasADi SX expressions.

An element of a one-dimensional array parameter at a literal index is the scalar of that
name (``a[2]``, :func:`fmu_build.flatten.element_trees`); ``sum`` of an array rumoca
unrolled (a reduction ``sum(f(k) for k in 1:n)``) is the sum of its elements.

User functions are inlined by symbolic execution of their algorithm sections:
assignments rebind names, ``if`` statements merge both branches with ``if_else``,
``for`` loops over literal ranges are unrolled. Anything else raises
ModelicaBuildError naming the construct and its source line.
"""

from __future__ import annotations

from typing import Any, Callable

import casadi as ca

from fmu_build.errors import ModelicaBuildError
from fmu_build.flatten import SourceMap, Tree, element_name

SX = ca.SX


def _mod(a: SX, b: SX) -> SX:
    """Modelica mod: a - floor(a/b)*b (result has the sign of b)."""
    return a - ca.floor(a / b) * b


def _trunc(a: SX) -> SX:
    return ca.sign(a) * ca.floor(ca.fabs(a))


_UNARY_BUILTINS: dict[str, Callable[[SX], SX]] = {
    "Sin": ca.sin, "Cos": ca.cos, "Tan": ca.tan, "Asin": ca.asin, "Acos": ca.acos,
    "Atan": ca.atan, "Sinh": ca.sinh, "Cosh": ca.cosh, "Tanh": ca.tanh, "Exp": ca.exp,
    "Log": ca.log, "Log10": lambda a: ca.log(a) / ca.log(10.0), "Sqrt": ca.sqrt,
    "Abs": ca.fabs, "Sign": ca.sign, "Floor": ca.floor, "Ceil": ca.ceil,
    "Integer": ca.floor, "NoEvent": lambda a: a,
}
_BINARY_BUILTINS: dict[str, Callable[[SX, SX], SX]] = {
    "Mod": _mod, "Rem": lambda a, b: a - _trunc(a / b) * b, "Div": lambda a, b: _trunc(a / b),
    "Min": ca.fmin, "Max": ca.fmax, "Atan2": ca.atan2,
}
_BINARY_OPS: dict[str, Callable[[SX, SX], SX]] = {
    "Add": lambda a, b: a + b, "Sub": lambda a, b: a - b, "Mul": lambda a, b: a * b,
    "Div": lambda a, b: a / b, "Exp": lambda a, b: a ** b,
    "Lt": lambda a, b: a < b, "Le": lambda a, b: a <= b, "Gt": lambda a, b: a > b,
    "Ge": lambda a, b: a >= b, "Eq": lambda a, b: a == b, "Neq": lambda a, b: a != b,
    "And": ca.logic_and, "Or": ca.logic_or,
}
_UNARY_OPS: dict[str, Callable[[SX], SX]] = {
    "Minus": lambda a: -a, "Plus": lambda a: a, "Not": ca.logic_not,
}
#: How deeply user functions may call each other before we call it recursion.
_MAX_CALL_DEPTH = 32


class ExpressionTranslator:
    """Turns trees into SX given a name -> SX environment and the model's functions."""

    def __init__(self, functions: dict[str, Tree], sources: SourceMap,
                 derivative: Callable[[str, str | None], SX] | None = None) -> None:
        self.functions = functions
        self.sources = sources
        self.derivative = derivative
        self._depth = 0

    def error(self, message: str, tree: Any) -> ModelicaBuildError:
        from fmu_build.flatten import _first_span
        return ModelicaBuildError(message, self.sources.locate(_first_span(tree)))

    # ------------------------------------------------------------------ expressions
    def translate(self, tree: Tree, env: dict[str, SX]) -> SX:
        (kind, node), = tree.items()
        if kind == "Literal":
            (_, value), = node["value"].items()
            if isinstance(value, str):
                raise self.error("string literals are not supported", tree)
            return SX(float(value))
        if kind == "VarRef":
            name = node["name"]["name"]
            if node.get("subscripts"):  # an element of an array parameter at a literal index
                try:
                    name = element_name(name, node["subscripts"])
                except ValueError as err:
                    raise self.error(f"{err} (only literal indices are supported)", tree) from err
            if name not in env:
                raise self.error(f"unknown name '{name}'", tree)
            return env[name]
        if kind == "Binary":
            op = _BINARY_OPS.get(node["op"])
            if op is None:
                raise self.error(f"binary operator {node['op']} is not supported", tree)
            return op(self.translate(node["lhs"], env), self.translate(node["rhs"], env))
        if kind == "Unary":
            op = _UNARY_OPS.get(node["op"])
            if op is None:
                raise self.error(f"unary operator {node['op']} is not supported", tree)
            return op(self.translate(node["rhs"], env))
        if kind == "If":
            result = self.translate(node["else_branch"], env)
            for cond, value in reversed(node["branches"]):
                result = ca.if_else(self.translate(cond, env), self.translate(value, env), result)
            return result
        if kind == "BuiltinCall":
            return self._builtin(tree, node, env)
        if kind == "FunctionCall":
            return self._call(tree, node, env)
        raise self.error(f"expression kind {kind} is not supported", tree)

    def _builtin(self, tree: Tree, node: Tree, env: dict[str, SX]) -> SX:
        name, args = node["function"], node["args"]
        if name == "Der":
            arg = args[0]
            if self.derivative is None or "VarRef" not in arg:
                raise self.error("der() is only supported on a variable, in equations", tree)
            return self.derivative(arg["VarRef"]["name"]["name"], self.sources.locate(
                arg["VarRef"].get("span")))
        if name == "Smooth":  # smooth(order, expr) is expr
            return self.translate(args[1], env)
        if name == "Sum" and len(args) == 1 and "Array" in args[0]:  # a reduction, unrolled
            total = SX(0.0)
            for element in args[0]["Array"]["elements"]:
                total = total + self.translate(element, env)
            return total
        if name in _UNARY_BUILTINS and len(args) == 1:
            return _UNARY_BUILTINS[name](self.translate(args[0], env))
        if name in _BINARY_BUILTINS and len(args) == 2:
            return _BINARY_BUILTINS[name](self.translate(args[0], env), self.translate(args[1], env))
        raise self.error(f"built-in function {name.lower()}() with {len(args)} argument(s) "
                         "is not supported", tree)

    # ------------------------------------------------------------------ functions
    def _call(self, tree: Tree, node: Tree, env: dict[str, SX]) -> SX:
        name = node["name"]["name"]
        func = self.functions.get(name)
        if func is None:
            raise self.error(f"function '{name}' is not known to the flat model", tree)
        if func.get("external"):
            raise self.error(f"external function '{name}' is not supported", tree)
        if len(func["outputs"]) != 1:
            raise self.error(f"function '{name}' must have exactly one output", tree)
        if node.get("is_constructor"):
            raise self.error(f"record constructor '{name}' is not supported", tree)
        inputs = func["inputs"]
        if len(node["args"]) > len(inputs):
            raise self.error(f"too many arguments in call of '{name}'", tree)
        if self._depth >= _MAX_CALL_DEPTH:
            raise self.error(f"function '{name}' calls itself (recursion is not supported)", tree)
        scope: dict[str, SX] = {}
        for i, formal in enumerate(inputs):
            if i < len(node["args"]):
                scope[formal["name"]] = self.translate(node["args"][i], env)
            elif formal.get("default") is not None:
                scope[formal["name"]] = self.translate(formal["default"], scope)
            else:
                raise self.error(f"missing argument '{formal['name']}' in call of '{name}'", tree)
        for local in func["outputs"] + func.get("locals", []):
            if local.get("shape_expr") or local.get("effective_type", {}).get("dimensions"):
                raise self.error(f"array variable '{local['name']}' in function '{name}' "
                                 "is not supported", tree)
            scope[local["name"]] = (self.translate(local["default"], scope)
                                    if local.get("default") is not None else SX(0.0))
        self._depth += 1
        try:
            scope = self._run(func["body"], scope)
        finally:
            self._depth -= 1
        return scope[func["outputs"][0]["name"]]

    def _run(self, statements: list[Tree], scope: dict[str, SX]) -> dict[str, SX]:
        for stmt in statements:
            scope = self._statement(stmt, scope)
        return scope

    def _statement(self, stmt: Tree, scope: dict[str, SX]) -> dict[str, SX]:
        (kind, node), = stmt.items()
        if kind == "Assignment":
            parts = node["comp"]["parts"]
            if len(parts) != 1 or parts[0].get("subs"):
                raise self.error("assignment to a record field or array element is not supported",
                                 stmt)
            scope = dict(scope)
            scope[parts[0]["ident"]] = self.translate(node["value"], scope)
            return scope
        if kind == "If":
            result = self._run(node.get("else_block") or [], dict(scope))
            for block in reversed(node["cond_blocks"]):
                cond = self.translate(block["cond"], scope)
                taken = self._run(block["stmts"], dict(scope))
                result = {k: (taken[k] if taken[k] is result.get(k) else
                              ca.if_else(cond, taken[k], result.get(k, scope.get(k, SX(0.0)))))
                          for k in taken}
            return result
        if kind == "For":
            if len(node["indices"]) != 1 or "Range" not in node["indices"][0]["range"]:
                raise self.error("only for-loops over one literal range are supported", stmt)
            index = node["indices"][0]
            rng = index["range"]["Range"]
            bounds = [self._constant(rng[k], scope, stmt) if rng.get(k) else None
                      for k in ("start", "step", "end")]
            start, step, end = bounds[0], bounds[1] or 1, bounds[2]
            i = start
            while (step > 0 and i <= end) or (step < 0 and i >= end):
                scope = dict(scope)
                scope[index["ident"]] = SX(float(i))
                scope = self._run(node["equations"], scope)
                i += step
            scope.pop(index["ident"], None)
            return scope
        raise self.error(f"statement '{kind.lower()}' in a function is not supported", stmt)

    def _constant(self, tree: Tree, scope: dict[str, SX], stmt: Tree) -> int:
        value = self.translate(tree, scope)
        if not value.is_constant():
            raise self.error("for-loop bounds must be constants", stmt)
        return int(float(value))
