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
import symengine as se
import sympy as sp

from lagcomp.errors import ModelError, SingularMassMatrixError
from lagcomp.mechanics.tidy import tidy as _tidy, tidy_small as _tidy_small, tidy_symengine as _tidy_symengine
from lagcomp.model.constraints import Holonomic
from lagcomp.model.contacts import Contact
from lagcomp.model.events import reset_target
from lagcomp.model.friction import Friction, slip_symbol
from lagcomp.model.inputs import plain_inputs
from lagcomp.model.system import System, t


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
    holonomic_separable : bool
        Whether RATTLE applies: separable as above apart from constraints,
        which are all holonomic and scleronomic, Φ(q) = 0 (free of t, so
        b = 0): H = ½ pᵀ M⁻¹ p + V(q, t) on the manifold Φ(q) = 0.  False
        without constraints (`separable` covers those).
    momentum_offset : Matrix, shape (n, 1)
        b(q, t) in p = M q̇ + b (momenta are affine in q̇).
    momentum_rate : Matrix, shape (n, 1)
        ṗ = ∂L/∂q + Q − ∂D/∂q̇ as a function of (q, q̇, t): with q̇ from
        M q̇ = p − b this is Hamilton's ṗ = −∂H/∂q (+ non-conservative forces).
    events : tuple of Expr
        The event functions g(q, q̇, t) of `System.events`, in order.
    resets : tuple of tuple
        Per event, in order, its reset as ((state index, value), ...): index i < n the coordinate q_i,
        n + i its velocity, the value over the plain symbols of the state before the event; () for none.
    restitutions : tuple
        Per event, in order, Newton's coefficient e of a contact (`lagcomp.model.contacts.Contact`, whose
        event function is its gap) as a plain expression (a number or a parameter); None for other events.
    frictions : tuple
        Per event, in order, (N, μs, μk) of a friction element (`lagcomp.model.friction.Friction`, whose event
        function is its sliding velocity v), N in plain symbols; None for other events.  Its slip force
        −μk |N| s ∂v/∂q̇ is part of F (and of ṗ), s the element's mode symbol (`slip_symbol`, in element order).
        N is the name of a contact (a str) for an element pressed by that contact's normal force: its slip force
        is not part of F (`lagcomp.codegen.contacts`).
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
    holonomic_separable: bool
    momentum_offset: sp.Matrix
    momentum_rate: sp.Matrix
    events: tuple = ()
    resets: tuple = ()
    restitutions: tuple = ()
    frictions: tuple = ()

    @property
    def n(self) -> int:
        return len(self.q)

    @property
    def k(self) -> int:
        """Number of constraints (multipliers)."""
        return len(self.constraint_names)


