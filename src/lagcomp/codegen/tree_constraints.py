"""The kernels of a kinematic tree with closed loops (`lagcomp.Loop`): the motion through the augmented system.

A tree whose cut joints add holonomic constraints Φ(q) = 0 (`lagcomp.multibody.loops`) gets the kernels a constrained
Lagrange module has (`lagcomp.codegen.lower`), with the same names, signatures and conventions, so that the drivers,
projection, ``reactions`` and `lagcomp.Solution` take it unchanged:

* ``rhs``, ``reactions``, ``rhs_and_reactions``: one solve of the augmented system
  [[M, −Λᵀ], [Λ, 0]] (q̈, λ) = (F, γ̃) (`lagcomp.ir.AugmentedSolve`), M by the composite-rigid-body algorithm, F by
  recursive Newton–Euler, Λ = ∂Φ/∂q and γ = −Λ̇ q̇ from the tree's forward kinematics (`lagcomp.multibody.closure`),
  γ̃ = γ − 2α Λ q̇ − β² Φ with the Baumgarte gains (α, β) the last two entries of p;
* ``constraint_residuals`` (Φ, then Λ q̇), ``constraint_residual_scales`` (the rounding scale of each, over the
  program that forms it: `lagcomp.codegen.rounding_scale.program_scales`) and ``constraint_matrix`` ([Λ | b], b = 0: the loops do not move with t).

Every part is in the tree's coordinates: a ball joint's (or a free joint's) rows and columns of M, its entries of F and
its columns of Λ are mapped from the recursions' body rates to its MRPs (`lagcomp.multibody.charts`), so the solve
gives σ̈ and the multipliers directly, as a Lagrange module in the same coordinates would.

A direction along which Λ's row is identically zero (the tree cannot pull the cut points apart that way) is refused
(`lagcomp.multibody.loops.refuse_idle_direction`): the augmented matrix would be singular at every state.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import sympy as sp

from lagcomp.codegen.bindings import BAUMGARTE
from lagcomp.codegen.rounding_scale import program_scales
from lagcomp.ir import AugmentedSolve
from lagcomp.multibody.charts import forces_in_coordinates, mass_matrix_in_coordinates
from lagcomp.multibody.closure import ClosureRows, closure_rows
from lagcomp.multibody.crba import mass_matrix
from lagcomp.multibody.loops import refuse_idle_direction
from lagcomp.multibody.program import Program
from lagcomp.multibody.rnea import forcing

ARGS = ("t", "y", "p", "out")


def gain_loads(tree) -> list[tuple[str, str]]:
    """The loads of the Baumgarte gains (α, β): the two entries of p after the parameters."""
    return [(name, f"p[{len(tree.parameters) + i}]") for i, name in enumerate(BAUMGARTE)]


def loop_kernels(tree, nodes, gravity, mapping: dict, kernel) -> tuple:
    """rhs, reactions, rhs_and_reactions, constraint_residuals, constraint_residual_scales and constraint_matrix of
    `tree` (with loops).

    `nodes` are its `lagcomp.multibody.kinematics.LocalNode` s, `gravity` over the locals, `mapping` each parameter
    to its local, `kernel(name, doc, args, build, solve=None)` the tree lowering's builder (a fresh
    `lagcomp.multibody.program.Program` given to ``build``, which returns the stores).
    """
    n, k = len(nodes), len(tree.constraint_names)
    _check_rows(tree, nodes, mapping)
    rhs = kernel(
        "rhs", "State derivative dy/dt = (q̇, q̈), shape (2n,), from the augmented system M q̈ = F + Λᵀ λ,\n"
        "Λ q̈ = γ (Baumgarte terms from the last two entries of p): M by the composite-rigid-body\n"
        "algorithm, F by recursive Newton-Euler, Λ and γ from the tree's forward kinematics.\n\n"
        "Returns 0, or j > 0 when the augmented matrix is singular (pivot j); `out` is then invalid.", ARGS,
        lambda prog: [(f"out[{i}]", nodes[i].qd) for i in range(n)] + _augmented_stores(prog, tree, nodes, gravity,
                                                                                          mapping),
        AugmentedSolve(size=n + k, mass_block=n, first=0, count=n, offset=n))
    reactions = replace(
        rhs, name="reactions",
        doc=f"Multipliers λ, shape ({k},), in constraint order {tree.constraint_names}: the component along\n"
            "each loop's direction of the force the second link exerts on the first at the cut joint (N).\n"
            "Returns 0, or j > 0 when singular.",
        stores=rhs.stores[n:], solve=AugmentedSolve(size=n + k, mass_block=n, first=n, count=k, offset=0))
    both = replace(
        rhs, name="rhs_and_reactions", args=(*ARGS, "lam"),
        doc="`rhs` into `out` and `reactions` into `lam` from one solve of the augmented system, both bitwise\n"
            "(the same code). Returns 0, or j > 0 when singular.", solve=replace(rhs.solve, multipliers=True))
    residuals = kernel(
        "constraint_residuals", f"Residuals, shape ({2 * k},): Φ of the {k} loop constraints, then Λ q̇.", ARGS,
        lambda prog: _residual_stores(prog, tree, nodes, mapping, k))
    scales = kernel(
        "constraint_residual_scales", f"Rounding scales, shape ({2 * k},), of the entries of `constraint_residuals`:\n"
        "the running bound of the forward kinematics that forms them (lagcomp.codegen.rounding_scale).", ARGS,
        lambda prog: _scale_stores(prog, tree, nodes, mapping))
    matrix = kernel(
        "constraint_matrix", f"Constraint matrix [Λ | b], shape ({k}, {n + 1}), into `out` (b = 0).", ARGS,
        lambda prog: [(f"out[{c}, {j}]", row[j] if j < n else sp.S.Zero)
                      for c, row in enumerate(loop_rows(prog, tree, nodes, mapping).rows) for j in range(n + 1)])
    return rhs, reactions, both, residuals, scales, matrix


def loop_rows(prog, tree, nodes, mapping):
    """The loops' `lagcomp.multibody.closure.ClosureRows` over the kernel's locals."""
    last_node = {node.link: i for i, node in enumerate(tree.nodes)}
    points = [(tuple(sp.sympify(x).xreplace(mapping) for x in c.first_point),
               tuple(sp.sympify(x).xreplace(mapping) for x in c.second_point)) for c in tree.closures]
    return closure_rows(prog, nodes, tree.closures, last_node, points)


def _check_rows(tree, nodes, mapping) -> None:
    """Refuse a loop direction whose row of Λ is identically zero (module docstring)."""
    rows = loop_rows(Program(), tree, nodes, mapping).rows
    c = 0
    for closure in tree.closures:
        for direction in range(len(closure.directions)):
            if all(sp.sympify(entry).is_zero for entry in rows[c]):
                refuse_idle_direction(closure, direction)
            c += 1


@dataclass(frozen=True)
class AugmentedParts:
    """What the augmented system of a tree with loops is made of, bound in one `Program`: M's lower triangle
    ({(i, j): M_ij}, i ≥ j, absent entries zero; composite-rigid-body algorithm), F (recursive Newton–Euler), the
    loops' `lagcomp.multibody.closure.ClosureRows` and γ̃ = γ − 2α Λ q̇ − β² Φ (α, β the Baumgarte gains)."""

    M: dict
    F: list
    loops: ClosureRows
    gamma: list

    def mass(self, i: int, j: int):
        """M_ij (M is symmetric: its lower triangle is kept)."""
        return self.M.get((max(i, j), min(i, j)), sp.S.Zero)


