r"""The on-demand kernels of a kinematic tree with closed loops: the augmented solve differentiated in forward mode.

A tree with cut joints (`lagcomp.Loop`) moves by the augmented (KKT) system of a constrained Lagrange module
(`lagcomp.codegen.tree_constraints`): z = (q̈, λ) solves K z = r with

    K = [M  −Λᵀ]    r = [F]      M by the composite-rigid-body algorithm, F by recursive Newton–Euler,
        [Λ    0 ]        [γ̃]      Λ = ∂Φ/∂q, γ̃ = γ − 2α Λ q̇ − β² Φ from the tree's forward kinematics.

Its on-demand kernels have the names, signatures and frames of the constrained Lagrange module's
(`lagcomp.codegen.constrained_jacobian`, `lagcomp.codegen.lower`'s DAE kernels), so that radau, the sensitivities and
``Model.jacobian`` take them unchanged; what differs is where the partials come from: forward mode over the
recursions (`lagcomp.multibody.forward_mode`), each assignment followed by its derivatives, no expression expanded.

* "jacobians": K(x) z(x) = r(x) differentiated along x (a state component or a parameter) gives
  K ∂z/∂x = ∂/∂x [F − M ā + Λᵀ λ̄; γ̃ − Λ ā] at (ā, λ̄) = (q̈, λ) held fixed, then bound to what
  ``rhs_and_reactions`` solves (`lagcomp.ir.AugmentedJacobianSolve`: one factorization of K for every column).
  ``rhs_with_jacobian``, ``rhs_jacobian``, ``rhs_parameter_jacobian``, ``rhs_with_full_jacobian`` and
  ``reaction_jacobian``: the derivatives of the ODE ``rhs`` integrates, Baumgarte terms included, on the loops or
  off them.
* "dae" (radau): the residual G(t, z) of the index-2 form of Gear, Gupta and Leimkuhler over z = (q, v, w, λ, μ),
  rows v + Λᵀ μ, w, M w − F − Λᵀ λ, Λ v, Φ (`lagcomp.integrate.dae`; every loop constraint is holonomic and
  scleronomic, b = 0), and its Jacobian ∂G/∂z along the 3n + 2k components of z.
* "directional" (a run of one sensitivity column): ``rhs_directional``, ``rhs_tangent``, ``rhs_tangent_parameters``,
  f and the derivative along one direction (v, w): K dz = Σ_j ∂R/∂x_j dx_j, the contraction by forward mode along
  that one direction, solved by a second factorization of K (`lagcomp.ir.DirectionalSolve`).  A run of more columns
  takes the full Jacobians (no ``rhs_tangents``).

``rest_partials`` ("analysis") is the open tree's (`lagcomp.codegen.tree_companion`): F is the same.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.directional import DIRECTIONAL_ARGS, RHS_DIRECTIONAL_DOC, tangent_kernels
from lagcomp.codegen.jacobian_blocks import (
    RHS_PARAMETER_JACOBIAN_DOC,
    RHS_WITH_FULL_JACOBIAN_DOC,
    RHS_WITH_JACOBIAN_DOC,
    WITH_JACOBIAN_ARGS,
    jacobian_entry,
    jacobian_only,
)
from lagcomp.codegen.tree_constraints import augmented_matrix, augmented_parts, gain_loads
from lagcomp.codegen.tree_lower import program_kernel
from lagcomp.ir import AugmentedJacobianSolve, DirectionalSolve, FlatMatrix, Kernel, ReturnZero
from lagcomp.multibody.forward_mode import derivatives
from lagcomp.multibody.program import Program

_HOW = ("\n(q̈, λ) solve [M −Λᵀ; Λ 0] (q̈, λ) = (F, γ̃), so ∂(q̈, λ)/∂x = [M −Λᵀ; Λ 0]⁻¹ R with\n"
        "R = ∂/∂x [F − M ā + Λᵀ λ̄; γ̃ − Λ ā] at ā = q̈, λ̄ = λ (`rhs_and_reactions`), by forward mode over the\n"
        "composite-rigid-body, Newton-Euler and forward-kinematics recursions (lagcomp.multibody.forward_mode).\n"
        "Returns 0, or j > 0 as `rhs` does, or when the factorization of [M −Λᵀ; Λ 0] finds pivot j zero;\n"
        "`out` is then invalid.")


def _symbols(stem: str, count: int) -> list:
    """The kernel locals ``<stem>0``, ``<stem>1``, ... (generated names start with ``_``: no user local is one)."""
    return [sp.Symbol(f"{stem}{i}", real=True) for i in range(count)]


def _unit_seeds(symbols, first: int = 0) -> dict:
    """{symbol: {first + j: 1}}: the j-th of `symbols` is the direction first + j."""
    return {s: {first + j: sp.S.One} for j, s in enumerate(symbols)}


def _parts(prog: Program, tree, local):
    """The tree's `lagcomp.codegen.tree_constraints.AugmentedParts` over the kernel locals `local`, bound in `prog`."""
    return augmented_parts(prog, tree, list(local.nodes), list(local.gravity), local.mapping)


