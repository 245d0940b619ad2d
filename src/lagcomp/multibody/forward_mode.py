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

Past a size (`derivatives`'s `step_above`), the derivatives are emitted grouped by the steps of the recursion they
differentiate, a step's partials first, then its derivatives along one direction after another: along a direction,
the links of a chain repeat the same little program, which `lagcomp.codegen.outline` emits once as a helper.

A partial of a non-smooth function (a torque's Heaviside) has its DiracDelta taken as 0, as the Lagrangian path's
Jacobians do (`lagcomp.codegen.lower`).
"""

from __future__ import annotations

import sympy as sp

from lagcomp.multibody.program import Program


def derivatives(prog: Program, outputs, seeds: dict, step_above: int | None = None) -> list[dict]:
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
    step_above : int, optional
        When the derivatives form more than this many assignments, give them the steps of the recursion they
        differentiate (`_stepped_order`), so that the kernel emits the repeated ones as shared helpers
        (`lagcomp.codegen.outline`); the assignments themselves are the same either way.  None: never.

    Returns
    -------
    list of dict
        Per output, ``{direction: derivative}`` (an expression, usually a local), its zero entries absent.
    """
    outputs = [sp.sympify(e) for e in outputs]
    tangent, start, formed = dict(seeds), len(prog.assignments), {}
    for local, expr in prog.live(outputs):
        first = len(prog.assignments)
        derivative = _chain(prog, expr, tangent)
        formed.update(dict.fromkeys((a for a, _ in prog.assignments[first:]), (local, derivative)))
        if derivative:
            tangent[local] = derivative
    if step_above is not None and len(prog.assignments) - start > step_above:
        _stepped_order(prog, start, formed)
    return [_chain(prog, e, tangent) for e in outputs]


def _stepped_order(prog: Program, start: int, formed: dict) -> None:
    """Regroup the derivative assignments of `prog` from `start` on (``formed[local]``: the recursion's local
    whose derivatives formed it, and those derivatives) by the steps of the recursion: each run of one step S
    (consecutive locals of the same `Program.step`) has its partials as the step ``(S, "partials")``, then its
    derivatives along each direction d as the step ``(S, d)``, direction after direction.

    Along one direction, the derivatives of the nodes of a chain are the same little program over their own inputs,
    so `lagcomp.codegen.outline` emits them once, as it does the recursion's steps.  The assignments and their
    locals' names stay those of the unstepped order (their sums list their terms in the same order); only the order
    they are emitted in changes, and it stays topological: an assignment that reads a later group of its own run
    joins that group (`Program.regroup`)."""
    rank, steps, run, previous = {}, {}, -1, object()
    for local, expr in prog.assignments[start:]:
        source, derivative = formed[local]
        step = prog.step_of.get(source)
        if step is None or step != previous:
            run += 1
        previous = step
        direction = next((d for d, value in derivative.items() if value == local), None)
        group = (0, 0) if direction is None else (1, direction)
        own = [rank[s] for s in expr.free_symbols if s in rank and rank[s][0] == run]
        rank[local] = max([(run, group), *own])
        if step is not None:
            steps[local] = (step, "partials" if rank[local][1] == (0, 0) else rank[local][1][1])
    prog.regroup(start, rank, steps)


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
