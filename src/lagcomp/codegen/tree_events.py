"""The event kernels of a kinematic tree: its spherical joints' shadow switches and the user's events.

The MRPs of a tree's spherical and free joints each switch to their shadow set at half a turn, an event with a
reset (`lagcomp.multibody.shadow`); the user's events and contacts follow them (`lagcomp.multibody.user_events`).
Here they become ``event_values``, ``event_gradients`` and ``event_reset`` with the conventions of a Lagrange
module's (`lagcomp.codegen.lower`), over the tree kernels' locals: a reset's branch per event that has one, and for
the contacts one impact branch and the modes of `lagcomp.codegen.tree_contacts`.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.cse import cse_kernel
from lagcomp.codegen.lower import event_reset_kernel
from lagcomp.ir import ReturnZero
from lagcomp.multibody.joints import t

ARGS = ("t", "y", "p", "out")


def event_functions(tree, q, qd, mapping) -> tuple[list, callable]:
    """Each event's function of `tree` over the locals (`q`, `qd` the coordinate and velocity locals, node order,
    `mapping` each parameter and t to its local), and the function that puts an expression over them."""
    signals = {c.diff(t): qd[i] for i, c in enumerate(tree.coordinates)}
    signals |= {c: q[i] for i, c in enumerate(tree.coordinates)}

    def local(e):
        return sp.sympify(e).xreplace(signals).xreplace(mapping)

    return [local(e.expr) for e in tree.events], local


def tree_event_kernels(tree, q, qd, mapping, loads, contacts=None) -> tuple:
    """``event_values``, ``event_gradients``, ``event_reset`` of `tree`'s events; `q`, `qd` the coordinate and
    velocity locals (node order), `mapping` each parameter (and t) to its local, `loads` the kernels' loads,
    `contacts` the `lagcomp.codegen.tree_contacts.TreeContacts` of a tree with contacts (None without)."""
    n, names = tree.n, tree.event_names
    values, local = event_functions(tree, q, qd, mapping)
    state_index = {c: i for i, c in enumerate(tree.coordinates)} | {c.diff(t): n + i
                                                                     for i, c in enumerate(tree.coordinates)}
    resets = tuple(tuple((state_index[key], local(value)) for key, value in e.reset or ()) for e in tree.events)
    variables = (*q, *qd, mapping[t], *(mapping[s] for s in tree.parameters))
    width = len(variables)
    doc = (f"Event functions g, shape ({len(names)},), in order {list(names)}, into `out`: the spherical joints'\n"
           "shadow switches σ·σ − 1 (lagcomp.multibody.shadow)" + (", then the tree's own events." if tree.user_events
                                                                    else "."))
    if contacts is not None:
        doc += "\nA closed contact's value is its normal force (contact_forces): its lift-off when it turns negative."
    event_values = cse_kernel("event_values", doc, ARGS, [(f"out[{e}]", g) for e, g in enumerate(values)], mapping,
                              loads, solve=None if contacts is None else contacts.event_modes())
    event_gradients = cse_kernel(
        "event_gradients", f"Partials of the event functions {list(names)}, shape ({len(names)}, {width}), into "
        "`out`:\nrow e is event e, columns ∂g_e/∂y_j, then ∂g_e/∂t, then ∂g_e/∂p_j.\nReturns 0.", ARGS,
        [(f"out[{e}, {j}]", g.diff(v)) for e, g in enumerate(values) for j, v in enumerate(variables)], mapping,
        loads, solve=ReturnZero())
    if contacts is None:
        return event_values, event_gradients, event_reset_kernel(names, resets, 2 * n, mapping, tuple(loads))
    return event_values, event_gradients, event_reset_kernel(names, resets, 2 * n, mapping, tuple(loads),
                                                             contacts.view.restitutions, contacts.impacts(),
                                                             contacts.switches())
