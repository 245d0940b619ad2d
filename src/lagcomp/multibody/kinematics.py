"""What every recursion over a tree starts from: each node's placement, motion subspace, velocity and joint force.

The recursions take the tree with its expressions over the kernel's locals (`local_nodes`): coordinates q_i,
velocities q̇_i and parameters as plain real symbols, so that what they bind is what the kernel computes.

A spherical joint is three consecutive nodes (kind "spherical", parts 0, 1, 2) whose motion subspaces are the body
axes e_x, e_y, e_z and whose "velocities" are the body-frame angular velocity ω = J(σ) σ̇ of the joint's MRPs σ
(`lagcomp.multibody.mrp`).  Part 0 carries the rotation R(σ) and the joint's placement, parts 1 and 2 identity
placements: the three frames coincide, the two first are massless.  The joint's velocity product
c = v ×ₘ (ω, 0) + (J̇ σ̇, 0) sits on part 2 (the body's acceleration depends on the sum over the parts only), so
the recursions' accelerations of the three nodes are ψ = J σ̈, and their generalized forces those along ω:
`lagcomp.multibody.charts` turns both into σ's.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from lagcomp.multibody import mrp
from lagcomp.multibody.joints import t
from lagcomp.multibody.program import Program, add, cross, dot, mat_vec
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
    spring, damper and torque, and its mass properties (mass, centre of mass, inertia about it).  A spherical
    joint's node also has its `part` (0, 1, 2) and the joint's MRP and rate locals `sigma`, `sigma_dot`."""

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
    part: int = -1
    sigma: tuple = ()
    sigma_dot: tuple = ()


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
        chart, rate = {}, qd[i]
        if j.kind == "spherical":   # (its torque and damping act along ω_k, the node's rate in the recursions)
            part = list(j.axis).index(1)
            chart = {"part": part, "sigma": tuple(q[i - part:i - part + 3]),
                     "sigma_dot": tuple(qd[i - part:i - part + 3])}
            rate = mrp.angular_velocity(chart["sigma"], chart["sigma_dot"])[part]
        force = local(j.torque) - local(j.stiffness) * (q[i] - local(j.rest)) - local(j.damping) * rate
        nodes.append(LocalNode(
            node.parent, j.kind, tuple(j.axis), tuple(tuple(local(e) for e in row) for row in j.rotation),
            tuple(local(e) for e in j.origin), q[i], qd[i], force, local(node.mass),
            tuple(local(e) for e in node.com), tuple(tuple(local(node.inertia[a, b]) for b in range(3))
                                                     for a in range(3)),
            local(j.stiffness), local(j.rest), **chart))
    return nodes


def placement(prog: Program, node: LocalNode) -> Placement:
    """The node's frame in its parent's: R = R_T R_J(q), r = r_T (+ R_T a q for a prismatic joint).

    A revolute joint's R_J(q) = cos q 1 + sin q [a]× + (1 − cos q) a aᵀ (Rodrigues), its zeros and ones folded for
    an axis along x, y or z.
    """
    a, RT = node.axis, [list(row) for row in node.rotation]
    if node.kind == "spherical":
        if node.part > 0:
            return Placement([[sp.S.One if i == j else sp.S.Zero for j in range(3)] for i in range(3)], list(ZERO3))
        s = prog.let(dot(node.sigma, node.sigma))
        RJ = [prog.vector(row) for row in mrp.rotation(node.sigma, s, prog.let(1 / (1 + s) ** 2))]
        R = [prog.vector(mat_vec(RT, [RJ[0][j], RJ[1][j], RJ[2][j]])) for j in range(3)]
        return Placement([[R[j][i] for j in range(3)] for i in range(3)], list(node.origin))
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
    """The motion subspace S (one column) in the node's frame: (a, 0) for a revolute (or spherical) joint, (0, a)
    prismatic."""
    a = list(node.axis)
    return (list(ZERO3), a) if node.kind == "prismatic" else (a, list(ZERO3))