def state_symbols(system: System) -> tuple[tuple, tuple]:
    """Plain symbols for the coordinates (same names) and velocities (``<name>_dot``).

    A name taken already — a coordinate named like a parameter or like time (``t``), a velocity
    ``x_dot`` named like a coordinate or a parameter ``x_dot`` — gets a symbol of another name, one
    no symbol of the system has: distinct by construction, so one quantity is never read as another
    (symengine, which derives and CSEs the equations, tells symbols apart by name only, not by
    assumptions, nor a Dummy from a Symbol).  Labels (``x_dot`` in solutions) keep the user's names;
    where such a label would be ambiguous (a sweep grid key) it is refused there.
    """
    names = system.coordinate_names
    taken = set(system.parameter_names)
    used = taken | set(names) | {f"{n}_dot" for n in names} | {t.name}

    def own(name: str) -> str:
        while name in used:
            name += "_"
        used.add(name)
        return name
    q = tuple(sp.Symbol(own(n) if n in taken or n == t.name else n, real=True) for n in names)
    qd = tuple(sp.Symbol(own(f"{n}_dot") if f"{n}_dot" in taken | set(names) else f"{n}_dot", real=True)
               for n in names)
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
    """Derive M, F, the energies, momenta and cyclic coordinates of `system`.

    T is split once into its parts of degree 2, 1 and 0 in q̇,
    T = ½ q̇ᵀ M q̇ + bᵀ q̇ + T₀ (`_kinetic_parts`), and everything else is
    built from these small, simplified pieces rather than from T itself:
    differentiating T (for a 10-link chain, thousands of terms in Cartesian
    form) costs seconds in sympy, the pieces milliseconds.  With
    Γ_ijk = ½ (∂M_ij/∂q_k + ∂M_ik/∂q_j − ∂M_jk/∂q_i) (Christoffel symbols),
    substituting the parts into the module docstring's F gives

        F_i = Q_i − ∂V/∂q_i − ∂D/∂q̇_i + ∂T₀/∂q_i − Σ_jk Γ_ijk q̇_j q̇_k
              + Σ_j (∂b_j/∂q_i − ∂b_i/∂q_j − ∂M_ij/∂t) q̇_j − ∂b_i/∂t,

    the momenta are p = M q̇ + b, the energy function h = T − bᵀ q̇ − 2 T₀ + V
    (T itself there: in Cartesian form its velocity sums share prefixes,
    which CSE turns into fewer operations than ½ q̇ᵀ M q̇).
    """
    q, qd = state_symbols(system)
    plain = lambda expr: to_plain(expr, system, q, qd)  # noqa: E731
    T, V, D = plain(system.T), plain(system.V), plain(system.dissipation)
    Q = [plain(Qi) for Qi in system.forces]
    if V.has(*qd):
        raise ModelError("The potential V depends on velocities; put velocity-dependent forces in `forces`.")
    _check_differentiable(system, (*q, *qd), T, V, D, Q, plain)
    frictions = _frictions(system, plain, qd)
    Q = [Qi + slip for Qi, slip in zip(Q, _slip_forces(system, frictions, plain, qd), strict=True)]
    n, variables = system.n, (*q, *qd, t)
    tidy = lambda expr: _tidy(expr, variables)  # noqa: E731

    M, b, T0 = _kinetic_parts(T, qd, variables)
    _check_dissipation(system, D, qd, variables)
    constraints = _constraints(system, q, qd, plain)
    _check_mass_matrix(M, constraints["C"], system, q)

    dM = [[[]] * n for _ in range(n)]  # dM[i][j][k] = ∂M_ij/∂q_k
    for i in range(n):
        for j in range(i + 1):
            dM[i][j] = dM[j][i] = _partials(M[i, j], q)
    db = [_partials(b[i], q) for i in range(n)]  # db[i][k] = ∂b_i/∂q_k
    dT0, dV = _gradient(T0, q, variables), _gradient(V, q, variables)
    dD = _gradient(D, qd, variables)
    dL_dq = [  # ∂L/∂q_i = ∂T/∂q_i − ∂V/∂q_i
        _quadratic(lambda j, k: dM[j][k][i] / 2 if j == k else dM[j][k][i], qd, tidy)
        + sum((tidy(db[j][i]) * qd[j] for j in range(n)), sp.S.Zero) + tidy(dT0[i] - dV[i])
        for i in range(n)
    ]
    F = sp.Matrix([
        tidy(Q[i] - dV[i] - dD[i] + dT0[i] - b[i].diff(t))
        - _quadratic(lambda j, k: dM[i][j][k] - dM[j][j][i] / 2 if j == k else dM[i][j][k] + dM[i][k][j] - dM[j][k][i],
                     qd, tidy)  # Σ_jk Γ_ijk q̇_j q̇_k: Γ_ijj, and Γ_ijk + Γ_ikj for j < k
        + sum((tidy(db[j][i] - db[i][j] - M[i, j].diff(t)) * qd[j] for j in range(n)), sp.S.Zero)
        for i in range(n)
    ])
    momenta = sp.Matrix([sum((M[i, j] * qd[j] for j in range(n)), b[i]) for i in range(n)])
    momentum_rate = sp.Matrix([Q[i] - dD[i] + dL_dq[i] for i in range(n)])
    T1 = sum((bi * v for bi, v in zip(b, qd)), sp.S.Zero)
    energy = _tidy_small(T + V, variables)
    # H = ½ pᵀ M⁻¹ p + V(q, t): M free of q and t, F free of q̇; constraints aside
    split = not any(entry.has(t, *q) for entry in M) and not any(entry.has(*qd) for entry in F)
    separable = split and not system.constraints
    holonomic_separable = (split and bool(system.constraints) and all(constraints["holonomic"])
                           and not constraints["Phi"].has(t))
    cyclic = tuple(
        name for name, dLi, dDi, Qi in zip(system.coordinate_names, dL_dq, dD, Q) if dLi == 0 and Qi == 0 and dDi == 0
    )
    return EOM(
        system=system, q=q, qd=qd, parameters=system.parameters,
        M=M, F=F, T=T, V=V, L=T - V,
        energy=energy, energy_function=energy if T1 == 0 and T0 == 0 else _tidy_small(T - T1 - 2 * T0 + V, variables),
        momenta=momenta, cyclic=cyclic,
        separable=separable, holonomic_separable=holonomic_separable, momentum_offset=b, momentum_rate=momentum_rate,
        events=tuple(plain(e.expr) for e in system.events), resets=_resets(system, plain),
        restitutions=tuple(e.restitution if isinstance(e, Contact) else None for e in system.events),
        frictions=frictions, **constraints,
    )


