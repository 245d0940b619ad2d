r"""Loads: forces and torques turned into generalized forces by virtual work.

A virtual displacement δq (at fixed t) moves a point by δr = Σ ∂r/∂q_i δq_i
and turns a body by δθ = Σ ∂ω/∂q̇_i δq_i.  The virtual work of a force F at r
and of a torque τ on the body gives

    Q_i = F · ∂r/∂q_i            (= F · ∂v/∂q̇_i, the partial velocity)
    Q_i = τ · ∂ω/∂q̇_i            (partial angular velocity; τ and ω in body axes)

Vectors are components along the system frame's axes (body axes for a
torque), or sympy.physics.vector Vectors.  F and τ may depend on q, q̇ and t.

Conveniences that are better written as energies than as forces:

* `Spring(a, b, k, l0)`: V = ½ k (|r_b − r_a| − l0)²;
* `Damper(a, b, c)`: Rayleigh function D = ½ c L̇² with L = |r_b − r_a|, i.e.
  the force −c L̇ along the line, on each end;
* `Gravity(g)`: V = −Σ m g·r_G over the bodies (g the acceleration vector,
  e.g. (0, 0, −g) with z up).

sympy.physics.mechanics loads — ``(Point, Vector)``, ``(ReferenceFrame, Vector)``
and its ``Force`` / ``Torque`` tuples — are accepted and read the same way.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp
from sympy.physics.mechanics import dynamicsymbols
from sympy.physics.vector import Point, ReferenceFrame, Vector

from lagcomp.errors import ModelError
from lagcomp.model.bodies import Particle, RigidBody, _point_motion, as_body
from lagcomp.model.frames import MovingFrame, column

__all__ = ["Force", "Torque", "Spring", "Damper", "Gravity", "Contribution", "as_load"]

t = dynamicsymbols._t


@dataclass(frozen=True)
class Contribution:
    """What a load adds to the System: potential V, generalized forces Q, dissipation D."""

    V: sp.Expr = sp.S.Zero
    Q: tuple = ()
    D: sp.Expr = sp.S.Zero


def _partials(v: sp.Matrix, coordinates) -> list[sp.Matrix]:
    return [v.diff(q.diff(t)) for q in coordinates]


@dataclass(frozen=True, eq=False)
class Force:
    """A force `vector` applied at `point` (a position, Vector, Point, Particle or RigidBody's centre)."""

    vector: object
    point: object
    name: str = "force"

    def contribution(self, frame: MovingFrame, coordinates, bodies) -> Contribution:
        F = column(self.vector, frame.axes, f"{self.name}: vector")
        _, v = _point_motion(self.point, frame, f"{self.name}: point")
        return Contribution(Q=tuple(F.dot(dv) for dv in _partials(v, coordinates)))


@dataclass(frozen=True, eq=False)
class Torque:
    """A torque `vector` on a rigid body, or on a (possibly massless) ReferenceFrame.

    Components are along the body's axes (the frame's axes for a ReferenceFrame),
    or a sympy Vector.
    """

    vector: object
    body: object
    name: str = "torque"

    def contribution(self, frame: MovingFrame, coordinates, bodies) -> Contribution:
        target = self.body
        if isinstance(target, ReferenceFrame):
            if frame.axes is None:
                raise ModelError(f"{self.name}: a torque on a ReferenceFrame needs the System `frame=` (its reference).")
            w = target.ang_vel_in(frame.axes).to_matrix(target)
            tau = column(self.vector, target, f"{self.name}: vector")
        else:
            body = as_body(target)
            if not isinstance(body, RigidBody):
                raise ModelError(f"{self.name}: a torque acts on a RigidBody or a ReferenceFrame, not on {target!r}.")
            w = body.kinematics(frame).angular_velocity
            if isinstance(self.vector, Vector) and not isinstance(body.axes, ReferenceFrame):
                raise ModelError(f"{self.name}: a torque Vector needs the body's axes as a ReferenceFrame.")
            tau = column(self.vector, body.axes if isinstance(body.axes, ReferenceFrame) else None, f"{self.name}: vector")
        return Contribution(Q=tuple(tau.dot(dw) for dw in _partials(w, coordinates)))


def _separation(a, b, frame: MovingFrame, name: str) -> sp.Matrix:
    ra, _ = _point_motion(a, frame, f"{name}: first end")
    rb, _ = _point_motion(b, frame, f"{name}: second end")
    if ra is None or rb is None:
        raise ModelError(f"{name}: the ends need positions; give the frame an origin Point (MovingFrame(origin=...)).")
    return rb - ra


@dataclass(frozen=True, eq=False)
class Spring:
    """A linear spring between two points: V = ½ k (|r_b − r_a| − l0)² (l0 = 0: V = ½ k |r_b − r_a|²)."""

    point_a: object
    point_b: object
    stiffness: object
    rest_length: object = 0
    name: str = "spring"

    def contribution(self, frame: MovingFrame, coordinates, bodies) -> Contribution:
        d = _separation(self.point_a, self.point_b, frame, self.name)
        k, l0 = sp.sympify(self.stiffness), sp.sympify(self.rest_length)
        if l0 == 0:
            return Contribution(V=k * d.dot(d) / 2)
        return Contribution(V=k * (sp.sqrt(d.dot(d)) - l0) ** 2 / 2)


@dataclass(frozen=True, eq=False)
class Damper:
    """A linear damper between two points: D = ½ c L̇², L = |r_b − r_a|."""

    point_a: object
    point_b: object
    coefficient: object
    name: str = "damper"

    def contribution(self, frame: MovingFrame, coordinates, bodies) -> Contribution:
        d = _separation(self.point_a, self.point_b, frame, self.name)
        c = sp.sympify(self.coefficient)
        rate = d.dot(d.diff(t))  # L L̇
        return Contribution(D=c * rate**2 / (2 * d.dot(d)))


@dataclass(frozen=True, eq=False)
class Gravity:
    """Uniform gravity of acceleration `vector` (e.g. (0, 0, −g)) on `bodies` (default: all of the System's)."""

    vector: object
    bodies: tuple | None = field(default=None)
    name: str = "gravity"

    def contribution(self, frame: MovingFrame, coordinates, bodies) -> Contribution:
        g = column(self.vector, frame.axes, f"{self.name}: vector")
        V = sp.S.Zero
        for body in (bodies if self.bodies is None else [as_body(b) for b in self.bodies]):
            kin = body.kinematics(frame)
            if kin.position is None:
                raise ModelError(f"{self.name}: {kin.name} has no position; give the frame an origin Point.")
            V -= kin.mass * g.dot(kin.position)
        return Contribution(V=V)


LOADS = (Force, Torque, Spring, Damper, Gravity)


def as_load(obj):
    """A lagcomp load from a lagcomp load or a sympy.physics.mechanics load pair."""
    if isinstance(obj, LOADS):
        return obj
    if isinstance(obj, tuple) and len(obj) == 2 and isinstance(obj[1], Vector):
        where, vector = obj
        if isinstance(where, Point):
            return Force(vector, where, name=f"force at {where}")
        if isinstance(where, ReferenceFrame):
            return Torque(vector, where, name=f"torque on {where}")
    if isinstance(obj, (Particle, RigidBody)):
        raise ModelError(f"{obj.name} is a body: pass it in `bodies=`, not `loads=`.")
    raise ModelError(
        f"{obj!r} is not a load: give Force, Torque, Spring, Damper, Gravity, or a sympy (Point, Vector) / "
        "(ReferenceFrame, Vector) pair."
    )
