r"""The on-demand kernels of a kinematic tree (`lagcomp.Tree`): its recursions differentiated in forward mode.

`lagcomp.codegen.tree_lower` emits the eager kernels of a tree from its recursions; the kinds here
(`lagcomp.codegen.kinds.TREE_KINDS`) are those recursions' derivatives, each its own program
(`lagcomp.multibody.program`) of the recursion followed by its forward-mode derivative
(`lagcomp.multibody.forward_mode`), never an expanded expression:

* "jacobians" (radau, sensitivities, fits, ``Model.jacobian``): ``rhs_with_jacobian`` (f = (q̇, q̈) of the
  articulated-body algorithm and ∂f/∂y along the 2n state directions), ``rhs_jacobian`` (the same, f dropped),
  ``rhs_parameter_jacobian`` (∂f/∂p along the P parameters) and ``rhs_with_full_jacobian`` (both);
* "directional" (a sensitivity run of one column): ``rhs_tangent`` and ``rhs_tangent_parameters``, f and J v
  (+ ∂f/∂p w) along one direction read from y's (and p's) tail: the recursion and one tangent, about three
  times ``rhs``; runs of more columns take the full Jacobians (`lagcomp.integrate.sensitivities`);
* "analysis" (``lagcomp.analysis.linearize``, equilibria): ``rest_partials``, ∂F/∂q and ∂F/∂q̇ of recursive
  Newton–Euler's F at q̇ = 0;
* "dynamics" (``Model.mass_matrix``, ``Model.forcing``, ``lagcomp.analysis``; a tree's own kind,
  `lagcomp.codegen.kinds.TREE_ON_DEMAND`): ``mass_matrix`` by the composite-rigid-body algorithm and ``forcing``
  by recursive Newton–Euler at q̈ = 0, not differentiated: a System's eager module has them, but no run of a tree
  calls them (its ``rhs`` is the articulated-body algorithm);
* "geometry" (animation): the links' frames by forward kinematics, no derivative (`lagcomp.codegen.tree_geometry`);
* "power" (``Solution.energy_balance``, a sweep's balance): the joints' torques' and dampers' power and V's explicit
  time, no derivative of the motion (`lagcomp.codegen.tree_power`).
* "taylor" (``method="taylor"``): ``taylor_coefficients``, the articulated-body algorithm in series arithmetic
  (`lagcomp.codegen.tree_taylor`; with contacts, one program per set of closed contacts, which factors M and returns
  a System's statuses);
* "lanes" (``sweep(..., batched=True)``): ``rhs_lanes``, the eager ``rhs`` evaluated per lane of a batch, bitwise
  (`lagcomp.codegen.tree_lanes`; none for a tree with loops, contacts or friction elements);
* "equations" (``Model.equations()``): no kernel, the constant ``EQUATIONS``: the recursion and the table of the
  tree's nodes as LaTeX and text (`lagcomp.codegen.tree_latex`).

A tree with closed loops (`lagcomp.Loop`) moves by an augmented solve, not by the articulated-body algorithm: its
kinds are built by `lagcomp.codegen.tree_loop_companion` (the Jacobians, the tangent kernels and the DAE kernels of
radau, "dae").  A tree without loops has no DAE kernels.

The program of a kernel that also writes f is the eager ``rhs``'s, assignment for assignment (same recursion,
same locals), so its f is ``rhs``'s bitwise.  No M is factored: the articulated-body algorithm's q̈ is explicit,
so every status is 0.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.emit import emit_companion
from lagcomp.codegen.kinds import KernelKind
from lagcomp.codegen.tree_canonical import tree_canonical_kernels
from lagcomp.codegen.tree_geometry import tree_geometry_kernels
from lagcomp.codegen.tree_lanes import tree_lanes_kernels
from lagcomp.codegen.tree_latex import tree_equations
from lagcomp.codegen.tree_locals import TreeLocals, tree_locals
from lagcomp.codegen.tree_loop_companion import LOOP_BUILDERS
from lagcomp.codegen.tree_lower import (
    FORMULATION,
    generalized_forcing,
    mass_matrix_stores,
    motion,
    program_kernel,
)
from lagcomp.codegen.tree_power import active_tree_power_terms, tree_power_kernels
from lagcomp.codegen.tree_taylor import tree_taylor_source
from lagcomp.ir import Delegate, FlatMatrix, Kernel, ModuleIR, ReturnZero
from lagcomp.multibody.forward_mode import derivatives, substituted
from lagcomp.multibody.program import Program
from lagcomp.multibody.tree import Tree


def tree_companion_source(tree: Tree, kind: KernelKind, eager_module: str) -> tuple[str, dict]:
    """The source of the companion module of `kind` (one of `lagcomp.codegen.kinds.TREE_KINDS`) of `tree`, and
    its metadata (``operations`` per kernel), as `lagcomp.codegen.companion_module.companion_source` gives a
    System's."""
    if kind.name == "taylor":   # (a series program, not kernels: `lagcomp.codegen.tree_taylor`)
        return tree_taylor_source(tree, tree_locals(tree), kind, eager_module)
    if kind.name == "equations":   # (data, no kernel: the recursion as LaTeX and text, `lagcomp.codegen.tree_latex`)
        ir = ModuleIR(system_name=tree.name, description=tree.description, coordinate_names=tree.coordinate_names,
                      parameter_names=tree.parameter_names, kernels=(), formulation=FORMULATION)
        return emit_companion(ir, kind, eager_module, equations=tree_equations(tree)), {"operations": {}}
    ir = lower_tree_kind(tree, kind.name)
    metadata = {"operations": {k.name: k.operation_count for k in ir.kernels}}
    if kind.name == "power":        # which terms of dh/dt the tree has (a sweep balances only where some has)
        metadata["power_terms"] = active_tree_power_terms(tree, tree_locals(tree))
    return emit_companion(ir, kind, eager_module), metadata