def loop_jacobian_kernels(tree, local) -> tuple[Kernel, ...]:
    """The "jacobians" kind of `tree` (with loops; `local` its `lagcomp.codegen.tree_companion.TreeLocals`): one
    program of K, the residual R and R's derivatives along the 2n + P directions (y, p), each kernel the part its
    stores read (module docstring)."""
    n, k, P = local.n, len(tree.constraint_names), len(local.p)
    size = 2 * n
    prog = Program()
    parts = _parts(prog, tree, local)
    acc, mult = _symbols("_acc", n), _symbols("_mult", k)
    tangent = derivatives(prog, _residual(parts, acc, mult, n, k),
                          {**_unit_seeds((*local.q, *local.qd)), **_unit_seeds(local.p, size)})
    top, bottom = augmented_matrix(parts, n)
    matrix = [(f"_kkt[{i}, {j}]", entry) for (i, j), entry in top + bottom]
    loads = (*local.loads, *gain_loads(tree), *((s.name, f"_ydot[{n + i}]") for i, s in enumerate(acc)),
             *((s.name, f"_lam[{c}]") for c, s in enumerate(mult)))

    def kernel(name, doc, args, directions, first, count, offset, with_f):
        width = len(directions)
        stores = matrix + [(f"_jac[{r * width + j}]", tangent[r][x])
                           for r in range(n + k) for j, x in enumerate(directions) if x in tangent[r]]
        solve = AugmentedJacobianSolve(n=n, k=k, width=width, first=first, count=count, offset=offset,
                                       identity=with_f, given_ydot=with_f)
        return program_kernel(name, doc + _HOW, args, prog, stores, loads, solve)

    return (
        kernel("rhs_with_jacobian", RHS_WITH_JACOBIAN_DOC + "Rows [0 | I], then ∂q̈/∂y:", WITH_JACOBIAN_ARGS,
               range(size), 0, n, n, with_f=True),
        jacobian_only(size),
        kernel("rhs_parameter_jacobian", RHS_PARAMETER_JACOBIAN_DOC + "Rows 0 (q̇ does not depend on p), then ∂q̈/∂p:",
               ("t", "y", "p", "out"), range(size, size + P), 0, n, n, with_f=False),
        kernel("rhs_with_full_jacobian", RHS_WITH_FULL_JACOBIAN_DOC + "Rows [0 | I | 0], then ∂q̈/∂(y, p):",
               WITH_JACOBIAN_ARGS, range(size + P), 0, n, n, with_f=True),
        kernel("reaction_jacobian",
               f"Exact Jacobian of the multipliers λ (`reactions`), shape ({k}, {size + P}) into `out`: row c the "
               f"constraint c of\n{tree.constraint_names}, columns ∂λ_c/∂y_j ({size} of them), then ∂λ_c/∂p_j for "
               "the model's\nparameters (not the Baumgarte gains):", ("t", "y", "p", "out"), range(size + P), n, k, 0,
               with_f=False),
    )


def loop_tangent_kernels(tree, local) -> tuple[Kernel, ...]:
    """The "directional" kind of `tree` (with loops): ``rhs_directional`` (f and its derivative along (v, w) at
    once, `lagcomp.ir.DirectionalSolve`: K (q̈, λ) = (F, γ̃) solved for f, then K dz = Σ_j ∂R/∂x_j dx_j, the
    contraction by forward mode along the one direction (v, w)), and its tangent kernels ``rhs_tangent``,
    ``rhs_tangent_parameters`` (`lagcomp.codegen.directional.tangent_kernels`: what a run of one sensitivity column
    calls as its rhs).  A run of more columns takes the full Jacobians."""
    n, k, P = local.n, len(tree.constraint_names), len(local.p)
    size = n + k
    prog = Program()
    parts = _parts(prog, tree, local)
    acc, mult = _symbols("_acc", n), _symbols("_mult", k)
    dy, dp = _symbols("_dy", 2 * n), _symbols("_dp", P)
    tangent = derivatives(prog, _residual(parts, acc, mult, n, k),
                          {s: {0: d} for s, d in zip((*local.q, *local.qd, *local.p), (*dy, *dp))})
    top, bottom = augmented_matrix(parts, n)
    first = [(f"ydot[{i}]", local.qd[i]) for i in range(n)]
    first += [(f"_kkt[{i}, {j}]", entry) for (i, j), entry in top + bottom]
    first += [(f"_kkt[{r}, {size}]", right) for r, right in enumerate((*parts.F, *parts.gamma))]
    second = [(f"out[{i}]", dy[n + i]) for i in range(n)]
    second += [(f"_direction[{r}, {size}]", tangent[r].get(0, sp.S.Zero)) for r in range(size)]
    loads = (*local.loads, *gain_loads(tree), *((s.name, f"v[{j}]") for j, s in enumerate(dy)),
             *((s.name, f"w[{j}]") for j, s in enumerate(dp)),
             *((s.name, f"_ydot[{n + i}]") for i, s in enumerate(acc)),
             *((s.name, f"_lam[{c}]") for c, s in enumerate(mult)))
    solve = DirectionalSolve(n=n, phase_one=len(first), solved=tuple(s.name for s in (*acc, *mult)), multipliers=k)
    directional = program_kernel(
        "rhs_directional", RHS_DIRECTIONAL_DOC + "K (q̈, λ) = (F, γ̃), then K dz = Σ_j ∂(r − K z̄)/∂x_j dx_j at "
        "z̄ = (q̈, λ), K = [M −Λᵀ; Λ 0],\nthe contraction by forward mode over the recursions; out = (v[n:], "
        "dz[:n]).\n"
        "Returns 0, or j > 0 when a factorization of K finds pivot j zero; `out` is then invalid.",
        DIRECTIONAL_ARGS, prog, first + second, loads, solve)
    return (directional, *tangent_kernels(directional, P))


