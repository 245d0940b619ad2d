"""Constraints at run time: consistent initial states, and reactions along a trajectory."""

from __future__ import annotations

import numpy as np

from lagcomp.errors import InitialConditionError

#: Default largest residual an initial state may have before it is refused.
INITIAL_TOLERANCE = 1e-9


def consistent_initial_state(model, t0: float, y0: np.ndarray, p: np.ndarray, project: bool,
                             tolerance: float = INITIAL_TOLERANCE) -> tuple[np.ndarray, bool]:
    """Check y0 against the constraints (position and velocity level), or project it.

    Returns the state to start from and whether it was projected.  Without
    `project`, a residual above `tolerance` raises `InitialConditionError`
    naming the constraint and the size of the violation.
    """
    if not model.residual_labels:
        return y0, False
    residuals = np.empty(len(model.residual_labels))
    model.kernels.constraint_residuals(t0, y0, p, residuals)
    worst_index = int(np.argmax(np.abs(residuals)))
    worst = residuals[worst_index]
    if abs(worst) <= tolerance:
        return y0, False
    if not project:
        constraint, level = model.residual_labels[worst_index]
        raise InitialConditionError(
            f"The initial state violates constraint `{constraint}` at {level} level by {worst:.3g} "
            f"(tolerance {tolerance:g}); fix q0/qd0, or pass project_initial=True (--project-initial on the "
            "command line) to project them onto the constraints."
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
