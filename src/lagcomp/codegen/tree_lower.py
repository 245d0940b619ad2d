"""Lower a kinematic tree (`lagcomp.multibody.Tree`) to the kernel IR, from the recursions, not from T and V.

Each kernel's temporaries are the assignments of one straight-line program (`lagcomp.multibody.program`): the
articulated-body algorithm's for ``rhs``, recursive Newton–Euler's for ``momenta`` (and, on demand, the
composite-rigid-body algorithm's for ``mass_matrix``, recursive Newton–Euler's for ``forcing``), the outward velocities' for ``energy``.  They go to the emitter as
they are (no CSE over the whole kernel: each is already a small expression of earlier locals), with the
assignments no output reads dropped, and the steps that identical nodes repeat emitted once as shared helpers
(`lagcomp.codegen.outline`: numba's compile time grows with the code it types).  The module has the eager kernels of a Lagrange module, with the same names,
signatures and locals (`lagcomp.codegen.bindings.user_local`), so the drivers, the cache and `lagcomp.Model`
take it as they take any other; the on-demand kinds a tree has are its recursions differentiated
(`lagcomp.codegen.tree_companion`), the others are refused (`lagcomp.multibody.tree.Tree.on_demand_refusal`).
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.outline import outline
from lagcomp.codegen.tree_constraints import gain_loads, loop_kernels
from lagcomp.codegen.tree_contacts import TreeContacts
from lagcomp.codegen.tree_events import event_functions, tree_event_kernels
from lagcomp.codegen.tree_locals import TreeLocals, tree_locals
from lagcomp.ir import Kernel, ModuleIR, ReturnZero
from lagcomp.model.friction import Friction
from lagcomp.multibody.aba import accelerations
from lagcomp.multibody.charts import (
    accelerations_in_coordinates,
    forces_in_coordinates,
    mass_matrix_in_coordinates,
)
from lagcomp.multibody.crba import mass_matrix
from lagcomp.multibody.energy import kinetic_energy, potential_energy
from lagcomp.multibody.program import Program
from lagcomp.multibody.rnea import forcing, momenta
from lagcomp.multibody.tree import Tree

FORMULATION = ("Equations of motion: q̈ by the articulated-body algorithm over the kinematic tree (lagcomp.multibody);\n"
               "M(q) q̈ = F(q, q̇, t) with M by the composite-rigid-body algorithm, F by recursive Newton-Euler.")
ARGS = ("t", "y", "p", "out")


def lower_tree(tree: Tree) -> ModuleIR:
    """The IR of the eager module of `tree`: rhs, energy (and energy_function), momenta and the event kernels (the
    ball joints' shadow switches, the tree's own events; with contacts, rhs with their modes:
    `lagcomp.codegen.tree_contacts`); ``mass_matrix`` and ``forcing``, which no run calls, are on demand
    (`lagcomp.codegen.tree_companion`)."""
    local = tree_locals(tree)
    q, qd, nodes, gravity, mapping, loads = local.q, local.qd, local.nodes, local.gravity, local.mapping, [*local.loads]

    def kernel(name, doc, args, build, solve=None):
        prog = Program()
        stores = build(prog)
        return program_kernel(name, doc, args, prog, stores, loads, solve)

    if tree.closures:   # closed loops: the motion through the augmented system (its kernels' own module)
        loads += gain_loads(tree)
        dynamics = loop_kernels(tree, nodes, gravity, mapping, kernel)
    else:
        dynamics = (open_rhs(local),)
    contacts = None
    if tree.contacts or any(isinstance(e, Friction) for e in tree.events):
        # the contacts' and friction elements' modes: rhs is rhs_free corrected for the held rows (`tree_contacts`)
        contacts = TreeContacts(tree, nodes, q, qd, mapping, loads, event_functions(tree, q, qd, mapping)[0])
        dynamics = contacts.motion(dynamics)
    kernels = (
        *dynamics,
        kernel("energy", "Total mechanical energy T + V (gravity and the joints' springs).", ("t", "y", "p"),
               lambda prog: [("return", prog.let(kinetic_energy(prog, nodes) + potential_energy(prog, nodes, gravity)))]),
        Kernel(name="energy_function", doc="Energy function h = Σ q̇ ∂L/∂q̇ − L: T is homogeneous quadratic in q̇,\n"
               "so h = T + V, the kernel `energy`.", args=("t", "y", "p"), loads=(), temps=(), stores=(),
               alias="energy"),
        kernel("momenta", "Conjugate momenta ∂T/∂q̇_i, shape (n,), into `out` (the subtrees' spatial momenta).", ARGS,
               lambda prog: [(f"out[{i}]", h) for i, h in enumerate(forces_in_coordinates(prog, nodes, momenta(prog, nodes)))]),
        *tree_event_kernels(tree, q, qd, mapping, loads, contacts),
    )
    return ModuleIR(system_name=tree.name, description=tree.description, coordinate_names=tree.coordinate_names,
                    parameter_names=tree.parameter_names, kernels=kernels, formulation=FORMULATION,
                    constraint_names=tree.constraint_names, holonomic=(True,) * len(tree.constraint_names),
                    event_names=tree.event_names if tree.user_events else ())


def open_rhs(local: TreeLocals, name: str = "rhs", outlined: bool = True) -> Kernel:
    """``rhs`` of a tree without loops: f = (q̇, q̈) into ``out[0:2n]``, q̈ by the articulated-body algorithm
    (`motion`).  The eager module's, and under `name` the program of the lanes of batched sweeps
    (`lagcomp.codegen.tree_lanes`), which are this kernel evaluated per lane: the same assignments in the same
    order (without `outlined`, its repeated steps written out: `program_kernel`)."""
    prog = Program()
    stores = [(f"out[{i}]", f) for i, f in enumerate(motion(prog, local.nodes, local.qd, local.gravity))]
    return program_kernel(name, "State derivative dy/dt = (q̇, q̈), shape (2n,), q̈ by the articulated-body "
                          "algorithm.\n\nReturns 0.", ARGS, prog, stores, local.loads, ReturnZero(), outlined)


def motion(prog: Program, nodes, qd, gravity) -> list:
    """f = (q̇, q̈) of a tree without loops, bound in `prog`: q̈ by the articulated-body algorithm, mapped to the
    coordinates' second derivatives (`lagcomp.multibody.charts`: σ̈ of a ball joint from its body-axis rates).
    The eager ``rhs`` and every on-demand kernel that writes f (`lagcomp.codegen.tree_companion`) bind it so."""
    return [*qd, *accelerations_in_coordinates(prog, nodes, accelerations(prog, nodes, gravity))]


def generalized_forcing(prog: Program, nodes, gravity) -> list:
    """F(q, q̇, t) of M q̈ = F over the coordinates, bound in `prog`: recursive Newton–Euler at q̈ = 0, mapped by
    `lagcomp.multibody.charts` (Jᵀ on a ball joint)."""
    return forces_in_coordinates(prog, nodes, forcing(prog, nodes, gravity))


def program_kernel(name: str, doc: str, args, prog: Program, stores, loads, solve=None, outlined: bool = True) -> Kernel:
    """A kernel whose temporaries are the assignments of `prog` its `stores` read, and whose loads are those they
    read; the steps its nodes repeat emitted once (`lagcomp.codegen.outline`), or with `outlined` False written out
    where they occur (the same assignments: the same bits)."""
    temps = prog.live([e for _, e in stores])
    used = set().union(*(sp.sympify(e).free_symbols for _, e in stores), *(e.free_symbols for _, e in temps))
    used_names = {s.name for s in used}
    if outlined:
        body, helpers = outline(name, temps, prog.step_of, [e for _, e in stores])
    else:
        body, helpers = tuple((local.name, e) for local, e in temps), ()
    return Kernel(name=name, doc=doc, args=args, loads=tuple((local, src) for local, src in loads if local in used_names),
                  temps=body, stores=tuple((target, sp.sympify(e)) for target, e in stores), solve=solve,
                  helpers=helpers)


def mass_matrix_stores(prog: Program, nodes) -> list:
    """The stores of M(q)'s nonzero lower triangle into the flat work array ``_jac`` of a symmetric
    `lagcomp.ir.FlatMatrix` (entry (i, j) at i n + j, i ≥ j; the emitted loop mirrors it), bound in `prog`: the
    composite-rigid-body algorithm, mapped to the coordinates by `lagcomp.multibody.charts`, its n² / 2 steps and
    block products emitted as calls (`lagcomp.codegen.outline`).  numba compiles a store into a 1-D array in
    about a third of the time of one into the 2-D `out`, and half of them are left."""
    n = len(nodes)
    entries = mass_matrix_in_coordinates(prog, nodes, mass_matrix(prog, nodes), stepped=True)
    return [(f"_jac[{i * n + j}]", entries[i, j]) for i in range(n) for j in range(i + 1) if (i, j) in entries]
