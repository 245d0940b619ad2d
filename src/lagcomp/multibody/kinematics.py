"""What every recursion over a tree starts from: each node's placement, motion subspace, velocity and joint force.

The recursions take the tree with its expressions over the kernel's locals (`local_nodes`): coordinates q_i,
velocities q̇_i and parameters as plain real symbols, so that what they bind is what the kernel computes.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from lagcomp.multibody.joints import t
from lagcomp.multibody.program import Program, add, cross, mat_vec
from lagcomp.multibody.spatial import (
    ZERO3,
    Inertia,
    Placement,
    add_spatial,
    rigid_inertia,
)
from lagcomp.multibody.tree import Tree


@dataclass(frozen=True)
class LocalNode:
    """A `lagcomp.multibody.tree.Node` over the kernel's locals: parent index, "revolute" or "prismatic", unit
    axis, placement (rotation rows, origin), coordinate and velocity locals, the generalized force τ of its
    spring, damper and torque, and its mass properties (mass, centre of mass, inertia about it)."""

    parent: int
    kind: str
    axis: tuple
    rotation: tuple
    origin: tuple
    q: sp.Symbol
    qd: sp.Symbol
    force: sp.Expr
    mass: sp.Expr
    com: tuple
    inertia: tuple
    stiffness: sp.Expr
    rest: sp.Expr


def local_nodes(tree: Tree, q, qd, mapping: dict) -> list[LocalNode]:
    """The nodes of `tree` over locals: `q`, `qd` the coordinate and velocity locals (node order), `mapping` each
    parameter (and t) to its local; a torque's q_i(t) and q̇_i(t) become q_i and q̇_i."""
    signals = {}
    for i, c in enumerate(tree.coordinates):
        signals[c.diff(t)] = qd[i]
    for i, c in enumerate(tree.coordinates):
        signals[c] = q[i]

    def local(e):
        return sp.sympify(e).xreplace(signals).xreplace(mapping)

    nodes = []
    for i, node in enumerate(tree.nodes):
        j = node.joint
        force = local(j.torque) - local(j.stiffness) * (q[i] - local(j.rest)) - local(j.damping) * qd[i]
        nodes.append(LocalNode(
            node.parent, j.kind, tuple(j.axis), tuple(tuple(local(e) for e in row) for row in j.rotation),
            tuple(local(e) for e in j.origin), q[i], qd[i], force, local(node.mass),
            tuple(local(e) for e in node.com), tuple(tuple(local(node.inertia[a, b]) for b in range(3))
                                                     for a in range(3)),
            local(j.stiffness), local(j.rest)))
    return nodes


def placement(prog: Program, node: LocalNode) -> Placement:
    """The node's frame in its parent's: R = R_T R_J(q), r = r_T (+ R_T a q for a prismatic joint).

    A revolute joint's R_J(q) = cos q 1 + sin q [a]× + (1 − cos q) a aᵀ (Rodrigues), its zeros and ones folded for
    an axis along x, y or z.
    """
    a, RT = node.axis, [list(row) for row in node.rotation]
    if node.kind == "revolute":
        c, s = prog.let(sp.cos(node.q)), prog.let(sp.sin(node.q))
        skew = [[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]]
        RJ = [[c * int(i == j) + s * skew[i][j] + (1 - c) * a[i] * a[j] for j in range(3)] for i in range(3)]
        RJ = [prog.vector(row) for row in RJ]
        R = [prog.vector(mat_vec(RT, [RJ[0][j], RJ[1][j], RJ[2][j]])) for j in range(3)]
        R = [[R[j][i] for j in range(3)] for i in range(3)]
        return Placement(R, list(node.origin))
    shift = prog.vector(mat_vec(RT, [x * node.q for x in a]))
    return Placement([[prog.let(e) for e in row] for row in RT], prog.vector(add(node.origin, shift)))


def subspace(node: LocalNode) -> tuple[list, list]:
    """The motion subspace S (one column) in the node's frame: (a, 0) for a revolute joint, (0, a) prismatic."""
    a = list(node.axis)
    return (a, list(ZERO3)) if node.kind == "revolute" else (list(ZERO3), a)


def joint_motion(node: LocalNode) -> tuple[list, list]:
    """S q̇, the velocity across the joint."""
    w, v = subspace(node)
    return [x * node.qd for x in w], [x * node.qd for x in v]


def velocities(prog: Program, nodes, placements) -> list:
    """Each node's spatial velocity in its frame: v_i = X_i v_parent + S_i q̇_i (v_base = 0)."""
    out = []
    for node, X in zip(nodes, placements):
        motion = joint_motion(node)
        if node.parent < 0:
            out.append((prog.vector(motion[0]), prog.vector(motion[1])))
        else:
            out.append(add_spatial(prog, X.to_child(prog, out[node.parent]), motion))
    return out


def inertias(prog: Program, nodes) -> list[Inertia]:
    """Each node's rigid-body spatial inertia in its frame (`lagcomp.multibody.spatial.rigid_inertia`)."""
    return [rigid_inertia(prog, node.mass, list(node.com), [list(row) for row in node.inertia]) for node in nodes]


def base_acceleration(gravity) -> tuple[list, list]:
    """The base's fictitious acceleration (0, −g): accelerating the base upwards puts gravity on every link."""
    return list(ZERO3), [-x for x in gravity]


def velocity_product(prog: Program, velocity, node: LocalNode):
    """c_i = v_i ×ₘ S_i q̇_i: the acceleration the joint's rate produces in the moving frame (S is constant)."""
    (w, v), (sw, sv) = velocity, joint_motion(node)
    return prog.vector(cross(w, sw)), prog.vector(add(cross(w, sv), cross(v, sw)))
