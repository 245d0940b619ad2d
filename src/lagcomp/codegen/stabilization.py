"""The Baumgarte-stabilized right-hand side of the constraint rows Λ q̈ = γ̃ (and the velocity residual it
damps), shared by the constrained ``rhs`` and the constrained Jacobian and directional kernels."""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.bindings import baumgarte_gains
from lagcomp.mechanics.lagrange import EOM


def velocity_residual(eom: EOM, c: int) -> sp.Expr:
    """Λ_c · q̇ + b_c, which vanishes on the constraint."""
    return sum((eom.C[c, j] * eom.qd[j] for j in range(eom.n)), eom.b[c])


def stabilized_gamma(eom: EOM) -> list:
    """γ̃_c = γ_c − 2α (Λ_c q̇ + b_c) − β² Φ_c (the last term for holonomic rows only), the right-hand side of
    Λ q̈ = γ̃ with the Baumgarte gains α, β (`baumgarte_gains`), one per constraint."""
    alpha, beta = baumgarte_gains(eom)
    holonomic_rows = [c for c in range(eom.k) if eom.holonomic[c]]
    rows = []
    for c in range(eom.k):
        stabilized = eom.gamma[c] - 2 * alpha * velocity_residual(eom, c)
        if eom.holonomic[c]:
            stabilized -= beta**2 * eom.Phi[holonomic_rows.index(c)]
        rows.append(stabilized)
    return rows
