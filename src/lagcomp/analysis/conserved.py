r"""Which quantities a model conserves, and why: a report read off the System, no derivation.

* The energy function h = Σ q̇_i ∂L/∂q̇_i − L (Jacobi integral) has
  dh/dt = −∂L/∂t + Σ_i (Q_i − ∂D/∂q̇_i) q̇_i + the power of the constraint
  forces, so it is conserved when L has no explicit t, no generalized forces
  or dissipation act, and the constraints are time-independent (then their
  reactions do no work: Λ q̇ = 0).  It equals T + V when T is homogeneous
  quadratic in q̇ (no imposed motion in T).
* The momentum p_i = ∂L/∂q̇_i of a cyclic coordinate (absent from L, no
  force along it) is conserved when no constraint acts along it either.

Along a run, `Solution.invariants()` evaluates these with their drift.
"""

from __future__ import annotations

from dataclasses import dataclass

from lagcomp.analysis._common import explicit_time, symbolic_system


@dataclass(frozen=True)
class Conserved:
    """One conserved quantity: its name in `Solution.invariants()`, what it is, and why it is conserved."""

    name: str
    what: str
    reason: str


def conserved_quantities(model) -> list[Conserved]:
    """The model's first integrals that follow from the form of its Lagrangian (cheap sympy checks only)."""
    from lagcomp.model.system import t

    system = symbolic_system(model, "conserved_quantities")
    found = []
    forces = any(Q != 0 for Q in system.forces) or system.dissipation != 0
    timed = explicit_time(system.T, system.V, system=system)
    moving_constraints = explicit_time(*(c.expr for c in system.constraints), system=system)
    if not (forces or timed or moving_constraints):
        found.append(Conserved(
            "h", "energy function Σ q̇ ∂L/∂q̇ − L",
            "L has no explicit t, no generalized forces or dissipation act"
            + (", and the constraints do not depend on t" if system.constraints else ""),
        ))
    for name in model.cyclic:
        i = model.coordinates.index(name)
        if any(c.expr.has(system.coordinates[i]) or c.expr.has(system.coordinates[i].diff(t))
               for c in system.constraints):
            continue
        found.append(Conserved(f"p_{name}", f"momentum conjugate to {name}",
                               f"{name} is cyclic: absent from L, with no force along it"))
    return found
