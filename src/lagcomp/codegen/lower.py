"""Lower derived equations (`EOM`) to the kernel IR, with one CSE per kernel.

Each kernel's outputs go through a single `sympy.cse` together, so that the
mass matrix and forcing of ``rhs`` share their sines, cosines and products.
Symbols are renamed to the locals the emitted code binds them to (`lagcomp.codegen.bindings.user_local`),
and ``_c0, _c1, ...`` for common subexpressions.

Names (DESIGN.md, "Two contracts of the emitted code").  A user may name a
coordinate or parameter anything; the emitted code cannot collide with it,
by construction:

- every local bound to a user symbol lies in the *user namespace*, the names
  matching `lagcomp.codegen.bindings.USER_NAMESPACE`: ``q_<name>`` for a coordinate, ``qd_<name>`` for
  its velocity, ``p_<name>`` for a parameter, ``mom_<name>`` for a conjugate
  momentum (``p_k = p[3]``), ``u_<name>``, ``ud_<name>``, ``udd_<name>``,
  ``uddd_<name>`` for an input and its derivatives (`lagcomp.codegen.bindings.input_slots`); a name
  that does not stay itself as a Python
  identifier (``x.1``, a keyword-free but NFKC-unstable ``ﬁ``, ...) becomes
  ``<prefix><i>_<its letters>`` with i its position (``p3_x_1``), which no
  identifier name reaches (a digit, not ``_``, follows the prefix letters);
- no other name the emitted modules bind or read (arguments, locals, loop
  variables, kernels, helpers, module constants, imports, the builtins they
  call) is in the user namespace: generated locals start with ``_`` or are
  the fixed names of the kernels (``t``, ``y``, ``p``, ``out``,
  ``X``, ``W``, ``k``, ``order``, ``range``, ``math``, ``np`` ...).

So a user's ``k`` is ``p_k`` in every kernel and the Taylor program's order
loop ``for k in range(order)`` cannot overwrite it.  The test
``tests/test_names.py`` checks the second half on the emitted source with
`ast`, builtins included.  The header docstring of a module keeps the
user's own names.
"""

from __future__ import annotations

from dataclasses import replace

import symengine as se
import sympy as sp

from lagcomp.codegen.bindings import (
    first_mode_slot,
    input_slots,
    symbol_bindings,
    symbol_slots,
    user_local,
)
from lagcomp.codegen.constrained_jacobian import constrained_jacobian_kernels
from lagcomp.codegen.contacts import (
    contacts_constant,
    friction_branches,
    impact_branches,
    mode_slots,
    modes_of,
    resting_kernels,
)
from lagcomp.codegen.cse import cse_kernel
from lagcomp.codegen.directional import (
    LARGEST_SYSTEM,
    directional_kernel,
    tangent_kernels,
    tangents_kernels,
)
from lagcomp.codegen.energy_lanes import energy_lanes_kernels
from lagcomp.codegen.geometry import geometry_kernel
from lagcomp.codegen.input_jacobian import input_jacobian_kernel
from lagcomp.codegen.jacobian_blocks import (
    RHS_PARAMETER_JACOBIAN_DOC,
    RHS_WITH_FULL_JACOBIAN_DOC,
    RHS_WITH_JACOBIAN_DOC,
    WITH_JACOBIAN_ARGS,
    acceleration_block,
    fresh_symbols,
    jacobian_entry,
    jacobian_only,
)
from lagcomp.codegen.kinds import ON_DEMAND
from lagcomp.codegen.power import power_kernel
from lagcomp.codegen.rounding_scale import rounding_scale
from lagcomp.codegen.stabilization import stabilized_gamma, velocity_residual
from lagcomp.ir import (
    NO_JACOBIAN,
    AugmentedSolve,
    EventResets,
    FlatMatrix,
    JacobianSolve,
    Kernel,
    LinearSolve,
    ModuleIR,
    ReturnZero,
    SymmetricProduct,
    Unavailable,
)
from lagcomp.mechanics.lagrange import EOM, kink_free_jacobian, rest_partials, symengine_ready
from lagcomp.model.inputs import is_input
from lagcomp.model.system import t

#: Largest system whose LDLᵀ solve is emitted unrolled; larger ones call a loop (`lagcomp.kernel_support.linear_solvers.ldlt_solve_inline`).
#: Unrolled, the 10-link chain's rhs costs 462 ns in a compiled loop against 635 ns looped
#: (`python -m bench --only kernels --cases n_link_pendulum_10` at aed6595 and at d880236, whose
#: limit was 8), for about 0.4 s more numba compile time of rhs (1.1 s at 12 links).
UNROLL_MAX = 12


def _spd_solve(M: sp.Matrix, rhs: list, offset: int) -> tuple[list, LinearSolve]:
    """Stores binding M (lower triangle) and the right-hand side, and the LDLᵀ solve that follows them."""
    n = M.rows
    unrolled = n <= UNROLL_MAX
    m = tuple(tuple(f"_m{i}_{j}" for j in range(i + 1)) for i in range(n))
    f = tuple(f"_f{i}" for i in range(n))
    stores = [(m[i][j], M[i, j]) for i in range(n) for j in range(i + 1)] + list(zip(f, rhs))
    zeros = frozenset((i, j) for i in range(n) for j in range(i) if M[i, j] == 0)
    return stores, LinearSolve(n=n, m=m, f=f, offset=offset, unrolled=unrolled, zeros=zeros)


