r"""``rhs_directional``: f and one directional derivative J v + (∂f/∂p) w in one CSE'd kernel.

A run with k sensitivity columns needs J S (+ ∂f/∂p in a parameter's column) at every stage.  The full
Jacobians (``rhs_with_jacobian``, ``rhs_parameter_jacobian``) cost N (N + P) entries and N + P substitutions
by M (or K) whatever k is; for few columns the derivative along each column is cheaper: forward mode on the
symbolic accelerations.  Differentiating M(x) a(x) = F(x) along the direction dx = (v, w) of x = (y, p):

    M da = dF − dM ā |_{ā = a} = Σ_j ∂(F − M ā)/∂x_j dx_j,

the residual's partials of `lagcomp.codegen.jacobian_blocks.acceleration_partials` (ā held fixed, then bound to the
accelerations ``rhs`` solved) contracted with the direction symbolically, so that one CSE shares them with M
and F, and one LDLᵀ substitution gives da.  With y = (q, q̇), f = (q̇, a):

    J v + (∂f/∂p) w = (v[n:2n], da).

A constrained system (Lagrange multipliers) solves K z = r for z = (q̈, λ), K = [M −Λᵀ; Λ 0]; along dx,
K dz = Σ_j ∂(r − K z̄)/∂x_j dx_j at z̄ = (q̈, λ) (`lagcomp.codegen.constrained_jacobian`, the residual with the
Baumgarte terms): a second ``kkt_solve`` of the direction's right-hand side (K copied before the first), the
first n entries of dz the accelerations' derivative.  f and the direction come from one CSE, so that the
sines, cosines and products of M, F (K, γ̃) serve both, and an unconstrained M is factored once for both
(`lagcomp.ir.DirectionalSolve`): a call costs about one ``rhs`` and one substitution.  f agrees with ``rhs``'s,
and the derivative with the full Jacobians' product, to rounding (other orders of the same sums).

The tangent kernels (`tangent_kernels`) are the same CSE with other arrays: ``rhs_tangent(t, y, p, out)`` reads
the direction v from y = (x, v) and writes (f, J v) into out (2N,), w's terms dropped, and
``rhs_tangent_parameters`` reads w from the end of p too.  They have ``rhs``'s signature, so that a run of one
sensitivity column passes the kernel itself to the driver, which calls it as it calls ``rhs``: no closure
between them, whose views of y and out and seven array arguments per call cost as much as the kernel.

The kernels of many columns (`tangents_kernels`: ``rhs_tangents``, ``rhs_tangents_parameters``) take
y = (x, S[:, 0], ..., S[:, m-1]) for any m: their CSE holds f, M (K) and the residual's nonzero partials
∂(F − M ā)/∂x_j as locals, computed once, and an emitted loop over the columns contracts them with each column
and substitutes by the one factorization (`lagcomp.ir.DirectionalSolve.columns`): a column costs about N
(nonzeros of a row) products and a substitution, and numba compiles the loop body once whatever m.
"""

from __future__ import annotations

import dataclasses

import symengine as se
import sympy as sp

from lagcomp.codegen.constrained_jacobian import (
    augmented_residual,
    matrix_stores,
    residual_partials,
)
from lagcomp.codegen.cse import cse_kernel
from lagcomp.codegen.jacobian_blocks import acceleration_block, fresh_symbols
from lagcomp.codegen.stabilization import stabilized_gamma
from lagcomp.ir import DirectionalSolve, Kernel
from lagcomp.mechanics.lagrange import EOM
from lagcomp.model.system import t

#: The largest n whose module has ``rhs_directional`` (and, unconstrained, ``rhs_with_full_jacobian``): their
#: sums over the 2n + P columns grow as the full Jacobians do, and are paid by every model at codegen.  Measured
#: for the n-link chain at n = 12 (`lagcomp.compile` 2.3 → 3.4 s, ``rhs_directional`` 4786 operations after CSE
#: against 966 for ``rhs``, and its numba compilation at the first sensitivity run 3.7 → 8.0 s); at n = 5: 0.44 →
#: 0.64 s, 834 operations, first sensitivity run 1.7 → 1.5 s (it replaces two kernels there).  Larger systems'
#: sensitivities take the full Jacobians.
LARGEST_SYSTEM = 6

