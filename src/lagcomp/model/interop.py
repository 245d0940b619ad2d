r"""Systems from sympy.physics.mechanics: ``LagrangesMethod`` and ``KanesMethod``.

`from_lagranges_method(lm)` reads what the LagrangesMethod was built with —
the Lagrangian L, the coordinates, the loads (forcelist, reduced to
generalized forces in its inertial frame exactly as sympy does:
Q_i = Σ F·∂v/∂q̇_i + Σ τ·∂ω/∂q̇_i), and the holonomic and nonholonomic
constraint equations — and returns the equivalent lagcomp `System`.  L is
split by degree in q̇: V = −L|_{q̇=0} and T = L + V (T + V is then the
mechanical energy of a natural system).

`from_kanes_method(km)` turns a Kane model into a Lagrange System — a
re-derivation, for Kane models whose generalized speeds u are invertible
linear functions of q̇ (u_i = q̇_i being the usual case): the kinetic energy
of km's bodies, the virtual work of its loads and its velocity constraints
are rewritten with u = u(q, q̇) from the kinematic differential equations,
and Lagrange's equations are derived from them.  ``lagcomp.compile(km)`` does
NOT take this path: it compiles Kane's equations as KanesMethod forms them
(`lagcomp.kane_model`), which is right for every KanesMethod.  Unsupported
here, with a clear error: auxiliary speeds, kinematic equations that do not
determine u from q̇, and velocities set by hand that are not the time
derivatives of the positions (rolling contacts written with
``v2pt_theory``): Lagrange's equations of such a T are those of another
system (`lagcomp.model.stated_velocities`).  The same check guards
`from_lagranges_method` for the bodies and load points the LagrangesMethod
was given (with ``bodies=`` unset sympy keeps only L, which cannot be checked).

Multipliers follow lagcomp's convention (`lagcomp.mechanics.lagrange`), not
sympy's ``lam_vec``: M q̈ = F + Λᵀ λ with Λ the Jacobian of the constraint as written.
"""

from __future__ import annotations

import sympy as sp
from sympy.physics import mechanics as me
from sympy.physics.mechanics import dynamicsymbols

from lagcomp.errors import ModelError
from lagcomp.model.bodies import as_body
from lagcomp.model.constraints import Holonomic, Nonholonomic
from lagcomp.model.frames import MovingFrame
from lagcomp.model.loads import as_load
from lagcomp.model.stated_velocities import check_stated_velocities
from lagcomp.model.system import System

__all__ = ["from_lagranges_method", "from_kanes_method"]

t = dynamicsymbols._t


def _generalized_forces(loads, frame: MovingFrame, coordinates) -> list[sp.Expr]:
    Q = [sp.S.Zero] * len(coordinates)
    for load in loads or ():
        for i, Qi in enumerate(as_load(load).contribution(frame, coordinates, ()).Q):
            Q[i] += Qi
    return Q


def _check_velocities(bodies, loads, inertial, kindiff) -> None:
    """Refuse velocities set by hand that are not d/dt of the positions (`stated_velocities`)."""
    points = [getattr(b, "masscenter", getattr(b, "point", None)) for b in bodies]
    frames = [getattr(b, "frame", None) for b in bodies]
    for where, _ in loads:
        (points if isinstance(where, me.Point) else frames).append(where)
    check_stated_velocities(points, frames, inertial, kindiff)


