r"""The composite-rigid-body algorithm (Featherstone 2008, §6.2): the mass matrix M(q) of a tree.

Inwards the composite inertia I^C_i = I_i + Σ_children X_cᵀ I^C_c X_c (its C block stays m·1: a composite rigid
body), then M_ii = S_iᵀ I^C_i S_i and, walking up from i through its ancestors j with F = I^C_i S_i carried along
(F ← X_jᵀ F), M_ij = M_ji = S_jᵀ F.  O(n d) entries for a tree of depth d (n² / 2 for a chain).  Each node's
composite step and each step of F up the tree is a step of the program (`Program.step`), shared when emitted
(`lagcomp.codegen.outline`).
"""

from __future__ import annotations

from lagcomp.multibody.kinematics import inertias, placement, subspace
from lagcomp.multibody.program import Program
from lagcomp.multibody.spatial import spatial_dot


def mass_matrix(prog: Program, nodes) -> dict:
    """{(i, j): M_ij} for i ≥ j where M_ij may be nonzero (j an ancestor of i, or i), bound in `prog`."""
    X = [placement(prog, node) for node in nodes]
    IC = inertias(prog, nodes)
    for i in reversed(range(len(nodes))):
        parent = nodes[i].parent
        if parent >= 0:
            with prog.step(("composite", i)):
                IC[parent] = IC[parent].plus(prog, IC[i].to_parent(prog, X[i]))
    entries = {}
    for i, node in enumerate(nodes):
        with prog.step(("diagonal", i)):
            F = IC[i].times(prog, subspace(node))
            entries[i, i] = prog.let(spatial_dot(subspace(node), F))
        j = i
        while nodes[j].parent >= 0:
            with prog.step(("column", i, j)):
                F = X[j].to_parent(prog, F)
                j = nodes[j].parent
                entries[i, j] = prog.let(spatial_dot(subspace(nodes[j]), F))
    return entries
