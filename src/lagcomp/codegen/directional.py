r"""``rhs_directional``: f and one directional derivative J v + (∂f/∂p) w in one CSE'd kernel.

A run with k sensitivity columns needs J S (+ ∂f/∂p in a parameter's column) at every stage.  The full
Jacobians (``rhs_with_jacobian``, ``rhs_parameter_jacobian``) cost N (N + P) entries and N + P substitutions
by M (or K) whatever k is; for few columns the derivative along each column is cheaper: forward mode on the
symbolic accelerations.  Differentiating M(x) a(x) = F(x) along the direction dx = (v, w) of x = (y, p):

    M da = dF − dM ā |_{ā = a} = Σ_j ∂(F − M ā)/∂x_j dx_j,

the residual's partials of `lagcomp.codegen.lower.acceleration_partials` (ā held fixed, then bound to the
accelerations ``rhs`` solved) contracted with the direction symbolically, so that one CSE shares them with M
and F, and one LDLᵀ substitution gives da.  With y = (q, q̇), f = (q̇, a):

    J v + (∂f/∂p) w = (v[n:2n], da).

A constrained system (Lagrange multipliers) solves K z = r for z = (q̈, λ), K = [M −Λᵀ; Λ 0]; along dx,
K dz = Σ_j ∂(r − K z̄)/∂x_j dx_j at z̄ = (q̈, λ) (`lagcomp.codegen.constrained_jacobian`, the residual with the
Baumgarte terms): one ``kkt_solve`` of the direction's right-hand side, the first n entries of dz the
accelerations' derivative.  ``rhs`` (``rhs_and_reactions``) runs first, as in the Jacobian kernels, so f comes
back bitwise ``rhs``'s.  The derivative agrees with the full Jacobians' product to rounding (another order of
the same sums).
"""

from __future__ import annotations

import symengine as se
import sympy as sp

from lagcomp.codegen.constrained_jacobian import _augmented_residual, _matrix_stores, _partials
from lagcomp.codegen.lower import UNROLL_MAX, _acceleration_block, _kernel, fresh_symbols
from lagcomp.ir import AugmentedSolve, DirectionalSolve, Kernel, LinearSolve
from lagcomp.mechanics.lagrange import EOM
from lagcomp.model.system import t

#: The arguments of every ``rhs_directional`` kernel: the direction (v (N,), w (P,)), then f into ``ydot``
#: (N,) and the derivative into ``out`` (N,).
DIRECTIONAL_ARGS = ("t", "y", "p", "v", "w", "ydot", "out")

#: The docstring of every ``rhs_directional`` kernel: what it computes; `directional_kernel` adds how.
RHS_DIRECTIONAL_DOC = (
    "f and its derivative along one direction at once: ydot = f(t, y, p) as `rhs` computes it (bitwise),\n"
    "out = ∂f/∂y v + ∂f/∂p w, (N,), for v (N,) and w (P,) (P = the model's parameters, in the order of p).\n"
    "Symbolic, no differences: the product the full Jacobians `rhs_with_jacobian` and `rhs_parameter_jacobian`\n"
    "give, to rounding, at the cost of one extra substitution (the sensitivities' kernel for few columns).\n"
)


def directional_kernel(eom: EOM, mapping, loads) -> Kernel:
    """``rhs_directional`` of `eom`, unconstrained (LDLᵀ of M) or constrained (one ``kkt_solve`` of K)."""
    n = eom.n
    variables = (*eom.q, *eom.qd, *eom.parameters)
    taken = {s.name for s in (*variables, t)}
    taken |= {s.name for e in (*eom.M, *eom.F, *eom.C) for s in e.free_symbols}
    directions = fresh_symbols("_dx", len(variables), taken)
    locals_ = [f"_dy{i}" for i in range(2 * n)] + [f"_dp{j}" for j in range(len(eom.parameters))]
    sources = [f"v[{i}]" for i in range(2 * n)] + [f"w[{j}]" for j in range(len(eom.parameters))]
    mapping = {**mapping, **{d: sp.Symbol(local, real=True) for d, local in zip(directions, locals_, strict=True)}}
    loads = loads + tuple(zip(locals_, sources, strict=True))
    velocity_rows = [(f"out[{i}]", directions[n + i]) for i in range(n)]
    if eom.k:
        residual, mapping, loads = _augmented_residual(eom, mapping, loads)
        size = n + eom.k
        stores = _matrix_stores(eom) + [(f"_kkt[{r}, {size}]", _contracted(row, directions))
                                        for r, row in enumerate(_partials(residual, variables))]
        solve = AugmentedSolve(size=size, mass_block=n, first=0, count=n, offset=n)
        how = ("K dz = Σ_j ∂(r − K z̄)/∂x_j dx_j at z̄ = (q̈, λ) from `rhs_and_reactions`, K = [M −Λᵀ; Λ 0], r with\n"
               "the Baumgarte terms; out = (v[n:], dz[:n]) (see lagcomp.codegen.directional).\n"
               "Returns 0, or j > 0 as `rhs` does, or when the factorization of K finds pivot j zero; `out` is then "
               "invalid.")
        multipliers = eom.k
    else:
        block, m, mapping, loads = _acceleration_block(eom, variables, mapping, loads)
        f = tuple(f"_f{i}" for i in range(n))
        stores = [(m[i][j], eom.M[i, j]) for i in range(n) for j in range(i + 1)]
        stores += [(f[i], _contracted(row, directions)) for i, row in enumerate(block)]
        solve = LinearSolve(n=n, m=m, f=f, offset=n, unrolled=n <= UNROLL_MAX)
        how = ("M da = Σ_j ∂(F − M ā)/∂x_j dx_j at ā = q̈ from `rhs`; out = (v[n:], da) (see "
               "lagcomp.codegen.directional).\n"
               "Returns 0, or k > 0 as `rhs` does, or when this LDLᵀ of M finds pivot k not positive; `out` is then "
               "invalid.")
        multipliers = 0
    return _kernel("rhs_directional", RHS_DIRECTIONAL_DOC + how, DIRECTIONAL_ARGS, velocity_rows + stores, mapping,
                   loads, solve=DirectionalSolve(solve=solve, multipliers=multipliers))


def _contracted(row, directions):
    """Σ_j row_j dx_j over the nonzero partials `row` (symengine or sympy entries), in symengine when it can."""
    terms = [(entry, d) for entry, d in zip(row, directions, strict=True) if entry != 0]
    if all(isinstance(entry, se.Basic) for entry, _ in terms):
        return sum((entry * se.sympify(d) for entry, d in terms), se.Integer(0))
    return sum((sp.sympify(entry) * d for entry, d in terms), sp.S.Zero)