def _augmented_stores(eom: EOM) -> list:
    """Stores filling ``_kkt`` = [[M, −Λᵀ, F], [Λ, 0, γ̃]], γ̃ with the Baumgarte terms.

    Unknowns (q̈, λ): M q̈ − Λᵀ λ = F and Λ q̈ = γ − 2α (Λ q̇ + b) − β² Φ.
    """
    n, k, N = eom.n, eom.k, eom.n + eom.k
    stores = [(f"_kkt[{i}, {j}]", eom.M[i, j]) for i in range(n) for j in range(n) if eom.M[i, j] != 0]
    stores += [(f"_kkt[{i}, {n + c}]", -eom.C[c, i]) for i in range(n) for c in range(k) if eom.C[c, i] != 0]
    stores += [(f"_kkt[{i}, {N}]", eom.F[i]) for i in range(n)]
    stores += [(f"_kkt[{n + c}, {j}]", eom.C[c, j]) for c in range(k) for j in range(n) if eom.C[c, j] != 0]
    return stores + [(f"_kkt[{n + c}, {N}]", gamma) for c, gamma in enumerate(stabilized_gamma(eom))]


def _constraint_kernels(eom: EOM, mapping, loads) -> tuple[Kernel, ...]:
    """rhs, reactions and both at once through the augmented system, and the constraint residuals and matrix."""
    n, k = eom.n, eom.k
    state_args = ("t", "y", "p")
    velocities = [(f"out[{i}]", eom.qd[i]) for i in range(n)]
    kh = len(eom.Phi)
    rhs = cse_kernel(
        "rhs",
        "State derivative dy/dt = (q̇, q̈), shape (2n,), from the augmented system\n"
        "M q̈ = F + Λᵀ λ, Λ q̈ = γ (Baumgarte terms from the last two entries of p).\n\n"
        "Returns 0, or j > 0 when the augmented matrix is singular (pivot j); `out` is then invalid.",
        (*state_args, "out"), velocities + _augmented_stores(eom), mapping, loads,
        solve=AugmentedSolve(size=n + k, mass_block=n, first=0, count=n, offset=n),
    )
    # the same augmented system, so the same CSE: only what is copied out differs
    reactions = replace(
        rhs, name="reactions",
        doc=f"Multipliers λ, shape ({k},), in constraint order {eom.constraint_names}: the generalized\n"
            "force each constraint exerts along its row Λ_k. Returns 0, or j > 0 when singular.",
        stores=rhs.stores[n:], solve=AugmentedSolve(size=n + k, mass_block=n, first=n, count=k, offset=0),
    )
    both = replace(
        rhs, name="rhs_and_reactions", args=(*state_args, "out", "lam"),
        doc="`rhs` into `out` and `reactions` into `lam` from one solve of the augmented system, both bitwise\n"
            "(the same code): what the Jacobian kernels start from. Returns 0, or j > 0 when singular.",
        solve=replace(rhs.solve, multipliers=True),
    )
    return (
        rhs,
        reactions,
        both,
        cse_kernel(
            "constraint_residuals",
            f"Residuals, shape ({kh + k},): Φ of the {kh} holonomic constraints, then Λ q̇ + b of all {k}.",
            (*state_args, "out"),
            [(f"out[{h}]", eom.Phi[h]) for h in range(kh)]
            + [(f"out[{kh + c}]", velocity_residual(eom, c)) for c in range(k)],
            mapping, loads,
        ),
        cse_kernel(
            "constraint_matrix",
            f"Constraint matrix [Λ | b], shape ({k}, {n + 1}), into `out`.",
            (*state_args, "out"),
            [(f"out[{c}, {j}]", eom.C[c, j]) for c in range(k) for j in range(n)]
            + [(f"out[{c}, {n}]", eom.b[c]) for c in range(k)],
            mapping, loads,
        ),
    )


def _residual_scales_kernel(eom: EOM, mapping, loads) -> Kernel:
    """``constraint_residual_scales``: the rounding scale A (`lagcomp.codegen.rounding_scale`) of each entry of
    ``constraint_residuals``, which the check of an initial state divides by (`lagcomp.integrate.constraints`).
    Eager: every run of a constrained model checks its start."""
    kh = len(eom.Phi)
    rows = list(eom.Phi) + [velocity_residual(eom, c) for c in range(eom.k)]
    return cse_kernel(
        "constraint_residual_scales",
        f"Rounding scales, shape ({kh + eom.k},), of the entries of `constraint_residuals`: each expression with\n"
        "its terms and factors in absolute value (lagcomp.codegen.rounding_scale), evaluated at the state.",
        ("t", "y", "p", "out"), [(f"out[{i}]", rounding_scale(row)) for i, row in enumerate(rows)], mapping, loads,
    )


def _velocities_kernel(eom: EOM, mapping, loads) -> Kernel:
    """q̇ from x = (q, p): solve M(q, t) q̇ = p − b(q, t) (the inverse Legendre map, numerically).

    The second half of the state argument holds the momenta here; M and b do
    not depend on q̇, so the velocity loads drop out as unused.
    """
    n = eom.n
    momenta = [sp.Symbol(user_local("mom", name, i), real=True) for i, name in enumerate(eom.system.coordinate_names)]
    loads += tuple((s.name, f"y[{n + i}]") for i, s in enumerate(momenta))
    stores, solve = _spd_solve(eom.M, [momenta[i] - eom.momentum_offset[i] for i in range(n)], offset=0)
    return cse_kernel(
        "velocities",
        "Velocities q̇, shape (n,), at x = (q, p) (here `y` holds q then the momenta p), from\n"
        "M(q, t) q̇ = p − b(q, t). Returns 0, or k > 0 when pivot k of M is not positive.",
        ("t", "y", "p", "out"), stores, mapping, loads, solve=solve,
    )


