"""The velocity response of a constrained system to generalized impulses: K = M⁻¹ − M⁻¹Aᵀ (A M⁻¹ Aᵀ)⁻¹ A M⁻¹.

A system with constraints A q̇ + b = 0 (A = Λ, the constraint matrix: ∂Φ/∂q for holonomic Φ(q, t) = 0, b = ∂Φ/∂t)
that takes a generalized impulse Jᵀ P (contacts of gap gradients J, `lagcomp.kernel_support.impacts`) jumps by

    M (q̇⁺ − q̇⁻) = Jᵀ P + Aᵀ Λ,    A q̇⁺ + b = 0,

Λ the constraints' impulses, which keep q̇⁺ on the constraints.  With A q̇⁻ + b = 0 before, the second row is
A (q̇⁺ − q̇⁻) = 0, so Λ = −S⁻¹ A M⁻¹ Jᵀ P with S = A M⁻¹ Aᵀ (symmetric positive definite when the constraints are
independent), and q̇⁺ − q̇⁻ = K Jᵀ P.  K is symmetric positive semi-definite and A K = 0: every velocity change it
gives keeps the constraints' velocities, b included (rheonomic constraints need nothing more).  The contacts'
Delassus matrix is then J K Jᵀ = J M⁻¹ Jᵀ − J M⁻¹ Aᵀ S⁻¹ A M⁻¹ Jᵀ, and an impact solves the block system

    [M  Aᵀ  Jᵀ] [ q̇⁺]   [M q̇⁻]
    [A  0   0 ] [ −Λ] = [ −b ]
    [J  0   0 ] [ −P]   [v⁺ − ∂g/∂t]

by that Schur complement (v⁺ = −e v⁻ on the pushing contacts, Newton's law).  Without constraints (A with no rows)
K = M⁻¹ and `response_columns` is `lagcomp.kernel_support.linear_solvers.ldlt_solve_matrix`, bit for bit.
"""

import numpy as np
from numba import njit

from lagcomp.kernel_support.linear_solvers import ldlt_solve_matrix

#: `response_columns`' status when S = A M⁻¹ Aᵀ is singular: the constraints are dependent there.
DEPENDENT_CONSTRAINTS = 2_000_000


@njit(cache=True, error_model="numpy", fastmath=False)
def response_columns(mass, constraint, columns):
    """K X for the columns X (n, c) in place, K = M⁻¹ − M⁻¹Aᵀ (A M⁻¹ Aᵀ)⁻¹ A M⁻¹ (module docstring).

    mass (n, n): M, lower triangle read and overwritten by its LDLᵀ factor (as ``ldlt_solve_matrix``);
    constraint (k, n): A, the constraint matrix Λ (k = 0: K = M⁻¹).  Returns 0, ``ldlt_solve_matrix``'s j + 1
    when M is not positive definite, or `DEPENDENT_CONSTRAINTS`; the columns are then invalid.
    """
    n, c = columns.shape
    k = constraint.shape[0]
    if k == 0:
        return ldlt_solve_matrix(mass, columns)
    both = np.empty((n, c + k))                 # [M⁻¹ X | M⁻¹ Aᵀ]
    for i in range(n):
        for a in range(c):
            both[i, a] = columns[i, a]
        for r in range(k):
            both[i, c + r] = constraint[r, i]
    status = ldlt_solve_matrix(mass, both)
    if status != 0:
        return status
    schur = np.empty((k, k))                    # S = A M⁻¹ Aᵀ
    coupling = np.empty((k, c))                 # A M⁻¹ X, then S⁻¹ A M⁻¹ X
    for r in range(k):
        for s in range(k):
            total = 0.0
            for i in range(n):
                total += constraint[r, i] * both[i, c + s]
            schur[r, s] = total
        for a in range(c):
            total = 0.0
            for i in range(n):
                total += constraint[r, i] * both[i, a]
            coupling[r, a] = total
    if ldlt_solve_matrix(schur, coupling) != 0:
        return DEPENDENT_CONSTRAINTS
    for i in range(n):
        for a in range(c):
            total = both[i, a]
            for r in range(k):
                total -= both[i, c + r] * coupling[r, a]
            columns[i, a] = total
    return 0