def from_lagranges_method(lm: me.LagrangesMethod, *, name: str = "system", **system_kwargs) -> System:
    """The lagcomp System of a sympy ``LagrangesMethod`` (its Lagrangian, loads and constraints).

    `system_kwargs` go to `System` (parameters, defaults, q0, qd0, t_end,
    description, events).  Constraints are named ``holonomic_<k>`` and
    ``nonholonomic_<k>`` in sympy's order.
    """
    if not isinstance(lm, me.LagrangesMethod):
        raise ModelError(f"from_lagranges_method needs a sympy LagrangesMethod, got {type(lm).__name__}.")
    if lm.inertial is not None:
        _check_velocities(lm.bodies or (), lm.forcelist or (), lm.inertial, {})
    coordinates = tuple(lm.q)
    L = sp.sympify(lm._L[0])
    at_rest = {q.diff(t): 0 for q in coordinates}
    V = -L.xreplace(at_rest)
    forces = (0,) * len(coordinates)
    if lm.forcelist:
        if lm.inertial is None:
            raise ModelError("The LagrangesMethod has loads but no inertial `frame`; sympy needs it too.")
        forces = _generalized_forces(lm.forcelist, MovingFrame(axes=lm.inertial), coordinates)
    holonomic = list(lm._hol_coneqs)
    nonholonomic = list(lm.coneqs)[len(holonomic):]
    constraints = [Holonomic(f"holonomic_{k}", c) for k, c in enumerate(holonomic)]
    constraints += [Nonholonomic(f"nonholonomic_{k}", c) for k, c in enumerate(nonholonomic)]
    return System(
        coordinates=coordinates, T=sp.expand(L + V), V=V, forces=forces, constraints=tuple(constraints),
        name=name, **system_kwargs,
    )


def from_kanes_method(km: me.KanesMethod, *, name: str = "system", **system_kwargs) -> System:
    """The lagcomp System of a sympy ``KanesMethod`` whose speeds are linear in q̇ (module docstring)."""
    if not isinstance(km, me.KanesMethod):
        raise ModelError(f"from_kanes_method needs a sympy KanesMethod, got {type(km).__name__}.")
    if len(km._uaux):
        raise ModelError("from_kanes_method does not take auxiliary speeds: compile the KanesMethod itself "
                         "(lagcomp.compile(km)), which reports their noncontributing forces as reactions.")
    _check_velocities(km.bodies, km.loads or (), km._inertial, km.kindiffdict())
    coordinates = tuple(km.q)
    qd = [q.diff(t) for q in coordinates]
    u = list(km.u)
    qd_of_u = km.kindiffdict()
    equations = [qdi - qd_of_u[qdi] for qdi in qd]
    try:
        A, b = sp.linear_eq_to_matrix(equations, u)
    except (ValueError, sp.PolynomialError) as err:
        raise ModelError("The kinematic differential equations are not linear in the speeds u.") from err
    if A.shape[0] != len(u) or A.det() == 0:
        raise ModelError(
            "The kinematic differential equations do not determine the speeds u from q̇; lagcomp needs "
            "u = u(q, q̇) (for example u_i = q̇_i)."
        )
    u_of_qd = dict(zip(u, A.LUsolve(b)))
    to_qd = lambda e: sp.sympify(e).xreplace(u_of_qd)  # noqa: E731

    T = sum((to_qd(b.kinetic_energy(km._inertial)) for b in km.bodies), sp.S.Zero)
    V = sum((to_qd(as_body(b).potential) for b in km.bodies), sp.S.Zero)
    Q = [sp.S.Zero] * len(coordinates)
    for load in km.loads or ():
        where, vector = load
        if isinstance(where, me.Point):
            v = to_qd(where.vel(km._inertial).to_matrix(km._inertial))
        else:
            v = to_qd(where.ang_vel_in(km._inertial).to_matrix(km._inertial))
        F = vector.to_matrix(km._inertial)
        for i, qdi in enumerate(qd):
            Q[i] += F.dot(v.diff(qdi))
    constraints = []
    if km._k_nh.rows:
        rows = km._k_nh * sp.Matrix(u) + km._f_nh
        constraints = [Nonholonomic(f"velocity_{k}", to_qd(r)) for k, r in enumerate(rows)]
    return System(
        coordinates=coordinates, T=T, V=V, forces=tuple(Q), constraints=tuple(constraints),
        name=name, **system_kwargs,
    )
