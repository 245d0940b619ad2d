"""The Taylor method's kernel of a kinematic tree (`lagcomp.Tree`): its articulated-body recursion in series arithmetic.

A tree's ``rhs`` is a straight-line program (`lagcomp.codegen.tree_lower`): loads, the assignments of the
articulated-body algorithm (sin and cos of the joint angles, the ball joints' rational functions of their modified
Rodrigues parameters, products, sums, divisions by the articulated inertias' pivots), and the stores of
f = (q̇, q̈), with q̈ explicit (no M to factor).  `lagcomp.codegen.taylor.decompose` splits such a program into
elementary operations with Taylor recurrences as it splits a Lagrange module's (whose q̈ is an LDLᵀ solve), so the
companion module of the kind "taylor" of a tree holds ``taylor_coefficients``, ``TAYLOR_WORK`` and
``TAYLOR_PERIODIC`` as a System's does, and `lagcomp.integrate.drivers.taylor` runs it with the tree's events (the
ball joints' shadow switches: a switch event's reset maps σ to its shadow, and the next step's series starts there).

The program is built from the recursion itself, every step written out: the eager ``rhs`` of a large tree calls the
steps its identical links share as helper functions (`lagcomp.codegen.outline`), which a series program cannot call
(each step's series are rows of one work array).  Its size is the recursion's, O(n) operations per order for an
n-link chain (about 106 per planar link; 596 for 2 ball joints, 1151 for 3), each a loop over the orders; above
`lagcomp.codegen.taylor_split.SPLIT_OPERATIONS` they are emitted as chunks of numba functions, so that numba's compile
time grows about linearly with the chain (CPU, fresh cache: planar chains of 5 links, 404 operations, 29 s; 10 links,
934, 69 s; 3 ball joints, 1151, 79 s; one function took 62 s for 5 links, 399 s and 4.5 GB for 10,
121 s and 2.3 GB for 2 ball joints).

A tree with contacts (or friction elements) gets a System's mode programs (`lagcomp.codegen.taylor.held_programs`):
one per set of held rows, the program above with q̈ corrected by the held rows' multipliers, q̈ = q̈_free +
M⁻¹ G_Aᵀ λ_A, from the ``closed_contacts`` kernel the tree's contacts module builds (`lagcomp.codegen.tree_contacts`:
the gaps' gradients and biases, and M by the composite-rigid-body algorithm, which the program factors by LDLᵀ in
series arithmetic as it factors a Lagrange module's M: `lagcomp.codegen.taylor._explicit_program` says why not the
articulated-body algorithm with unit forces).  ``taylor_coefficients`` branches on the modes in p, and the driver
switches programs where the impacts and lift-offs switch modes, as for a System.

Refused, with ``TAYLOR_REFUSED`` saying why (``method="taylor"`` then raises `taylor-not-applicable`): closed loops
(`lagcomp.Loop`: q̈ from an augmented solve with multipliers, as a System's constraints) and a load without a
recurrence (sign, Abs, Piecewise).
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.emit import emit_companion
from lagcomp.codegen.kinds import KernelKind
from lagcomp.codegen.taylor import (
    ModePrograms,
    TaylorProgram,
    Unsupported,
    decompose,
    held_programs,
    taylor_program,
)
from lagcomp.codegen.tree_contacts import TreeContacts
from lagcomp.codegen.tree_events import event_functions
from lagcomp.codegen.tree_lower import FORMULATION, motion
from lagcomp.ir import Kernel, ModuleIR, ReturnZero
from lagcomp.model.friction import Friction
from lagcomp.multibody.program import Program
from lagcomp.multibody.tree import Tree


def tree_taylor_source(tree: Tree, local, kind: KernelKind, eager_module: str) -> tuple[str, dict]:
    """The source of the companion module of the kind "taylor" of `tree` (its locals `local`, a
    `lagcomp.codegen.tree_companion.TreeLocals`), and its metadata: ``operations`` and ``taylor_program``
    (`lagcomp.codegen.taylor.taylor_program`, None when refused), as a System's companion gives them."""
    taylor = tree_taylor_decomposition(tree, local)
    program = taylor_program(taylor)
    ir = ModuleIR(system_name=tree.name, description=tree.description, coordinate_names=tree.coordinate_names,
                  parameter_names=tree.parameter_names, kernels=(), formulation=FORMULATION)
    operations = {"taylor_coefficients": program["operations"]} if program else {}
    return emit_companion(ir, kind, eager_module, taylor=taylor), {"operations": operations, "taylor_program": program}


def tree_taylor_decomposition(tree: Tree, local) -> TaylorProgram | ModePrograms | Unsupported:
    """The Taylor program of `tree`'s motion (programs, with contacts or friction elements), or the `Unsupported`
    saying why it has none (module docstring)."""
    if tree.closures:
        return Unsupported(f"closed loops ({', '.join(tree.constraint_names)}: their multipliers are not covered)")
    try:
        free = motion_kernel(local)
        if tree.contacts or any(isinstance(e, Friction) for e in tree.events):
            return held_programs(free, closed_contacts_kernel(tree, local, free), local.n)
        return decompose(free, local.n)
    except Unsupported as err:
        return err


def closed_contacts_kernel(tree: Tree, local, free: Kernel) -> Kernel:
    """The ``closed_contacts`` kernel of `tree` (`lagcomp.codegen.tree_contacts`, as the eager module's: the rows'
    gradients and biases, M by the composite-rigid-body algorithm), over the locals `local`; `free` is the motion
    with every row free, which the contacts module renames ``rhs_free``."""
    functions, _ = event_functions(tree, local.q, local.qd, local.mapping)
    contacts = TreeContacts(tree, local.nodes, local.q, local.qd, local.mapping, local.loads, functions)
    return next(kernel for kernel in contacts.motion((free,)) if kernel.name == "closed_contacts")


def motion_kernel(local) -> Kernel:
    """``rhs`` of the tree whose locals are `local`, un-outlined: the articulated-body algorithm's live assignments
    as temporaries, f = (q̇, q̈) stored into out (2n,)."""
    prog = Program()
    f = motion(prog, list(local.nodes), list(local.qd), list(local.gravity))
    temps = tuple((symbol.name, expr) for symbol, expr in prog.live(f))
    stores = tuple((f"out[{i}]", sp.sympify(e)) for i, e in enumerate(f))
    return Kernel(name="rhs", doc="f = (q̇, q̈) of the articulated-body algorithm, every step written out.",
                  args=("t", "y", "p", "out"), loads=tuple(local.loads), temps=temps, stores=stores,
                  solve=ReturnZero())
