r"""The holonomic constraints of a tree's cut joints (`lagcomp.multibody.loops`) from its forward kinematics.

For each cut joint the two points P_first and P_second are followed out from the base, in the base frame, along
the nodes on their paths only.  Each node i (parent λ, base: R = 1, o = ω = v = α = a = 0) has its frame's
rotation R_i = R_λ R_Xi and origin o_i = o_λ + r_i (r_i = R_λ r_Xi), its joint axis ŝ_i = R_i a_i in base axes,
and, at q̈ = 0 (the acceleration terms that do not multiply q̈, what the constraint rows need):

* revolute: ω_i = ω_λ + ŝ_i q̇_i, v_i = v_λ + ω_λ × r_i, α_i = α_λ + (ω_λ × ŝ_i) q̇_i,
  a_i = a_λ + α_λ × r_i + ω_λ × (ω_λ × r_i);
* prismatic: ω_i = ω_λ, v_i = v_λ + ω_λ × r_i + ŝ_i q̇_i, α_i = α_λ,
  a_i = a_λ + α_λ × r_i + ω_λ × (ω_λ × r_i) + 2 ω_λ × ŝ_i q̇_i,

with v, a the velocity and acceleration of the origin o_i.  A point p fixed in link L (r_P = R_L p) has position
o_L + r_P, velocity v_L + ω_L × r_P and acceleration (at q̈ = 0) a_L + α_L × r_P + ω_L × (ω_L × r_P); its
Jacobian column for node j on its path is ŝ_j × (P − o_j) (revolute) or ŝ_j (prismatic).  Then for direction d_k:

    Φ_k = d_k·(P_first − P_second),   Λ_k = d_k·(J_first − J_second),
    Λ_k q̇ = d_k·(v_first − v_second),   γ_k = −Λ̇_k q̇ = −d_k·(a_first − a_second)   (Λ q̈ = γ).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from lagcomp.errors import ModelError
from lagcomp.multibody.joints import ISSUE
from lagcomp.multibody.kinematics import placement
from lagcomp.multibody.program import Program, add, cross, dot, mat_vec

IDENTITY = [[sp.S.One if i == j else sp.S.Zero for j in range(3)] for i in range(3)]
ZERO = [sp.S.Zero] * 3


@dataclass(frozen=True)
class WorldNode:
    """A node's frame in base axes: rotation (rows), origin, axis ŝ, angular velocity, origin velocity, and the
    angular and origin accelerations at q̈ = 0 (module docstring)."""

    R: list
    o: list
    axis: list
    w: list
    v: list
    alpha: list
    a: list


BASE = WorldNode(IDENTITY, ZERO, ZERO, ZERO, ZERO, ZERO, ZERO)


@dataclass(frozen=True)
class ClosureRows:
    """What the kernels read of a tree's cut joints, one entry per constraint, bound in a `Program`: the residuals
    Φ, the rows of Λ = ∂Φ/∂q (lists of n), the velocity residuals Λ q̇ and γ = −Λ̇ q̇."""

    Phi: list
    rows: list
    velocity: list
    gamma: list


class WorldKinematics:
    """The nodes' `WorldNode` s, each formed the first time a path asks for it (nodes off every loop never are)."""

    def __init__(self, prog: Program, nodes):
        self.prog, self.nodes, self._done = prog, nodes, {}

    def node(self, i: int) -> WorldNode:
        if i < 0:
            return BASE
        if i not in self._done:
            self._done[i] = self._outward(i)
        return self._done[i]

    def _outward(self, i: int) -> WorldNode:
        prog, node = self.prog, self.nodes[i]
        if node.kind not in ("revolute", "prismatic"):   # (the formulas above are those of one-axis joints)
            raise ModelError(f"A loop passes through a {node.kind} joint: loops close through revolute and "
                             f"prismatic joints (and the joints made of them) only, for now ({ISSUE}).")
        parent, X = self.node(node.parent), placement(self.prog, node)
        R = [prog.vector(mat_vec(parent.R, [X.R[0][j], X.R[1][j], X.R[2][j]])) for j in range(3)]
        R = [[R[j][k] for j in range(3)] for k in range(3)]   # columns to rows
        r = prog.vector(mat_vec(parent.R, X.r))
        axis = prog.vector(mat_vec(R, node.axis))
        rate = [x * node.qd for x in axis]
        transport = add(cross(parent.alpha, r), cross(parent.w, cross(parent.w, r)))
        v = add(parent.v, cross(parent.w, r))
        if node.kind == "revolute":
            w, alpha, a = add(parent.w, rate), add(parent.alpha, cross(parent.w, rate)), add(parent.a, transport)
        else:
            w, alpha = parent.w, parent.alpha
            v, a = add(v, rate), add(add(parent.a, transport), [2 * x for x in cross(parent.w, rate)])
        return WorldNode(R, prog.vector(add(parent.o, r)), axis, prog.vector(w), prog.vector(v), prog.vector(alpha),
                         prog.vector(a))

    def path(self, i: int) -> list[int]:
        """Node `i` and its ancestors."""
        out = []
        while i >= 0:
            out.append(i)
            i = self.nodes[i].parent
        return out

    def point(self, i: int, p) -> tuple[list, list, list, dict]:
        """Position, velocity, acceleration at q̈ = 0 and Jacobian columns {node: 3-vector} of the point `p` fixed
        in node `i`'s frame (the base's for i < 0)."""
        prog, L = self.prog, self.node(i)
        r = prog.vector(mat_vec(L.R, p))
        P = prog.vector(add(L.o, r))
        v = prog.vector(add(L.v, cross(L.w, r)))
        a = prog.vector(add(add(L.a, cross(L.alpha, r)), cross(L.w, cross(L.w, r))))
        columns = {}
        for j in self.path(i):
            J = self.node(j)
            columns[j] = (prog.vector(cross(J.axis, [x - y for x, y in zip(P, J.o)]))
                          if self.nodes[j].kind == "revolute" else J.axis)
        return P, v, a, columns


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
            rows.append([prog.let(dot(d, J1.get(j, ZERO)) - dot(d, J2.get(j, ZERO))) for j in range(n)])
    return ClosureRows(Phi, rows, velocity, gamma)
