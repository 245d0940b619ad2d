"""The event kernels of a kinematic tree: its spherical joints' shadow switches (`lagcomp.multibody.shadow`).

A tree declares no events of its own yet; the MRPs of its spherical and free joints each switch to their shadow
set at half a turn, an event with a reset.  Here those events become ``event_values``, ``event_gradients`` and
``event_reset`` with the conventions of a Lagrange module's (`lagcomp.codegen.lower`), over the tree kernels' locals.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.cse import cse_kernel
from lagcomp.codegen.lower import event_reset_kernel
from lagcomp.ir import ReturnZero
from lagcomp.multibody.joints import t

ARGS = ("t", "y", "p", "out")


def tree_event_kernels(tree, q, qd, mapping, loads) -> tuple:
    """``event_values``, ``event_gradients``, ``event_reset`` of `tree`'s events; `q`, `qd` the coordinate and
    velocity locals (node order), `mapping` each parameter (and t) to its local, `loads` the kernels' loads."""
    n, names = tree.n, tuple(e.name for e in tree.events)
    signals = {c.diff(t): qd[i] for i, c in enumerate(tree.coordinates)}
    signals |= {c: q[i] for i, c in enumerate(tree.coordinates)}

    def local(e):
        return sp.sympify(e).xreplace(signals).xreplace(mapping)

    values = [local(e.expr) for e in tree.events]
    state_index = {c: i for i, c in enumerate(tree.coordinates)} | {c.diff(t): n + i
                                                                     for i, c in enumerate(tree.coordinates)}
    resets = tuple(tuple((state_index[key], local(value)) for key, value in e.reset or ()) for e in tree.events)
    variables = (*q, *qd, mapping[t], *(mapping[s] for s in tree.parameters))
    width = len(variables)
    event_values = cse_kernel(
        "event_values", f"Event functions g, shape ({len(names)},), in order {list(names)}, into `out`: the "
        "spherical joints'\nshadow switches σ·σ − 1 (lagcomp.multibody.shadow).", ARGS,
        [(f"out[{e}]", g) for e, g in enumerate(values)], mapping, loads)
    event_gradients = cse_kernel(
        "event_gradients", f"Partials of the event functions {list(names)}, shape ({len(names)}, {width}), into "
        "`out`:\nrow e is event e, columns ∂g_e/∂y_j, then ∂g_e/∂t, then ∂g_e/∂p_j.\nReturns 0.", ARGS,
        [(f"out[{e}, {j}]", g.diff(v)) for e, g in enumerate(values) for j, v in enumerate(variables)], mapping,
        loads, solve=ReturnZero())
    return event_values, event_gradients, event_reset_kernel(names, resets, 2 * n, mapping, tuple(loads))