def _canonical_partials_kernel(eom: EOM, mapping, loads) -> Kernel:
    """M, P_q, R_q, R_v at y = (q, q̇): the blocks of the Jacobian of the canonical equations.

    With P(q, q̇, t) = M q̇ + b (the momenta) and r(q, q̇, t) the momentum rate,
    P_q = ∂P/∂q, R_q = ∂r/∂q and R_v = ∂r/∂q̇ are partials at fixed q̇; the
    library `lagcomp.integrate.drivers.canonical.canonical_jacobian` combines them (its docstring derives how).
    A force that jumps (Coulomb friction's sign(q̇)) contributes its derivative
    away from the jump: the DiracDelta at the jump is dropped.
    """
    n = eom.n
    if symengine_ready([*eom.momenta, *eom.momentum_rate]):
        momenta, rate = [se.sympify(e) for e in eom.momenta], [se.sympify(e) for e in eom.momentum_rate]
        q, qd = [se.sympify(x) for x in eom.q], [se.sympify(x) for x in eom.qd]
        blocks = [eom.M.tolist()] + [[[f[i].diff(x[j]) for j in range(n)] for i in range(n)]
                            for f, x in ((momenta, q), (rate, q), (rate, qd))]
    else:
        blocks = [eom.M.tolist(), kink_free_jacobian(eom.momenta, eom.q), kink_free_jacobian(eom.momentum_rate, eom.q),
                  kink_free_jacobian(eom.momentum_rate, eom.qd)]
    return cse_kernel(
        "canonical_partials",
        "At y = (q, q̇), shape (4, n, n) into `out`: out[0] = M, out[1] = ∂P/∂q, out[2] = ∂r/∂q,\n"
        "out[3] = ∂r/∂q̇ (P = M q̇ + b the momenta, r = ∂L/∂q + Q − ∂D/∂q̇ their rate; row i is\n"
        "component i, column j the variable j).",
        ("t", "y", "p", "out"),
        [(f"out[{k}, {i}, {j}]", block[i][j]) for k, block in enumerate(blocks) for i in range(n) for j in range(n)],
        mapping, loads,
    )


def _rhs_kernel(eom: EOM, mapping, loads) -> Kernel:
    """dy/dt = (q̇, q̈) of an unconstrained system, q̈ by LDLᵀ of M; stores q̇ into out[:n] first, then M, F."""
    n = eom.n
    stores, solve = _spd_solve(eom.M, list(eom.F), offset=n)
    return cse_kernel(
        "rhs",
        "State derivative dy/dt = (q̇, q̈), shape (2n,), with M(q, t) q̈ = F(q, q̇, t).\n\n"
        "Returns 0, or k > 0 when pivot k of the LDLᵀ factorization of M is not\n"
        "positive (M is singular or indefinite at this state); `out` is then invalid.",
        ("t", "y", "p", "out"), [(f"out[{i}]", eom.qd[i]) for i in range(n)] + stores, mapping, loads, solve=solve,
    )


def _rhs_jacobian_kernels(eom: EOM, mapping, loads) -> tuple[Kernel, Kernel]:
    """``rhs_with_jacobian`` and ``rhs_jacobian``: the exact Jacobian of y' = f(t, y) = (q̇, a),
    M(q, t) a = F(q, q̇, t), of an unconstrained system, with f (into ``ydot``) and without.

    Differentiating M a = F along y = (q, q̇) gives M ∂a/∂y = ∂F/∂y − ∂(M ā)/∂y |_{ā = a}: symbols ā
    for the accelerations, held fixed while differentiating (`acceleration_partials`), then bound to
    the solved values.  So the kernel calls `rhs` for a (same LDLᵀ, same pivot status), evaluates the
    (n, 2n) block with ā = a, puts it in out[n:] below the rows [0 | I] and overwrites it with M⁻¹
    times itself by one LDLᵀ of M and 2n substitutions (`JacobianSolve`).  One CSE for M and the block.
    The sensitivities need f and J at every stage: ``rhs_with_jacobian`` hands back the f it computed;
    ``rhs_jacobian`` (radau) calls it and drops f (`Delegate`), so that numba compiles the body once.
    """
    n = eom.n
    block, m, mapping, loads = acceleration_block(eom, (*eom.q, *eom.qd), mapping, loads)
    stores = [(m[i][j], eom.M[i, j]) for i in range(n) for j in range(i + 1)]
    stores += [(jacobian_entry(i, n + i, 2 * n), sp.S.One) for i in range(n)]
    stores += [(jacobian_entry(n + i, j, 2 * n), block[i][j])
               for i in range(n) for j in range(2 * n) if block[i][j] != 0]
    combined = cse_kernel(
        "rhs_with_jacobian",
        RHS_WITH_JACOBIAN_DOC +
        "Rows [0 | I], then ∂a/∂q = M⁻¹ (∂F/∂q − ∂(M ā)/∂q |ā=a), ∂a/∂q̇ = M⁻¹ ∂F/∂q̇ (a = q̈ from `rhs`).\n"
        "Returns 0, or k > 0 as `rhs` does, or when this LDLᵀ of M finds pivot k not positive (then `rhs`\n"
        "was within rounding of its threshold); `out` is then invalid.",
        WITH_JACOBIAN_ARGS, stores, mapping, loads, solve=JacobianSolve(n=n, size=2 * n, m=m, given_ydot=True),
    )
    return combined, jacobian_only(2 * n)


def _rhs_parameter_jacobian_kernel(eom: EOM, mapping, loads) -> Kernel:
    """∂f/∂p of y' = f(t, y, p) = (q̇, a), M(q, t, p) a = F(q, q̇, t, p), of an unconstrained system.

    As `_rhs_jacobian_kernels` along the parameters: M ∂a/∂p = ∂F/∂p − ∂(M ā)/∂p |_{ā = a}, the
    accelerations ā held fixed while differentiating and bound to the values `rhs` solved; q̇ does not
    depend on p, so out[:n] = 0.  One CSE for M and the (n, P) block, one LDLᵀ of M and P substitutions
    (`JacobianSolve` with ``columns`` = P).  A feedback law's gains are parameters like any other (the law is
    substituted before the derivation); inputs read from tables are not parameters and get no column.
    """
    n, width = eom.n, len(eom.parameters)
    block, m, mapping, loads = acceleration_block(eom, eom.parameters, mapping, loads)
    stores = [(m[i][j], eom.M[i, j]) for i in range(n) for j in range(i + 1)]
    stores += [(jacobian_entry(n + i, j, width), block[i][j])
               for i in range(n) for j in range(width) if block[i][j] != 0]
    return cse_kernel(
        "rhs_parameter_jacobian",
        RHS_PARAMETER_JACOBIAN_DOC +
        "Rows 0 (q̇ does not depend on p), then ∂a/∂p = M⁻¹ (∂F/∂p − ∂(M ā)/∂p |ā=a) (a = q̈ from `rhs`).\n"
        "Returns 0, or k > 0 as `rhs` does, or when this LDLᵀ of M finds pivot k not positive (then `rhs`\n"
        "was within rounding of its threshold); `out` is then invalid.",
        ("t", "y", "p", "out"), stores, mapping, loads, solve=JacobianSolve(n=n, size=2 * n, m=m, columns=width),
    )