#: The arguments of every ``rhs_directional`` kernel: the direction (v (N,), w (P,)), then f into ``ydot``
#: (N,) and the derivative into ``out`` (N,).
DIRECTIONAL_ARGS = ("t", "y", "p", "v", "w", "ydot", "out")

#: The docstring of every ``rhs_directional`` kernel: what it computes; `directional_kernel` adds how.
RHS_DIRECTIONAL_DOC = (
    "f and its derivative along one direction at once: ydot = f(t, y, p) as `rhs` computes it (to rounding),\n"
    "out = ∂f/∂y v + ∂f/∂p w, (N,), for v (N,) and w (P,) (P = the model's parameters, in the order of p).\n"
    "Symbolic, no differences: the product of the full Jacobians `rhs_with_jacobian` and `rhs_parameter_jacobian`\n"
    "to rounding, at about the cost of `rhs` and one substitution (the sensitivities' kernel for few columns).\n"
)


def directional_kernel(eom: EOM, mapping, loads) -> Kernel:
    """``rhs_directional`` of `eom` (n ≤ `LARGEST_SYSTEM`), unconstrained (LDLᵀ of M, written out) or constrained
    (``kkt_solve`` of K), one CSE for f and the direction (`lagcomp.ir.DirectionalSolve` orders it around the
    solve)."""
    n = eom.n
    variables = (*eom.q, *eom.qd, *eom.parameters)
    taken = {s.name for s in (*variables, t)}
    taken |= {s.name for e in (*eom.M, *eom.F, *eom.C) for s in e.free_symbols}
    directions = fresh_symbols("_dx", len(variables), taken)
    locals_ = [f"_dy{i}" for i in range(2 * n)] + [f"_dp{j}" for j in range(len(eom.parameters))]
    sources = [f"v[{i}]" for i in range(2 * n)] + [f"w[{j}]" for j in range(len(eom.parameters))]
    mapping = {**mapping, **{d: sp.Symbol(local, real=True) for d, local in zip(directions, locals_, strict=True)}}
    loads = loads + tuple(zip(locals_, sources, strict=True))
    velocities = [(f"ydot[{i}]", eom.qd[i]) for i in range(n)]
    velocity_rows = [(f"out[{i}]", directions[n + i]) for i in range(n)]
    if eom.k:
        residual, mapping, loads = augmented_residual(eom, mapping, loads)
        size, k = n + eom.k, eom.k
        right = [*eom.F, *stabilized_gamma(eom)]
        first = velocities + matrix_stores(eom) + [(f"_kkt[{r}, {size}]", right[r]) for r in range(size)]
        second = velocity_rows + [(f"_direction[{r}, {size}]", _contracted(row, directions))
                                  for r, row in enumerate(residual_partials(residual, variables))]
        solved = tuple(f"_acc{i}" for i in range(n)) + tuple(f"_mult{c}" for c in range(k))
        solve = DirectionalSolve(n=n, phase_one=len(first), solved=solved, multipliers=k)
        how = ("K (q̈, λ) = (F, γ̃), then K dz = Σ_j ∂(r − K z̄)/∂x_j dx_j at z̄ = (q̈, λ), K = [M −Λᵀ; Λ 0], γ̃\n"
               "with the Baumgarte terms; out = (v[n:], dz[:n]) (see lagcomp.codegen.directional).\n"
               "Returns 0, or j > 0 when a factorization of K finds pivot j zero; `out` is then invalid.")
    else:
        block, m, mapping, loads = acceleration_block(eom, variables, mapping, loads)
        f, g = tuple(f"_f{i}" for i in range(n)), tuple(f"_g{i}" for i in range(n))
        first = velocities + [(m[i][j], eom.M[i, j]) for i in range(n) for j in range(i + 1)]
        first += list(zip(f, eom.F, strict=True))
        second = velocity_rows + [(g[i], _contracted(row, directions)) for i, row in enumerate(block)]
        solve = DirectionalSolve(n=n, phase_one=len(first), solved=tuple(f"_acc{i}" for i in range(n)), m=m, f=f,
                                 g=g)
        how = ("M q̈ = F, then M da = Σ_j ∂(F − M ā)/∂x_j dx_j at ā = q̈ by the same LDLᵀ of M; out = (v[n:], da)\n"
               "(see lagcomp.codegen.directional).\n"
               "Returns 0, or k > 0 as `rhs` does when pivot k of M's LDLᵀ is not positive; `out` is then invalid.")
    return cse_kernel("rhs_directional", RHS_DIRECTIONAL_DOC + how, DIRECTIONAL_ARGS, first + second, mapping, loads,
                   solve=solve)


