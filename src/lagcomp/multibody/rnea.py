r"""Recursive Newton–Euler (Featherstone 2008, §5.3) for the forcing F of M(q) q̈ = F(q, q̇, t), and the momenta.

F_i = τ_i − S_iᵀ f_i with the inverse dynamics at q̈ = 0: outwards a_i = X_i a_λ + c_i (a_base = (0, −g)),
f_i = I_i a_i + v_i ×* I_i v_i; inwards f_λ += X_iᵀ f_i.  The conjugate momenta ∂T/∂q̇_i = S_iᵀ h^C_i, with the
subtree's spatial momentum h^C_i = I_i v_i + Σ_children X_cᵀ h^C_c, by the same inward pass.  Each node's share
of a pass is a step of the program (`Program.step`), shared when emitted (`lagcomp.codegen.outline`).
"""

from __future__ import annotations

from lagcomp.multibody.kinematics import (
    base_acceleration,
    inertias,
    placement,
    subspace,
    velocities,
    velocity_product,
)
from lagcomp.multibody.program import Program
from lagcomp.multibody.spatial import add_spatial, force_cross, spatial_dot


def forcing(prog: Program, nodes, gravity) -> list:
    """F of M q̈ = F, one expression per node, bound in `prog`."""
    X = [placement(prog, node) for node in nodes]
    v = velocities(prog, nodes, X)
    I = inertias(prog, nodes)
    f = []
    a = []
    for i, node in enumerate(nodes):
        with prog.step(("forces", i)):
            parent = base_acceleration(gravity) if node.parent < 0 else a[node.parent]
            a.append(add_spatial(prog, X[i].to_child(prog, parent), velocity_product(prog, v[i], node)))
            f.append(add_spatial(prog, I[i].times(prog, a[i]), force_cross(prog, v[i], I[i].times(prog, v[i]))))
    return [prog.let(node.force - spatial_dot(subspace(node), s)) for node, s in zip(nodes, _inward_sums(prog, nodes, X, f))]


def momenta(prog: Program, nodes) -> list:
    """∂T/∂q̇ per node, bound in `prog`."""
    X = [placement(prog, node) for node in nodes]
    v = velocities(prog, nodes, X)
    I = inertias(prog, nodes)
    h = [I[i].times(prog, v[i]) for i in range(len(nodes))]
    return [prog.let(spatial_dot(subspace(node), s)) for node, s in zip(nodes, _inward_sums(prog, nodes, X, h))]


def _inward_sums(prog: Program, nodes, X, forces) -> list:
    """Each node's force plus its subtree's, transformed into its frame (leaves first)."""
    total = list(forces)
    for i in reversed(range(len(nodes))):
        parent = nodes[i].parent
        if parent >= 0:
            with prog.step(("inward", i)):
                total[parent] = add_spatial(prog, total[parent], X[i].to_parent(prog, total[i]))
    return total
