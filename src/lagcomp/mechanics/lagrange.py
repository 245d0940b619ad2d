r"""Lagrange's equations of a `System`, derived symbolically (sympy only).

The one normal form lagcomp produces
------------------------------------
With T(q, q̇, t) at most quadratic in q̇, Lagrange's equations

    A_i = d/dt ∂T/∂q̇_i − ∂T/∂q_i = Q_i − ∂V/∂q_i − ∂D/∂q̇_i

are linear in the accelerations and are written

    M(q, t) q̈ = F(q, q̇, t)

    M_ij = ∂²T / ∂q̇_i ∂q̇_j                                  (symmetric)
    F_i  = Q_i − ∂V/∂q_i − ∂D/∂q̇_i + ∂T/∂q_i
           − Σ_j (∂²T/∂q̇_i ∂q_j) q̇_j − ∂²T/∂q̇_i ∂t

so F collects every term of the equation that does not multiply q̈: applied
and conservative forces, dissipation, and the velocity- and time-dependent
inertial terms (Coriolis, centrifugal, imposed-motion terms).

Also derived: the conjugate momenta p_i = ∂L/∂q̇_i (L = T − V), the energy
function (Jacobi integral) h = Σ q̇_i ∂L/∂q̇_i − L — the Hamiltonian H(q, p, t)
written in (q, q̇) — which is conserved when L
does not depend on t explicitly and Q = 0, D = 0; the total mechanical energy
E = T + V (equal to h when T is homogeneous quadratic in q̇); and the cyclic
coordinates, those absent from L with no force acting along them, whose
momenta are conserved.

Constraints
-----------
Constraint k is Λ_k(q, t)·q̇ + b_k(q, t) = 0; a holonomic Φ_k(q, t) = 0 gives
Λ_k = ∂Φ_k/∂q and b_k = ∂Φ_k/∂t.  With multipliers λ the equations become

    M q̈ = F + Λᵀ λ,        Λ q̈ = γ,    γ = −(dΛ/dt q̇ + db/dt)

(the second is the constraint differentiated once more in time, its ∂/∂t
terms included).  λ_k is the generalized force the constraint exerts along
row Λ_k — the reaction — in the units set by how the constraint is written.

Expressions here use plain symbols: `EOM.q[i]` for q_i(t) and `EOM.qd[i]`
for q̇_i(t), never functions of t, so that later stages see ordinary algebra.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp
from sympy.simplify.fu import TR5, TR10i

from lagcomp.errors import ModelError, SingularMassMatrixError
from lagcomp.model.constraints import Holonomic
from lagcomp.model.system import System, t


#: Expressions with more operations than this are not simplified (see `_tidy`).
TIDY_MAX_OPS = 300


@dataclass(frozen=True)
class EOM:
    """Equations of motion M(q, t) q̈ = F(q, q̇, t) and the derived quantities.

    Attributes
    ----------
    system : System
        The description these were derived from.
    q, qd : tuple of Symbol
        Plain symbols standing for q_i(t) and q̇_i(t).
    parameters : tuple of Symbol
        Parameters in kernel order.
    M : Matrix, shape (n, n)
        Mass matrix, symmetric, depends on q and t only.
    F : Matrix, shape (n, 1)
        Forcing: everything but M q̈ (sign convention in the module docstring).
    T, V, L : Expr
        Kinetic and potential energy and the Lagrangian, in plain symbols.
    energy : Expr
        Total mechanical energy T + V.
    energy_function : Expr
        Jacobi integral h = Σ q̇_i ∂L/∂q̇_i − L.
    momenta : Matrix, shape (n, 1)
        Conjugate momenta ∂L/∂q̇_i.
    cyclic : tuple of str
        Names of cyclic coordinates (∂L/∂q_i = 0 and Q_i = 0, ∂D/∂q̇_i = 0).
    constraint_names : tuple of str
        Constraint names, the row order of Λ, b, γ and λ.
    holonomic : tuple of bool
        Which constraints are holonomic.
    Phi : Matrix, shape (k_h, 1)
        Position residuals Φ(q, t) of the holonomic constraints, in order.
    C : Matrix, shape (k, n)
        Constraint matrix Λ(q, t).
    b : Matrix, shape (k, 1)
        Velocity-constraint offsets b(q, t).
    gamma : Matrix, shape (k, 1)
        Right-hand side of the acceleration-level constraints Λ q̈ = γ.
    separable : bool
        Whether explicit symplectic methods apply: no constraints, M constant
        (free of q and t) and F free of q̇, i.e. H = ½ pᵀ M⁻¹ p + V(q, t)
        with forces depending on q and t only.
    momentum_offset : Matrix, shape (n, 1)
        b(q, t) in p = M q̇ + b (momenta are affine in q̇).
    momentum_rate : Matrix, shape (n, 1)
        ṗ = ∂L/∂q + Q − ∂D/∂q̇ as a function of (q, q̇, t): with q̇ from
        M q̇ = p − b this is Hamilton's ṗ = −∂H/∂q (+ non-conservative forces).
    events : tuple of Expr
        The event functions g(q, q̇, t) of `System.events`, in order.
    """

    system: System
    q: tuple
    qd: tuple
    parameters: tuple
    M: sp.Matrix
    F: sp.Matrix
    T: sp.Expr
    V: sp.Expr
    L: sp.Expr
    energy: sp.Expr
    energy_function: sp.Expr
    momenta: sp.Matrix
    cyclic: tuple
    constraint_names: tuple
    holonomic: tuple
    Phi: sp.Matrix
    C: sp.Matrix
    b: sp.Matrix
    gamma: sp.Matrix
    separable: bool
    momentum_offset: sp.Matrix
    momentum_rate: sp.Matrix
    events: tuple = ()

    @property
    def n(self) -> int:
        return len(self.q)

    @property
    def k(self) -> int:
        """Number of constraints (multipliers)."""
        return len(self.constraint_names)


def state_symbols(system: System) -> tuple[tuple, tuple]:
    """Plain symbols for the coordinates (same names) and velocities (``<name>_dot``)."""
    names = system.coordinate_names
    taken = set(system.parameter_names)
    q = tuple(sp.Dummy(n) if n in taken else sp.Symbol(n, real=True) for n in names)
    qd = tuple(sp.Symbol(f"{n}_dot", real=True) for n in names)
    clash = taken & {s.name for s in qd}
    if clash:
        raise ModelError(f"Parameter name(s) {sorted(clash)} clash with velocity names; rename the parameter(s).")
    return q, qd


def to_plain(expr: sp.Expr, system: System, q, qd) -> sp.Expr:
    """Replace q_i(t) by q[i] and q_i'(t) by qd[i]; accelerations are an error."""
    coords = system.coordinates
    velocities = {c.diff(t): v for c, v in zip(coords, qd)}
    expr = expr.xreplace(velocities)
    leftover = [d for d in expr.atoms(sp.Derivative) if d.expr in coords]
    if leftover:
        raise ModelError(f"{leftover[0]} appears in the system; T, V and forces may depend on q, q̇ and t only.")
    return expr.xreplace(dict(zip(coords, q)))