def lower_tree_kind(tree: Tree, kind: str) -> ModuleIR:
    """The IR of the kernels of the on-demand `kind` of `tree` (module docstring)."""
    local = tree_locals(tree)
    if kind == "geometry":
        kernels = tree_geometry_kernels(tree, local)
    else:
        kernels = (_LOOP_BUILDERS if tree.closures else _BUILDERS)[kind](tree, local)
    return ModuleIR(system_name=tree.name, description=tree.description, coordinate_names=tree.coordinate_names,
                    parameter_names=tree.parameter_names, kernels=kernels, formulation=FORMULATION)


def _motion(prog: Program, local: TreeLocals) -> list:
    """f = (q̇, q̈) of the articulated-body algorithm, bound in `prog` as ``rhs`` binds it."""
    return motion(prog, list(local.nodes), list(local.qd), list(local.gravity))


def _unit_seeds(symbols, first: int = 0) -> dict:
    """{symbol: {first + j: 1}}: the j-th of `symbols` is the direction first + j."""
    return {s: {first + j: sp.S.One} for j, s in enumerate(symbols)}


def _jacobian_stores(f: list, tangent: list, directions: range, with_f: bool, flat: bool) -> list:
    """The stores of ∂f/∂x into out (2n, len(`directions`)), every entry, x the `directions` of `tangent`; with
    `with_f` f into ydot first.  With `flat` (a large tree), into `out` seen flat as ``_jac`` (row-major:
    `lagcomp.ir.FlatMatrix` in place): numba compiles a store into a 1-D array in about a third of the time of one
    into the 2-D `out`, but the reshape costs a call (a small tree's Jacobian ran ~20-30% slower)."""
    width = len(directions)
    stores = [(f"ydot[{i}]", e) for i, e in enumerate(f)] if with_f else []
    return stores + [(f"_jac[{i * width + j}]" if flat else f"out[{i}, {j}]", tangent[i].get(x, sp.S.Zero))
                     for i in range(len(f)) for j, x in enumerate(directions)]