def _rhs_with_full_jacobian_kernel(eom: EOM, mapping, loads) -> Kernel:
    """``rhs_with_full_jacobian``: `_rhs_jacobian_kernels`' rows along (q, q̇) and the parameters together,
    M ∂a/∂x = ∂(F − M ā)/∂x |_{ā = a} for x = (y, p), one CSE, one LDLᵀ of M and 2n + P substitutions
    (`JacobianSolve` with ``columns`` = 2n + P), where ``rhs_with_jacobian`` and ``rhs_parameter_jacobian`` call
    `rhs` and factor M each."""
    n, width = eom.n, 2 * eom.n + len(eom.parameters)
    block, m, mapping, loads = acceleration_block(eom, (*eom.q, *eom.qd, *eom.parameters), mapping, loads)
    stores = [(m[i][j], eom.M[i, j]) for i in range(n) for j in range(i + 1)]
    stores += [(jacobian_entry(i, n + i, width), sp.S.One) for i in range(n)]
    stores += [(jacobian_entry(n + i, j, width), block[i][j])
               for i in range(n) for j in range(width) if block[i][j] != 0]
    return cse_kernel(
        "rhs_with_full_jacobian",
        RHS_WITH_FULL_JACOBIAN_DOC +
        "Rows [0 | I | 0], then ∂a/∂x = M⁻¹ (∂F/∂x − ∂(M ā)/∂x |ā=a), x = (q, q̇, p) (a = q̈ from `rhs`).\n"
        "Returns 0, or k > 0 as `rhs` does, or when this LDLᵀ of M finds pivot k not positive (then `rhs`\n"
        "was within rounding of its threshold); `out` is then invalid.",
        WITH_JACOBIAN_ARGS, stores, mapping, loads,
        solve=JacobianSolve(n=n, size=2 * n, m=m, columns=width, given_ydot=True),
    )


def dae_size(eom: EOM) -> int:
    """N' = 3n + k + kh, the length of the DAE state z = (q, v, w, λ, μ) of a constrained system."""
    return 3 * eom.n + eom.k + len(eom.Phi)


def dae_residual(eom: EOM, w, lam, mu) -> list:
    """G(t, z), N' entries, of the index-2 DAE Mdae z' = G (Gear–Gupta–Leimkuhler), Mdae = diag(1 × 2n, 0 × rest).

    z = (q, v, w, λ, μ) with v where q̇ sits (F, M, Λ, b, Φ are evaluated at (q, v, t)); `w`, `lam`, `mu` are
    the symbols of the last three.  Rows: v + Λ_hᵀ μ (q' of the differential part, Λ_h the holonomic rows),
    w (v'), M w − F − Λᵀ λ, Λ v + b (all k rows), Φ (the kh holonomic rows).  At a solution μ = 0, w = q̈
    and λ the multipliers `reactions` returns.
    """
    n, k = eom.n, eom.k
    holonomic_rows = [c for c in range(k) if eom.holonomic[c]]
    rows = [eom.qd[i] + sum((eom.C[c, i] * m for c, m in zip(holonomic_rows, mu, strict=True)), sp.S.Zero)
            for i in range(n)]
    rows += list(w)
    rows += [sum((eom.M[i, j] * w[j] for j in range(n) if eom.M[i, j] != 0), sp.S.Zero) - eom.F[i]
             - sum((eom.C[c, i] * lam[c] for c in range(k) if eom.C[c, i] != 0), sp.S.Zero) for i in range(n)]
    rows += [velocity_residual(eom, c) for c in range(k)]
    return rows + list(eom.Phi)


def dae_jacobian(residual: list, z) -> list[list]:
    """∂G_i/∂z_j of `residual` (`dae_residual`), (N', N'), symengine's derivatives when it can (as
    `acceleration_partials`), else sympy's with a force's jump (Coulomb friction's sign(v)) contributing its
    derivative away from the jump: the DiracDelta is dropped.  Entries are symengine or sympy expressions."""
    if symengine_ready(residual):
        images, xs = [se.sympify(g) for g in residual], [se.sympify(x) for x in z]
        return [[image.diff(x) for x in xs] for image in images]
    return kink_free_jacobian(residual, z)


#: The docstrings' common ending: where the formulation is described.
DAE_SEE_ALSO = "See lagcomp.integrate.drivers.radau, DAEs."