def _frictions(system: System, plain, qd) -> tuple:
    """`EOM.frictions`: (N, μs, μk) per friction element's event, None for the others; a velocity that is not
    linear in q̇ is a ModelError (its stick row a q̈ + b = 0 needs v = a(q, t)·q̇ + c(q, t))."""
    out = []
    for e in system.events:
        if not isinstance(e, Friction):
            out.append(None)
            continue
        v = plain(e.expr)
        if not any(v.diff(a) != 0 for a in qd) or any(v.diff(a).diff(b) != 0 for a in qd for b in qd):
            raise ModelError(f"Friction `{e.name}`: its velocity must be linear in the velocities q̇ (a(q, t)·q̇ + "
                             f"c(q, t), not constant in them); got {e.expr}.")
        out.append((e.normal if isinstance(e.normal, str) else plain(e.normal), e.static, e.kinetic))
    return tuple(out)


def _slip_forces(system: System, frictions: tuple, plain, qd) -> list:
    """Σ_f −μk_f |N_f| s_f ∂v_f/∂q̇_i per coordinate i: the slipping elements' generalized forces, s_f the mode
    symbol of element f (`lagcomp.model.friction.slip_symbol`; 0 while it sticks).  |N|: a normal force written
    with a sign (m g cos θ on a curved track) presses either way; sympy drops the bars where N is positive."""
    forces = [sp.S.Zero] * len(qd)
    elements = [(e, friction) for e, friction in zip(system.events, frictions, strict=True) if friction is not None]
    for f, (event, (normal, _, kinetic)) in enumerate(elements):
        if isinstance(normal, str):     # pressed by a contact: its slip force joins the contact's column
            continue                    # (`lagcomp.kernel_support.resting.pressed_frictional_accelerations`)
        v = plain(event.expr)
        forces = [Qi - kinetic * sp.Abs(normal) * slip_symbol(f) * v.diff(a) for Qi, a in zip(forces, qd, strict=True)]
    return forces


def _resets(system: System, plain) -> tuple:
    """`EOM.resets`: each event's reset with its keys as state indices, its values in plain symbols."""
    n, index = system.n, {q: i for i, q in enumerate(system.coordinates)}
    return tuple(
        tuple((index[q] + n * order, plain(value)) for (q, order), value in
              ((reset_target(key), value) for key, value in e.reset or ()))
        for e in system.events)