#: Derivative assignments past which a tree's Jacobians get the steps of the recursion they differentiate
#: (`lagcomp.multibody.forward_mode.derivatives`): about `lagcomp.codegen.outline.INLINE_LIMIT` operations (some
#: three an assignment), where the outlined helpers are called, not inlined, and where the Jacobians are stored flat
#: (`_jacobian_stores`).  Below it the kernels stay straight-line code into the 2-D `out`, as before: a small tree's
#: Jacobian with inlined helpers ran ~25% slower (planar_2, 0.32 -> 0.40 µs a call), flat ~20-30% slower.
STEP_ABOVE = 2500

_HOW = ("Forward mode over the articulated-body algorithm (lagcomp.multibody.forward_mode): each of its\n"
        "assignments followed by its derivatives, no expression expanded.  Returns 0.")


def _jacobian_kernels(local: TreeLocals) -> tuple[Kernel, ...]:
    """``rhs_with_jacobian``, ``rhs_jacobian``, ``rhs_parameter_jacobian``, ``rhs_with_full_jacobian``: one program
    of f and its derivatives along the 2n + P directions (y, p), each kernel the part its stores read."""
    size, P = 2 * local.n, len(local.p)
    prog = Program()
    f = _motion(prog, local)
    start = len(prog.assignments)
    tangent = derivatives(prog, f, {**_unit_seeds((*local.q, *local.qd)), **_unit_seeds(local.p, size)},
                          step_above=STEP_ABOVE)
    flat = STEP_ABOVE is not None and len(prog.assignments) - start > STEP_ABOVE

    def kernel(name, doc, directions, with_f):
        args = ("t", "y", "p", "ydot", "out") if with_f else ("t", "y", "p", "out")
        stores = _jacobian_stores(f, tangent, directions, with_f, flat)
        return program_kernel(name, doc + _HOW, args, prog, stores, local.loads,
                              FlatMatrix(size, width=len(directions), in_place=True) if flat else ReturnZero())

    return (
        kernel("rhs_with_jacobian", "f and its exact Jacobian at once: ydot = f(t, y) as `rhs` computes it (bitwise),\n"
               f"out[i, j] = ∂f_i/∂y_j, ({size}, {size}).\n", range(size), with_f=True),
        Kernel(name="rhs_jacobian", doc=f"out[i, j] = ∂f_i/∂y_j, ({size}, {size}): `rhs_with_jacobian`, f dropped.",
               args=("t", "y", "p", "out"), loads=(), temps=(), stores=(), solve=Delegate("rhs_with_jacobian", size)),
        kernel("rhs_parameter_jacobian", f"out[i, k] = ∂f_i/∂p_k, ({size}, {P}), p the model's parameters in order.\n",
               range(size, size + P), with_f=False),
        kernel("rhs_with_full_jacobian", "f and both Jacobians at once: ydot = f(t, y) as `rhs` computes it "
               f"(bitwise),\nout = [∂f/∂y | ∂f/∂p], ({size}, {size + P}).\n", range(size + P), with_f=True),
    )


def _tangent_kernel(local: TreeLocals, name: str, doc: str, parameters: bool) -> Kernel:
    """f and its derivative along v = y[2n:4n] (and w = p's last P floats) into out (4n,)."""
    prog, size, P = Program(), 2 * local.n, len(local.p)
    v = [sp.Symbol(f"_dy{j}", real=True) for j in range(size)]
    w = [sp.Symbol(f"_dp{k}", real=True) for k in range(P)] if parameters else []
    seeds = {s: {0: v[j]} for j, s in enumerate((*local.q, *local.qd))}
    seeds.update({s: {0: w[k]} for k, s in enumerate(local.p[:len(w)])})
    f = _motion(prog, local)
    tangent = derivatives(prog, f, seeds)
    stores = [(f"out[{i}]", e) for i, e in enumerate(f)]
    stores += [(f"out[{size + i}]", tangent[i].get(0, sp.S.Zero)) for i in range(size)]
    loads = (*local.loads, *((s.name, f"y[{size + j}]") for j, s in enumerate(v)),
             *((s.name, f"p[p.shape[0] - {P - k}]") for k, s in enumerate(w)))
    return program_kernel(name, doc, ("t", "y", "p", "out"), prog, stores, loads, ReturnZero())


