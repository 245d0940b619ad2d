r"""The holonomic constraints of a tree's cut joints (`lagcomp.multibody.loops`) from its forward kinematics.

For each cut joint the two points P_first and P_second are followed out from the base, in the base frame, along
the nodes on their paths only (`lagcomp.multibody.frames`: positions, velocities, accelerations at q̈ = 0 and
Jacobian columns along the recursions' joint rates).  Then for direction d_k:

    Φ_k = d_k·(P_first − P_second),   Λ_k = d_k·(J_first − J_second),
    Λ_k q̇ = d_k·(v_first − v_second),   γ_k = −Λ̇_k q̇ = −d_k·(a_first − a_second)   (Λ q̈ = γ).

A ball joint's columns are along its body rates ω = J(σ) σ̇; Λ's row on its MRPs is Jᵀ of them
(`lagcomp.multibody.charts`), so that Λ q̇ is the velocity residual in the coordinates, and γ, the acceleration at
σ̈ = 0 (ω̇ = J σ̈ + J̇ σ̇, the J̇ σ̇ part in the frames' α), the coordinates' −Λ̇ q̇.  A shadow switch σ → −σ/|σ|²
leaves the rotation, the angular velocity and so Φ, Λ q̇ and γ where they were.
"""

from __future__ import annotations

from dataclasses import dataclass

from lagcomp.multibody.charts import forces_in_coordinates
from lagcomp.multibody.frames import ZERO, WorldKinematics
from lagcomp.multibody.program import Program, dot


@dataclass(frozen=True)
class ClosureRows:
    """What the kernels read of a tree's cut joints, one entry per constraint, bound in a `Program`: the residuals
    Φ, the rows of Λ = ∂Φ/∂q (lists of n), the velocity residuals Λ q̇ and γ = −Λ̇ q̇."""

    Phi: list
    rows: list
    velocity: list
    gamma: list


def closure_rows(prog: Program, nodes, closures, last_node: dict, points) -> ClosureRows:
    """The `ClosureRows` of `closures` (`lagcomp.multibody.loops.Closure`) over the `nodes` (local, node order):
    `last_node` maps a link's name to its last node, `points` each closure to its (first, second) points over the
    kernel's locals."""
    world, n = WorldKinematics(prog, nodes), len(nodes)
    Phi, rows, velocity, gamma = [], [], [], []
    for closure, (p_first, p_second) in zip(closures, points):
        ends = [world.point(last_node[closure.first], p_first),
                world.point(-1 if closure.second is None else last_node[closure.second], p_second)]
        (P1, v1, a1, J1), (P2, v2, a2, J2) = ends
        for d in closure.directions:
            Phi.append(prog.let(dot(d, [x - y for x, y in zip(P1, P2)])))
            velocity.append(prog.let(dot(d, [x - y for x, y in zip(v1, v2)])))
            gamma.append(prog.let(-dot(d, [x - y for x, y in zip(a1, a2)])))
            row = [prog.let(dot(d, J1.get(j, ZERO)) - dot(d, J2.get(j, ZERO))) for j in range(n)]
            rows.append(forces_in_coordinates(prog, nodes, row))
    return ClosureRows(Phi, rows, velocity, gamma)
