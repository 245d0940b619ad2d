"""The rounding scale A(e) of an expression: the size of what its floating-point evaluation adds and multiplies.

A residual Φ(q) evaluated in floating point is wrong by about ε·A(Φ) (ε the unit roundoff), where A is the
standard running-error bound of the expression (Higham, *Accuracy and Stability of Numerical Algorithms*, §3.3):
every sum's terms and every product's factors taken in absolute value,

* A(c) = |c| for a number, A(s) = |s| for a symbol (a coordinate, velocity, parameter, t, an input's value);
* A(a + b) = A(a) + A(b), A(a b) = A(a) A(b), A(aⁿ) = A(a)ⁿ for a positive integer n;
* A(f(x, ...)) = |f| + Σ_i |∂f/∂x_i| A(x_i) for any other function, power (1/x, √x, aˣ) included: f's own
  rounding, plus the rounding of its arguments carried through its slope.

So a rounded exact start has |Φ| of a few ε·A(Φ) whatever the units of Φ, and |Φ| / A(Φ) is a unit-free measure
of how far a state is off its constraint (`lagcomp.integrate.constraints.consistent_initial_state`).  The bound
is not Σ_j |∂Φ/∂q_j| |q_j|, which vanishes where every q_j or its slope does (a four-bar at θ = 0), while
the products and sines evaluated there still round.  A symbol of `known` (a local a program bound,
`lagcomp.multibody.program.Program`) has the scale given there instead of its value's size, so that a
straight-line program's bound follows its assignments (`program_scales`).
"""

from __future__ import annotations

import sympy as sp
from sympy.core.function import AppliedUndef


def rounding_scale(expr, known: dict | None = None) -> sp.Expr:
    """A(`expr`) (module docstring), a sympy expression over the same symbols, ≥ 0 wherever it is real.

    `known` maps symbols to their own scales (locals of a program); every other symbol's is its absolute value.
    """
    known = known or {}
    memo: dict = {}

    def scale(e):
        if e not in memo:
            memo[e] = _scale(e, scale, known)
        return memo[e]

    return scale(sp.sympify(expr))


def _scale(e, scale, known: dict) -> sp.Expr:
    """One node of `rounding_scale`: `scale` for the node's arguments."""
    if e in known:
        return known[e]
    if e.is_Number or e.is_Symbol or e.is_NumberSymbol or isinstance(e, (AppliedUndef, sp.Derivative)):
        return sp.Abs(e)
    if e.is_Add:
        return sp.Add(*(scale(a) for a in e.args))
    if e.is_Mul:
        return sp.Mul(*(scale(a) for a in e.args))
    if e.is_Pow and e.exp.is_Integer and e.exp > 0:
        return scale(e.base) ** e.exp
    if (e.is_Pow or isinstance(e, sp.Function)) and all(isinstance(a, sp.Expr) for a in e.args):
        return sp.Abs(e) + sp.Add(*(sp.Abs(slope) * scale(a) for a, slope in zip(e.args, _slopes(e), strict=True)
                                    if not a.is_Number))
    return sp.Abs(e)   # (a Piecewise, a relational: its size, with no propagation)


def _slopes(e) -> list:
    """∂f/∂x_i of e = f(x_1, ...), at e's arguments; a jump's DiracDelta dropped (the slope away from it)."""
    dummies = [sp.Dummy(real=True) for _ in e.args]
    image = e.func(*dummies)
    back = dict(zip(dummies, e.args, strict=True))
    return [image.diff(d).replace(sp.DiracDelta, lambda *_: sp.S.Zero).xreplace(back) for d in dummies]


def program_scales(prog, outputs) -> list:
    """A(output) of each of `outputs` (expressions over the locals of `prog`, a
    `lagcomp.multibody.program.Program`), each assignment's scale bound in `prog` in turn: the running bound of
    the straight-line program, not of its outputs multiplied out."""
    known: dict = {}
    for local, expr in prog.live(outputs):
        known[local] = prog.let(rounding_scale(expr, known))
    return [rounding_scale(output, known) for output in outputs]