def augmented_parts(prog, tree, nodes, gravity, mapping) -> AugmentedParts:
    """The `AugmentedParts` of `tree` over the kernel's locals (`loop_kernels`' arguments), bound in `prog`: what
    ``rhs`` solves and what the on-demand kernels differentiate (`lagcomp.codegen.tree_loop_companion`)."""
    alpha, beta = (sp.Symbol(name, real=True) for name in BAUMGARTE)
    M = mass_matrix_in_coordinates(prog, nodes, mass_matrix(prog, nodes))
    F = forces_in_coordinates(prog, nodes, forcing(prog, nodes, gravity))
    loops = loop_rows(prog, tree, nodes, mapping)
    gamma = [prog.let(g - 2 * alpha * v - beta**2 * phi) for g, v, phi in zip(loops.gamma, loops.velocity, loops.Phi)]
    return AugmentedParts(M, F, loops, gamma)


def _augmented_stores(prog, tree, nodes, gravity, mapping) -> list:
    """Stores filling ``_kkt`` = [[M, −Λᵀ, F], [Λ, 0, γ̃]] (`lagcomp.ir.AugmentedSolve`)."""
    n, k = len(nodes), len(tree.constraint_names)
    parts = augmented_parts(prog, tree, nodes, gravity, mapping)
    N = n + k
    top, bottom = augmented_matrix(parts, n)
    stores = [(f"_kkt[{i}, {j}]", entry) for (i, j), entry in top]
    stores += [(f"_kkt[{i}, {N}]", F_i) for i, F_i in enumerate(parts.F)]
    stores += [(f"_kkt[{i}, {j}]", entry) for (i, j), entry in bottom]
    return stores + [(f"_kkt[{n + c}, {N}]", g) for c, g in enumerate(parts.gamma)]


def augmented_matrix(parts: AugmentedParts, n: int) -> tuple[list, list]:
    """The nonzero entries ((row, column), entry) of K = [[M, −Λᵀ], [Λ, 0]] ((n + k, n + k)): those of its first
    n rows (M's, then −Λᵀ's), and those of its last k rows (Λ's)."""
    top = [((i, j), parts.mass(i, j)) for i in range(n) for j in range(n) if (max(i, j), min(i, j)) in parts.M]
    top += [((i, n + c), -row[i]) for c, row in enumerate(parts.loops.rows) for i in range(n) if row[i] != 0]
    return top, [((n + c, j), row[j]) for c, row in enumerate(parts.loops.rows) for j in range(n) if row[j] != 0]


def _residual_stores(prog, tree, nodes, mapping, k: int) -> list:
    loops = loop_rows(prog, tree, nodes, mapping)
    return [(f"out[{c}]", phi) for c, phi in enumerate(loops.Phi)] + \
        [(f"out[{k + c}]", v) for c, v in enumerate(loops.velocity)]


def _scale_stores(prog, tree, nodes, mapping) -> list:
    """The rounding scale of each entry of ``constraint_residuals``, following the program that forms them."""
    loops = loop_rows(prog, tree, nodes, mapping)
    return [(f"out[{i}]", scale) for i, scale in enumerate(program_scales(prog, [*loops.Phi, *loops.velocity]))]
