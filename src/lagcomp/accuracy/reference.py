r"""The equations of motion of a `System` evaluated in many-digit arithmetic: the accuracy reference.

Independent of `lagcomp.mechanics` on purpose: Lagrange's equations are
formed here from the System's T, V, forces, dissipation and constraints by
plain sympy differentiation, with no simplification, expansion or CSE, and
evaluated by mpmath at `digits` significant digits.  The float64 inputs are
exact binary numbers, so the only rounding left is mpmath's, ~10^−digits.

With L = T − V and y = (q, q̇):

    M = ∂²T/∂q̇²,
    F_i = ∂L/∂q_i + Q_i − ∂D/∂q̇_i − Σ_j ∂²L/∂q̇_i∂q_j q̇_j − ∂²L/∂q̇_i∂t,
    [M  −Λᵀ] [q̈]   [F]
    [Λ   0 ] [λ] = [γ − 2α (Λ q̇ + b) − β² Φ],   γ = −(dΛ/dt q̇ + db/dt),

constraint k being Λ_k q̇ + b_k = 0 (Λ = ∂Φ/∂q, b = ∂Φ/∂t for a holonomic
Φ = 0), α, β the Baumgarte gains the kernels take from the end of p (the
sign convention of DESIGN.md: λ is the generalized force along Λ_k).
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import sympy as sp

from lagcomp.model.constraints import Holonomic
from lagcomp.model.system import System, t


@dataclass(frozen=True)
class ReferenceEquations:
    """Callables over mpmath numbers, argument order (t, q, q̇, parameters, α, β).

    `matrix` gives the rows of the (augmented) matrix, `right` the right-hand
    side, `energies` the pair (T, V).  n coordinates, k constraints.
    """

    n: int
    k: int
    matrix: object
    right: object
    energies: object

    def evaluate(self, t_value, y, p, digits: int) -> tuple[list, list, tuple]:
        """(q̈, λ, (T, V)) at one state, as mpmath numbers computed with `digits` digits."""
        with mpmath.workdps(digits):
            args = [mpmath.mpf(float(t_value)), *(mpmath.mpf(float(v)) for v in y), *(mpmath.mpf(float(v)) for v in p)]
            A = mpmath.matrix(self.matrix(*args))
            solution = mpmath.lu_solve(A, mpmath.matrix(self.right(*args)))
            T, V = self.energies(*args)
            return ([+solution[i] for i in range(self.n)], [+solution[self.n + c] for c in range(self.k)],
                    (+mpmath.mpf(T), +mpmath.mpf(V)))


def _plain(system: System, q, qd):
    velocities = {c.diff(t): v for c, v in zip(system.coordinates, qd)}
    positions = dict(zip(system.coordinates, q))
    return lambda expr: sp.sympify(expr).xreplace(velocities).xreplace(positions)


def _total_derivative(expr, q, qd):
    """d/dt of f(q, t) along the motion."""
    return sum((sp.diff(expr, qj) * vj for qj, vj in zip(q, qd)), sp.diff(expr, t))


def reference_equations(system: System) -> ReferenceEquations:
    """Lagrange's equations of `system`, unsimplified, as mpmath callables (see the module docstring)."""
    n = system.n
    q = sp.symbols(f"_rq0:{n}", real=True)
    qd = sp.symbols(f"_rv0:{n}", real=True)
    plain = _plain(system, q, qd)
    T, V, D = plain(system.T), plain(system.V), plain(system.dissipation)
    L = T - V
    dL_dqd = [sp.diff(L, v) for v in qd]
    M = [[sp.diff(dL_dqd[i], qd[j]) for j in range(n)] for i in range(n)]
    F = [sp.diff(L, q[i]) + plain(system.forces[i]) - sp.diff(D, qd[i])
         - sum((sp.diff(dL_dqd[i], q[j]) * qd[j] for j in range(n)), sp.S.Zero) - sp.diff(dL_dqd[i], t)
         for i in range(n)]
    alpha, beta = sp.symbols("_ralpha _rbeta", real=True)
    rows, gammas = [], []
    for c in system.constraints:
        expr = plain(c.expr)
        if isinstance(c, Holonomic):
            Lam, b, residual = [sp.diff(expr, qi) for qi in q], sp.diff(expr, t), expr
        else:
            Lam, b, residual = [sp.diff(expr, v) for v in qd], expr.xreplace({v: 0 for v in qd}), sp.S.Zero
        gamma = -(sum((_total_derivative(Lam[j], q, qd) * qd[j] for j in range(n)), sp.S.Zero)
                  + _total_derivative(b, q, qd))
        velocity = sum((Lam[j] * qd[j] for j in range(n)), b)
        rows.append(Lam)
        gammas.append(gamma - 2 * alpha * velocity - beta**2 * residual)
    k = len(rows)
    matrix = [M[i] + [-rows[c][i] for c in range(k)] for i in range(n)]
    matrix += [rows[c] + [sp.S.Zero] * k for c in range(k)]
    args = (t, *q, *qd, *system.parameters, alpha, beta)
    compile_ = lambda exprs: sp.lambdify(args, exprs, modules="mpmath")  # noqa: E731
    return ReferenceEquations(n=n, k=k, matrix=compile_(matrix), right=compile_(F + gammas),
                              energies=compile_([T, V]))
