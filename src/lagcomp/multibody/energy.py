r"""The kinetic and potential energy of a tree, from the velocities of the outward pass.

T = Σ_i ½ v_iᵀ I_i v_i = Σ_i (½ ω·I_o ω + v·(ω × m c) + ½ m v·v) in each link's frame.  V = Σ_i −m_i g·r_Gi + the
joints' springs ½ k (q − rest)², with g·r_Gi = s_i + g_i·c_i: g_i = R_iᵀ g_λ (gravity in link i's axes; g_base = g)
and s_i = s_λ + g_λ·r_i (g dotted into the origin of frame i; s_base = 0): no world rotation is formed.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.multibody.kinematics import inertias, placement, velocities
from lagcomp.multibody.program import Program, dot, mat_t_vec
from lagcomp.multibody.spatial import spatial_dot


def kinetic_energy(prog: Program, nodes) -> sp.Expr:
    """T, bound in `prog`."""
    X = [placement(prog, node) for node in nodes]
    v = velocities(prog, nodes, X)
    I = inertias(prog, nodes)
    return prog.let(sp.Add(*(spatial_dot(v[i], I[i].times(prog, v[i])) for i in range(len(nodes)))) / 2)


def potential_energy(prog: Program, nodes, gravity) -> sp.Expr:
    """V of gravity and the joints' springs, bound in `prog`."""
    X = [placement(prog, node) for node in nodes]
    g, s, terms = [], [], []
    for i, node in enumerate(nodes):
        g_parent = list(gravity) if node.parent < 0 else g[node.parent]
        s_parent = sp.S.Zero if node.parent < 0 else s[node.parent]
        g.append(prog.vector(mat_t_vec(X[i].R, g_parent)))
        s.append(prog.let(s_parent + dot(g_parent, X[i].r)))
        if node.mass != 0:
            terms.append(-node.mass * (s[i] + dot(g[i], node.com)))
        if node.stiffness != 0:
            terms.append(node.stiffness * (node.q - node.rest) ** 2 / 2)
    return prog.let(sp.Add(*terms))