def _dae_kernels(eom: EOM, mapping, loads) -> tuple[Kernel, Kernel]:
    """``dae_residual`` and ``dae_jacobian``: G(t, z) and ∂G/∂z of `dae_residual`, one CSE each.

    The kernels read q, v from z[:2n] with the state's loads, and w, λ, μ from z[2n:] as the locals
    ``_w<i>``, ``_lam<c>``, ``_mu<h>``, bound to fresh symbols (`fresh_symbols`).  No Baumgarte gains.
    """
    n, k, kh, size = eom.n, eom.k, len(eom.Phi), dae_size(eom)
    taken = {s.name for s in (*eom.q, *eom.qd, *eom.parameters, t)}
    taken |= {s.name for e in (*eom.M, *eom.F, *eom.C, *eom.b, *eom.Phi) for s in e.free_symbols}
    unknowns = {"_w": (n, 2 * n), "_lam": (k, 3 * n), "_mu": (kh, 3 * n + k)}  # locals' stem: count, index in z
    symbols = {stem: fresh_symbols(stem, count, taken) for stem, (count, _) in unknowns.items()}
    mapping = {**mapping, **{s: sp.Symbol(f"{stem}{i}", real=True)
                             for stem, group in symbols.items() for i, s in enumerate(group)}}
    loads = loads + tuple((f"{stem}{i}", f"y[{first + i}]") for stem, (count, first) in unknowns.items()
                          for i in range(count))
    residual = dae_residual(eom, *symbols.values())
    jacobian = dae_jacobian(residual, (*eom.q, *eom.qd, *(s for group in symbols.values() for s in group)))
    layout = f"z = (q, v, w, λ, μ), DAE_SIZE = {size} (n = {n}, k = {k}, kh = {kh}); λ has the sign of `reactions`.\n"
    return (
        cse_kernel(
            "dae_residual",
            "Residual G(t, z), shape (DAE_SIZE,), of the constrained system as the index-2 DAE Mdae z' = G(t, z),\n"
            "Mdae = diag(1 × 2n, 0 × (n + k + kh)): rows v + Λ_hᵀ μ, w, M w − F − Λᵀ λ, Λ v + b, Φ.\n"
            + layout + f"Returns 0. {DAE_SEE_ALSO}",
            ("t", "y", "p", "out"), [(f"out[{i}]", g) for i, g in enumerate(residual)], mapping, loads,
            solve=ReturnZero(),
        ),
        cse_kernel(
            "dae_jacobian",
            "Exact Jacobian out[i, j] = ∂G_i/∂z_j, (DAE_SIZE, DAE_SIZE), of `dae_residual` (symbolic, no\n"
            "differences), every entry written.\n" + layout + f"Returns 0. {DAE_SEE_ALSO}",
            ("t", "y", "p", "out"),
            [(jacobian_entry(i, j, size), entry)
             for i, row in enumerate(jacobian) for j, entry in enumerate(row) if entry != 0],
            mapping, loads, solve=FlatMatrix(size=size),
        ),
    )


#: The lane kernel's arrays (structure of arrays): ``Y[i, _l]`` is ``y[i]`` of lane ``_l``, ``P[k, _l]`` its ``p[k]``.
LANE_ARRAYS = {"y": "Y", "p": "P"}


def _rhs_lanes_kernel(rhs: Kernel, eom: EOM) -> Kernel:
    """`rhs` over a batch of trajectories in lock-step (one SIMD lane each), from the same CSE.

    The same loads, temporaries and stores, each lane reading its own column: a local bound to
    ``y[i]`` (`symbol_slots`) reads ``Y[i, _l]``, one bound to ``p[k]`` reads ``P[k, _l]``, and the
    velocities q̇_i that `_rhs_kernel` stores first, into ``out[i]``, go to ``out[i, _l]`` (the
    solve's q̈ too: `Kernel.lanes`).  Only for unrolled solves (n ≤ UNROLL_MAX): the looped LDLᵀ
    would need a work array per lane.  Each lane has its own time (adaptive steps).
    """
    n = rhs.solve.n
    uses_t = any(sp.Symbol("t", real=True) in e.free_symbols for _, e in rhs.temps + rhs.stores)
    columns = {local: f"{LANE_ARRAYS[array]}[{index}, _l]" for _, local, array, index in symbol_slots(eom)}
    velocities = tuple((f"out[{i}, _l]", expr) for i, (_, expr) in enumerate(rhs.stores[:n]))
    return replace(
        rhs, name="rhs_lanes", args=("T", "Y", "P", "out", "bad"), lanes=True,
        doc="dy/dt of `rhs` for every lane l: T (B,) times, Y (2n, B) states, P (n_p, B) parameters,\n"
            f"out (2n, B); bad[l] is set when M is singular in lane l (n = {n}).",
        loads=(("t", "T[_l]"),) * uses_t + tuple((local, columns[local]) for local, _ in rhs.loads),
        stores=velocities + rhs.stores[n:],
    )


def _momenta_kernel(eom: EOM, mapping, loads) -> Kernel:
    """p = M q̇ + b; for n > UNROLL_MAX the product is a loop (`SymmetricProduct`) over the entries
    of M, which halves the operations numba compiles (a 24-link chain: 2400 -> 1220)."""
    n, doc, args = eom.n, "Conjugate momenta ∂L/∂q̇_i, shape (n,), into `out`.", ("t", "y", "p", "out")
    if n <= UNROLL_MAX:
        return cse_kernel("momenta", doc, args, [(f"out[{i}]", eom.momenta[i]) for i in range(n)], mapping, loads)
    stores, solve = _spd_solve(eom.M, list(eom.momentum_offset), offset=0)
    solve = SymmetricProduct(n=n, m=solve.m, f=solve.f, start=n, offset=0)
    return cse_kernel("momenta", doc, args, stores, mapping, loads, solve=solve)


def _energy_function_kernel(eom: EOM, mapping, loads) -> Kernel:
    """h = Σ q̇_i ∂L/∂q̇_i − L; when it is T + V (T homogeneous quadratic in q̇), the `energy` kernel itself."""
    doc = "Energy function (Jacobi integral) h = Σ q̇_i ∂L/∂q̇_i − L."
    if eom.energy_function == eom.energy:
        doc += "\nHere T is homogeneous quadratic in q̇, so h = T + V: the kernel `energy`."
        return Kernel(name="energy_function", doc=doc, args=("t", "y", "p"), loads=(), temps=(), stores=(),
                      alias="energy")
    return cse_kernel("energy_function", doc, ("t", "y", "p"), [("return", eom.energy_function)], mapping, loads)


