r"""Points of a kinematic tree's links as the outputs of a state-space model: rows of C at an equilibrium.

A link's point is its frame's origin o(q), in the tree's base frame from its origin (what the tree's ``geometry``
kernel writes, `lagcomp.codegen.tree_geometry`).  A tree's placements do not depend on t (`lagcomp.Tree` lets
only a joint's torque read it), so about the equilibrium q₀ (q̇₀ = 0) of `lagcomp.analysis.linearize`, with
x = (δq, δq̇),

    δo = J δq,    δv = J δq̇,    J = ∂o/∂q at q₀,

and the row of ``"<link>.x"`` (``.y``, ``.z``) is [J_x, 0], that of ``"<link>.vx"`` (``.vy``, ``.vz``) [0, J_x];
D is 0.  J is forward mode over the forward kinematics of positions (`lagcomp.multibody.forward_mode` over
`lagcomp.multibody.frames`: the recursion's derivatives, nothing expanded), evaluated in floats at q₀ and the
run's parameters: no finite difference.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from lagcomp.errors import OptionError

#: The components of a point's position and velocity, as output names' suffixes.
POSITION, VELOCITY = ("x", "y", "z"), ("vx", "vy", "vz")


def tree_point_rows(model, tree, q: np.ndarray, params: dict, wanted) -> dict:
    """{name: (C row (2n,), D row (U,))} of each link output among `wanted` (``"<link>.<part>"`` names, parts of
    `POSITION` and `VELOCITY`) of `model` compiled from `tree`; an OptionError naming the links for an unknown one."""
    from lagcomp.codegen.tree_locals import tree_locals
    from lagcomp.multibody.forward_mode import derivatives
    from lagcomp.multibody.frames import link_nodes, world_frames
    from lagcomp.multibody.program import Program

    last = link_nodes(tree)
    unknown = [name for name in wanted if name.rpartition(".")[0] not in last]
    if unknown:
        raise OptionError(f"Unknown output(s) {unknown}: a link's point is '<link>.x' (.y, .z; .vx, .vy, .vz for its "
                          f"velocity), the origin of its frame; links of {model.name!r}: {sorted(last)}.")
    local, prog = tree_locals(tree), Program()
    frames = world_frames(prog, list(local.nodes))
    links = sorted({name.rpartition(".")[0] for name in wanted})
    origins = [frames[last[link]][1][c] for link in links for c in range(3)]
    tangent = derivatives(prog, origins, {s: {j: sp.S.One} for j, s in enumerate(local.q)})
    p = model.parameter_vector(params)
    env = {**{s: sp.Float(float(v)) for s, v in zip(local.q, q, strict=True)},
           **{s: sp.Float(float(p[k])) for k, s in enumerate(local.p)}}
    columns = [e for row in tangent for e in row.values()]
    for symbol, expr in prog.live(columns):
        env[symbol] = expr.xreplace(env)
    n, rows = model.n, {}
    for name in wanted:
        link, _, part = name.rpartition(".")
        row = tangent[3 * links.index(link) + (POSITION + VELOCITY).index(part) % 3]
        jacobian = np.array([float(sp.sympify(row.get(j, 0)).xreplace(env)) for j in range(n)])
        zero = np.zeros(n)
        rows[name] = (np.concatenate([jacobian, zero] if part in POSITION else [zero, jacobian]),
                      np.zeros(len(model.inputs)))
    return rows
