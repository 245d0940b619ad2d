"""The contact kernels of a kinematic tree (`lagcomp.Contact` in ``lc.Tree(..., events=)``).

A tree's contacts get the kernels, names, signatures, module constants and p layout of an unconstrained Lagrange
module's (`lagcomp.codegen.contacts`), so that the drivers, the impact solver (`lagcomp.kernel_support.impacts`)
and the resting contacts (`lagcomp.kernel_support.resting`) take them unchanged:

* ``rhs`` reads the contacts' modes from p (`lagcomp.ir.ContactModes`): ``rhs_free`` — the tree's
  articulated-body rhs, all contacts open — then, while some contact is closed, ``closed_contacts`` corrects q̈ by
  the normal forces; ``contact_forces`` gives them for the saved rows;
* ``event_values`` gives a closed contact's normal force instead of its gap, and ``event_reset``'s impact branch
  writes M(q), each gap g_d, its gradient G_d = ∂g_d/∂q, its rate ġ_d = G_d q̇ + ∂g_d/∂t, e_d and the bias
  b_d of g̈_d = G_d q̈ + b_d, then calls the impact solver (velocities jump by M⁻¹ Gᵀ P).
* friction elements pressed by a contact (`lagcomp.multibody.user_events`): a sticking one's row v̇ = a q̈ + b
  after the contacts' in ``closed_contacts``, ``friction_limits`` (μs times the contact's normal force), a branch
  of ``event_reset`` per element that writes its new mode, and the frictional impact's stores;
* friction elements pressed by an expression N (with or without contacts): the same rows, limits μs |N| and
  branches; their slip force is in the nodes' generalized forces, hence in ``rhs_free``
  (`lagcomp.codegen.tree_slip`).

The module builds those stores with the Lagrange path's own functions (`lagcomp.codegen.contacts.resting_kernels`,
`impact_branches`), given `ContactView`, which holds what they read of an EOM: M by the composite-rigid-body
algorithm (bound in a `lagcomp.multibody.program.Program`, not expanded), and the gaps as expressions of the
coordinate locals (a link's point from `lagcomp.multibody.link_point`), differentiated symbolically.  The gap
quantities are CSE'd into the same program; each kernel keeps the assignments its stores read, inline (the
branches of ``event_reset`` have no helpers: `lagcomp.codegen.outline` is not used here).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import sympy as sp

from lagcomp.codegen.contacts import friction_branches, impact_branches, modes_of, resting_kernels
from lagcomp.codegen.tree_constraints import loop_rows
from lagcomp.codegen.tree_slip import first_mode_slot
from lagcomp.ir import Kernel
from lagcomp.model.contacts import Contact
from lagcomp.model.friction import Friction
from lagcomp.multibody.charts import mass_matrix_in_coordinates
from lagcomp.multibody.crba import mass_matrix
from lagcomp.multibody.joints import t
from lagcomp.multibody.program import Program


@dataclass(frozen=True)
class ContactView:
    """What `lagcomp.codegen.contacts` reads of an EOM, for a tree: n, M (over program locals), the coordinate and
    velocity locals, each event's function over the locals, the restitutions (the user's: a number or a parameter,
    None for an event that is not a contact), the friction elements' (normal contact's name, μs, μk) (None for
    another event), the tree (its ``event_names``), its parameters (the modes' first slot of p follows them, and
    the Baumgarte gains of a tree with loops), and the loops' constraint rows: k and C (k, n), Λ = ∂Φ/∂q over the
    locals (`lagcomp.multibody.closure`; none without loops)."""

    n: int
    M: sp.Matrix
    q: tuple
    qd: tuple
    events: tuple
    restitutions: tuple
    frictions: tuple
    system: object
    parameters: tuple
    k: int = 0
    C: sp.Matrix | None = None


class TreeContacts:
    """The contact kernels of `tree` over the tree kernels' locals (module docstring).

    Parameters
    ----------
    tree : lagcomp.Tree
        With at least one contact or friction element among its events.
    nodes : list of lagcomp.multibody.kinematics.LocalNode
    q, qd : sequences of Symbol
        The coordinate and velocity locals, node order.
    mapping : dict
        Each parameter (and t) to its local.
    loads : list of (local, source)
        The tree kernels' loads.
    values : list of Expr
        Each event's function over the locals (`lagcomp.codegen.tree_events`).
    """

    def __init__(self, tree, nodes, q, qd, mapping: dict, loads, values):
        self.prog, self.mapping, self.loads, self.time = Program(), mapping, loads, mapping[t]
        n = len(nodes)
        entries = mass_matrix_in_coordinates(self.prog, nodes, mass_matrix(self.prog, nodes))
        M = sp.Matrix(n, n, lambda i, j: entries.get((max(i, j), min(i, j)), sp.S.Zero))
        restitutions = tuple(e.restitution if isinstance(e, Contact) else None for e in tree.events)
        signals = {c.diff(t): qd[i] for i, c in enumerate(tree.coordinates)} | {c: q[i]
                                                                               for i, c in enumerate(tree.coordinates)}
        frictions = tuple(None if not isinstance(e, Friction) else (e.normal if isinstance(e.normal, str) else
                                                                    sp.sympify(e.normal).xreplace(signals),
                                                                    e.static, e.kinetic)
                          for e in tree.events)
        k = len(tree.constraint_names)
        C = sp.Matrix(loop_rows(self.prog, tree, nodes, mapping).rows) if k else None
        self.view = ContactView(n, M, tuple(q), tuple(qd), tuple(values), restitutions, frictions, tree,
                                tree.parameters, k, C)
        self.first = first_mode_slot(tree)

    def kernel(self, name: str, doc: str, args, stores, solve=None) -> Kernel:
        """A kernel of `stores` (target, expression over the locals or the user's parameters): the expressions
        CSE'd into the program, the assignments they read kept in order, no helpers."""
        exprs = [sp.sympify(e).xreplace(self.mapping) for _, e in stores]
        replacements, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("_c", real=True), order="canonical")
        bound = {}
        for symbol, expr in replacements:
            bound[symbol] = self.prog.let(expr.xreplace(bound))
        outputs = [e.xreplace(bound) for e in reduced]
        temps = self.prog.live(outputs)
        used = {s.name for s in set().union(*(sp.sympify(e).free_symbols for e in outputs),
                                            *(e.free_symbols for _, e in temps))}
        return Kernel(name=name, doc=doc, args=tuple(args),
                      loads=tuple((local, src) for local, src in self.loads if local in used),
                      temps=tuple((s.name, e) for s, e in temps),
                      stores=tuple((target, e) for (target, _), e in zip(stores, outputs, strict=True)), solve=solve)

    def motion(self, dynamics: tuple[Kernel, ...]) -> tuple[Kernel, ...]:
        """``rhs`` with the contacts' modes, ``closed_contacts``, ``contact_forces`` and ``rhs_free`` (the tree's
        rhs, ``dynamics[0]``, with every contact open, renamed); with loops (`dynamics` are then
        `lagcomp.codegen.tree_constraints.loop_kernels`'), ``reactions`` with the modes too, ``reactions_free``
        and the other loop kernels as they are (`lagcomp.codegen.lower`'s constrained motion with contacts)."""
        rhs, *rest = dynamics
        free = replace(rhs, name="rhs_free", doc="The motion without contacts (all open): " + rhs.doc)
        kernels = (*resting_kernels(self.view, self.time, self.first, self.kernel), free)
        if not self.view.k:
            return kernels
        reactions, *others = rest
        with_contacts = self.kernel("reactions", reactions.doc + "\nWhile some contact is closed, with the change "
                                    "its normal force causes (closed_contacts).", ("t", "y", "p", "out"), [],
                                    modes_of(self.view, "reactions", self.first))
        return (*kernels, with_contacts, replace(reactions, name="reactions_free", doc="The multipliers without "
                                                 "contacts (all open): " + reactions.doc), *others)

    def event_modes(self):
        """The `lagcomp.ir.ContactModes` of ``event_values``: a closed contact's value is its normal force."""
        return modes_of(self.view, "events", self.first)

    def impacts(self) -> tuple:
        """The impact branch of ``event_reset`` (`lagcomp.codegen.contacts.impact_branches`)."""
        return impact_branches(self.view, self.view.restitutions, self.time, self.kernel, self.first)

    def switches(self) -> tuple:
        """The friction elements' branches of ``event_reset`` (`lagcomp.codegen.contacts.friction_branches`)."""
        return friction_branches(self.view, self.first, self.kernel)
