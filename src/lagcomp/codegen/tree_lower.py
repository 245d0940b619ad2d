"""Lower a kinematic tree (`lagcomp.multibody.Tree`) to the kernel IR, from the recursions, not from T and V.

Each kernel's temporaries are the assignments of one straight-line program (`lagcomp.multibody.program`): the
articulated-body algorithm's for ``rhs``, the composite-rigid-body algorithm's for ``mass_matrix``, recursive
Newton–Euler's for ``forcing`` and ``momenta``, the outward velocities' for ``energy``.  They go to the emitter as
they are (no CSE over the whole kernel: each is already a small expression of earlier locals), with the
assignments no output reads dropped, and the steps that identical nodes repeat emitted once as shared helpers
(`lagcomp.codegen.outline`: numba's compile time grows with the code it types).  The module has the eager kernels of a Lagrange module, with the same names,
signatures and locals (`lagcomp.codegen.bindings.user_local`), so the drivers, the cache and `lagcomp.Model`
take it as they take any other; the on-demand kinds (`lagcomp.codegen.kinds`) are refused for now
(`lagcomp.multibody.tree.Tree.on_demand_refusal`).
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.bindings import user_local
from lagcomp.codegen.lower import event_reset_kernel
from lagcomp.codegen.outline import outline
from lagcomp.ir import Kernel, ModuleIR, ReturnZero
from lagcomp.multibody.aba import accelerations
from lagcomp.multibody.crba import mass_matrix
from lagcomp.multibody.energy import kinetic_energy, potential_energy
from lagcomp.multibody.joints import t
from lagcomp.multibody.kinematics import local_nodes
from lagcomp.multibody.program import Program
from lagcomp.multibody.rnea import forcing, momenta
from lagcomp.multibody.tree import Tree

FORMULATION = ("Equations of motion: q̈ by the articulated-body algorithm over the kinematic tree (lagcomp.multibody);\n"
               "M(q) q̈ = F(q, q̇, t) with M by the composite-rigid-body algorithm, F by recursive Newton-Euler.")
ARGS = ("t", "y", "p", "out")


def lower_tree(tree: Tree) -> ModuleIR:
    """The IR of the eager module of `tree`: rhs, mass_matrix, forcing, energy (and energy_function), momenta and
    the event kernels of a model without events."""
    n, names = tree.n, tree.coordinate_names
    q = [sp.Symbol(user_local("q", name, i), real=True) for i, name in enumerate(names)]
    qd = [sp.Symbol(user_local("qd", name, i), real=True) for i, name in enumerate(names)]
    mapping = {s: sp.Symbol(user_local("p", s.name, k), real=True) for k, s in enumerate(tree.parameters)}
    loads = [(s.name, f"y[{i}]") for i, s in enumerate(q)] + [(s.name, f"y[{n + i}]") for i, s in enumerate(qd)]
    loads += [(local.name, f"p[{k}]") for k, local in enumerate(mapping.values())]
    mapping[t] = sp.Symbol("t", real=True)
    nodes = local_nodes(tree, q, qd, mapping)
    gravity = [sp.sympify(g).xreplace(mapping) for g in tree.gravity]

    def kernel(name, doc, args, build, solve=None):
        prog = Program()
        stores = build(prog)
        return program_kernel(name, doc, args, prog, stores, loads, solve)

    kernels = (
        kernel("rhs", "State derivative dy/dt = (q̇, q̈), shape (2n,), q̈ by the articulated-body algorithm.\n\n"
               "Returns 0.", ARGS,
               lambda prog: [(f"out[{i}]", qd[i]) for i in range(n)]
               + [(f"out[{n + i}]", a) for i, a in enumerate(accelerations(prog, nodes, gravity))], ReturnZero()),
        kernel("mass_matrix", "Mass matrix M(q), shape (n, n), into `out` (composite-rigid-body algorithm).", ARGS,
               lambda prog: _matrix_stores(mass_matrix(prog, nodes), n)),
        kernel("forcing", "Forcing F(q, q̇, t) of M q̈ = F, shape (n,), into `out` (recursive Newton-Euler at q̈ = 0).",
               ARGS, lambda prog: [(f"out[{i}]", f) for i, f in enumerate(forcing(prog, nodes, gravity))]),
        kernel("energy", "Total mechanical energy T + V (gravity and the joints' springs).", ("t", "y", "p"),
               lambda prog: [("return", prog.let(kinetic_energy(prog, nodes) + potential_energy(prog, nodes, gravity)))]),
        Kernel(name="energy_function", doc="Energy function h = Σ q̇ ∂L/∂q̇ − L: T is homogeneous quadratic in q̇,\n"
               "so h = T + V, the kernel `energy`.", args=("t", "y", "p"), loads=(), temps=(), stores=(),
               alias="energy"),
        kernel("momenta", "Conjugate momenta ∂T/∂q̇_i, shape (n,), into `out` (the subtrees' spatial momenta).", ARGS,
               lambda prog: [(f"out[{i}]", h) for i, h in enumerate(momenta(prog, nodes))]),
        Kernel(name="event_values", doc="Event functions g, shape (0,): a tree has no events yet.", args=ARGS,
               loads=(), temps=(), stores=()),
        Kernel(name="event_gradients", doc=f"Partials of the event functions, shape (0, {2 * n + 1 + len(tree.parameters)})"
               ": none.\nReturns 0.", args=ARGS, loads=(), temps=(), stores=(), solve=ReturnZero()),
        event_reset_kernel((), (), 2 * n, mapping, tuple(loads)),
    )
    return ModuleIR(system_name=tree.name, description=tree.description, coordinate_names=names,
                    parameter_names=tree.parameter_names, kernels=kernels, formulation=FORMULATION)


def program_kernel(name: str, doc: str, args, prog: Program, stores, loads, solve=None) -> Kernel:
    """A kernel whose temporaries are the assignments of `prog` its `stores` read, and whose loads are those they
    read; the steps its nodes repeat emitted once (`lagcomp.codegen.outline`)."""
    temps = prog.live([e for _, e in stores])
    used = set().union(*(sp.sympify(e).free_symbols for _, e in stores), *(e.free_symbols for _, e in temps))
    used_names = {s.name for s in used}
    body, helpers = outline(name, temps, prog.step_of, [e for _, e in stores])
    return Kernel(name=name, doc=doc, args=args, loads=tuple((local, src) for local, src in loads if local in used_names),
                  temps=body, stores=tuple((target, sp.sympify(e)) for target, e in stores), solve=solve,
                  helpers=helpers)


def _matrix_stores(entries: dict, n: int) -> list:
    """Every entry of the symmetric (n, n) `out` from M's lower triangle `entries` ({(i, j): M_ij}, i ≥ j; absent
    entries are zero)."""
    stores = []
    for i in range(n):
        for j in range(n):
            stores.append((f"out[{i}, {j}]", entries.get((max(i, j), min(i, j)), sp.S.Zero)))
    return stores