def node_rate(prog: Program, node: LocalNode):
    """The node's velocity along S: q̇, or for a spherical joint's part k the body rate ω_k = (J(σ) σ̇)_k."""
    if node.kind != "spherical":
        return node.qd
    return joint_rates(prog, node)[node.part]


def mrp_matrices(prog: Program, sigma) -> tuple[list, list]:
    """J(σ) and J⁻¹(σ) = B / 4 (rows), bound entry by entry (`lagcomp.multibody.mrp`): s = σ·σ and 4 / (1 + s)²
    formed once.  Binding the same σ again returns the same locals (`Program.let` hash-conses)."""
    s = prog.let(dot(sigma, sigma))
    k = prog.let(4 / (1 + s) ** 2)
    B = mrp.b_matrix(sigma, s)
    J = [[prog.let(k * B[j][i]) for j in range(3)] for i in range(3)]
    return J, [[prog.let(B[i][j] / 4) for j in range(3)] for i in range(3)]


def joint_rates(prog: Program, node: LocalNode) -> list:
    """A spherical joint's body-frame angular velocity ω = J(σ) σ̇, bound (the same locals for its three parts)."""
    J, _ = mrp_matrices(prog, node.sigma)
    return prog.vector(mat_vec(J, node.sigma_dot))


def joint_motion(prog: Program, node: LocalNode) -> tuple[list, list]:
    """S q̇, the velocity across the joint (S ω_k for a spherical joint's part k)."""
    w, v = subspace(node)
    rate = node_rate(prog, node)
    return [x * rate for x in w], [x * rate for x in v]


def velocities(prog: Program, nodes, placements) -> list:
    """Each node's spatial velocity in its frame: v_i = X_i v_parent + S_i q̇_i (v_base = 0)."""
    out = []
    for node, X in zip(nodes, placements):
        motion = joint_motion(prog, node)
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
    """c_i = v_i ×ₘ S_i q̇_i: the acceleration the joint's rate produces in the moving frame (S is constant).

    A spherical joint's is v ×ₘ (ω, 0) + (J̇ σ̇, 0) on its part 2, zero on parts 0 and 1 (module docstring)."""
    if node.kind == "spherical":
        return spherical_velocity_product(prog, velocity, node)
    (w, v), (sw, sv) = velocity, joint_motion(prog, node)
    return prog.vector(cross(w, sw)), prog.vector(add(cross(w, sv), cross(v, sw)))


def spherical_velocity_product(prog: Program, velocity, node: LocalNode):
    """v ×ₘ (ω, 0) + (J̇ σ̇, 0) on part 2 of a spherical joint (v its body's velocity), zero on the others."""
    if node.part != 2:
        return list(ZERO3), list(ZERO3)
    (w, v), (omega, jdot) = velocity, rate_product(prog, node)
    return prog.vector(add(cross(w, omega), jdot)), prog.vector(cross(v, omega))


def rate_product(prog: Program, node: LocalNode) -> tuple[list, list]:
    """(ω, J̇ σ̇) of a spherical joint's node: its body rate ω = J(σ) σ̇ (bound) and what ω̇ holds besides J σ̈,
    J̇ σ̇ = −4 (σ·σ̇) ω / (1 + s) + 8 |σ̇|² σ / (1 + s)² (`lagcomp.multibody.mrp.rate_product`), its two scalar
    factors bound, its entries not."""
    omega = joint_rates(prog, node)
    sigma, rates = node.sigma, node.sigma_dot
    one_plus_s = prog.let(1 + prog.let(dot(sigma, sigma)))
    a = prog.let(-4 * dot(sigma, rates) / one_plus_s)
    b = prog.let(8 * dot(rates, rates) / one_plus_s ** 2)
    return omega, [a * omega[i] + b * sigma[i] for i in range(3)]