def _event_kernel(eom: EOM, mapping, loads) -> Kernel:
    """The event functions g_e(t, q, q̇), all at once (a kernel with no stores when there are none); with contact
    modes, a closed contact's value is its normal force (`lagcomp.ir.ContactModes`)."""
    names = eom.system.event_names
    doc = f"Event functions g, shape ({len(names)},), in order {names}, into `out`; the drivers locate their zeros."
    solve = None
    if mode_slots(eom):
        solve = modes_of(eom, "events", first_mode_slot(eom))
        if solve.events:
            doc += ("\nA closed contact's value is its normal force (contact_forces): its lift-off when it turns "
                    "negative.")
        if solve.frictions:
            doc += ("\nA friction element's value is s·v while it slips (mode s = ±1: v reaching 0), μs |N| − |λ_f| "
                    "while it sticks\n(friction_limits, contact_forces: the force needed reaching its limit).")
    return cse_kernel("event_values", doc, ("t", "y", "p", "out"), [(f"out[{e}]", g) for e, g in enumerate(eom.events)],
                   mapping, loads, solve=solve)


def event_reset_kernel(names: tuple[str, ...], resets: tuple, size: int, mapping, loads, restitutions=(),
                       impacts=(), switches=()) -> Kernel:
    """``event_reset(t, y, p, e, out) -> int``: the state just after event e into `out` (size `size`): y, with
    what e's reset sets (`resets[e]`: ((state index, value over the state before the event), ...)) overwritten,
    or the contacts' impact (`impacts`: the branch of `lagcomp.codegen.contacts.impact_branches`; `restitutions`
    per event, None for an event that is not a contact, give the module's ``CONTACTS``), or a friction element's
    switch of mode (`switches`: `lagcomp.codegen.contacts.friction_branches`).
    Returns 0 or the impact solver's status.  Shared by the Lagrange and Kane modules (their `mapping` and
    `loads`)."""
    branches = tuple(
        (e, cse_kernel("event_reset", "", ("t", "y", "p", "e", "out"), [(f"out[{i}]", v) for i, v in reset], mapping,
                    loads))
        for e, reset in enumerate(resets) if reset) + tuple(impacts) + tuple(switches)
    reset_names = [names[e] for e, reset in enumerate(resets) if reset]
    contact_names = [names[e] for events, _ in impacts for e in events]
    doc = (f"The state just after event e into `out`, shape ({size},): `y`, the state just before, with what the\n"
           f"reset of e sets (events with a reset: {reset_names}; the others leave y as it is). Returns 0.\n"
           "Drivers pass a p of their own run: a contact's reset writes its mode slots there.")
    if contact_names:
        doc += (f"\nThe contacts {contact_names} change the velocities by their impact (Newton's restitution,\n"
                "simultaneous impacts solved together); a negative return is the impact solver's failure\n"
                "(lagcomp.kernel_support.impacts).")
    if any(branch.solve.modes is not None for _, branch in impacts):
        doc += ("\nWith modes in p (CONTACT_MODES): a closed contact's event opens it (lift-off), an impact may\n"
                "close one (lagcomp.kernel_support.resting.contact_event); the reset writes them into p.")
    if switches:
        doc += ("\nA friction element's event switches its mode in p (FRICTIONS; lagcomp.kernel_support.resting."
                "friction_mode_after),\nthe state unchanged.")
    switching = {e for e, _ in switches}
    resetting = tuple(names[e] for e, restitution in enumerate(restitutions or (None,) * len(names))
                      if resets[e] or restitution is not None or e in switching)
    return Kernel(name="event_reset", doc=doc, args=("t", "y", "p", "e", "out"), loads=(), temps=(), stores=(),
                  solve=EventResets(size=size, branches=branches),
                  constants=(("RESET_EVENTS", "The events whose reset event_reset applies, the contacts' impacts "
                              "included (none: the drivers take a library kernel that copies y, which numba has "
                              "compiled already).", resetting),) + contacts_constant(names, restitutions))


#: Why a module whose events read inputs has no event partials (its ``EVENT_GRADIENTS_REFUSED``).
EVENTS_WITH_INPUTS_REFUSED = ("events that read inputs: ∂g/∂t would need the inputs' derivatives, which a linear "
                              "table does not have")


def _event_gradients_kernel(eom: EOM, mapping, loads) -> Kernel:
    """The partial derivatives of the event functions, (E, N + 1 + P): ∂g_e/∂y (y = (q, q̇)), ∂g_e/∂t, ∂g_e/∂p.

    For the sensitivities of an event's time (`lagcomp.integrate.sensitivities.event_sensitivities`):
    dt*/dw = −(∂g/∂y · ∂y/∂w + ∂g/∂p_w) / (∂g/∂y · f + ∂g/∂t).  One CSE; no stores without events.  Events
    that read an input get a refusing stub (`EVENTS_WITH_INPUTS_REFUSED`): their u̇ would raise the order every
    table of the input must have (`_input_orders`), in runs without sensitivities too.
    """
    names, size, width = eom.system.event_names, 2 * eom.n, 2 * eom.n + 1 + len(eom.parameters)
    doc = (f"Partials of the event functions {names}, shape ({len(names)}, {width}), into `out`: row e is event e,\n"
           f"columns ∂g_e/∂y_j (y = (q, q̇), {size} of them), then ∂g_e/∂t, then ∂g_e/∂p_j for the model's\n"
           "parameters (symbolic, no differences; the sensitivities of the events' times).\n")
    if any(is_input(u) for g in eom.events for u in g.atoms(sp.core.function.AppliedUndef)):
        return Kernel(
            name="event_gradients",
            doc=doc + f"Not available for this system: {EVENTS_WITH_INPUTS_REFUSED}.\nWrites nothing and returns "
                f"NO_JACOBIAN = {NO_JACOBIAN} (EVENT_GRADIENTS_REFUSED says why).",
            args=("t", "y", "p", "out"), loads=(), temps=(), stores=(),
            solve=Unavailable(status=NO_JACOBIAN, constant="EVENT_GRADIENTS_REFUSED",
                              reason=EVENTS_WITH_INPUTS_REFUSED),
        )
    variables = (*eom.q, *eom.qd, t, *eom.parameters)
    stores = [(f"out[{e}, {j}]", g.diff(v)) for e, g in enumerate(eom.events) for j, v in enumerate(variables)]
    return cse_kernel("event_gradients", doc + "Returns 0.", ("t", "y", "p", "out"), stores, mapping, loads,
                   solve=ReturnZero())


