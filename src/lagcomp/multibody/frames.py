r"""Where each frame of a tree is: the nodes' rotations and origins in the base frame, from their placements.

Node i (parent λ; the base: C = 1, o = 0) is placed in its parent's frame by X_i = (R_i, r_i)
(`lagcomp.multibody.kinematics.placement`: x_λ = R_i x_i, r_i its origin in λ's axes), so in the base frame

    C_i = C_λ R_i,    o_i = o_λ + C_λ r_i,

C_i's column j being node i's axis j in base components (x_base = C_i x_i + o_i).  This is the forward kinematics
of positions alone (no velocity, no acceleration: `lagcomp.multibody.closure` carries those, for one-axis joints),
so it serves every joint kind the placements know: revolute, prismatic, and a ball joint's three nodes (part 0
turned by R(σ), parts 1 and 2 at identity: one frame).  A link's frame is the frame of its joint's last node.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.multibody.kinematics import placement
from lagcomp.multibody.program import Program, add, mat_vec

IDENTITY = [[sp.S.One if i == j else sp.S.Zero for j in range(3)] for i in range(3)]
ZERO = [sp.S.Zero] * 3


def world_frames(prog: Program, nodes) -> list[tuple[list, list]]:
    """(C (rows), o) of each of `nodes` (`lagcomp.multibody.kinematics.LocalNode`, parents first) in the base
    frame, bound in `prog` (module docstring)."""
    frames: list[tuple[list, list]] = []
    for node in nodes:
        C_parent, o_parent = (IDENTITY, ZERO) if node.parent < 0 else frames[node.parent]
        X = placement(prog, node)
        columns = [prog.vector(mat_vec(C_parent, [X.R[0][j], X.R[1][j], X.R[2][j]])) for j in range(3)]
        C = [[columns[j][i] for j in range(3)] for i in range(3)]
        frames.append((C, prog.vector(add(o_parent, mat_vec(C_parent, X.r)))))
    return frames


def link_nodes(tree) -> dict[str, int]:
    """{link name: the index of its joint's last node} of `tree` (`lagcomp.multibody.Tree`): the node whose frame
    is the link's."""
    return {node.link: i for i, node in enumerate(tree.nodes)}
