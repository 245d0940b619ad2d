r"""Particles and rigid bodies: lagcomp writes their kinetic energy.

Conventions
-----------
Positions are 3-vectors in the frame R the system is described in
(`lagcomp.model.frames`): components along R's axes, measured from R's
origin, functions of q(t), t and parameters.  Each may be given as

* a sequence or sympy Matrix of three expressions;
* a sympy.physics.vector ``Vector`` from R's origin (R's axes are then needed:
  ``System(frame=N)``);
* a sympy.physics.vector ``Point`` (R's axes, and its origin for anything that
  needs a position rather than a velocity: springs, gravity, a moving frame).

A rigid body's angular velocity ω (relative to R) and its inertia tensor I
about the centre of mass G are written in the same body axes: principal
axes, or any axes in which I is constant (for a body symmetric about an axis,
axes that do not spin with it).  Then, by Koenig's theorem,

    T = ½ M v_G·v_G + ½ ωᵀ I ω.

ω may be given as three components, or as a sympy ``ReferenceFrame`` attached
to the body: lagcomp then takes ω = B.ang_vel_in(R) in the body's axes.  Build
such a frame from elementary rotations — about the current (body) axes or about
fixed axes, with imposed angles such as Ω t allowed — with `rotated`, or
directly with sympy (``orientnew``, ``orient_body_fixed``).

sympy.physics.mechanics ``Particle`` and ``RigidBody`` objects are accepted
wherever lagcomp bodies are (`as_body`), with their ``potential_energy``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import sympy as sp
from sympy.physics import mechanics as me
from sympy.physics.mechanics import dynamicsymbols
from sympy.physics.vector import Dyadic, Point, ReferenceFrame, Vector

from lagcomp.errors import ModelError
from lagcomp.model.stated_velocities import check_stated_velocities
from lagcomp.model.frames import MovingFrame, column

__all__ = ["Particle", "RigidBody", "Kinematics", "as_body", "rotated", "body_rates"]

t = dynamicsymbols._t


@dataclass(frozen=True)
class Kinematics:
    """A body resolved in a frame: what the kinetic energy and the loads need.

    position : Matrix (3, 1) or None
        r_G in the frame's axes (None when only the velocity is known).
    velocity : Matrix (3, 1)
        v_G relative to the frame.
    inertia, angular_velocity : Matrix or None
        I about G and ω relative to the frame, in body axes (None for particles).
    to_body : callable or None
        Maps components along the frame's axes to components along the body's axes.
    """

    name: str
    mass: sp.Expr
    position: sp.Matrix | None
    velocity: sp.Matrix
    inertia: sp.Matrix | None = None
    angular_velocity: sp.Matrix | None = None
    to_body: Callable | None = None
    potential: sp.Expr = sp.S.Zero


# -- checks -----------------------------------------------------------------------------


def _derivatives(expr) -> list:
    return [d for d in sp.sympify(expr).atoms(sp.Derivative)]


def _check_no_velocities(vec: sp.Matrix, what: str) -> None:
    for e in vec:
        if _derivatives(e):
            raise ModelError(f"{what} contains {_derivatives(e)[0]}: a position depends on q and t only, not on velocities.")


def _check_no_accelerations(vec: sp.Matrix, what: str) -> None:
    for e in vec:
        for d in _derivatives(e):
            if d.derivative_count > 1:
                raise ModelError(
                    f"{what} contains the acceleration {d}: an angular velocity depends on q, q̇ and t only."
                )


def _check_mass(mass, name: str) -> sp.Expr:
    try:
        mass = sp.sympify(mass)
    except (sp.SympifyError, TypeError) as err:
        raise ModelError(f"{name}: the mass must be a sympy expression, got {mass!r}.") from err
    if mass.is_negative:
        raise ModelError(f"{name}: the mass {mass} is negative.")
    return mass


def _point_motion(point, frame: MovingFrame, what: str) -> tuple[sp.Matrix | None, sp.Matrix]:
    """(position or None, velocity relative to the frame) of a position-like object."""
    if isinstance(point, (Particle, RigidBody)):
        kin = point.kinematics(frame)
        return kin.position, kin.velocity
    if isinstance(point, Point):
        if frame.axes is None:
            raise ModelError(f"{what} is a sympy Point: give the System `frame=` (a ReferenceFrame or MovingFrame).")
        if frame.origin is not None:
            try:
                r = point.pos_from(frame.origin).to_matrix(frame.axes)
            except ValueError as err:
                raise ModelError(f"{what}: no position of {point} from the frame's origin {frame.origin}: {err}") from err
        else:
            check_stated_velocities([point], [], frame.axes)
            try:
                return None, point.vel(frame.axes).to_matrix(frame.axes)
            except ValueError as err:
                raise ModelError(
                    f"{what}: the velocity of {point} in {frame.axes} is unknown ({err}); locate the point from "
                    "the frame's origin and give MovingFrame(axes=..., origin=...)."
                ) from err
    else:
        r = column(point, frame.axes, what)
    _check_no_velocities(r, what)
    return r, r.diff(t)


# -- inertia ----------------------------------------------------------------------------


def inertia_matrix(inertia, axes, name: str) -> sp.Matrix:
    """I about G in body axes from principal moments, a 3×3 tensor or a Dyadic; checked."""
    if isinstance(inertia, Dyadic):
        if not isinstance(axes, ReferenceFrame):
            raise ModelError(f"{name}: an inertia Dyadic needs the body's axes as a ReferenceFrame.")
        I = inertia.to_matrix(axes)
    else:
        try:
            I = sp.Matrix(inertia)
        except (ValueError, TypeError, sp.SympifyError) as err:
            raise ModelError(f"{name}: inertia must be 3 principal moments or a 3×3 tensor, got {inertia!r}.") from err
        if I.shape in ((3, 1), (1, 3)):
            I = sp.diag(*I)
        if I.shape != (3, 3):
            raise ModelError(f"{name}: inertia must be 3 principal moments or a 3×3 tensor, got shape {I.shape}.")
    for i in range(3):
        for j in range(i + 1, 3):
            if sp.simplify(I[i, j] - I[j, i]) != 0:
                raise ModelError(
                    f"{name}: the inertia tensor is not symmetric (I[{i},{j}] = {I[i, j]} but I[{j},{i}] = {I[j, i]})."
                )
    _check_positive(I, name)
    return I


def _check_positive(I: sp.Matrix, name: str) -> None:
    """Reject a tensor that is certainly not an inertia tensor (numeric, or signs decidable)."""
    if all(e.is_number for e in I):
        values = np.linalg.eigvalsh(np.array(I.evalf(), dtype=float))
        scale = max(abs(values).max(), 1e-300)
        if values.min() < -1e-12 * scale:
            raise ModelError(
                f"{name}: the inertia tensor is not positive semidefinite (principal moments {values.tolist()})."
            )
        a, b, c = sorted(values)
        if a + b < c * (1 - 1e-12):
            raise ModelError(
                f"{name}: principal moments {values.tolist()} violate the triangle inequality I_a + I_b ≥ I_c "
                "that every rigid body satisfies."
            )
        return
    minors = [I[i, i] for i in range(3)]
    minors += [I.extract([i, j], [i, j]).det() for i, j in ((0, 1), (0, 2), (1, 2))] + [I.det()]
    for m in minors:
        if sp.sympify(m).is_negative:
            raise ModelError(f"{name}: the inertia tensor is not positive semidefinite (a principal minor is {m}).")
    if I.is_diagonal():
        d = [I[i, i] for i in range(3)]
        for k in range(3):
            if (d[k - 1] + d[k - 2] - d[k]).is_negative:
                raise ModelError(f"{name}: principal moments {d} violate the triangle inequality I_a + I_b ≥ I_c.")


# -- bodies ------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Particle:
    """A point mass.

    Parameters
    ----------
    mass : expression
    position : 3-vector, sympy Vector or Point
        Position in the system's frame (module docstring).
    name : str, optional
        Used in error messages.
    potential : expression, optional
        A potential energy carried by the particle (added to V).
    """

    mass: object
    position: object
    name: str = "particle"
    potential: object = 0

    def __post_init__(self):
        object.__setattr__(self, "mass", _check_mass(self.mass, self.name))
        object.__setattr__(self, "potential", sp.sympify(self.potential))
        if not isinstance(self.position, (Vector, Point)):
            object.__setattr__(self, "position", column(self.position, None, f"{self.name}: position"))
            _check_no_velocities(self.position, f"{self.name}: position")

    def kinematics(self, frame: MovingFrame | None = None) -> Kinematics:
        r, v = _point_motion(self.position, frame or MovingFrame(), f"{self.name}: position")
        return Kinematics(self.name, self.mass, r, v, potential=self.potential)

    def kinetic_energy(self, frame: MovingFrame | None = None) -> sp.Expr:
        """½ m v² relative to `frame` (Galilean by default; see `MovingFrame.kinetic_energy`)."""
        frame = frame or MovingFrame()
        return frame.kinetic_energy(self.kinematics(frame))


@dataclass(frozen=True, eq=False)
class RigidBody:
    """A rigid body: T = ½ M v_G² + ½ ωᵀ I ω (Koenig's theorem).

    Parameters
    ----------
    mass : expression
    com : 3-vector, sympy Vector or Point
        Position of the centre of mass G in the system's frame.
    inertia : 3 principal moments, 3×3 tensor, or sympy Dyadic
        Inertia about G in body axes; must be symmetric and positive
        semidefinite (checked where the entries' signs are known).
    angular_velocity : 3-vector, sympy Vector, or ReferenceFrame
        ω relative to the system's frame in body axes, functions of q, q̇, t;
        or the body's ReferenceFrame B, giving ω = B.ang_vel_in(frame axes).
    axes : ReferenceFrame or 3×3 Matrix, optional
        The body axes, when they are not the frame given as `angular_velocity`:
        a ReferenceFrame, or the rotation matrix C whose columns are the body
        axes in the system's axes (r_frame = C r_body).  Needed in a turning
        frame, and to give torques as Vectors.
    name : str, optional
    potential : expression, optional
        A potential energy carried by the body (added to V).
    """

    mass: object
    com: object
    inertia: object
    angular_velocity: object
    axes: object = None
    name: str = "body"
    potential: object = 0

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, "mass", _check_mass(self.mass, self.name))
        set_(self, "potential", sp.sympify(self.potential))
        if self.axes is None and isinstance(self.angular_velocity, ReferenceFrame):
            set_(self, "axes", self.angular_velocity)
        if self.axes is not None and not isinstance(self.axes, ReferenceFrame):
            C = sp.Matrix(self.axes)
            if C.shape != (3, 3):
                raise ModelError(f"{self.name}: `axes` must be a ReferenceFrame or a 3×3 rotation matrix.")
            set_(self, "axes", C)
        set_(self, "inertia", inertia_matrix(self.inertia, self.axes, self.name))
        if not isinstance(self.com, (Vector, Point)):
            set_(self, "com", column(self.com, None, f"{self.name}: com"))
            _check_no_velocities(self.com, f"{self.name}: com")
        w = self.angular_velocity
        if isinstance(w, Vector) and not isinstance(self.axes, ReferenceFrame):
            raise ModelError(f"{self.name}: an angular velocity Vector needs the body's `axes` as a ReferenceFrame.")
        if not isinstance(w, (Vector, ReferenceFrame)):
            w = column(w, None, f"{self.name}: angular_velocity")
            _check_no_accelerations(w, f"{self.name}: angular_velocity")
            set_(self, "angular_velocity", w)

    def _omega(self, frame: MovingFrame) -> sp.Matrix:
        w = self.angular_velocity
        if isinstance(w, ReferenceFrame):
            if frame.axes is None:
                raise ModelError(
                    f"{self.name}: the angular velocity is a ReferenceFrame; give the System `frame=` (the "
                    "ReferenceFrame the system is described in, or a MovingFrame with `axes`)."
                )
            check_stated_velocities([], [w], frame.axes)
            w = w.ang_vel_in(frame.axes)
        if isinstance(w, Vector):
            w = w.to_matrix(self.axes)
        _check_no_accelerations(w, f"{self.name}: angular_velocity")
        return w

    def _to_body(self, frame: MovingFrame) -> Callable | None:
        axes = self.axes
        if isinstance(axes, sp.MatrixBase):
            return lambda c: axes.T * c
        if isinstance(axes, ReferenceFrame) and frame.axes is not None:
            R = frame.axes
            return lambda c: (c[0] * R.x + c[1] * R.y + c[2] * R.z).to_matrix(axes)
        return None

    def kinematics(self, frame: MovingFrame | None = None) -> Kinematics:
        frame = frame or MovingFrame()
        r, v = _point_motion(self.com, frame, f"{self.name}: com")
        return Kinematics(
            self.name, self.mass, r, v, self.inertia, self._omega(frame), self._to_body(frame), self.potential
        )

    def kinetic_energy(self, frame: MovingFrame | None = None) -> sp.Expr:
        """½ M v_G² + ½ ωᵀ I ω relative to `frame` (Galilean by default)."""
        frame = frame or MovingFrame()
        return frame.kinetic_energy(self.kinematics(frame))


def as_body(obj):
    """A lagcomp body from a lagcomp or sympy.physics.mechanics Particle / RigidBody."""
    if isinstance(obj, (Particle, RigidBody)):
        return obj
    if isinstance(obj, me.Particle):
        return Particle(obj.mass, obj.point, name=obj.name, potential=obj.potential_energy)
    if isinstance(obj, me.RigidBody):
        inertia = obj.central_inertia.to_matrix(obj.frame)
        return RigidBody(obj.mass, obj.masscenter, inertia, obj.frame, name=obj.name, potential=obj.potential_energy)
    raise ModelError(
        f"{obj!r} is not a body: give lagcomp Particle / RigidBody or sympy.physics.mechanics Particle / RigidBody."
    )


# -- composing rotations -------------------------------------------------------------------


def rotated(reference: ReferenceFrame, *rotations, name: str = "B") -> ReferenceFrame:
    """The frame reached from `reference` by successive rotations ``(angle, axis)``.

    `axis` is ``"x"``, ``"y"`` or ``"z"`` — an axis of the frame reached so far
    (body axes, intrinsic rotations: Euler angles) — or a sympy Vector with
    constant components in `reference` (``N.z``: a rotation about a fixed axis).
    Angles are expressions in q(t), t and parameters; an imposed rate is an
    angle such as ``Omega*t``.  The angular velocity follows from sympy:
    ``body_rates(B, reference)``.

    With R the rotation matrix, a body-axis rotation A multiplies it on the
    right (R → R A), a fixed-axis rotation E on the left (R → E R), so
    R = (E_m ⋯ E_1)(A_1 ⋯ A_p): the fixed-axis rotations, last first, then the
    body-axis ones in order.  Each factor is a rotation about an axis with
    constant components in its parent frame, which is what sympy's ``orientnew``
    needs to give the angular velocity as a sum of rates.
    """
    fixed, body = [], []
    for rotation in rotations:
        try:
            angle, axis = rotation
        except (TypeError, ValueError):
            raise ModelError(f"Rotation {rotation!r} must be a pair (angle, axis).") from None
        if isinstance(axis, str):
            if axis not in ("x", "y", "z"):
                raise ModelError(f"Rotation axis {axis!r} must be 'x', 'y', 'z' or a sympy Vector.")
            body.append((sp.sympify(angle), sp.Matrix([int(axis == c) for c in "xyz"])))
        elif isinstance(axis, Vector):
            n = axis.to_matrix(reference)
            if any(e.has(t) for e in n):
                raise ModelError(f"Fixed rotation axis {axis} must have constant components in {reference}.")
            fixed.append((sp.sympify(angle), n))
        else:
            raise ModelError(f"Rotation axis {axis!r} must be 'x', 'y', 'z' or a sympy Vector.")
    steps = fixed[::-1] + body
    frame = reference
    for k, (angle, n) in enumerate(steps):
        label = name if k == len(steps) - 1 else f"{name}_{k + 1}"
        axis = n[0] * frame.x + n[1] * frame.y + n[2] * frame.z
        frame = frame.orientnew(label, "Axis", (angle, axis))
    return frame


def body_rates(frame: ReferenceFrame, reference: ReferenceFrame) -> sp.Matrix:
    """Angular velocity of `frame` relative to `reference`, components along `frame`'s axes."""
    return frame.ang_vel_in(reference).to_matrix(frame)