def _residual(parts, acc, mult, n: int, k: int) -> list:
    """R = [F − M ā + Λᵀ λ̄; γ̃ − Λ ā] over the symbols ā = `acc`, λ̄ = `mult` (module docstring)."""
    rows = parts.loops.rows
    residual = [parts.F[i] - sum((parts.mass(i, j) * acc[j] for j in range(n)), sp.S.Zero)
                + sum((rows[c][i] * mult[c] for c in range(k)), sp.S.Zero) for i in range(n)]
    return residual + [parts.gamma[c] - sum((rows[c][j] * acc[j] for j in range(n)), sp.S.Zero) for c in range(k)]


def loop_dae_kernels(tree, local) -> tuple[Kernel, Kernel]:
    """The "dae" kind of `tree` (with loops): ``dae_residual`` and ``dae_jacobian`` over z = (q, v, w, λ, μ), the
    residual's program and its derivatives along the N' = 3n + 2k components of z (module docstring).  q, v load
    from z[:2n] as the state does; w, λ, μ are the locals ``_w<i>``, ``_lam<c>``, ``_mu<c>``."""
    n, k = local.n, len(tree.constraint_names)
    size = 3 * n + 2 * k
    prog = Program()
    parts = _parts(prog, tree, local)
    w, lam, mu = _symbols("_w", n), _symbols("_lam", k), _symbols("_mu", k)
    rows = parts.loops.rows
    residual = [local.qd[i] + sum((rows[c][i] * mu[c] for c in range(k)), sp.S.Zero) for i in range(n)]
    residual += list(w)
    residual += [sum((parts.mass(i, j) * w[j] for j in range(n)), sp.S.Zero) - parts.F[i]
                 - sum((rows[c][i] * lam[c] for c in range(k)), sp.S.Zero) for i in range(n)]
    residual += [*parts.loops.velocity, *parts.loops.Phi]
    tangent = derivatives(prog, residual, _unit_seeds((*local.q, *local.qd, *w, *lam, *mu)))
    loads = (*local.loads, *((s.name, f"y[{2 * n + i}]") for i, s in enumerate(w)),
             *((s.name, f"y[{3 * n + c}]") for c, s in enumerate(lam)),
             *((s.name, f"y[{3 * n + k + c}]") for c, s in enumerate(mu)))
    layout = (f"z = (q, v, w, λ, μ), DAE_SIZE = {size} (n = {n}, k = kh = {k}); λ has the sign of `reactions`.\n"
              "Forward mode over the recursions (lagcomp.multibody.forward_mode). Returns 0. "
              "See lagcomp.integrate.drivers.radau, DAEs.")
    return (
        program_kernel(
            "dae_residual",
            "Residual G(t, z), shape (DAE_SIZE,), of the constrained system as the index-2 DAE Mdae z' = G(t, z),\n"
            "Mdae = diag(1 × 2n, 0 × (n + 2k)): rows v + Λᵀ μ, w, M w − F − Λᵀ λ, Λ v, Φ.\n" + layout,
            ("t", "y", "p", "out"), prog, [(f"out[{i}]", g) for i, g in enumerate(residual)], loads, ReturnZero()),
        program_kernel(
            "dae_jacobian",
            "Exact Jacobian out[i, j] = ∂G_i/∂z_j, (DAE_SIZE, DAE_SIZE), of `dae_residual`, every entry written.\n"
            + layout, ("t", "y", "p", "out"), prog,
            [(jacobian_entry(i, j, size), row[j]) for i, row in enumerate(tangent) for j in range(size) if j in row],
            loads, FlatMatrix(size=size)),
    )


#: The kernels of the on-demand kinds of a tree with loops, from (tree, its locals) (`lagcomp.codegen.tree_companion`
#: adds ``rest_partials``, the same as a tree's without loops).
LOOP_BUILDERS = {"jacobians": loop_jacobian_kernels, "directional": loop_tangent_kernels, "dae": loop_dae_kernels}