def _tangent_kernels(local: TreeLocals) -> tuple[Kernel, ...]:
    """``rhs_tangent`` and ``rhs_tangent_parameters`` (module docstring)."""
    size = 2 * local.n
    return (
        _tangent_kernel(local, "rhs_tangent",
                        f"The augmented rhs of one initial-state sensitivity column: y = (x, v) ({2 * size},),\n"
                        "out = (f(x), ∂f/∂y v), f as `rhs` computes it (bitwise).\n" + _HOW, parameters=False),
        _tangent_kernel(local, "rhs_tangent_parameters",
                        f"`rhs_tangent` plus ∂f/∂p w, w the last {len(local.p)} floats of p (the parameters'\n"
                        "direction, after everything the other kernels read).\n" + _HOW, parameters=True),
    )


def _rest_partials_kernels(local: TreeLocals) -> tuple[Kernel, ...]:
    """``rest_partials``: ∂F/∂q, ∂F/∂q̇ of recursive Newton–Euler's F, then q̇ = 0 put into the program
    (`lagcomp.multibody.forward_mode.substituted`: the velocity terms fold away)."""
    n, prog = local.n, Program()
    F = generalized_forcing(prog, list(local.nodes), list(local.gravity))
    tangent = derivatives(prog, F, _unit_seeds((*local.q, *local.qd)))
    stores = [(f"out[{k}, {i}, {j}]", tangent[i].get(k * n + j, sp.S.Zero))
              for k in range(2) for i in range(n) for j in range(n)]
    prog, values = substituted(prog, [e for _, e in stores], {s: sp.S.Zero for s in local.qd})
    stores = [(target, e) for (target, _), e in zip(stores, values)]
    return (program_kernel(
        "rest_partials",
        "At (q, q̇ = 0, t), shape (2, n, n) into `out`: out[0] = ∂F/∂q, out[1] = ∂F/∂q̇ (row i is F_i,\n"
        "column j the variable j). The velocities in `y` are ignored: the partials are those at rest.\n"
        "Forward mode over recursive Newton-Euler's F (lagcomp.multibody.forward_mode).",
        ("t", "y", "p", "out"), prog, stores, local.loads),)


def _dynamics_kernels(local: TreeLocals) -> tuple[Kernel, ...]:
    """``mass_matrix`` (the composite-rigid-body algorithm) and ``forcing`` (recursive Newton–Euler at q̈ = 0): the
    tree's M q̈ = F, which no run calls (module docstring)."""
    nodes, args = list(local.nodes), ("t", "y", "p", "out")
    prog = Program()
    mass = program_kernel("mass_matrix", "Mass matrix M(q), shape (n, n), into `out` (composite-rigid-body "
                          "algorithm).", args, prog, mass_matrix_stores(prog, nodes), local.loads,
                          FlatMatrix(len(nodes), symmetric=True, status=False))
    prog = Program()
    stores = [(f"out[{i}]", f) for i, f in enumerate(generalized_forcing(prog, nodes, list(local.gravity)))]
    forcing = program_kernel("forcing", "Forcing F(q, q̇, t) of M q̈ = F, shape (n,), into `out` (recursive "
                             "Newton-Euler at q̈ = 0).", args, prog, stores, local.loads)
    return mass, forcing


#: The kernels of each on-demand kind a tree has (`lagcomp.codegen.kinds.TREE_KINDS`), from (tree, its locals):
#: a tree without loops has no DAE kernels (radau integrates its ODE, as a Lagrange module's without constraints).
_BUILDERS = {"jacobians": lambda tree, local: _jacobian_kernels(local),
             "directional": lambda tree, local: _tangent_kernels(local),
             "analysis": lambda tree, local: _rest_partials_kernels(local), "dae": lambda tree, local: (),
             "dynamics": lambda tree, local: _dynamics_kernels(local),
             "power": tree_power_kernels,
             "canonical": tree_canonical_kernels,
             "lanes": tree_lanes_kernels}

#: The same for a tree with loops: the augmented solve differentiated (`lagcomp.codegen.tree_loop_companion`);
#: ``rest_partials`` is the open tree's (F is the same).
_LOOP_BUILDERS = {**_BUILDERS, **LOOP_BUILDERS}