def _quadratic(coefficient, qd, tidy) -> sp.Expr:
    """Σ_{j≤k} c_jk q̇_j q̇_k with c_jk = `coefficient`(j, k), each c_jk simplified on its own.

    Simplifying the coefficients one by one is cheap where simplifying the
    whole sum is not (it is quadratic in the number of terms).
    """
    n, terms = len(qd), []
    for j in range(n):
        for k in range(j, n):
            c = coefficient(j, k)
            if c != 0:
                terms.append(tidy(c) * qd[j] * qd[k])
    return sp.Add(*terms)


def _diff(expr: sp.Expr, x: sp.Symbol) -> sp.Expr:
    """∂expr/∂x, skipping the (common) case where expr does not contain x."""
    return expr.diff(x) if x in expr.free_symbols else sp.S.Zero


def _partials(expr: sp.Expr, xs) -> list:
    """[∂expr/∂x for x in xs], zero without differentiating where expr does not contain x."""
    present = expr.free_symbols
    return [_diff_dependent(expr, x) if x in present else sp.S.Zero for x in xs]


def _diff_dependent(expr: sp.Expr, x: sp.Symbol) -> sp.Expr:
    """∂expr/∂x, the factors of a product that do not contain x (sums of masses) left alone."""
    constant, dependent = expr.as_independent(x, as_Add=False)
    return constant * dependent.diff(x)


def _check_dissipation(system: System, D: sp.Expr, qd, variables) -> None:
    """Refuse a Rayleigh function D that is not a quadratic form ½ q̇ᵀ C(q, t) q̇ in the velocities.

    The forces −∂D/∂q̇ are what D is for: a part of D without velocities (c θ²/2) adds no force at all, and
    a part linear in q̇ a force that does not damp, so both would be dropped or misread without a word.
    """
    if D == 0:
        return
    try:
        _, b, D0 = _kinetic_parts(D, qd, variables)
    except ModelError:
        b, D0 = None, None
    if b is None or any(entry != 0 for entry in b) or D0 != 0:
        raise ModelError(
            f"The dissipation function D of {system.name!r} must be a quadratic form in the velocities, "
            f"D = ½ q̇ᵀ C(q, t) q̇ (its forces are −∂D/∂q̇ = −C q̇), got D = {system.dissipation}. "
            "Write the Rayleigh function as such (c*x.diff(t)**2/2 for a damper on x), and put other forces, "
            "velocity-dependent or not, in `forces`.")


NOT_QUADRATIC = "The kinetic energy T is not quadratic in the velocities (its Hessian in q̇ depends on q̇)."


def _kinetic_parts(T: sp.Expr, qd, variables) -> tuple[sp.Matrix, sp.Matrix, sp.Expr]:
    """M, b and T₀ of T = ½ q̇ᵀ M q̇ + bᵀ q̇ + T₀, each simplified (`lagcomp.mechanics.tidy`).

    Raises ModelError when T is not quadratic in q̇ (its Hessian depends on q̇).
    """
    n = len(qd)
    at_rest = {v: 0 for v in qd}
    pairs = [(i, j) for i in range(n) for j in range(i + 1)]
    if symengine_ready([T]):
        to_se, to_sympy = _symengine_maps({*T.free_symbols, *qd})
        Te, ve = to_se(T), [to_se(v) for v in qd]
        gradient = [Te.diff(v) for v in ve]
        rest = {v: 0 for v in ve}
        hessian = {(i, j): gradient[i].diff(ve[j]) for i, j in pairs}
        if any(entry.free_symbols & set(ve) and se.expand(entry).free_symbols & set(ve) for entry in hessian.values()):
            raise ModelError(NOT_QUADRATIC)
        tidy = lambda image: _tidy_symengine(image, [to_se(v) for v in variables], to_sympy)  # noqa: E731
        lower = {ij: tidy(entry) for ij, entry in hessian.items()}
        b, T0 = [tidy(g.subs(rest)) for g in gradient], tidy(Te.subs(rest))
    else:
        gradient = [T.diff(v) for v in qd]
        hessian = {(i, j): gradient[i].diff(qd[j]) for i, j in pairs}
        if any(entry.has(*qd) for entry in hessian.values()):
            raise ModelError(NOT_QUADRATIC)
        lower = {ij: _tidy(entry, variables) for ij, entry in hessian.items()}
        b, T0 = [_tidy(g.xreplace(at_rest), variables) for g in gradient], _tidy(T.xreplace(at_rest), variables)
    return sp.Matrix(n, n, lambda i, j: lower[(i, j) if j <= i else (j, i)]), sp.Matrix(b), T0


