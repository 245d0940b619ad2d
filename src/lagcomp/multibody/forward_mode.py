r"""Forward-mode differentiation of a straight-line `Program`: the Jacobians of a recursion from the recursion.

A recursion over a tree (`lagcomp.multibody.aba`, `lagcomp.multibody.rnea`) is a list of assignments
b_k = e_k(earlier locals, q, q̇, parameters, t), each a small expression.  Its derivatives along directions
x_1, ..., x_m (the state's components for ∂q̈/∂y, the parameters for ∂q̈/∂p, one symbolic direction for J v)
follow the assignments in order, the chain rule once per assignment:

    ḃ_k[d] = Σ_a (∂e_k/∂a) ȧ[d],   a ranging over the locals and independent symbols e_k reads,

so each derivative is one more assignment of the same program: its partials ∂e_k/∂a are bound once per
assignment and shared by every direction (a partial that is already a local, cos q of sin q say, is that local:
`Program.rebound`), and an expression formed twice is bound once (the program's hash-consing).  Nothing is
expanded: the derivative program has the recursion's structure, and its size is at most the number of directions
times the recursion's, less where a quantity does not depend on a direction (a link's quantities of the outward
pass depend on its ancestors' coordinates only): each local carries only its nonzero derivatives.

A partial of a non-smooth function (a torque's Heaviside) has its DiracDelta taken as 0, as the Lagrangian path's
Jacobians do (`lagcomp.codegen.lower`).
"""

from __future__ import annotations

import sympy as sp

from lagcomp.multibody.program import Program


def derivatives(prog: Program, outputs, seeds: dict) -> list[dict]:
    """The derivatives of each of `outputs` along the directions `seeds` defines, bound in `prog`.

    Parameters
    ----------
    prog : Program
        The program the outputs' locals are bound in; the derivatives' assignments are appended to it.
    outputs : sequence of expressions
        Expressions over `prog`'s locals and the independent symbols (``rhs``'s q̇ and q̈, ``forcing``'s F).
    seeds : dict
        ``{symbol: {direction: derivative}}``: each independent symbol's derivative along each direction (1 for
        the Jacobian's own variable, a direction's component for J v); a symbol absent is constant.

    Returns
    -------
    list of dict
        Per output, ``{direction: derivative}`` (an expression, usually a local), its zero entries absent.
    """
    outputs = [sp.sympify(e) for e in outputs]
    tangent = dict(seeds)
    for local, expr in prog.live(outputs):
        derivative = _chain(prog, expr, tangent)
        if derivative:
            tangent[local] = derivative
    return [_chain(prog, e, tangent) for e in outputs]


def substituted(prog: Program, outputs, values: dict) -> tuple[Program, list]:
    """A new program computing `outputs` with the symbols of `values` replaced by them (numbers: q̇ = 0 for the
    partials at rest), and the outputs over its locals: each assignment `outputs` read, in order, with what it
    reads replaced, through the new program's `Program.let`, so that zeros fold and the assignments they cancel
    go."""
    folded, env = Program(), dict(values)
    for local, expr in prog.live(outputs):
        env[local] = folded.let(expr.xreplace(env))
    return folded, [sp.sympify(e).xreplace(env) for e in outputs]


def _chain(prog: Program, expr: sp.Expr, tangent: dict) -> dict:
    """{direction: Σ_a ∂expr/∂a · ȧ[direction]} over the symbols a of `expr` that have derivatives, bound."""
    atoms = sorted((s for s in expr.free_symbols if s in tangent), key=sp.default_sort_key)
    terms: dict = {}
    for a in atoms:
        partial = prog.let(prog.rebound(_partial(expr, a)))
        if partial == 0:
            continue
        for direction, derivative in tangent[a].items():
            terms.setdefault(direction, []).append(partial * derivative)
    bound = {direction: prog.let(sp.Add(*parts)) for direction, parts in terms.items()}
    return {direction: value for direction, value in bound.items() if value != 0}


def _partial(expr: sp.Expr, a: sp.Symbol) -> sp.Expr:
    """∂expr/∂a, a DiracDelta of a non-smooth function taken as 0."""
    partial = sp.diff(expr, a)
    return partial.replace(sp.DiracDelta, lambda *args: sp.S.Zero) if partial.has(sp.DiracDelta) else partial