def _rest_partials_kernel(eom: EOM, mapping, loads) -> Kernel:
    """∂F/∂q and ∂F/∂q̇ at rest (q̇ = 0), for equilibria and small oscillations (`lagcomp.analysis`).

    Built from `rest_partials`, which avoids differentiating the full F (about
    10 s of sympy for a 10-link chain, 0.2 s its way).
    """
    n = eom.n
    blocks = [block.replace(sp.DiracDelta, lambda *args: sp.S.Zero) for block in rest_partials(eom)]
    return cse_kernel(
        "rest_partials",
        "At (q, q̇ = 0, t), shape (2, n, n) into `out`: out[0] = ∂F/∂q, out[1] = ∂F/∂q̇ (row i is F_i,\n"
        "column j the variable j). The velocities in `y` are ignored: the partials are those at rest.",
        ("t", "y", "p", "out"),
        [(f"out[{k}, {i}, {j}]", block[i, j]) for k, block in enumerate(blocks) for i in range(n) for j in range(n)],
        mapping, loads,
    )


def _directional_kernels(eom: EOM, mapping, loads) -> tuple[Kernel, ...]:
    """(``rhs_directional``, ``rhs_tangent``, ``rhs_tangent_parameters``, ``rhs_tangents``,
    ``rhs_tangents_parameters``) for systems of at most `lagcomp.codegen.directional.LARGEST_SYSTEM` coordinates,
    () for larger ones, whose sensitivities take the full Jacobians."""
    if eom.n > LARGEST_SYSTEM:
        return ()
    directional = directional_kernel(eom, mapping, loads)
    return (directional, *tangent_kernels(directional, len(eom.parameters)), *tangents_kernels(eom, mapping, loads))


#: What `lower` builds besides one kind (`lagcomp.codegen.kinds`, and "motion", the kernels ``rhs`` comes with):
#: the kernels of every kind, or those of the eager module.
PARTS = ("all", "eager")


def lower(eom: EOM, part: str = "all") -> ModuleIR:
    """Build the IR of the module for `eom`: rhs, its Jacobians ∂f/∂y and ∂f/∂p (for n ≤
    `lagcomp.codegen.directional.LARGEST_SYSTEM` both at once too) and its directional derivative (that n
    only), mass_matrix, forcing, energies,
    momenta, and for constrained systems reactions and their Jacobian (`lagcomp.codegen.constrained_jacobian`),
    constraint residuals and matrix, and the DAE's residual and Jacobian; last the bodies' `geometry`
    (`lagcomp.codegen.geometry`).

    `part` chooses which kinds are lowered (`lagcomp.codegen.kinds`): "all" every kernel, "eager" the kernels
    of the eager module, the name of an on-demand kind (or "motion": ``rhs`` and what the same CSE gives) that
    kind's kernels alone.  A kernel is the same whichever part it is lowered in.
    """
    on_demand = {kind.name for kind in ON_DEMAND}
    if part not in PARTS and part not in on_demand and part != "motion":
        raise ValueError(f"part must be one of {PARTS}, 'motion' or an on-demand kind {sorted(on_demand)}, "
                         f"got {part!r}")
    mapping, loads = symbol_bindings(eom)
    wanted = {"all": lambda kind: True, "eager": lambda kind: kind not in on_demand}.get(part, part.__eq__)
    kernels = tuple(kernel for kind, build in _builders(eom, mapping, loads) if wanted(kind) for kernel in build())
    system = eom.system
    return ModuleIR(
        system_name=system.name, description=system.description,
        coordinate_names=system.coordinate_names, parameter_names=system.parameter_names,
        kernels=kernels, constraint_names=eom.constraint_names, holonomic=eom.holonomic,
        event_names=system.event_names, input_names=system.input_names, input_orders=_input_orders(eom, kernels),
    )


