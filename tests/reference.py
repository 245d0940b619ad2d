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
