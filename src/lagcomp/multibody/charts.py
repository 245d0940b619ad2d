r"""From the recursions' joint variables to the tree's coordinates: a spherical joint's MRPs σ.

The recursions treat a spherical joint as three nodes moving along the body axes with the body-frame angular
velocity ω = J(σ) σ̇ (`lagcomp.multibody.kinematics`).  What they return for those nodes is therefore in ω's terms:
accelerations ψ = J σ̈ (the J̇ σ̇ part of ω̇ is in the joint's velocity product), generalized forces and momenta
along ω, and the mass matrix M_ω of the variables (.., ω, ..).  In the coordinates σ (T(σ, σ̇) = T(ω(σ, σ̇))):

* σ̈ = J⁻¹ ψ;
* forces and momenta: Q_σ = Jᵀ Q_ω (∂T/∂σ̇ = Jᵀ ∂T/∂ω);
* M_σ = Tᵀ M_ω T with T the block-diagonal matrix of one J per spherical joint (1 elsewhere).

Every other node passes through unchanged, so a tree without spherical joints gets back what it gave.
"""

from __future__ import annotations

import contextlib

import sympy as sp

from lagcomp.multibody.kinematics import mrp_matrices
from lagcomp.multibody.program import Program, mat_t_vec, mat_vec


def spherical_joints(nodes) -> list:
    """(first node index, σ locals) of each spherical joint of `nodes` (`lagcomp.multibody.kinematics.LocalNode`)."""
    return [(i, node.sigma) for i, node in enumerate(nodes) if node.kind == "spherical" and node.part == 0]


def accelerations_in_coordinates(prog: Program, nodes, psi) -> list:
    """q̈ from the recursions' accelerations `psi` (node order): σ̈ = J⁻¹ ψ on each spherical joint."""
    out = list(psi)
    for i, sigma in spherical_joints(nodes):
        out[i:i + 3] = prog.vector(mat_vec(mrp_matrices(prog, sigma)[1], psi[i:i + 3]))
    return out


def forces_in_coordinates(prog: Program, nodes, values) -> list:
    """Generalized forces (or momenta) on q from those along the recursions' variables: Jᵀ on each spherical
    joint."""
    out = list(values)
    for i, sigma in spherical_joints(nodes):
        out[i:i + 3] = prog.vector(mat_t_vec(mrp_matrices(prog, sigma)[0], values[i:i + 3]))
    return out


def mass_matrix_in_coordinates(prog: Program, nodes, entries: dict, stepped: bool = False) -> dict:
    """M_σ = Tᵀ M_ω T from the recursion's lower triangle `entries` ({(i, j): M_ij}, i ≥ j; absent entries are
    zero), returned the same way.  With `stepped`, each block's product by Jᵀ is a step of `prog` (`Program.step`:
    the n² / 3 of them on a long chain are emitted as calls of a few shared helpers, `lagcomp.codegen.outline`), the
    arithmetic unchanged."""
    joints = spherical_joints(nodes)
    if not joints:
        return entries
    n = len(nodes)
    step = prog.step if stepped else (lambda key: contextlib.nullcontext())
    full = [[entries.get((max(i, j), min(i, j)), sp.S.Zero) for j in range(n)] for i in range(n)]
    for i, sigma in joints:   # the rows: each column's block through Jᵀ
        J = mrp_matrices(prog, sigma)[0]
        for j in range(n):
            full_column = [full[i + k][j] for k in range(3)]
            if any(e != 0 for e in full_column):
                with step(("chart rows", i, j)):
                    full[i][j], full[i + 1][j], full[i + 2][j] = prog.vector(mat_t_vec(J, full_column))
    for j, sigma in joints:   # the columns: each row's block through Jᵀ again (M is symmetric: (Jᵀ M J)ᵀ)
        J = mrp_matrices(prog, sigma)[0]
        for i in range(n):
            full_row = [full[i][j + k] for k in range(3)]
            if any(e != 0 for e in full_row):
                with step(("chart columns", i, j)):
                    full[i][j], full[i][j + 1], full[i][j + 2] = prog.vector(mat_t_vec(J, full_row))
    return {(i, j): full[i][j] for i in range(n) for j in range(i + 1) if full[i][j] != 0}