def _gradient(expr: sp.Expr, xs, variables) -> list:
    """[∂expr/∂x for x in xs], simplified; through symengine when it can (far faster on large expressions)."""
    if symengine_ready([expr]) and any(x in expr.free_symbols for x in xs):
        to_se, to_sympy = _symengine_maps({*expr.free_symbols, *xs})
        image = to_se(expr)
        partials = [to_sympy(image.diff(to_se(x))) for x in xs]  # not expanded: `_tidy` keeps the structure
    else:
        partials = [_diff(expr, x) for x in xs]
    return [_tidy(d, variables) for d in partials]


def jacobian(exprs: sp.Matrix, xs) -> sp.Matrix:
    """∂exprs_i/∂x_j, shape (len(exprs), len(xs)), through symengine when it can.

    The same derivatives as `sympy.Matrix.jacobian`, unsimplified, 10-100×
    faster on the large expressions of long chains.
    """
    exprs = list(exprs)
    if not symengine_ready(exprs):
        return real_jacobian(exprs, xs)
    to_se, to_sympy = _symengine_maps(set(xs).union(*(e.free_symbols for e in exprs)))
    images, variables = [to_se(e) for e in exprs], [to_se(x) for x in xs]
    return sp.Matrix(len(exprs), len(xs), lambda i, j: to_sympy(images[i].diff(variables[j])))


def real_jacobian(exprs, xs) -> sp.Matrix:
    """sympy's ∂exprs_i/∂x_j, shape (len(exprs), len(xs)), every symbol taken as the real number it stands for.

    A parameter declared without assumptions (``m, g = sp.symbols("m g")``) is complex to sympy, which
    differentiates |m g cos θ| into derivatives of its real and imaginary parts that no kernel can evaluate;
    as reals, the derivative is sign(m g cos θ) ∂(m g cos θ)/∂x.  The symbols go over to real dummies and
    come back, so the result is over the caller's symbols.
    """
    exprs, xs = sp.Matrix(list(exprs)), list(xs)
    complex_symbols = [s for s in exprs.free_symbols | set(xs) if isinstance(s, sp.Symbol) and s.is_real is not True]
    real = {s: sp.Dummy(s.name, real=True) for s in complex_symbols}
    block = exprs.xreplace(real).jacobian([x.xreplace(real) for x in xs])
    return block.xreplace({dummy: s for s, dummy in real.items()})


def kink_free_jacobian(exprs, xs) -> list[list]:
    """`real_jacobian` with a force's jump (Coulomb friction's sign(v), a Heaviside) contributing its
    derivative away from the jump: the DiracDelta at the jump is dropped."""
    return real_jacobian(exprs, xs).replace(sp.DiracDelta, lambda *args: sp.S.Zero).tolist()


#: Functions that symengine differentiates as sympy does; expressions with others go through sympy.
SYMENGINE_FUNCTIONS = (sp.sin, sp.cos, sp.tan, sp.cot, sp.exp, sp.log, sp.sinh, sp.cosh, sp.tanh,
                       sp.asin, sp.acos, sp.atan, sp.atan2)


