r"""The articulated-body algorithm (Featherstone 2008, §7.3): q̈ of a tree in O(n), as a straight-line program.

Three passes over the nodes (`lagcomp.multibody.kinematics`), every quantity bound as it is formed:

1. outwards: placement X_i, velocity v_i = X_i v_λ + S_i q̇_i, velocity product c_i = v_i ×ₘ S_i q̇_i, and the
   articulated inertia and bias force started from the link's own: I^A_i = I_i, p^A_i = v_i ×* I_i v_i;
2. inwards: U_i = I^A_i S_i, D_i = S_iᵀ U_i, u_i = τ_i − S_iᵀ p^A_i, and into the parent λ
   I^A_λ += X_iᵀ (I^A_i − U_i U_iᵀ / D_i) X_i, p^A_λ += X_iᵀ (p^A_i + I^a_i c_i + U_i u_i / D_i);
3. outwards: a'_i = X_i a_λ + c_i (a_base = (0, −g): gravity), q̈_i = (u_i − U_iᵀ a'_i) / D_i, a_i = a'_i + S_i q̈_i.

D_i > 0 for any tree whose subtrees have inertia along their joints' axes; 1/D_i is formed once per node.
Each node's share of a pass is a step of the program (`Program.step`), which identical nodes share when emitted
(`lagcomp.codegen.outline`).
"""

from __future__ import annotations

from lagcomp.multibody.kinematics import (
    base_acceleration,
    joint_motion,
    placement,
    subspace,
    velocity_product,
)
from lagcomp.multibody.program import Program, add
from lagcomp.multibody.spatial import ZERO3, add_spatial, force_cross, rigid_inertia, spatial_dot


def accelerations(prog: Program, nodes, gravity) -> list:
    """q̈ of every node (its local or expression), in node order, bound in `prog`."""
    X, v, c, IA, pA = [], [], [], [], []
    for i, node in enumerate(nodes):
        with prog.step(("velocities", i)):
            X.append(placement(prog, node))
            motion = joint_motion(prog, node)
            moved = X[i].to_child(prog, v[node.parent]) if node.parent >= 0 else (ZERO3, ZERO3)
            v.append(add_spatial(prog, moved, motion))
            c.append(velocity_product(prog, v[i], node))
            IA.append(rigid_inertia(prog, node.mass, list(node.com), [list(row) for row in node.inertia]))
            pA.append(force_cross(prog, v[i], IA[i].times(prog, v[i])))
    U, Dinv, u = _inward(prog, nodes, X, c, IA, pA)
    return _outward(prog, nodes, X, c, U, Dinv, u, gravity)


def _inward(prog: Program, nodes, X, c, IA, pA):
    """Pass 2: U_i, 1/D_i, u_i per node; the articulated inertias and bias forces folded into the parents."""
    n = len(nodes)
    U, Dinv, u = [None] * n, [None] * n, [None] * n
    for i in reversed(range(n)):
        with prog.step(("inward", i)):
            U[i], Dinv[i], u[i] = _inward_step(prog, nodes, i, X, c, IA, pA)
    return U, Dinv, u


def _inward_step(prog: Program, nodes, i, X, c, IA, pA):
    """U_i, 1/D_i, u_i of node i; its articulated inertia and bias force folded into its parent's entries of
    `IA` and `pA`."""
    node, S = nodes[i], subspace(nodes[i])
    U = IA[i].times(prog, S)
    Dinv = prog.let(1 / prog.let(spatial_dot(S, U)))
    u = prog.let(node.force - spatial_dot(S, pA[i]))
    if node.parent < 0:
        return U, Dinv, u
    k = _unit_index(S)
    Ia = IA[i].minus_outer(prog, U, Dinv, k)
    scale = prog.let(u * Dinv)
    Iac = Ia.times(prog, c[i])
    pa = [*add(add(pA[i][0], Iac[0]), [x * scale for x in U[0]]),
          *add(add(pA[i][1], Iac[1]), [x * scale for x in U[1]])]
    if k is not None:   # Sᵀ pa = Sᵀ pA + 0 + D u / D = τ exactly
        pa[k] = node.force
    pa = (prog.vector(pa[:3]), prog.vector(pa[3:]))
    parent = node.parent
    IA[parent] = IA[parent].plus(prog, Ia.to_parent(prog, X[i]))
    pA[parent] = add_spatial(prog, pA[parent], X[i].to_parent(prog, pa))
    return U, Dinv, u


def _unit_index(S) -> int | None:
    """k when the motion subspace S = (w, v) is the unit vector e_k of the six (a joint along a frame axis)."""
    entries = [*S[0], *S[1]]
    nonzero = [k for k, e in enumerate(entries) if e != 0]
    return nonzero[0] if len(nonzero) == 1 and entries[nonzero[0]] == 1 else None


def _outward(prog: Program, nodes, X, c, U, Dinv, u, gravity) -> list:
    """Pass 3: the accelerations a_i and q̈_i, from the base's (0, −g)."""
    base = base_acceleration(gravity)
    a, qdd = [None] * len(nodes), [None] * len(nodes)
    for i, node in enumerate(nodes):
        with prog.step(("accelerations", i)):
            parent = base if node.parent < 0 else a[node.parent]
            moved = X[i].to_child(prog, parent)
            a_prime = add_spatial(prog, moved, c[i])
            qdd[i] = prog.let((u[i] - spatial_dot(a_prime, U[i])) * Dinv[i])
            S = subspace(node)
            a[i] = add_spatial(prog, a_prime, ([x * qdd[i] for x in S[0]], [x * qdd[i] for x in S[1]]))
    return qdd
