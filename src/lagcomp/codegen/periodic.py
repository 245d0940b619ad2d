"""Which coordinates the ``rhs`` kernel sees only through sin and cos (angles whose turns it cannot tell).

A coordinate q is *periodic* here when the rhs is unchanged by q → q + 2π
by its structure: every path from q to an output goes through the argument
of a sin, cos or tan, and that argument is q times an integer plus terms
that do not depend on q or are periodic in q themselves (``sin(θ1 − θ2)``,
``cos(2θ)``; not ``sin(θ/2)``, not ``θ sin θ``).  Found from the
expressions of the kernel alone, not by evaluating it: a coordinate is
either proved periodic or treated as an ordinary number.

Why: an angle that winds up (a double pendulum's θ2 reaches hundreds of
radians in a chaotic run) is stored with ulp(θ) of absolute rounding, 256
times that of |θ| < 2 at θ ≈ 500, and the rhs evaluated at that rounded θ
feeds this rounding into every step.  ``taylor_run`` evaluates the series
at the angle reduced to [−π, π] with its compensated-sum carry folded in
(`lagcomp.kernel_support.angles.reduced_angle`), so the rhs sees each periodic coordinate to the
rounding of a number below π, however far it has wound (the double
pendulum's relative energy error to t = 10⁴, rms over 16 starts 1 ulp
apart: 2.0e-11 -> 5.4e-13, ``python -m bench.taylor_error_sources``).
"""

from __future__ import annotations

import sympy as sp

from lagcomp.ir import Kernel, target_local

#: The kinds of an expression: coordinate name -> integer n (the expression is n q plus a part periodic
#: in q; 0 is left out) or None (neither).  A coordinate not in the dict: periodic in it or independent.
Kinds = dict[str, "int | None"]

_TRIG = (sp.sin, sp.cos, sp.tan, sp.cot, sp.sec, sp.csc)


def periodic_coordinates(rhs: Kernel, n: int) -> tuple[int, ...]:
    """Indices i < n of the state components y[i] (coordinates) the rhs is 2π-periodic in, by structure."""
    env: dict[str, Kinds] = {}
    coordinates = []
    for local, source in rhs.loads:
        if source.startswith("y[") and int(source[2:-1]) < n:
            env[local] = {local: 1}
            coordinates.append((int(source[2:-1]), local))
    for name, expr in rhs.temps:
        env[name] = _kinds(expr, env)
    spoiled: set[str] = set()
    for target, expr in rhs.stores:
        kinds = _kinds(expr, env)
        spoiled.update(kinds)   # an output linear in q (n ≠ 0) is not periodic in q either
        if not target.startswith("out["):
            env[target_local(target)] = kinds
    return tuple(sorted(i for i, local in coordinates if local not in spoiled))


def _kinds(expr: sp.Expr, env: dict[str, Kinds]) -> Kinds:
    """How `expr` depends on each coordinate (`Kinds`), from the kinds of the locals it reads (`env`)."""
    if expr.is_Symbol:
        return env.get(expr.name, {})
    if expr.is_Number or not expr.args:
        return {}
    parts = [_kinds(a, env) for a in expr.args]
    names = set().union(*parts)
    if expr.is_Add:
        return _drop_zeros({q: _total([p.get(q, 0) for p in parts]) for q in names})
    if expr.is_Mul:
        return {q: _scaled(expr.args, parts, q) for q in names}
    if expr.func in _TRIG:
        return {q: None for q in names if parts[0][q] is None}     # n q + (periodic) inside: periodic
    return {q: None for q in names}                                 # pow, exp, sqrt, ...: only periodic arguments


def _total(coefficients: list) -> int | None:
    return None if None in coefficients else sum(coefficients)


def _drop_zeros(kinds: Kinds) -> Kinds:
    return {q: v for q, v in kinds.items() if v != 0}


def _scaled(factors, parts: list[Kinds], q: str) -> int | None:
    """Kind in q of a product: n q times numbers stays linear when the product of n and them is an integer."""
    linear = [i for i, p in enumerate(parts) if q in p]
    if len(linear) != 1 or parts[linear[0]][q] is None:
        return None
    if any(not f.is_Number for i, f in enumerate(factors) if i != linear[0]):
        return None     # n q times a parameter, a velocity or a function of q: not periodic in q
    coefficient = sp.Mul(*[f for i, f in enumerate(factors) if i != linear[0]]) * parts[linear[0]][q]
    if coefficient == int(coefficient):
        return int(coefficient)
    return None