def symengine_ready(exprs) -> bool:
    """Whether every function in `exprs` is one symengine handles exactly (not Abs, sign, f(t), ...)."""
    return all(isinstance(f, SYMENGINE_FUNCTIONS) for e in exprs for f in e.atoms(sp.Function))


def _symengine_maps(symbols):
    """(to symengine, back to sympy) for expressions over `symbols`.

    Symbols go over under unique plain names and come back as themselves,
    assumptions included (symengine keeps neither the assumptions nor the
    difference between a Dummy and a Symbol of the same name).
    """
    forward = {s: sp.Symbol(f"_lagcomp{k}") for k, s in enumerate(sorted(symbols, key=sp.default_sort_key))}
    backward = {v: s for s, v in forward.items()}
    return (lambda expr: se.sympify(sp.sympify(expr).xreplace(forward)),
            lambda image: sp.sympify(image).xreplace(backward))


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
    tidy = lambda expr: _tidy(expr, (*q, *qd, t))  # noqa: E731
    C = sp.Matrix(k, n, lambda i, j: rows[i][j])
    b = sp.Matrix(k, 1, offsets)
    gamma = sp.Matrix(
        k, 1,
        lambda i, _: -(sum((_time_derivative(C[i, j], q, qd) * qd[j] for j in range(n)), sp.S.Zero)
                       + _time_derivative(b[i], q, qd)),
    )
    return dict(
        constraint_names=system.constraint_names, holonomic=tuple(holonomic),
        Phi=sp.Matrix(len(residuals), 1, residuals), C=C.applyfunc(tidy), b=b.applyfunc(tidy),
        gamma=gamma.applyfunc(tidy),
    )


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


def _numeric(args: tuple, entries: list):
    """`entries` as a function of values of `args` (a vector of floats): symengine's Lambdify where it handles
    every function of them (a 32-link chain's M in 0.1 s instead of lambdify's 2 s), else sympy's lambdify,
    dummified (user names such as "ﬁ" beside "fi", or keywords, are no Python arguments)."""
    if symengine_ready(entries) and len({str(a) for a in args}) == len(args):
        # (symengine tells symbols apart by their names only: an input's stand-in named like a parameter
        # takes lambdify)
        function = se.Lambdify([se.sympify(a) for a in args], [se.sympify(e) for e in entries], backend="lambda")
        return lambda *values: function(np.asarray(values, dtype=float))
    return sp.lambdify(args, entries, modules="numpy", dummify=True)


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
    size = M.rows
    rows, cols = np.tril_indices(size)
    # inputs u(t) and their derivatives as plain symbols: lambdify prints no undefined function
    entries, signals = plain_inputs([M[i, j] for i, j in zip(rows, cols)], system.inputs)
    args = (*q, t, *system.parameters, *signals.values())
    lower = _numeric(args, entries)  # M is symmetric: its lower triangle
    rng = np.random.default_rng(20261122)
    negative = 0
    for _ in range(3):
        values = rng.uniform(0.3, 1.7, size=len(args))
        m = np.empty((size, size))
        with np.errstate(all="ignore"):
            m[rows, cols] = m[cols, rows] = np.asarray(lower(*values), dtype=float)
        if not np.all(np.isfinite(m)):
            return  # cannot judge at this random point; the kernel checks at run time
        if not C.rows and np.linalg.eigvalsh(m)[0] < -1e-12 * np.abs(m).max():
            negative += 1  # T < 0 for some velocities here: not a kinetic energy
            continue
        singular_values = np.linalg.svd(m, compute_uv=False)  # not det / Π|rows|: tiny for any large chain
        if singular_values[-1] > 1e-10 * singular_values[0]:
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
    B_q = jacobian(eom.momentum_offset, eom.q)
    F_q = jacobian(eom.F.xreplace(at_rest), eom.q)
    F_v = B_q.T - B_q - eom.M.diff(t) + jacobian(Q_d, eom.qd).xreplace(at_rest)
    return F_q, F_v