def derive(system: System) -> EOM:
    """Derive M, F, the energies, momenta and cyclic coordinates of `system`."""
    q, qd = state_symbols(system)
    plain = lambda expr: to_plain(expr, system, q, qd)  # noqa: E731
    T, V, D = plain(system.T), plain(system.V), plain(system.dissipation)
    Q = [plain(Qi) for Qi in system.forces]
    if V.has(*qd):
        raise ModelError("The potential V depends on velocities; put velocity-dependent forces in `forces`.")
    _check_differentiable(system, (*q, *qd), T, V, D, Q, plain)

    dT_dqd = [T.diff(v) for v in qd]
    M = sp.Matrix(system.n, system.n, lambda i, j: dT_dqd[i].diff(qd[j]))
    if any(entry.has(*qd) for entry in M):
        raise ModelError("The kinetic energy T is not quadratic in the velocities (its Hessian in q̇ depends on q̇).")
    constraints = _constraints(system, q, qd, plain)
    _check_mass_matrix(M, constraints["C"], system, q)

    F = sp.Matrix(
        [
            Q[i] - V.diff(q[i]) - D.diff(qd[i]) + T.diff(q[i])
            - sum(dT_dqd[i].diff(q[j]) * qd[j] for j in range(system.n))
            - dT_dqd[i].diff(t)
            for i in range(system.n)
        ]
    )
    L = T - V
    momenta = sp.Matrix([L.diff(v) for v in qd])
    at_rest = {v: 0 for v in qd}
    momentum_offset = momenta.xreplace(at_rest)
    momentum_rate = sp.Matrix([Q[i] - D.diff(qd[i]) + L.diff(q[i]) for i in range(system.n)])
    h = sum(v * p for v, p in zip(qd, momenta)) - L
    separable = (
        not system.constraints
        and not any(entry.has(t, *q) for entry in M)
        and not any(entry.has(*qd) for entry in F)
    )
    cyclic = tuple(
        name
        for name, qi, vi, Qi in zip(system.coordinate_names, q, qd, Q)
        if L.diff(qi) == 0 and Qi == 0 and D.diff(vi) == 0
    )
    return EOM(
        system=system, q=q, qd=qd, parameters=system.parameters,
        M=M.applyfunc(_tidy), F=F.applyfunc(_tidy), T=T, V=V, L=L,
        energy=_tidy(T + V), energy_function=_tidy(h), momenta=momenta.applyfunc(_tidy), cyclic=cyclic,
        separable=separable, momentum_offset=momentum_offset.applyfunc(_tidy),
        momentum_rate=momentum_rate.applyfunc(_tidy), events=tuple(plain(e.expr) for e in system.events),
        **constraints,
    )


