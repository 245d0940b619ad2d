"""The slip forces of a tree's friction elements pressed by an expression (`lagcomp.Friction` with ``normal=`` a
normal force N(q, q̇, t), not a contact's name), as generalized forces of the recursions.

Slipping with mode s = ±1 (0 while it sticks, a slot of p: `lagcomp.ir.ContactModes`), element f pushes the
coordinates with Q_i = −μk |N| s ∂v/∂q̇_i, as on a System (`lagcomp.mechanics.lagrange`; its velocity v is linear
in q̇).  Here Q joins each node's generalized force τ (`lagcomp.multibody.kinematics.LocalNode.force`), so the
articulated-body algorithm's ``rhs`` (``rhs_free`` of the contact kernels) and every kernel built from the same
nodes (the Jacobians, M and F on demand) include it.  On a ball joint τ acts along the body rates ω, whose power
τ·ω is Q_σ·σ̇ with σ̇ = J⁻¹ ω = B ω / 4 (`lagcomp.multibody.mrp`): τ = Bᵀ Q_σ / 4.

A friction element pressed by a contact (``normal="floor"``) has no slip force here: its force joins the contact's
column of the held rows (`lagcomp.kernel_support.resting.pressed_frictional_accelerations`).
"""

from __future__ import annotations

from dataclasses import replace

import sympy as sp

from lagcomp.model.friction import Friction, slip_symbol
from lagcomp.multibody import mrp
from lagcomp.multibody.joints import t


def generalized_slip_forces(tree) -> list:
    """Q_i = Σ_f −μk_f |N_f| s_f ∂v_f/∂q̇_i per coordinate (the tree's coordinates q_i(t), node order), s_f the
    mode symbol of element f (`lagcomp.model.friction.slip_symbol`)."""
    rates = [c.diff(t) for c in tree.coordinates]
    forces = [sp.S.Zero] * tree.n
    elements = [e for e in tree.events if isinstance(e, Friction)]
    for f, e in enumerate(elements):
        if isinstance(e.normal, str):
            continue
        size = e.kinetic * sp.Abs(sp.sympify(e.normal)) * slip_symbol(f)
        forces = [Q - size * sp.sympify(e.expr).diff(rate) for Q, rate in zip(forces, rates, strict=True)]
    return forces


def pressed_by_expressions(tree) -> bool:
    """Whether some friction element of `tree` is pressed by an expression (it has slip forces here)."""
    return any(isinstance(e, Friction) and not isinstance(e.normal, str) for e in tree.events)


def with_slip_forces(tree, nodes: list, local) -> list:
    """`nodes` (`lagcomp.multibody.kinematics.local_nodes` of `tree`) with the slip forces added to their τ,
    through `local` (an expression of the tree's coordinates, parameters and mode symbols over the kernels'
    locals); the nodes themselves when no element slips by an expression."""
    if not pressed_by_expressions(tree):
        return nodes
    Q = [local(force) for force in generalized_slip_forces(tree)]
    out = list(nodes)
    for i, node in enumerate(nodes):
        if node.kind != "spherical":
            added = Q[i]
        else:   # τ_k = (Bᵀ Q_σ)_k / 4 over the joint's three coordinates
            first = i - node.part
            B = mrp.b_matrix(node.sigma)
            added = sum((B[j][node.part] * Q[first + j] for j in range(3)), sp.S.Zero) / 4
        if added != 0:
            out[i] = replace(node, force=node.force + added)
    return out
