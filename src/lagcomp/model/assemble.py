"""Bodies, loads and the frame of a System turned into T, V, Q and D.

    T = Σ_bodies T_R(body)                         (`MovingFrame.kinetic_energy`)
    V = Σ_bodies (V_R(body) + body potential) + Σ_loads V
    Q_i = Σ_loads Q_i,    D = Σ_loads D

A body's T is simplified once (`_tidy`): written from Cartesian components
of the centre's velocity it carries sin² ψ + cos² ψ factors that hide a cyclic
coordinate (the top's precession angle) from the derivation's structural test
for cyclic coordinates.

The System adds these to what the user wrote directly.  Each contribution is
also returned under a role naming its body or load, so that validation can
say where an undeclared symbol came from.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp
from sympy.simplify.fu import TR5, TR10i

from lagcomp.model.bodies import as_body
from lagcomp.model.frames import MovingFrame
from lagcomp.model.loads import as_load


@dataclass(frozen=True)
class Parts:
    bodies: tuple
    loads: tuple
    T: sp.Expr
    V: sp.Expr
    Q: tuple
    D: sp.Expr
    roles: dict


def assemble(coordinates, bodies, loads, frame: MovingFrame) -> Parts:
    """The energies and generalized forces contributed by `bodies` and `loads` in `frame`."""
    bodies = tuple(as_body(b) for b in bodies)
    loads = tuple(as_load(x) for x in loads)
    n = len(coordinates)
    T, V, D = sp.S.Zero, sp.S.Zero, sp.S.Zero
    Q = [sp.S.Zero] * n
    roles: dict[str, sp.Expr] = {}
    for k, body in enumerate(bodies):
        kin = body.kinematics(frame)
        Tb = sum((_tidy(part) for part in frame.kinetic_energy_parts(kin)), sp.S.Zero)
        Vb = frame.driving_potential(kin) + kin.potential
        roles[f"bodies[{k}] {body.name} (T)"], roles[f"bodies[{k}] {body.name} (V)"] = Tb, Vb
        T, V = T + Tb, V + Vb
    for k, load in enumerate(loads):
        c = load.contribution(frame, coordinates, bodies)
        for key, value in (("V", c.V), ("D", c.D)):
            if value != 0:
                roles[f"loads[{k}] {load.name} ({key})"] = value
        V, D = V + c.V, D + c.D
        for i, Qi in enumerate(c.Q):
            if Qi != 0:
                roles[f"loads[{k}] {load.name} (Q[{i}])"] = Qi
                Q[i] += Qi
    return Parts(bodies, loads, T, V, tuple(Q), D, roles)



#: Kinetic energies with more operations than this are left as they are.
TIDY_MAX_OPS = 600


def _trig_atoms(expr: sp.Expr) -> set:
    return {f for f in expr.atoms(sp.sin, sp.cos)}


def _tidy(expr: sp.Expr) -> sp.Expr:
    """Cancel sin² + cos² (Fu's TR5, then TR10i as in `lagcomp.mechanics.lagrange`).

    The result is kept when it has no more operations, or when it depends on
    fewer sines and cosines (an angle that cancels out, such as the top's ψ);
    trigsimp would do as well at 10–30 times the cost.
    """
    if sp.count_ops(expr) > TIDY_MAX_OPS:
        return expr
    tidied = sp.factor_terms(TR10i(sp.expand(TR5(sp.expand(expr)))))
    if sp.count_ops(tidied) <= sp.count_ops(expr) or _trig_atoms(tidied) < _trig_atoms(expr):
        return tidied
    return expr
