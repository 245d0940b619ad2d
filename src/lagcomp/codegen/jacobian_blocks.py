"""The pieces every exact-Jacobian kernel is built from, whatever the family (unconstrained, constrained,
directional, Kane): the residual's partials at held accelerations (`acceleration_partials`,
`acceleration_block`), fresh symbols that cannot merge with a model's, the flat store targets and the
shared arguments and docstrings of the ``rhs_*jacobian`` kernels.
"""

from __future__ import annotations

import symengine as se
import sympy as sp

from lagcomp.ir import Delegate, Kernel
from lagcomp.mechanics.lagrange import EOM, kink_free_jacobian, symengine_ready
from lagcomp.model.system import t


def fresh_symbols(stem: str, count: int, taken: set[str]) -> tuple[sp.Symbol, ...]:
    """`count` real symbols ``<stem>0, <stem>1, ...``, each name lengthened by ``_`` until no name in `taken`
    has it (symengine tells symbols apart by name only: a model symbol of the same name would merge with it)."""
    symbols = []
    for i in range(count):
        name = f"{stem}{i}"
        while name in taken:
            name += "_"
        symbols.append(sp.Symbol(name, real=True))
    return tuple(symbols)


def jacobian_entry(i: int, j: int, size: int) -> str:
    """The store target of entry (i, j) of an ``rhs_jacobian``, ``rhs_parameter_jacobian`` or ``dae_jacobian``:
    the flat work array ``_jac``, row-major, rows of `size` entries.

    Stores into a 1-D local array compile several times faster than into the 2-D `out`: the
    24-link chain's kernel took numba 16 s that way against 48 s (`JacobianSolve`).
    """
    return f"_jac[{i * size + j}]"


def acceleration_partials(M, F, accelerations, variables) -> list[list]:
    """R_ij = ∂(F_i − Σ_k M_ik ā_k)/∂x_j for the symbols ā = `accelerations` held fixed, shape (rows of F, len(x)).

    At ā = a, the solution of M a = F, differentiating M a = F gives M ∂a/∂x = R: the Jacobian of the
    accelerations is M⁻¹ R (the `rhs_jacobian` kernels).  symengine differentiates when it can (as in
    `lagcomp.codegen.lower._canonical_partials_kernel`); otherwise sympy, and a force that jumps (Coulomb friction's sign(q̇))
    contributes its derivative away from the jump: the DiracDelta at the jump is dropped.
    Entries are symengine or sympy expressions (`cse_kernel` takes either).
    """
    rows, columns = M.rows, len(accelerations)
    if not variables:   # a model without parameters: its (n, 0) parameter block (sympy's jacobian refuses no x)
        return [[] for _ in range(rows)]
    if symengine_ready([*M, *F]):   # the residual built in symengine too: sympy's additions took 0.26 s at 24 links
        bars, xs = [se.sympify(a) for a in accelerations], [se.sympify(x) for x in variables]
        images = [se.sympify(F[i]) - sum((se.sympify(M[i, k]) * bars[k] for k in range(columns) if M[i, k] != 0),
                                         se.Integer(0))
                  for i in range(rows)]
        return [[image.diff(x) for x in xs] for image in images]
    residual = [F[i] - sum((M[i, k] * accelerations[k] for k in range(columns) if M[i, k] != 0), sp.S.Zero)
                for i in range(rows)]
    return kink_free_jacobian(residual, variables)


#: The docstring of every ``rhs_jacobian`` kernel: what it computes; `lagcomp.codegen.lower` adds how.
RHS_JACOBIAN_DOC = (
    "Exact Jacobian out[i, j] = ∂f_i/∂y_j, (N, N), of y' = f(t, y) as `rhs` computes it (symbolic, no differences).\n"
)


#: The arguments of every ``rhs_with_jacobian`` kernel: f goes into ``ydot`` (N,), J into ``out`` (N, N).
WITH_JACOBIAN_ARGS = ("t", "y", "p", "ydot", "out")


#: The docstring of every ``rhs_with_jacobian`` kernel: what it computes; the emitters add how.
RHS_WITH_JACOBIAN_DOC = (
    "f and its exact Jacobian at once: ydot = f(t, y) as `rhs` computes it (bitwise), out[i, j] = ∂f_i/∂y_j,\n"
    "(N, N), symbolic, no differences (what `rhs_jacobian` returns, bitwise).\n"
)


def jacobian_only(size: int) -> Kernel:
    """``rhs_jacobian``: ``rhs_with_jacobian`` with f dropped (`Delegate`), the same values bitwise."""
    return Kernel(
        name="rhs_jacobian",
        doc=RHS_JACOBIAN_DOC + "The Jacobian `rhs_with_jacobian` computes, its f dropped; its statuses.",
        args=("t", "y", "p", "out"), loads=(), temps=(), stores=(),
        solve=Delegate(kernel="rhs_with_jacobian", scratch=size),
    )


def acceleration_block(eom: EOM, variables, mapping, loads) -> tuple:
    """R = ∂(F − M ā)/∂x for x = `variables` (`acceleration_partials`, (n, len(x))), the locals of M's lower
    triangle, and `mapping`, `loads` extended by the symbols ā bound to the locals ``_acc<i>`` = ``_ydot[n + i]``
    (the accelerations `rhs` solved; `JacobianSolve` calls it first)."""
    n = eom.n
    taken = {s.name for s in (*eom.q, *eom.qd, *eom.parameters, t)}
    taken |= {s.name for e in (*eom.M, *eom.F) for s in e.free_symbols}
    accelerations = fresh_symbols("_acc", n, taken)
    locals_ = [f"_acc{i}" for i in range(n)]
    mapping = {**mapping, **{a: sp.Symbol(local, real=True) for a, local in zip(accelerations, locals_, strict=True)}}
    loads = loads + tuple((local, f"_ydot[{n + i}]") for i, local in enumerate(locals_))
    m = tuple(tuple(f"_m{i}_{j}" for j in range(i + 1)) for i in range(n))
    return acceleration_partials(eom.M, eom.F, accelerations, variables), m, mapping, loads


#: The docstring of every ``rhs_parameter_jacobian`` kernel: what it computes; `lagcomp.codegen.lower`
#: adds how.
RHS_PARAMETER_JACOBIAN_DOC = (
    "Exact parameter Jacobian out[i, j] = ∂f_i/∂p_j, (N, P), of y' = f(t, y, p) as `rhs` computes it (symbolic,\n"
    "no differences): P = the model's parameters, in the order of p (not the Baumgarte gains nor the\n"
    "inputs' tables that follow them).\n"
)


#: The docstring of every ``rhs_with_full_jacobian`` kernel: what it computes; the emitters add how.
RHS_WITH_FULL_JACOBIAN_DOC = (
    "f and both its exact Jacobians at once: ydot = f(t, y) as `rhs` computes it (bitwise), out (N, N + P) =\n"
    "[∂f/∂y | ∂f/∂p] (what `rhs_with_jacobian` and `rhs_parameter_jacobian` give, to rounding: another CSE), P the\n"
    "model's parameters in the order of p; one solve for f, one factorization for both (the sensitivities' kernel\n"
    "for parameter columns).\n"
)
