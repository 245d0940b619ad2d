r"""The exact Jacobians of a constrained Lagrange system: ∂f/∂y, ∂f/∂p and the multipliers' ∂λ/∂(y, p).

The constrained ``rhs`` solves, at each state, the augmented (KKT) system for z = (q̈, λ)

    K z = r,    K = [M  −Λᵀ]    r = [F]        (DESIGN.md, "Constraints and reaction forces"),
                    [Λ    0 ]        [γ̃]

with M(q, t, p), Λ(q, t, p), F(q, q̇, t, p) and γ̃ = γ − 2α (Λ q̇ + b) − β² Φ the constraints' right-hand side
with the Baumgarte terms (`lagcomp.codegen.stabilization.stabilized_gamma`; α, β read from p, not parameters one
differentiates by).  Differentiating K(x) z(x) = r(x) along any variable x (a state component or a parameter):

    (∂K/∂x) z + K ∂z/∂x = ∂r/∂x    ⇒    K ∂z/∂x = ∂/∂x (r − K z̄) |_{z̄ = z}
                                                 = ∂/∂x [F − M ā + Λᵀ λ̄ ;  γ̃ − Λ ā] |_{(ā, λ̄) = (q̈, λ)},

z̄ = (ā, λ̄) symbols held fixed while differentiating and then bound to the values ``rhs`` and ``reactions``
solve (one call of ``rhs_and_reactions``, bitwise both): the unconstrained kernels' trick
(`lagcomp.codegen.jacobian_blocks.acceleration_partials`) with the constraint rows added; the sign of λ̄'s term follows
K's −Λᵀ.  So ∂(q̈, λ)/∂x = K⁻¹ R with R the partials above, all columns from one factorization of K
(`lagcomp.kernel_support.linear_solvers.kkt_solve_matrix`, the Schur complement path of ``kkt_solve``, LU
where M is singular).  With y = (q, q̇) and f = (q̇, q̈):

    ∂f/∂y = [0  I ; ∂q̈/∂q  ∂q̈/∂q̇],    ∂f/∂p = [0 ; ∂q̈/∂p],    ∂λ/∂(y, p): the λ rows of K⁻¹ R.

These are the derivatives of the ODE ``rhs`` integrates (with Baumgarte's terms), everywhere in the state
space, on the constraint manifold or off it.  A force that jumps (Coulomb friction's sign(q̇)) contributes its
derivative away from the jump, as in the unconstrained kernels.
"""

from __future__ import annotations

import symengine as se
import sympy as sp

from lagcomp.codegen.cse import cse_kernel
from lagcomp.codegen.jacobian_blocks import (
    RHS_PARAMETER_JACOBIAN_DOC,
    RHS_WITH_FULL_JACOBIAN_DOC,
    RHS_WITH_JACOBIAN_DOC,
    WITH_JACOBIAN_ARGS,
    fresh_symbols,
    jacobian_only,
)
from lagcomp.codegen.stabilization import stabilized_gamma
from lagcomp.ir import AugmentedJacobianSolve, Kernel
from lagcomp.mechanics.lagrange import EOM, kink_free_jacobian, symengine_ready
from lagcomp.model.system import t

#: What every constrained Jacobian kernel returns, after what it computes.
STATUSES = ("Returns 0, or j > 0 as `rhs` (`reactions`) does, or when the factorization of the augmented matrix\n"
            "[M −Λᵀ; Λ 0] finds pivot j zero (then `rhs` was within rounding of it); `out` is then invalid.")


