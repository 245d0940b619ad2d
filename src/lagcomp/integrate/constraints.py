"""Constraints at run time: consistent initial states, and reactions along a trajectory."""

from __future__ import annotations

import numpy as np

from lagcomp.errors import InitialConditionError

#: Largest residual an initial state may have, as a fraction of the rounding scale of its row: |Φ_i| ≤ 1e-9 A(Φ_i),
#: A(Φ_i) the size of the terms and factors Φ_i is made of (`lagcomp.codegen.rounding_scale`), so the test reads
#: the same in any units.  A rounded exact start sits at a few ε A (ε = 1.1e-16; rounding of q0 included: A counts
#: each coordinate's size through its slope), a million times below; a start typed or computed to ten significant
#: digits passes; one off its constraints by more than a part in 10⁹ of what they balance is refused (at the unit
#: scale, where A ~ 1, the absolute 1e-9 this replaces).  A row that is a single term (Ψ = u2) has A = |Φ|: any
#: nonzero value is refused, as rounding cannot make one.
INITIAL_TOLERANCE = 1e-9


def consistent_initial_state(model, t0: float, y0: np.ndarray, p: np.ndarray, project: bool,
                             tolerance: float = INITIAL_TOLERANCE) -> tuple[np.ndarray, bool]:
    """Check y0 against the constraints (position and velocity level), or project it.

    Returns the state to start from and whether it was projected.  Without `project`, a residual row above
    `tolerance` times its rounding scale (`INITIAL_TOLERANCE`; the kernel ``constraint_residual_scales``) raises
    `InitialConditionError` naming the constraint, the size of the violation and its scale.
    """
    if not model.residual_labels:
        return y0, False
    residuals, scales = np.empty(len(model.residual_labels)), np.empty(len(model.residual_labels))
    model.kernels.constraint_residuals(t0, y0, p, residuals)
    model.kernels.constraint_residual_scales(t0, y0, p, scales)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.where(np.abs(residuals) <= tolerance * scales, 0.0, np.abs(residuals) / scales)
    ratios[np.isnan(ratios)] = np.inf    # (a NaN residual or scale: refused, first)
    if not ratios.any():
        return y0, False
    if not project:
        worst = int(np.argmax(ratios))
        constraint, level = model.residual_labels[worst]
        raise InitialConditionError(
            f"The initial state violates constraint `{constraint}` at {level} level by {residuals[worst]:.3g}, "
            f"{ratios[worst]:.3g} of the size {scales[worst]:.3g} of its terms (tolerance {tolerance:g} of that "
            "size); fix q0/qd0, or pass project_initial=True (--project-initial on the command line) to project "
            "them onto the constraints."
        )
    y = y0.copy()
    status = model.kernels.project(t0, y, p)
    if status:
        raise InitialConditionError(
            f"The initial state could not be projected onto the constraints {list(model.constraints)}: "
            "their Jacobian is rank-deficient there (redundant constraints)."
        )
    return y, True


def reactions_along(model, ts: np.ndarray, ys: np.ndarray, p: np.ndarray) -> tuple[dict, float]:
    """Multipliers by constraint name, each shape (m,), and the largest residual over the rows (0.0 without
    constraints, NaN if a row's is)."""
    if not model.k:
        return {}, 0.0
    lam = np.full((ts.size, model.k), np.nan)
    residual = np.full(ts.size, np.nan)
    model.kernels.reactions_along(ts, ys, p, lam, residual)
    return {name: lam[:, j].copy() for j, name in enumerate(model.constraints)}, float(np.max(residual, initial=0.0))