def _time_derivative(expr: sp.Expr, q, qd) -> sp.Expr:
    """d/dt of f(q, t) along the motion: Σ ∂f/∂q_j q̇_j + ∂f/∂t."""
    return sum((expr.diff(qj) * vj for qj, vj in zip(q, qd)), expr.diff(t))


def _constraints(system: System, q, qd, plain) -> dict:
    """Λ, b, γ and Φ of the system's constraints (see the module docstring)."""
    rows, offsets, residuals, holonomic = [], [], [], []
    for c in system.constraints:
        expr = plain(c.expr)
        if isinstance(c, Holonomic):
            rows.append([expr.diff(qi) for qi in q])
            offsets.append(expr.diff(t))
            residuals.append(expr)
        else:
            row = [expr.diff(v) for v in qd]
            if any(entry.has(*qd) for entry in row):
                raise ModelError(f"Nonholonomic constraint `{c.name}` is not linear in the velocities.")
            rows.append(row)
            offsets.append(expr.xreplace({v: 0 for v in qd}))
        holonomic.append(isinstance(c, Holonomic))
    k, n = len(rows), len(q)
    C = sp.Matrix(k, n, lambda i, j: rows[i][j])
    b = sp.Matrix(k, 1, offsets)
    gamma = sp.Matrix(
        k, 1,
        lambda i, _: -(sum((_time_derivative(C[i, j], q, qd) * qd[j] for j in range(n)), sp.S.Zero)
                       + _time_derivative(b[i], q, qd)),
    )
    return dict(
        constraint_names=system.constraint_names, holonomic=tuple(holonomic),
        Phi=sp.Matrix(len(residuals), 1, residuals), C=C.applyfunc(_tidy), b=b.applyfunc(_tidy),
        gamma=gamma.applyfunc(_tidy),
    )