def constrained_jacobian_kernels(eom: EOM, mapping, loads) -> tuple[Kernel, ...]:
    """``rhs_with_jacobian``, ``rhs_jacobian`` (delegating), ``rhs_parameter_jacobian``, ``rhs_with_full_jacobian``
    (both Jacobians from one factorization of K, for the sensitivities) and ``reaction_jacobian`` of the
    constrained `eom` (module docstring), one CSE each."""
    n, k, parameters = eom.n, eom.k, tuple(eom.parameters)
    state = (*eom.q, *eom.qd)
    residual, mapping, loads = augmented_residual(eom, mapping, loads)

    def kernel(name, doc, args, variables, first, count, offset, identity=False, given_ydot=False) -> Kernel:
        width = len(variables)
        stores = matrix_stores(eom) + [(f"_jac[{r * width + j}]", entry)
                                        for r, row in enumerate(residual_partials(residual, variables))
                                        for j, entry in enumerate(row) if entry != 0]
        solve = AugmentedJacobianSolve(n=n, k=k, width=width, first=first, count=count, offset=offset,
                                       identity=identity, given_ydot=given_ydot)
        return cse_kernel(name, doc, args, stores, mapping, loads, solve=solve)

    how = ("\n(q̈, λ) solve [M −Λᵀ; Λ 0] (q̈, λ) = (F, γ̃), so ∂(q̈, λ)/∂x = [M −Λᵀ; Λ 0]⁻¹ R with\n"
           "R = ∂/∂x [F − M ā + Λᵀ λ̄; γ̃ − Λ ā] at ā = q̈ (`rhs`), λ̄ = λ (`reactions`), γ̃ with the Baumgarte\n"
           "terms (see lagcomp.codegen.constrained_jacobian).\n")
    return (
        kernel("rhs_with_jacobian",
               RHS_WITH_JACOBIAN_DOC + "Rows [0 | I], then ∂q̈/∂y: " + how + STATUSES,
               WITH_JACOBIAN_ARGS, state, first=0, count=n, offset=n, identity=True, given_ydot=True),
        jacobian_only(2 * n),
        kernel("rhs_parameter_jacobian",
               RHS_PARAMETER_JACOBIAN_DOC + "Rows 0 (q̇ does not depend on p), then ∂q̈/∂p: " + how + STATUSES,
               ("t", "y", "p", "out"), parameters, first=0, count=n, offset=n),
        kernel("rhs_with_full_jacobian",
               RHS_WITH_FULL_JACOBIAN_DOC + "Rows [0 | I | 0], then ∂q̈/∂(y, p), one factorization of K for both: "
               + how + STATUSES,
               WITH_JACOBIAN_ARGS, (*state, *parameters), first=0, count=n, offset=n, identity=True, given_ydot=True),
        kernel("reaction_jacobian",
               f"Exact Jacobian of the multipliers λ (`reactions`), shape ({k}, {2 * n + len(parameters)}) into "
               f"`out`: row c the constraint c of\n{eom.constraint_names}, columns ∂λ_c/∂y_j (y = (q, q̇), "
               f"{2 * n} of them), then ∂λ_c/∂p_j for the model's\nparameters (not the Baumgarte gains nor the "
               "inputs' tables). Symbolic, no differences:" + how + STATUSES,
               ("t", "y", "p", "out"), (*state, *parameters), first=n, count=k, offset=0),
    )


def augmented_residual(eom: EOM, mapping, loads) -> tuple[list, dict, tuple]:
    """The rows [F − M ā + Λᵀ λ̄; γ̃ − Λ ā] (n + k, sympy) over fresh symbols ā, λ̄, and `mapping`, `loads`
    extended by them: ā_i bound to the local ``_acc<i>`` = ``_ydot[n + i]``, λ̄_c to ``_mult<c>`` = ``_lam[c]``
    (what `rhs` and `reactions` solve: `AugmentedJacobianSolve` calls ``rhs_and_reactions`` first)."""
    n, k = eom.n, eom.k
    gamma = stabilized_gamma(eom)
    taken = {s.name for s in (*eom.q, *eom.qd, *eom.parameters, t)}
    taken |= {s.name for e in (*eom.M, *eom.F, *eom.C, *gamma) for s in e.free_symbols}
    accelerations, multipliers = fresh_symbols("_acc", n, taken), fresh_symbols("_mult", k, taken)
    bound = {**{a: (f"_acc{i}", f"_ydot[{n + i}]") for i, a in enumerate(accelerations)},
             **{m: (f"_mult{c}", f"_lam[{c}]") for c, m in enumerate(multipliers)}}
    mapping = {**mapping, **{s: sp.Symbol(local, real=True) for s, (local, _) in bound.items()}}
    loads = loads + tuple(bound.values())
    rows = [eom.F[i] - sum((eom.M[i, j] * accelerations[j] for j in range(n) if eom.M[i, j] != 0), sp.S.Zero)
            + sum((eom.C[c, i] * multipliers[c] for c in range(k) if eom.C[c, i] != 0), sp.S.Zero)
            for i in range(n)]
    rows += [gamma[c] - sum((eom.C[c, j] * accelerations[j] for j in range(n) if eom.C[c, j] != 0), sp.S.Zero)
             for c in range(k)]
    return rows, mapping, loads


def matrix_stores(eom: EOM) -> list:
    """Stores filling ``_kkt`` = [M −Λᵀ; Λ 0], (n + k, n + k), its nonzero entries."""
    n, k = eom.n, eom.k
    stores = [(f"_kkt[{i}, {j}]", eom.M[i, j]) for i in range(n) for j in range(n) if eom.M[i, j] != 0]
    stores += [(f"_kkt[{i}, {n + c}]", -eom.C[c, i]) for i in range(n) for c in range(k) if eom.C[c, i] != 0]
    return stores + [(f"_kkt[{n + c}, {j}]", eom.C[c, j]) for c in range(k) for j in range(n) if eom.C[c, j] != 0]


def residual_partials(rows: list, variables) -> list[list]:
    """∂rows_r/∂x_j, (len(rows), len(variables)): symengine's derivatives when it can (as
    `lagcomp.codegen.jacobian_blocks.acceleration_partials`), else sympy's with a force's jump contributing its
    derivative away from the jump (the DiracDelta dropped).  Entries are symengine or sympy expressions."""
    if not variables:
        return [[] for _ in rows]
    if symengine_ready(rows):
        images, xs = [se.sympify(r) for r in rows], [se.sympify(x) for x in variables]
        return [[image.diff(x) for x in xs] for image in images]
    return kink_free_jacobian(rows, variables)
