"""Causalise a residual DAE into an explicit ODE: solve for derivatives and algebraics.

Given residuals ``0 = r_i(x, z, der(x), p, t)`` and unknowns ``der(x)`` and ``z``:

1. Repeatedly take an equation with exactly one unknown left in which that unknown
   enters linearly (its Jacobian does not depend on it), solve it by substitution
   and substitute the solution everywhere (a sorted, BLT-like pass).
2. Whatever remains is solved jointly if it is linear in the remaining unknowns
   (a symbolic linear solve); otherwise the equations are reported as a nonlinear
   algebraic loop, with their source lines.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from fmu_build.errors import ModelicaBuildError

SX = ca.SX


@dataclass(eq=False)
class Residual:
    expr: SX
    location: str | None


def _depends(expr: SX, symbol: SX) -> bool:
    return bool(ca.depends_on(expr, symbol))


def _appearing(expr: SX, ids: dict[int, str]) -> set[str]:
    """The names of the unknowns (``ids``: symbol hash -> name) whose symbols ``expr``
    holds."""
    return {ids[h] for h in (s.element_hash() for s in ca.symvar(expr)) if h in ids}


def causalise(residuals: list[Residual], unknowns: dict[str, SX]) -> dict[str, SX]:
    """Return ``{unknown name: explicit expression in the knowns}``.

    ``unknowns`` maps names to pure SX symbols; every other symbol is known
    (states, parameters, time).
    """
    if len(residuals) != len(unknowns):
        raise ModelicaBuildError(
            f"model is not balanced: {len(residuals)} equations for {len(unknowns)} unknowns")
    remaining = list(residuals)
    open_unknowns = dict(unknowns)
    ids = {sym.element_hash(): name for name, sym in unknowns.items()}
    # the open unknowns whose symbol each residual holds, read once and kept up to date: a
    # scan of every residual for every unknown after each substitution is quadratic
    appears = [_appearing(r.expr, ids) for r in remaining]
    solved: dict[str, SX] = {}
    progress = True
    while remaining and progress:
        progress = False
        for i, res in enumerate(remaining):
            present = [n for n in open_unknowns
                       if n in appears[i] and _depends(res.expr, open_unknowns[n])]
            if len(present) == 0:
                raise ModelicaBuildError(
                    "equation determines no unknown (redundant or over-determined)", res.location)
            if len(present) != 1:
                continue
            name = present[0]
            sym = open_unknowns[name]
            slope = ca.jacobian(res.expr, sym)
            if _depends(slope, sym):
                continue  # nonlinear in its only unknown: left for the joint step (error there)
            value = ca.simplify(-ca.substitute(res.expr, sym, SX(0.0)) / slope)
            solved[name] = value
            del open_unknowns[name], ids[sym.element_hash()], remaining[i], appears[i]
            for j, other in enumerate(remaining):
                if name in appears[j]:
                    remaining[j] = Residual(ca.substitute(other.expr, sym, value),
                                            other.location)
                    appears[j] = _appearing(remaining[j].expr, ids)
            progress = True
            break  # rescan: the substitution may have left other equations with one unknown
    for res in remaining:
        present = [n for n, s in open_unknowns.items() if _depends(res.expr, s)]
        if len(present) == 1:
            raise ModelicaBuildError(
                f"equation is nonlinear in its only unknown {present[0]}; only explicit or "
                "linear equations can be causalised", res.location)
    if remaining:
        names = list(open_unknowns)
        syms = ca.vertcat(*[open_unknowns[n] for n in names])
        exprs = ca.vertcat(*[r.expr for r in remaining])
        jac = ca.jacobian(exprs, syms)
        where = ", ".join(r.location or "?" for r in remaining)
        if _depends(jac, syms):
            raise ModelicaBuildError(
                f"nonlinear algebraic loop in {', '.join(names)} (equations at {where}); "
                "only explicit or linear equations can be causalised")
        rhs = -ca.substitute(exprs, syms, ca.DM.zeros(syms.shape))
        solution = ca.solve(jac, rhs)
        for i, name in enumerate(names):
            solved[name] = solution[i]
    return solved
