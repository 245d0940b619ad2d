"""The slip forces of a tree's friction elements pressed by an expression, over a tree kernel's locals: each
element's mode (0 stick, ±1 slip) loaded from its slot of p, and the nodes' generalized forces with the slip forces
added (`lagcomp.multibody.slip`).  The eager module (`lagcomp.codegen.tree_lower`) and the on-demand kernels
(`lagcomp.codegen.tree_companion`) bind them alike, so that every kernel built from the nodes sees the same motion.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.bindings import BAUMGARTE, user_local
from lagcomp.model.contacts import Contact
from lagcomp.model.friction import Friction, slip_symbol
from lagcomp.multibody.joints import t
from lagcomp.multibody.slip import pressed_by_expressions, with_slip_forces


def first_mode_slot(tree) -> int:
    """The first slot of p that holds a mode of `tree`'s contacts and friction elements: after the parameters and,
    with closed loops, the Baumgarte gains (`lagcomp.codegen.tree_constraints.gain_loads`)."""
    return len(tree.parameters) + (len(BAUMGARTE) if tree.closures else 0)


def slip_slots(tree) -> list[tuple[sp.Symbol, str, int]]:
    """(mode symbol, its local's name, slot of p) of each friction element of `tree` pressed by an expression: the
    modes follow `first_mode_slot`, one per contact and the closing flag, then one per friction element
    (`lagcomp.codegen.contacts.mode_slots`)."""
    first = first_mode_slot(tree) + len([e for e in tree.events if isinstance(e, Contact)]) + 1
    elements = [e for e in tree.events if isinstance(e, Friction)]
    return [(slip_symbol(f), user_local("slip", e.name, f), first + f)
            for f, e in enumerate(elements) if not isinstance(e.normal, str)]


def slipping_nodes(tree, nodes, q, qd, mapping: dict) -> tuple[list, list]:
    """(`nodes` with the slip forces in their τ, the loads of the modes' locals), the modes' symbols added to
    `mapping` (in place); (`nodes`, []) when no friction element of `tree` is pressed by an expression.  `q`, `qd`
    are the coordinate and velocity locals (node order), `mapping` each parameter and t to its local."""
    if not pressed_by_expressions(tree):
        return list(nodes), []
    loads = []
    for symbol, local, slot in slip_slots(tree):
        mapping[symbol] = sp.Symbol(local, real=True)
        loads.append((local, f"p[{slot}]"))
    signals = {c.diff(t): qd[i] for i, c in enumerate(tree.coordinates)} | {c: q[i]
                                                                           for i, c in enumerate(tree.coordinates)}

    def local(e):
        return sp.sympify(e).xreplace(signals).xreplace(mapping)

    return with_slip_forces(tree, list(nodes), local), loads