#: The docstrings of the tangent kernels: ``rhs_directional`` with the direction read from y (and p), for the
#: sensitivity runs of one column, which call them as their ``rhs`` (no closure between them and the driver).
RHS_TANGENT_DOC = (
    "The augmented rhs of one initial-state sensitivity column: y = (x, v) (2N,), out = (f(x), ∂f/∂y v)\n"
    "(2N,): `rhs_directional` along (v, 0) with its arrays in y and out (the same CSE, the terms of w dropped):\n"
    "f as `rhs_directional` computes it, bitwise; the derivative to rounding.\n"
)
RHS_TANGENT_PARAMETERS_DOC = (
    "The augmented rhs of one sensitivity column with a parameter direction: y = (x, v) (2N,), out = (f(x),\n"
    "∂f/∂y v + ∂f/∂p w) (2N,), w (P,) the last P floats of p (the run's work space, after the model's\n"
    "parameters, gains, modes and tables): `rhs_directional` along (v, w) with its arrays in y, p and out\n"
    "(the same CSE), bitwise.\n"
)


def tangent_kernels(directional: Kernel, n_parameters: int) -> tuple[Kernel, Kernel]:
    """``rhs_tangent`` and ``rhs_tangent_parameters`` of the module whose ``rhs_directional`` is `directional`:
    its CSE with the direction loaded from ``y[N:]`` (and ``p``'s last `n_parameters` floats) and f and the
    derivative stored into ``out`` (2N,), so that a run of one sensitivity column takes it as its ``rhs``, of
    the drivers' signature.  ``rhs_tangent`` drops w: its terms are zero for an initial-state column (the
    temporaries left unused go too).  Measured on the double pendulum (ns per call through the drivers'
    function type): ``rhs_directional`` in the closure over it 104, ``rhs_tangent_parameters`` 65,
    ``rhs_tangent`` 54, ``rhs`` 37."""
    solve = directional.solve
    n = solve.n
    size = 2 * n
    targets = {**{f"ydot[{i}]": f"out[{i}]" for i in range(n)}, **{f"out[{i}]": f"out[{size + i}]" for i in range(n)}}
    stores = tuple((targets.get(target, target), expr) for target, expr in directional.stores)
    state = {f"v[{i}]": f"y[{size + i}]" for i in range(size)}
    parameters = {f"w[{j}]": f"p[p.shape[0] - {n_parameters - j}]" for j in range(n_parameters)}
    frame = dataclasses.replace(solve, ydot="out", offset=size)
    both = dataclasses.replace(
        directional, name="rhs_tangent_parameters", doc=RHS_TANGENT_PARAMETERS_DOC + _how(directional.doc),
        args=("t", "y", "p", "out"), stores=stores, solve=frame,
        loads=tuple((local, state.get(source, parameters.get(source, source))) for local, source in directional.loads))
    dropped = {local for local, source in directional.loads if source in parameters}
    temps, stores = _without(directional.temps, stores, dropped)
    used = set().union(*(e.free_symbols for _, e in (*temps, *stores)))
    used_names = {s.name for s in used} | set(solve.solved)
    loads = tuple((local, state.get(source, source)) for local, source in directional.loads
                  if local not in dropped and local in used_names)
    alone = dataclasses.replace(both, name="rhs_tangent", doc=RHS_TANGENT_DOC + _how(directional.doc), loads=loads,
                                temps=temps, stores=stores)
    return alone, both


