r"""The "canonical" kernels of a kinematic tree (`lagcomp.Tree`): the Hamiltonian form that gauss1/2/3 integrate.

A tree's kinetic energy is homogeneous quadratic in the velocities, so its conjugate momenta are
p = ∂L/∂q̇ = M(q) q̇ (the eager ``momenta``, recursive Newton–Euler's subtree momenta; no b(q, t)).  The three
kernels are a System's (`lagcomp.codegen.lower`, `lagcomp.integrate.drivers.canonical`), built from the recursions:

* ``velocities(t, x, p, out)``: q̇ = M(q)⁻¹ p at x = (q, p), M by the composite-rigid-body algorithm and solved
  numerically (LDLᵀ), as a System's ``velocities`` solves M q̇ = p − b;
* ``momentum_rate(t, y, p, out)``: ṗ = ∂L/∂q + Q at y = (q, q̇).  Lagrange's equations read
  d/dt P(q, q̇) = ∂L/∂q + Q, and d/dt P = (∂P/∂q) q̇ + M q̈ with M q̈ = F (recursive Newton–Euler at q̈ = 0), so

      ṗ = F(q, q̇, t) + (∂P/∂q) q̇,

  the second term one forward-mode tangent of the momenta's recursion along the direction q̇ in q
  (`lagcomp.multibody.forward_mode`): O(n), where the gradient ∂L/∂q would take n tangents.  Q holds the joints'
  torques and dampers (a System's Q − ∂D/∂q̇), both in F;
* ``canonical_partials(t, y, p, out)``: (4, n, n) = M, ∂P/∂q, ∂ṗ/∂q, ∂ṗ/∂q̇ at y = (q, q̇), partials at fixed q̇ (the
  layout `lagcomp.integrate.drivers.canonical.canonical_jacobian` combines): M by the composite-rigid-body
  algorithm, ∂P/∂q by n tangents of the momenta's recursion, the partials of ṗ by 2n tangents of the program of
  ṗ above (itself a recursion followed by one tangent), so O(n²) in all, as the blocks' n² entries are.

On a spherical joint the coordinates are MRPs σ and everything is in σ and σ̇ (`lagcomp.multibody.charts`:
P_σ = Jᵀ P_ω, F_σ = Jᵀ F_ω, M_σ = Jᵀ M_ω J), the derivatives going through J(σ) too.  A tree with closed loops has
no canonical form (its momenta do not determine its velocities; the gauss methods refuse a constrained model): its
"canonical" kind has ``momentum_rate`` only, as a constrained System's.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.bindings import user_local
from lagcomp.codegen.lower import UNROLL_MAX
from lagcomp.codegen.tree_lower import generalized_forcing, program_kernel
from lagcomp.ir import LinearSolve
from lagcomp.multibody.charts import forces_in_coordinates, mass_matrix_in_coordinates
from lagcomp.multibody.crba import mass_matrix
from lagcomp.multibody.forward_mode import derivatives
from lagcomp.multibody.program import Program
from lagcomp.multibody.rnea import momenta

_ARGS = ("t", "y", "p", "out")
_HOW = ("\nFrom the tree's recursions (lagcomp.codegen.tree_canonical): ṗ = F + (∂P/∂q) q̇, F by recursive\n"
        "Newton-Euler, (∂P/∂q) q̇ by forward mode over the momenta's recursion.")


def tree_canonical_kernels(tree, local) -> tuple:
    """``momentum_rate``, ``velocities`` and ``canonical_partials`` of `tree` over its kernel locals `local`
    (`lagcomp.codegen.tree_companion.TreeLocals`); ``momentum_rate`` alone for a tree with loops (module docstring)."""
    rate = _momentum_rate_kernel(local)
    if tree.closures:
        return (rate,)
    return rate, _velocities_kernel(tree, local), _canonical_partials_kernel(local)


def _coordinate_momenta(prog: Program, local) -> list:
    """P(q, q̇) = M(q) q̇ over the coordinates (Jᵀ on a spherical joint), bound in `prog`."""
    return forces_in_coordinates(prog, list(local.nodes), momenta(prog, list(local.nodes)))


def _momentum_rate(prog: Program, local) -> list:
    """ṗ = F + (∂P/∂q) q̇ at (q, q̇) (module docstring), bound in `prog`."""
    forcing = generalized_forcing(prog, list(local.nodes), list(local.gravity))
    along_velocity = derivatives(prog, _coordinate_momenta(prog, local),
                                 {q: {0: qd} for q, qd in zip(local.q, local.qd)})
    return [prog.let(f + d.get(0, sp.S.Zero)) for f, d in zip(forcing, along_velocity)]


def _momentum_rate_kernel(local):
    """``momentum_rate``: ṗ (n,) into `out` at y = (q, q̇)."""
    prog = Program()
    stores = [(f"out[{i}]", r) for i, r in enumerate(_momentum_rate(prog, local))]
    return program_kernel(
        "momentum_rate",
        "ṗ = ∂L/∂q + Q − ∂D/∂q̇ at y = (q, q̇), shape (n,), into `out`: Hamilton's −∂H/∂q plus forces." + _HOW,
        _ARGS, prog, stores, local.loads)


def _mass_entries(prog: Program, local) -> dict:
    """M(q)'s lower triangle over the coordinates ({(i, j): M_ij}, i ≥ j, zeros absent), bound in `prog`."""
    return mass_matrix_in_coordinates(prog, list(local.nodes), mass_matrix(prog, list(local.nodes)))