def _tidy(expr: sp.Expr) -> sp.Expr:
    """Cheap simplification that pays off in operation count (e.g. sin²+cos² → 1).

    Two of Fu's rules (far cheaper than a full `trigsimp`): chains of links
    written in Cartesian form give l1 l2 (sin θ1 sin θ2 + cos θ1 cos θ2), which
    becomes l1 l2 cos(θ1 − θ2), and m l² (sin² θ + cos² θ), which becomes m l².
    The result is kept only when it has no more operations than the input.
    Large expressions are left alone: the rules are quadratic in the number of
    terms (a 10-link chain's forcing would take ~40 s) and CSE recovers much of
    the sharing anyway.
    """
    if sp.count_ops(expr) > TIDY_MAX_OPS:
        return expr
    tidied = sp.expand(TR5(sp.expand(expr)))  # sin² → 1 − cos², so sin² + cos² cancels
    tidied = sp.factor_terms(TR10i(tidied))  # cos a cos b + sin a sin b → cos(a − b)
    return tidied if sp.count_ops(tidied) <= sp.count_ops(expr) else expr


#: Functions without a derivative everywhere (a kink, a jump or a branch change).
NON_SMOOTH = (sp.Abs, sp.sign, sp.Piecewise, sp.Heaviside, sp.DiracDelta, sp.floor, sp.ceiling, sp.frac,
              sp.Min, sp.Max, sp.Mod)


def _check_differentiable(system: System, state, T, V, D, Q, plain) -> None:
    """Refuse non-smooth functions of the state where lagcomp differentiates them.

    T and the constraints are differentiated twice (M, F; Λ, γ), so any kink
    or jump there is refused.  V and D are differentiated once: a kink is
    allowed (|x| gives the force sign(x)), a jump is not (its derivative is a
    DiracDelta impulse).  Forces are only evaluated (a Coulomb friction
    sign(q̇) is fine), but their derivative must exist away from the jumps.
    """
    def culprits(expr):
        return [f for f in expr.atoms(*NON_SMOOTH) if f.has(*state)]

    twice = {"T": T, **{f"constraint `{c.name}`": plain(c.expr) for c in system.constraints}}
    for role, expr in twice.items():
        bad = culprits(expr)
        if bad:
            raise ModelError(
                f"{role} of {system.name!r} contains {bad[0]}, which has no derivative where its argument changes "
                f"sign or branch; Lagrange's equations differentiate {role} twice. Write it as a smooth "
                "expression (e.g. sqrt(x**2 + eps**2) for |x|), or make each regime its own System and switch "
                "between them at a terminal Event."
            )
    once = {"V": V, "dissipation": D, **{f"forces[{name}]": Qi for name, Qi in zip(system.coordinate_names, Q)}}
    for role, expr in once.items():
        for f in culprits(expr):
            for v in sorted(f.free_symbols & set(state), key=str):
                derivative = f.diff(v)
                impulse = derivative.has(sp.DiracDelta) and not role.startswith("forces")
                if impulse or derivative.has(sp.Derivative):
                    raise ModelError(
                        f"{role} of {system.name!r} contains {f}, whose derivative in {v} is {derivative}: "
                        f"{'a jump in a potential is an impulse, which' if impulse else 'that'} lagcomp cannot "
                        "integrate. Write it as a smooth expression, or make each regime its own System and "
                        "switch between them at a terminal Event."
                    )