#: The docstrings of the kernels of many columns (`tangents_kernels`).
RHS_TANGENTS_DOC = (
    "The augmented rhs of m initial-state sensitivity columns, any m: y = (x, S[:, 0], ..., S[:, m-1])\n"
    "(N (1 + m),), out = (f(x), ∂f/∂y S[:, 0], ..., ∂f/∂y S[:, m-1]), m = len(y) / N − 1.  What does not\n"
    "depend on the column is computed once (f, M's factors or K, the residual's partials ∂r/∂x into the locals\n"
    "``_part<r>_<j>``); then a loop over the columns contracts the partials with each column and substitutes\n"
    "(one body whatever m: numba compiles it once).  `rhs_directional` column by column, to rounding.\n"
)
RHS_TANGENTS_PARAMETERS_DOC = (
    "The augmented rhs of m sensitivity columns, any m, some of them a parameter's: `rhs_tangents` with\n"
    "out's block c = ∂f/∂y S[:, c] + s ∂f/∂p_j where p[-1 - m + c] = j ≥ 0 (−1: an initial-state column) and\n"
    "s = p[-1] (the run's scale of S): the last m + 1 floats of p are the run's work space, after the model's\n"
    "parameters, gains, modes and tables.  `rhs_directional` along (S[:, c], s e_j) column by column, to\n"
    "rounding.\n"
)


def tangents_kernels(eom: EOM, mapping, loads) -> tuple[Kernel, Kernel]:
    """``rhs_tangents`` and ``rhs_tangents_parameters`` of `eom` (n ≤ `LARGEST_SYSTEM`): one CSE of f, M and F
    (or K and its right-hand side) and the residual's nonzero partials ∂(F − M ā)/∂x (constrained: of
    `augmented_residual`) at the solved ā (λ̄), x = (y, p), stored into locals; the emitted loop over the
    columns of S (`lagcomp.ir.DirectionalSolve.columns`) contracts them per column and substitutes by the one
    factorization of M (constrained: one ``kkt_solve_matrix`` of all columns).  ``rhs_tangents`` is the same
    CSE without the parameters' partials (the temporaries only they read left out).  A column then costs its
    contraction (the nonzero partials of the rows' products) and a substitution; the shared part about
    ``rhs_tangent``'s (ns per call, double pendulum: k = 2 66, k = 4 72, ``rhs_tangent`` 54, ``rhs`` 37).
    Measured at codegen (`lagcomp.compile`, CPU s, three fresh caches, before / after): double pendulum 0.11 /
    0.12-0.13, 5-link 0.64-0.73 / 0.72-0.78; the first run with k = 2 columns (numba compiling the kernel) 0.98
    / 0.29 s and 1.86 / 1.15 s (before: the full Jacobians' closure)."""
    n = eom.n
    size = 2 * n
    variables = (*eom.q, *eom.qd, *eom.parameters)
    velocities = [(f"out[{i}]", eom.qd[i]) for i in range(n)]
    if eom.k:
        residual, mapping, loads = augmented_residual(eom, mapping, loads)
        right = [*eom.F, *stabilized_gamma(eom)]
        rank = n + eom.k
        first = velocities + matrix_stores(eom) + [(f"_kkt[{r}, {rank}]", right[r]) for r in range(rank)]
        rows = residual_partials(residual, variables)
        solved = tuple(f"_acc{i}" for i in range(n)) + tuple(f"_mult{c}" for c in range(eom.k))
        frame = DirectionalSolve(n=n, phase_one=len(first), solved=solved, multipliers=eom.k, ydot="out")
        how = ("K (q̈, λ) = (F, γ̃), then K dz_c = Σ_j ∂(r − K z̄)/∂x_j dx_j for every column c at once at z̄ =\n"
               "(q̈, λ), K = [M −Λᵀ; Λ 0], γ̃ with the Baumgarte terms (see lagcomp.codegen.directional).\n"
               "Returns 0, or j > 0 when a factorization of K finds pivot j zero; `out` is then invalid.")
    else:
        rows, m, mapping, loads = acceleration_block(eom, variables, mapping, loads)
        f = tuple(f"_f{i}" for i in range(n))
        first = velocities + [(m[i][j], eom.M[i, j]) for i in range(n) for j in range(i + 1)]
        first += list(zip(f, eom.F, strict=True))
        frame = DirectionalSolve(n=n, phase_one=len(first), solved=tuple(f"_acc{i}" for i in range(n)), m=m, f=f,
                                 ydot="out")
        how = ("M q̈ = F, then M da_c = Σ_j ∂(F − M ā)/∂x_j dx_j at ā = q̈ by the same LDLᵀ of M, per column c\n"
               "(see lagcomp.codegen.directional).\n"
               "Returns 0, or k > 0 as `rhs` does when pivot k of M's LDLᵀ is not positive; `out` is then invalid.")
    partials = [(r, j, f"_part{r}_{j}", entry) for r, row in enumerate(rows) for j, entry in enumerate(row)
                if entry != 0]
    columns = lambda width: tuple(tuple((j, local) for rr, j, local, _ in partials if rr == r and j < width)  # noqa: E731
                                  for r in range(len(rows)))
    both = cse_kernel("rhs_tangents_parameters", RHS_TANGENTS_PARAMETERS_DOC + how, ("t", "y", "p", "out"),
                   first + [(local, entry) for _, _, local, entry in partials], mapping, loads,
                   solve=dataclasses.replace(frame, columns=columns(len(variables))))
    state = {local for _, j, local, _ in partials if j < size}
    temps, stores = _without(both.temps, tuple(store for store in both.stores[:frame.phase_one]) + tuple(
        store for store in both.stores[frame.phase_one:] if store[0] in state), set())
    used = {s.name for _, e in (*temps, *stores) for s in e.free_symbols} | set(frame.solved)
    alone = dataclasses.replace(both, name="rhs_tangents", doc=RHS_TANGENTS_DOC + how, temps=temps, stores=stores,
                                loads=tuple((local, source) for local, source in both.loads if local in used),
                                solve=dataclasses.replace(frame, columns=columns(size)))
    return alone, both


