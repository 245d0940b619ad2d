r"""The first-order form of a mechanical system, in coordinates q and speeds u (sympy only).

Lagrange's equations (`lagcomp.mechanics.lagrange`) and Kane's equations
(`sympy.physics.mechanics.KanesMethod`) both come down to one form,

    q̇ = N(q, u, t)                          kinematic differential equations, n_q rows
    M(q, t) u̇ = F(q, u, t) + Cᵀ λ            dynamics, n_u rows
    C(q, t) u̇ = γ(q, u, t)                   acceleration-level constraints with multipliers λ
    Φ(q, t) = 0                              configuration (holonomic) constraints, n_h rows
    Ψ(q, u, t) = 0                           velocity constraints, n_v rows, linear in u

- Lagrange: u = q̇ (N = u), M symmetric, C = Λ and γ as in `lagrange.EOM`,
  Ψ = Λ q̇ + b (every constraint, the holonomic ones differentiated once).
- Kane: N from the kinematic differential equations, M and F as KanesMethod forms
  them (the differentiated velocity constraints are rows of M, so M is not
  symmetric), no multipliers (C has no rows), Ψ = k_nh u + f_nh.

Consequences used downstream: a state (q, u) is consistent when Φ = 0 and Ψ = 0;
n_q − n_h coordinates and n_u − n_v speeds are independent, and a linearization
reduced to them has n_q − n_h + n_u − n_v states.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import sympy as sp


@dataclass(frozen=True)
class FirstOrderForm:
    """q̇ = N, M u̇ = F + Cᵀλ, C u̇ = γ, Φ = 0, Ψ = 0 (module docstring), in plain symbols.

    Attributes
    ----------
    q, u : tuple of Symbol
        Coordinates (n_q) and speeds (n_u), plain symbols (not functions of t).
    parameters : tuple of Symbol
        Parameters in kernel order.
    coordinate_names, speed_names : tuple of str
        Labels for results (eigenvector components, plots).
    N : Matrix, shape (n_q, 1)
        q̇ as a function of (q, u, t).
    M : Matrix, shape (n_u, n_u)
        Regular where the system is well posed; need not be symmetric.
    F : Matrix, shape (n_u, 1)
    C : Matrix, shape (k, n_u)
        Rows that carry multipliers λ (k = 0 for Kane's equations).
    gamma : Matrix, shape (k, 1)
    Phi : Matrix, shape (n_h, 1)
        Configuration constraints Φ(q, t).
    Psi : Matrix, shape (n_v, 1)
        Velocity constraints Ψ(q, u, t), linear in u.
    multiplier_names : tuple of str
        Names of the k multipliers, in the row order of C.
    input_names : tuple of str
        Inputs (`lagcomp.Input` supplied at run time) held at constant values: the last parameters, one
        symbol per input (`inputs_as_parameters`), in this order; () when none.
    input_derivatives : tuple of str
        Those of `input_names` whose derivatives the equations read (u̇, ü dropped with the inputs held
        constant): no input matrix B with respect to them alone.
    """

    q: tuple
    u: tuple
    parameters: tuple
    coordinate_names: tuple
    speed_names: tuple
    N: sp.Matrix
    M: sp.Matrix
    F: sp.Matrix
    C: sp.Matrix
    gamma: sp.Matrix
    Phi: sp.Matrix
    Psi: sp.Matrix
    multiplier_names: tuple = ()
    input_names: tuple = ()
    input_derivatives: tuple = ()

    @property
    def n_q(self) -> int:
        return len(self.q)

    @property
    def n_u(self) -> int:
        return len(self.u)


def inputs_as_parameters(form: FirstOrderForm, inputs) -> FirstOrderForm:
    """`form` with each input u(t) of `inputs` (`lagcomp.Input`, supplied at run time) held constant: u a
    parameter (a symbol of its name, after the others), its time derivatives 0.  For linearizations about a
    steady motion under constant inputs, whose input matrix B is the derivative along those parameters."""
    if not inputs:
        return form
    from lagcomp.model.inputs import MAX_ORDER
    from lagcomp.model.system import t

    taken = {s.name for part in (form.N, form.M, form.F, form.C, form.gamma, form.Phi, form.Psi)
             for s in part.free_symbols} | {s.name for s in (*form.q, *form.u, *form.parameters)}
    symbols = []
    for u in inputs:    # (symengine tells symbols apart by name: none may share one with the form's)
        name = f"_input_{u.func.__name__}"
        while name in taken:
            name += "_"
        taken.add(name)
        symbols.append(sp.Symbol(name, real=True))
    still = {u.diff(t, k): sp.S.Zero for u in inputs for k in range(MAX_ORDER + 2, 0, -1)}
    held = dict(zip(inputs, symbols, strict=True))
    parts = ("N", "M", "F", "C", "gamma", "Phi", "Psi")
    read = tuple(u.func.__name__ for u in inputs
                 if any(d.expr == u for part in parts for d in getattr(form, part).atoms(sp.Derivative)))
    values = {part: getattr(form, part).xreplace(still).xreplace(held) for part in parts}
    return replace(form, parameters=(*form.parameters, *symbols), input_names=tuple(u.func.__name__ for u in inputs),
                   input_derivatives=read, **values)


def from_eom(eom) -> FirstOrderForm:
    """The first-order form of Lagrange's equations `eom` (a `lagrange.EOM`): u = q̇."""
    names = tuple(eom.system.coordinate_names)
    qd = sp.Matrix(eom.qd)
    return FirstOrderForm(
        q=tuple(eom.q), u=tuple(eom.qd), parameters=tuple(eom.parameters),
        coordinate_names=names, speed_names=tuple(f"{name}_dot" for name in names),
        N=qd, M=eom.M, F=eom.F, C=eom.C, gamma=eom.gamma, Phi=eom.Phi,
        Psi=eom.C * qd + eom.b, multiplier_names=tuple(eom.constraint_names),
    )