def _check_mass_matrix(M: sp.Matrix, C: sp.Matrix, system: System, q) -> None:
    """Refuse equations that are singular for every state and parameter value.

    Without constraints M itself must be regular.  With constraints only the
    augmented matrix [M Λᵀ; Λ 0] must be: a massless hoop carrying a point
    mass has a singular M and well-posed constrained equations.  Symbolically
    cheap checks first (a coordinate with no inertia at all), then the
    determinant at a few random states and positive parameter values; a
    state-dependent singularity is left to the kernel, which reports it with
    the state where it happens.
    """
    names = system.coordinate_names
    if C.rows:
        M = sp.BlockMatrix([[M, C.T], [C, sp.zeros(C.rows, C.rows)]]).as_explicit()
    for i in range(system.n if not C.rows else 0):
        if all(M[i, j] == 0 for j in range(system.n)):
            raise SingularMassMatrixError(
                f"T does not depend on the velocity of coordinate `{names[i]}` (its mass-matrix row is zero): "
                "the kinetic energy must be positive definite in the velocities."
            )
    args = (*q, t, *system.parameters)
    evaluate = sp.lambdify(args, M, modules="numpy")
    rng = np.random.default_rng(20261122)
    negative = 0
    for _ in range(3):
        values = rng.uniform(0.3, 1.7, size=len(args))
        with np.errstate(all="ignore"):
            m = np.asarray(evaluate(*values), dtype=float)
        if not np.all(np.isfinite(m)):
            return  # cannot judge at this random point; the kernel checks at run time
        if not C.rows and np.linalg.eigvalsh(m)[0] < -1e-12 * np.abs(m).max():
            negative += 1  # T < 0 for some velocities here: not a kinetic energy
            continue
        scale = np.prod(np.maximum(np.linalg.norm(m, axis=1), 1e-300))
        if abs(np.linalg.det(m)) > 1e-10 * scale:
            return
    if negative == 3:
        raise SingularMassMatrixError(
            f"The mass matrix ∂²T/∂q̇² has a negative eigenvalue at every state tried: T is negative for some "
            f"velocities of {', '.join(names)}, so it is not a kinetic energy. Check the signs in T (L = T − V)."
        )
    if C.rows:
        raise SingularMassMatrixError(
            "The constrained equations are singular at every state tried: the augmented matrix [M Λᵀ; Λ 0] has "
            f"no inverse. Either constraints {list(system.constraint_names)} are redundant, or the kinetic energy "
            f"is not positive definite on the motions they allow ({', '.join(names)})."
        )
    raise SingularMassMatrixError(
        "The mass matrix ∂²T/∂q̇² is singular at every state tried: the kinetic energy is not positive definite "
        f"in the velocities of {', '.join(names)}. Check T for a missing term or a redundant coordinate."
    )


def rest_partials(eom: EOM) -> tuple[sp.Matrix, sp.Matrix]:
    """∂F/∂q and ∂F/∂q̇ at rest, q̇ = 0: the stiffness and velocity terms of small oscillations.

    Linearizing M q̈ = F(q, q̇, t) about an equilibrium (F(q*, 0, t) = 0, so
    q̈ = 0 there and ∂M/∂q q̈ drops out) gives M δq̈ = F_q δq + F_v δq̇ with
    F_q = ∂F/∂q and F_v = ∂F/∂q̇ at (q*, 0, t).

    F_q is the Jacobian of F(q, 0, t), which is small: every q̇ term drops out
    before differentiating.  F_v is not taken from F itself.  With
    L = ½ q̇ᵀM q̇ + bᵀq̇ + L₀(q, t) and Q_d = Q − ∂D/∂q̇, Lagrange's equations
    d/dt (M q̇ + b) − ∂L/∂q = Q_d have as their part linear in q̇

        F_v q̇ = (B_qᵀ − B_q − ∂M/∂t) q̇ + ∂Q_d/∂q̇ q̇,     B_q = ∂b/∂q,

    (−Ṁ q̇ and −ḃ from d/dt p, b_q·q̇ from ∂L/∂q), so F_v needs only M, b and
    Q_d: differentiating the full F costs ~10 s of sympy for a 10-link chain,
    this 0.2 s.  B_qᵀ − B_q is skew: the gyroscopic coupling of a rotating
    frame or an imposed rotation.
    """
    at_rest = {v: 0 for v in eom.qd}
    system = eom.system
    D = to_plain(system.dissipation, system, eom.q, eom.qd)
    Q_d = sp.Matrix([to_plain(Q, system, eom.q, eom.qd) - D.diff(v) for Q, v in zip(system.forces, eom.qd)])
    B_q = eom.momentum_offset.jacobian(eom.q)
    F_q = eom.F.xreplace(at_rest).jacobian(eom.q)
    F_v = B_q.T - B_q - eom.M.diff(t) + Q_d.jacobian(eom.qd).xreplace(at_rest)
    return F_q, F_v
