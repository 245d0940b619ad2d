"""The lane kernel of a kinematic tree (`lagcomp.Tree`): ``rhs_lanes``, the articulated-body algorithm over a batch.

A batched sweep (``Model.sweep(..., batched=True)``, `lagcomp.integrate.drivers.lanes`) evaluates the right-hand
side of B trajectories in one call, laid out as structure of arrays (``Y[i, l]``: component i of lane l), in a loop
over the lanes that LLVM vectorizes.  A System's lane kernel is its ``rhs`` with each lane reading its own column
(`lagcomp.codegen.lower`); a tree's is the same: the eager ``rhs`` of a tree without loops
(`lagcomp.codegen.tree_lower.open_rhs`: the articulated-body recursion, its repeated steps as inlined helpers),
assignment for assignment, with

* a local bound to ``y[i]`` reading ``Y[i, _l]``, one bound to ``p[k]`` reading ``P[k, _l]``, ``t`` reading
  ``T[_l]``, and f_i stored into ``out[i, _l]``: past `PLAIN_ROWS` rows through a stack buffer of `LANE_CHUNK` lanes
  (`lagcomp.ir.LaneBuffer`), without which LLVM leaves the loop scalar (too many runtime alias checks);
* the steps its links repeat written out where they occur, not called as helpers (`lagcomp.codegen.outline`), while
  ``rhs`` inlines its helpers (below ``INLINE_LIMIT`` operations): with them LLVM left the loop of the 12-link planar
  chain scalar (1.0x the scalar ``rhs`` per lane), written out it vectorizes (4.2x), at a longer numba compile
  (about 1 ms per operation, as an un-outlined ``rhs``); past the limit the helpers are calls either way;
* ``sin`` and ``cos`` printed as ``vsin`` and ``vcos`` (`lagcomp.kernel_support.trig`), in the kernel and in its
  helpers: the scalar kernels' polynomials without their branch to libm, so that the loop holds no call.

No fastmath in either kernel, so LLVM's vector code rounds as the scalar code does: each lane computes the scalar
``rhs``'s bits (for |x| < 10⁵ in every sin and cos, where the scalar ``sin`` takes the polynomial too), and a batched
sweep gives bitwise the unbatched sweep's trajectories.  ``bad`` is never set: the recursion factors no mass matrix
(its articulated inertias are inverted joint by joint, as in ``rhs``, which returns 0 always).

A tree whose motion is not that one ``rhs`` has no lane kernel: closed loops (an augmented solve per lane,
`lagcomp.codegen.tree_constraints`), contacts and friction elements (their modes switch per lane,
`lagcomp.codegen.tree_contacts`): its kind "lanes" is empty, as a constrained System's is, and its batched sweep
raises a ModelError that names them (`lagcomp.multibody.tree.Tree.lanes_refusal`).
"""

from __future__ import annotations

from dataclasses import replace

import sympy as sp

from lagcomp.codegen.tree_locals import TreeLocals
from lagcomp.codegen.tree_lower import open_rhs
from lagcomp.ir import Kernel, LaneBuffer
from lagcomp.multibody.tree import Tree

#: The arguments of ``rhs_lanes``, as a System's (`lagcomp.integrate.drivers.kernel_types.RHS_LANES`).
ARGS = ("T", "Y", "P", "out", "bad")
#: Lanes per chunk of the stack buffer the stores go through (`lagcomp.ir.LaneBuffer`), and the most rows of `out`
#: stored without it.  Per lane, against the scalar ``rhs`` (one process, CPU time): the 4-link planar chain 1.2x
#: faster stored straight into `out` (LLVM did not vectorize the loop), 3.8x, 4.1x and 3.8x through chunks of 8, 32
#: and 16 lanes; the 2-ball chain 1.1x, 2.4x, 2.7x, 2.5x; the 2-link chain, whose 4 rows LLVM vectorizes as they
#: are, 5.3x straight, 2.8x, 3.3x, 3.1x through the buffer.
LANE_CHUNK, PLAIN_ROWS = 32, 4


def tree_lanes_kernels(tree: Tree, local: TreeLocals) -> tuple[Kernel, ...]:
    """``rhs_lanes`` of `tree` (module docstring); none for a tree with loops, contacts or friction elements
    (`lagcomp.multibody.tree.Tree.lanes_refusal`)."""
    if tree.lanes_refusal() is not None:
        return ()
    rhs = open_rhs(local, name="rhs_lanes")
    if all(helper.inline for helper in rhs.helpers):   # (LLVM vectorizes the loop with its steps written out only)
        rhs = open_rhs(local, name="rhs_lanes", outlined=False)
    n = local.n
    columns = {s.name: f"Y[{i}, _l]" for i, s in enumerate((*local.q, *local.qd))}
    columns.update({s.name: f"P[{k}, _l]" for k, s in enumerate(local.p)})
    uses_t = any(sp.Symbol("t", real=True) in e.free_symbols for _, e in rhs.temps + rhs.stores)
    # (f_i into out[i]: `open_rhs`; past PLAIN_ROWS, lane _c + _j's into the buffer of its chunk, `LaneBuffer`)
    buffered = 2 * n > PLAIN_ROWS
    stores = tuple((f"_buf[{i * LANE_CHUNK} + _j]" if buffered else f"out[{i}, _l]", expr)
                   for i, (_, expr) in enumerate(rhs.stores))
    return (replace(
        rhs, args=ARGS, lanes=True, solve=LaneBuffer(rows=2 * n, width=LANE_CHUNK) if buffered else None,
        stores=stores,
        doc="dy/dt of `rhs` for every lane l: T (B,) times, Y (2n, B) states, P (n_p, B) parameters,\n"
            f"out (2n, B), n = {n}: the articulated-body algorithm per lane, as `rhs` computes it (bitwise);\n"
            "bad is never set (no mass matrix is factored).",
        loads=(("t", "T[_l]"),) * uses_t + tuple((name, columns[name]) for name, _ in rhs.loads),
    ),)
