"""Independent references: sympy.physics.mechanics.LagrangesMethod evaluated numerically."""

from __future__ import annotations

import sympy as sp
from sympy.physics.mechanics import LagrangesMethod

from lagcomp.model import t


def lagranges_method_functions(system):
    """Numerical M(q, p) and F(q, qd, p) of `system` derived by LagrangesMethod (L = T − V, plus Q).

    Returns two callables taking (q, qd, params_vector) in the System's parameter order.
    """
    coords = list(system.coordinates)
    lm = LagrangesMethod(system.T - system.V, coords)
    lm.form_lagranges_equations()
    M = lm.mass_matrix
    F = lm.forcing + sp.Matrix(system.forces)
    q = sp.symbols(f"q0:{len(coords)}")
    u = sp.symbols(f"u0:{len(coords)}")
    to_plain = {c.diff(t): ui for c, ui in zip(coords, u)}
    to_plain_q = dict(zip(coords, q))
    M = M.xreplace(to_plain).xreplace(to_plain_q)
    F = F.xreplace(to_plain).xreplace(to_plain_q)
    args = (q, u, t, system.parameters)
    return sp.lambdify(args, M, "numpy"), sp.lambdify(args, F, "numpy")


def lagranges_method_rhs(system):
    """ẏ = f(t, y) of an unconstrained `system` at its default parameters, derived by LagrangesMethod.

    y = (q, q̇); q̈ = M⁻¹ F with M, F from `lagranges_method_functions` and the
    Rayleigh forces −∂D/∂q̇ added to F.  For scipy's `solve_ivp`.
    """
    import numpy as np

    if system.constraints:
        raise ValueError(f"{system.name} has constraints: LagrangesMethod's multipliers are not set up here")
    M, F = lagranges_method_functions(system)
    n = len(system.coordinates)
    velocities = [c.diff(t) for c in system.coordinates]
    rayleigh = sp.Matrix([-system.dissipation.diff(v) for v in velocities])
    q, u = sp.symbols(f"q0:{n}"), sp.symbols(f"u0:{n}")
    plain = {**dict(zip(velocities, u)), **dict(zip(system.coordinates, q))}
    R = sp.lambdify((q, u, t, system.parameters), rayleigh.xreplace(plain), "numpy")
    p = [system.defaults[s.name] for s in system.parameters]

    def rhs(time, y):
        qv, uv = y[:n], y[n:]
        force = np.asarray(F(qv, uv, time, p), dtype=float).ravel()
        force = force + np.asarray(R(qv, uv, time, p), dtype=float).ravel()
        return np.concatenate([uv, np.linalg.solve(np.asarray(M(qv, uv, time, p), dtype=float), force)])

    return rhs