def _builders(eom: EOM, mapping, loads) -> list:
    """(kind, build) for every kernel of `eom`, in module order: build() returns the kind's kernels (lowered when
    called: `lower` calls only the builders of the kinds it wants).  Kinds are those of `lagcomp.codegen.kinds`,
    "motion" (rhs and what the same CSE gives) and "eager" (the rest of the eager module)."""
    n = eom.n
    rhs = _once(lambda: _rhs_kernel(eom, mapping, loads))

    def kernel(name, doc, args, stores, solve=None):
        return cse_kernel(name, doc, args, stores, mapping, loads, solve=solve)

    if eom.k:
        first = [("motion", lambda: _constrained_motion(eom, mapping, loads, kernel)),
                 ("eager", lambda: (_residual_scales_kernel(eom, mapping, loads),)),
                 ("jacobians", lambda: constrained_jacobian_kernels(eom, mapping, loads)),
                 ("directional", lambda: _directional_kernels(eom, mapping, loads)),
                 ("dae", lambda: _dae_kernels(eom, mapping, loads))]
    elif mode_slots(eom):   # contacts that may close: rhs is rhs_free corrected for them (no lanes: they reset;
        # no directional kernels: sensitivities refuse contacts)
        def motion():
            free = _rhs_kernel(eom, mapping, loads)
            free = replace(free, name="rhs_free", doc="The motion without contacts (all open): " + free.doc)
            return (*resting_kernels(eom, t, first_mode_slot(eom), kernel), free)
        first = [("motion", motion), ("jacobians", lambda: (*_rhs_jacobian_kernels(eom, mapping, loads),
                                                             _rhs_parameter_jacobian_kernel(eom, mapping, loads)))]
    else:
        # no lanes with inputs: each lane would read its own tables, which a SIMD loop cannot
        lanes = n <= UNROLL_MAX and not eom.system.inputs   # (rhs's LDLᵀ is unrolled: `_spd_solve`)
        first = [("motion", lambda: (rhs(),)), ("lanes", lambda: (_rhs_lanes_kernel(rhs(), eom),) if lanes else ()),
                 ("jacobians", lambda: (*_rhs_jacobian_kernels(eom, mapping, loads),
                                        _rhs_parameter_jacobian_kernel(eom, mapping, loads))
                  + ((_rhs_with_full_jacobian_kernel(eom, mapping, loads),) if n <= LARGEST_SYSTEM else ())),
                 ("directional", lambda: _directional_kernels(eom, mapping, loads) if n <= LARGEST_SYSTEM else ())]
    energy = _once(lambda: kernel("energy", "Total mechanical energy T + V.", ("t", "y", "p"),
                                  [("return", eom.energy)]))
    energy_function = _once(lambda: _energy_function_kernel(eom, mapping, loads))
    # a summary's energies over many rows (no inputs: each row would read the tables through a call, which keeps
    # the loop scalar; above UNROLL_MAX a second copy of a long energy costs its compile on a first summary)
    summary_lanes = n <= UNROLL_MAX and not eom.system.inputs
    return first + [
        ("eager", lambda: (kernel("mass_matrix", "Mass matrix M(q, t) = ∂²T/∂q̇², shape (n, n), into `out`.",
                                  ("t", "y", "p", "out"),
                                  [(f"out[{i}, {j}]", eom.M[i, j]) for i in range(n) for j in range(n)]),
                           kernel("forcing", "Forcing F(q, q̇, t) of M q̈ = F, shape (n,), into `out`.",
                                  ("t", "y", "p", "out"), [(f"out[{i}]", eom.F[i]) for i in range(n)]),
                           energy(), energy_function(), _momenta_kernel(eom, mapping, loads))),
        ("canonical", lambda: (kernel(
            "momentum_rate",
            "ṗ = ∂L/∂q + Q − ∂D/∂q̇ at y = (q, q̇), shape (n,), into `out`: Hamilton's −∂H/∂q plus forces.",
            ("t", "y", "p", "out"), [(f"out[{i}]", eom.momentum_rate[i]) for i in range(n)]),)),
        ("eager", lambda: (_event_kernel(eom, mapping, loads), _event_gradients_kernel(eom, mapping, loads),
                           _event_reset_kernel(eom, mapping, loads))),
        ("analysis", lambda: (_rest_partials_kernel(eom, mapping, loads),)),
        ("canonical", lambda: () if eom.k else (_velocities_kernel(eom, mapping, loads),
                                                _canonical_partials_kernel(eom, mapping, loads))),
        ("geometry", lambda: (geometry_kernel(eom, lambda name, doc, args, stores: kernel(name, doc, args, stores)),)),
        ("power", lambda: (power_kernel(eom, mapping, loads),)),
        ("input_jacobian", lambda: () if eom.k or mode_slots(eom) or not eom.system.inputs
         else (input_jacobian_kernel(eom, mapping, loads),)),
        ("energy_lanes", lambda: energy_lanes_kernels(energy(), energy_function(), eom) if summary_lanes else ()),
    ]


def _constrained_motion(eom: EOM, mapping, loads, kernel) -> tuple[Kernel, ...]:
    """The motion kernels of a constrained system (`_constraint_kernels`); with contacts, ``rhs`` and ``reactions``
    read their modes: ``rhs_free`` and ``reactions_free`` are the motion without contacts, ``closed_contacts``
    holds the closed contacts beside the constraints (`lagcomp.ir.ContactModes`), ``reactions`` adds the change
    of the multipliers they cause.  ``rhs_and_reactions`` (what the Jacobians start from) stays the motion without
    contacts, as an unconstrained module's Jacobians are those of ``rhs_free``."""
    kernels = _constraint_kernels(eom, mapping, loads)
    if not mode_slots(eom):
        return kernels
    rhs, reactions, *rest = kernels
    first = first_mode_slot(eom)
    free = replace(rhs, name="rhs_free", doc="The motion without contacts (all open): " + rhs.doc)
    reactions_free = replace(reactions, name="reactions_free",
                             doc="The multipliers without contacts (all open): " + reactions.doc)
    with_contacts = kernel("reactions", reactions.doc + "\nWhile some contact is closed (its mode p[first + d] = 1), "
                           "with the change its normal force\ncauses (closed_contacts: the constraints' rows held "
                           "beside the contacts').", ("t", "y", "p", "out"), [], modes_of(eom, "reactions", first))
    return (*resting_kernels(eom, t, first, kernel), with_contacts, free, reactions_free, *rest)


def _once(build):
    """`build`, called at most once: later calls return its first result (a kernel two kinds start from)."""
    done = []

    def call():
        if not done:
            done.append(build())
        return done[0]
    return call


def _event_reset_kernel(eom: EOM, mapping, loads) -> Kernel:
    """``event_reset`` of `eom`: its events' resets, the contacts' impacts and the friction elements' switches."""
    def kernel(name, doc, args, stores, solve):
        return cse_kernel(name, doc, args, stores, mapping, loads, solve=solve)

    first = first_mode_slot(eom) if mode_slots(eom) else None
    return event_reset_kernel(eom.system.event_names, eom.resets, 2 * eom.n, mapping, loads, eom.restitutions,
                              impact_branches(eom, eom.restitutions, t, kernel, first),
                              friction_branches(eom, first_mode_slot(eom), kernel))


def _input_orders(eom: EOM, kernels) -> tuple[int, ...]:
    """The highest derivative of each input that some kernel reads (−1: none reads it)."""
    read = {local for kernel in kernels for local, _ in kernel.loads}
    highest = {u: -1 for u in eom.system.inputs}
    for u, order, local, _ in input_slots(eom):
        if local in read:
            highest[u] = max(highest[u], order)
    return tuple(highest[u] for u in eom.system.inputs)
