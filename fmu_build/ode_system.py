"""Assemble a FlatModel into an explicit ODE system of CasADi SX expressions."""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from fmu_build.causalise import Residual, causalise
from fmu_build.errors import ModelicaBuildError
from fmu_build.expressions import ExpressionTranslator
from fmu_build.flatten import FlatModel

SX = ca.SX


@dataclass
class Quantity:
    """A named model quantity with its metadata."""

    name: str
    unit: str | None = None
    description: str | None = None


@dataclass
class Parameter(Quantity):
    value: float = 0.0
    type_name: str = "Real"
    symbol: SX = field(default_factory=lambda: SX(0))


@dataclass
class State(Quantity):
    symbol: SX = field(default_factory=lambda: SX(0))
    start: SX = field(default_factory=lambda: SX(0))  # may depend on parameters
    nominal: float | None = None  # scale of the state; solvers use it for absolute tolerance


@dataclass
class Computed(Quantity):
    expr: SX = field(default_factory=lambda: SX(0))


@dataclass
class Derived(Computed):
    """A parameter computed from the free parameters (``expr`` uses free ones only)."""

    symbol: SX = field(default_factory=lambda: SX(0))


@dataclass
class OdeSystem:
    """dx/dt = f(t, x, p, d); outputs and locals y = g(t, x, p, d); derived parameters d = h(p).

    Derivatives, outputs, locals and state starts refer to the derived parameters by their
    symbols, so an FMU can compute ``h`` once per parameter set instead of on every call
    (a Modelica tool's parameter stage); :meth:`in_free_parameters` substitutes them.
    """

    name: str
    time: SX
    parameters: list[Parameter]
    states: list[State]
    derivatives: list[SX]
    outputs: list[Computed]
    locals: list[Computed]
    derived: list[Derived]

    def parameter_values(self) -> dict[str, float]:
        return {p.name: p.value for p in self.parameters}

    def in_free_parameters(self, expr: SX) -> SX:
        """``expr`` with every derived parameter replaced by its expression."""
        if not self.derived:
            return expr
        return ca.substitute([expr], [d.symbol for d in self.derived],
                             [d.expr for d in self.derived])[0]

    def functions(self) -> tuple[ca.Function, ca.Function, ca.Function]:
        """(rhs(t, x, p) -> dx, out(t, x, p) -> y, x0(p) -> x(0)) as CasADi Functions."""
        t = self.time
        x = ca.vertcat(*[s.symbol for s in self.states])
        p = ca.vertcat(*[q.symbol for q in self.parameters])
        free = self.in_free_parameters
        rhs = ca.Function("rhs", [t, x, p], [free(ca.vertcat(*self.derivatives))])
        out = ca.Function("out", [t, x, p], [free(ca.vertcat(*[o.expr for o in self.outputs]))])
        x0 = ca.Function("x0", [p], [free(ca.vertcat(*[s.start for s in self.states]))])
        return rhs, out, x0


def _literal(tree) -> float | None:
    if tree and "Literal" in tree:
        (_, value), = tree["Literal"]["value"].items()
        return None if isinstance(value, str) else float(value)
    return None


def _resolve_dependents(exprs: dict[str, SX], symbols: dict[str, SX]) -> dict[str, SX]:
    """Substitute derived parameters into each other until none refers to another."""
    names = list(exprs)
    for _ in range(len(names) + 1):
        pending = [n for n in names if any(ca.depends_on(exprs[n], symbols[m]) for m in names)]
        if not pending:
            return exprs
        syms = [symbols[m] for m in names]
        vals = [exprs[m] for m in names]
        exprs = {n: ca.substitute([exprs[n]], syms, vals)[0] for n in names}
    raise ModelicaBuildError(f"parameter bindings form a cycle: {', '.join(sorted(pending))}")


def build_ode_system(model: FlatModel) -> OdeSystem:
    variables = model.variables
    t = SX.sym("time")
    sym = {name: SX.sym(name) for name in variables}
    env: dict[str, SX] = {"time": t, **sym}
    ders = {name: SX.sym(f"der({name})") for name in model.names("state")}

    def derivative(name: str, location: str | None) -> SX:
        if name not in ders:
            raise ModelicaBuildError(f"der({name}) of a variable that is not a state", location)
        return ders[name]

    tr = ExpressionTranslator(model.functions, model.sources, derivative)

    # Parameters: literal bindings stay free (tunable in the FMU); others are derived.
    free: list[Parameter] = []
    dependent: dict[str, SX] = {}
    for var in variables.values():
        if var.role != "parameter":
            continue
        tree = var.binding if var.binding is not None else var.start
        if tree is None:
            raise ModelicaBuildError(f"parameter '{var.name}' has no value", var.location)
        value = _literal(tree)
        if value is not None:
            free.append(Parameter(var.name, var.unit, var.description, value, var.type_name,
                                  sym[var.name]))
        else:
            dependent[var.name] = tr.translate(tree, env)
    dependent = _resolve_dependents(dependent, sym)
    dep_syms = [sym[n] for n in dependent]
    dep_vals = list(dependent.values())

    def in_free_params(expr: SX) -> SX:
        return ca.substitute([expr], dep_syms, dep_vals)[0] if dep_syms else expr

    # Residuals: equations plus declaration equations of continuous variables.
    residuals = [Residual(tr.translate(eq.residual, env), eq.location) for eq in model.equations]
    for var in variables.values():
        if var.role in ("algebraic", "output") and var.binding is not None:
            residuals.append(Residual(sym[var.name] - tr.translate(var.binding, env), var.location))
        if var.role == "state" and var.binding is not None:
            raise ModelicaBuildError(f"state '{var.name}' has a declaration equation", var.location)

    unknowns = {f"der({n})": ders[n] for n in ders}
    unknowns.update({n: sym[n] for n, v in variables.items() if v.role in ("algebraic", "output")})
    solved = causalise(residuals, unknowns)

    states = []
    for name in ders:
        var = variables[name]
        start = tr.translate(var.start, env) if var.start is not None else SX(0.0)
        if ca.depends_on(start, ca.vertcat(t, *[sym[n] for n in ders])):
            raise ModelicaBuildError(f"start value of state '{name}' must depend on parameters only",
                                     var.location)
        nominal = None
        if var.nominal is not None:
            value = in_free_params(tr.translate(var.nominal, env))
            p_syms = ca.vertcat(*[q.symbol for q in free])
            value = ca.Function("nominal", [p_syms], [value])([q.value for q in free])
            nominal = abs(float(value))
            if not nominal > 0:
                raise ModelicaBuildError(f"nominal of state '{name}' must be positive", var.location)
        states.append(State(name, var.unit, var.description, sym[name], start, nominal))

    def computed(role: str) -> list[Computed]:
        return [Computed(v.name, v.unit, v.description, solved[v.name])
                for v in variables.values() if v.role == role]

    derived = [Derived(n, variables[n].unit, variables[n].description, e, sym[n])
               for n, e in dependent.items()]
    return OdeSystem(model.name, t, free, states, [solved[f"der({n})"] for n in ders],
                     computed("output"), computed("algebraic"), derived)