def _velocities_kernel(tree, local):
    """``velocities``: q̇ = M(q)⁻¹ p at x = (q, p), the momenta read from y's second half."""
    n, prog = local.n, Program()
    mom = [sp.Symbol(user_local("mom", name, i), real=True) for i, name in enumerate(tree.coordinate_names)]
    loads = (*local.loads, *((s.name, f"y[{n + i}]") for i, s in enumerate(mom)))
    entries = _mass_entries(prog, local)
    m = tuple(tuple(f"_m{i}_{j}" for j in range(i + 1)) for i in range(n))
    f = tuple(f"_f{i}" for i in range(n))
    stores = [(m[i][j], entries.get((i, j), sp.S.Zero)) for i in range(n) for j in range(i + 1)]
    stores += list(zip(f, mom))
    return program_kernel(
        "velocities",
        "Velocities q̇, shape (n,), at x = (q, p) (here `y` holds q then the momenta p), from M(q) q̇ = p, M by\n"
        "the composite-rigid-body algorithm. Returns 0, or k > 0 when pivot k of M is not positive.",
        _ARGS, prog, stores, loads, LinearSolve(n=n, m=m, f=f, offset=0, unrolled=n <= UNROLL_MAX))


def _canonical_partials_kernel(local):
    """``canonical_partials``: M, ∂P/∂q, ∂ṗ/∂q, ∂ṗ/∂q̇ into `out` (4, n, n) at y = (q, q̇)."""
    n, prog = local.n, Program()
    entries = _mass_entries(prog, local)
    momentum_q = derivatives(prog, _coordinate_momenta(prog, local), {q: {j: sp.S.One} for j, q in enumerate(local.q)})
    seeds = {s: {j: sp.S.One} for j, s in enumerate((*local.q, *local.qd))}
    rate = derivatives(prog, _momentum_rate(prog, local), seeds)
    blocks = (
        lambda i, j: entries.get((max(i, j), min(i, j)), sp.S.Zero),
        lambda i, j: momentum_q[i].get(j, sp.S.Zero),
        lambda i, j: rate[i].get(j, sp.S.Zero),
        lambda i, j: rate[i].get(n + j, sp.S.Zero),
    )
    stores = [(f"out[{k}, {i}, {j}]", block(i, j)) for k, block in enumerate(blocks)
              for i in range(n) for j in range(n)]
    return program_kernel(
        "canonical_partials",
        "At y = (q, q̇), shape (4, n, n) into `out`: out[0] = M, out[1] = ∂P/∂q, out[2] = ∂r/∂q,\n"
        "out[3] = ∂r/∂q̇ (P = M q̇ the momenta, r = ∂L/∂q + Q − ∂D/∂q̇ their rate; row i is\n"
        "component i, column j the variable j). Forward mode over the recursions (lagcomp.codegen.tree_canonical).",
        _ARGS, prog, stores, local.loads)