def _how(doc: str) -> str:
    """The lines of ``rhs_directional``'s docstring after the shared first ones: how it computes (M q̈ = F ...)."""
    return doc[len(RHS_DIRECTIONAL_DOC):]


def _without(temps, stores, dropped: set[str]):
    """`temps` and `stores` with the locals named in `dropped` zero: the temporaries that come out a number are
    substituted into the later ones, and those no store reads (directly or through another) are left out."""
    zero, kept = {}, []
    names = set(dropped)
    for name, expr in temps:
        image = expr.xreplace(_zeros(expr, names, zero))
        if image.is_Number:
            zero[name] = image
            names.add(name)
        else:
            kept.append((name, image))
    stores = tuple((target, expr.xreplace(_zeros(expr, names, zero))) for target, expr in stores)
    live = {s.name for _, e in stores for s in e.free_symbols}
    needed = []
    for name, expr in reversed(kept):
        if name in live:
            needed.append((name, expr))
            live |= {s.name for s in expr.free_symbols}
    return tuple(reversed(needed)), stores


def _zeros(expr, names: set[str], values: dict) -> dict:
    """{symbol of `expr` named in `names`: its value (0 for a dropped direction, the number a temporary became)}."""
    return {s: values.get(s.name, sp.S.Zero) for s in expr.free_symbols if s.name in names}


def _contracted(row, directions):
    """Σ_j row_j dx_j over the nonzero partials `row` (symengine or sympy entries), in symengine when it can."""
    terms = [(entry, d) for entry, d in zip(row, directions, strict=True) if entry != 0]
    if all(isinstance(entry, se.Basic) for entry, _ in terms):
        return sum((entry * se.sympify(d) for entry, d in terms), se.Integer(0))
    return sum((sp.sympify(entry) * d for entry, d in terms), sp.S.Zero)
