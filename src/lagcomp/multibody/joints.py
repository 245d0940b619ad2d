"""Joints of a kinematic tree: how a link moves relative to its parent.

Every joint is placed in the parent link's frame by `origin` (the joint frame's origin, parent axes, metres) and
`rotation` (3×3, columns the joint frame's axes in the parent's axes; identity by default), as a URDF ``<origin>``
or Pinocchio's joint placement.  The joint's motion then moves the child link's frame relative to that joint frame:

* `Revolute`: a rotation by the coordinate q (radians, right-handed about `axis`);
* `Prismatic`: a translation by q (metres) along `axis`;
* `Universal`, `Cylindrical`, `Planar`: chains of those with massless frames in between (two rotations about
  `axes`; a translation and a rotation along/about one axis; translations along x, y and a rotation about z of the
  joint frame).

`axis` is ``"x"``, ``"y"``, ``"z"`` (the joint frame's axes) or three numbers (normalised).  A revolute or prismatic
joint may carry a spring (stiffness k about `rest`), a viscous damper (`damping`) and a driving `torque` (a force
for a prismatic joint) along its axis: generalized force τ = torque − k (q − rest) − c q̇ (N m or N).

`Spherical` (3 DOF) and `Free` (6 DOF: three translations, then a spherical rotation) joints turn the link by the
modified Rodrigues parameters of `lagcomp.multibody.mrp`, switched to their shadow set at half a turn.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from lagcomp.errors import ModelError

t = dynamicsymbols._t

#: The issue that tracks what this step of the multibody path leaves out (for messages).
ISSUE = "issue 39"


def coordinate_of(value, what: str):
    """A coordinate q(t): `value` itself (from ``lc.coordinates``) or one made from a name."""
    if isinstance(value, str):
        if not value.isidentifier():
            raise ModelError(f"{what}: the coordinate name {value!r} must be a Python identifier (like 'theta1').")
        return dynamicsymbols(value)
    if isinstance(value, sp.core.function.AppliedUndef) and value.args == (t,):
        return value
    raise ModelError(f"{what}: a coordinate is a name or a function of time from lc.coordinates, got {value!r}.")


def unit_axis(axis, what: str) -> tuple:
    """`axis` as a unit 3-vector of sympy numbers (``"x"``, ``"y"``, ``"z"`` or three numbers)."""
    if isinstance(axis, str):
        if axis not in ("x", "y", "z"):
            raise ModelError(f"{what}: axis {axis!r} must be 'x', 'y', 'z' or three numbers.")
        return tuple(sp.S.One if axis == c else sp.S.Zero for c in "xyz")
    try:
        values = [sp.sympify(v) for v in axis]
    except (TypeError, sp.SympifyError) as err:
        raise ModelError(f"{what}: axis {axis!r} must be 'x', 'y', 'z' or three numbers.") from err
    if len(values) != 3 or not all(v.is_number for v in values):
        raise ModelError(f"{what}: axis {axis!r} must be 'x', 'y', 'z' or three numbers.")
    if any(v.has(sp.Float) for v in values):   # measured numbers (a URDF's): normalised in floats, every digit kept
        unit = np.array([float(v) for v in values])
        norm = float(np.linalg.norm(unit))
        if norm == 0:
            raise ModelError(f"{what}: the axis is the zero vector.")
        return tuple(sp.Float(float(x)) if x != 0 else sp.S.Zero for x in unit / norm)
    norm = sp.sqrt(sum(v ** 2 for v in values))   # exact numbers: an exact unit vector ((1, 1, 0) → (√2/2, √2/2, 0))
    if norm == 0:
        raise ModelError(f"{what}: the axis is the zero vector.")
    return tuple(sp.nsimplify(v / norm) for v in values)


@dataclass(frozen=True)
class Elementary:
    """One degree of freedom: "revolute" or "prismatic" motion by `coordinate` along the unit `axis` of its joint
    frame, or "spherical": MRP `coordinate` along `axis` = e_k, one of three consecutive nodes of a ball joint, placed by (`rotation`, `origin`) in its parent frame, with the generalized force `torque` − k (q − rest)
    − c q̇."""

    kind: str
    coordinate: object
    axis: tuple
    origin: tuple = (0, 0, 0)
    rotation: tuple = ((1, 0, 0), (0, 1, 0), (0, 0, 1))
    stiffness: object = 0
    rest: object = 0
    damping: object = 0
    torque: object = 0


@dataclass(frozen=True)
class Joint:
    """Base of the joints: a placement in the parent link's frame (module docstring)."""

    origin: tuple = field(default=(0, 0, 0), kw_only=True)
    rotation: object = field(default=None, kw_only=True)

    def elementary(self) -> list[Elementary]:   # pragma: no cover - every joint overrides it
        raise NotImplementedError

    def _placement(self, what: str) -> dict:
        """The checked `origin` and `rotation` as keyword arguments of the first `Elementary`."""
        try:
            origin = tuple(sp.sympify(v) for v in self.origin)
        except (TypeError, sp.SympifyError) as err:
            raise ModelError(f"{what}: `origin` must be three expressions, got {self.origin!r}.") from err
        if len(origin) != 3:
            raise ModelError(f"{what}: `origin` must be three expressions, got {self.origin!r}.")
        if self.rotation is None:
            return {"origin": origin}
        try:
            R = sp.Matrix(self.rotation)
        except (TypeError, ValueError, sp.SympifyError) as err:
            raise ModelError(f"{what}: `rotation` must be a 3×3 rotation matrix, got {self.rotation!r}.") from err
        if R.shape != (3, 3):
            raise ModelError(f"{what}: `rotation` must be a 3×3 rotation matrix, got shape {R.shape}.")
        if all(e.is_number for e in R):
            error = (R.T * R - sp.eye(3)).evalf()
            if max(abs(float(e)) for e in error) > 1e-12 or float(R.det().evalf()) < 0:
                raise ModelError(f"{what}: `rotation` {R.tolist()} is not a rotation (RᵀR = 1, det R = +1).")
        return {"origin": origin, "rotation": tuple(tuple(R.row(i)) for i in range(3))}


@dataclass(frozen=True)
class Revolute(Joint):
    """A hinge: rotation by `coordinate` (rad) about `axis` of the joint frame, right-handed.

    Parameters
    ----------
    coordinate : str or function of t
        The joint angle q (a name, or a coordinate from ``lc.coordinates``).
    axis : {"x", "y", "z"} or 3 numbers, default "z"
    stiffness, rest, damping, torque : expressions, optional
        Generalized force on q: τ = torque − stiffness·(q − rest) − damping·q̇ (N m); torque may depend on t, the
        coordinates, their velocities and parameters.
    origin, rotation : keyword-only
        The joint frame in the parent link's frame (module docstring).
    """

    coordinate: object
    axis: object = "z"
    stiffness: object = 0
    rest: object = 0
    damping: object = 0
    torque: object = 0

    def elementary(self) -> list[Elementary]:
        what = f"Revolute({self.coordinate})"
        return [Elementary("revolute", coordinate_of(self.coordinate, what), unit_axis(self.axis, what),
                           stiffness=sp.sympify(self.stiffness), rest=sp.sympify(self.rest),
                           damping=sp.sympify(self.damping), torque=sp.sympify(self.torque),
                           **self._placement(what))]


@dataclass(frozen=True)
class Prismatic(Revolute):
    """A slider: translation by `coordinate` (m) along `axis` of the joint frame; as `Revolute` otherwise (its
    generalized force τ is a force, N)."""

    def elementary(self) -> list[Elementary]:
        return [replace(e, kind="prismatic") for e in super().elementary()]


@dataclass(frozen=True)
class Universal(Joint):
    """Two rotations: by `coordinates[0]` about `axes[0]` of the joint frame, then by `coordinates[1]` about
    `axes[1]` of the frame the first reached (a Cardan joint; default axes x then y)."""

    coordinates: tuple
    axes: tuple = ("x", "y")

    def elementary(self) -> list[Elementary]:
        what = f"Universal{tuple(self.coordinates)}"
        _pairs(self.coordinates, self.axes, 2, what)
        first = Elementary("revolute", coordinate_of(self.coordinates[0], what), unit_axis(self.axes[0], what),
                           **self._placement(what))
        return [first, Elementary("revolute", coordinate_of(self.coordinates[1], what), unit_axis(self.axes[1], what))]


@dataclass(frozen=True)
class Cylindrical(Joint):
    """A translation by `coordinates[0]` (m) along `axis`, then a rotation by `coordinates[1]` (rad) about it."""

    coordinates: tuple
    axis: object = "z"

    def elementary(self) -> list[Elementary]:
        what = f"Cylindrical{tuple(self.coordinates)}"
        _pairs(self.coordinates, (self.axis, self.axis), 2, what)
        axis = unit_axis(self.axis, what)
        return [Elementary("prismatic", coordinate_of(self.coordinates[0], what), axis, **self._placement(what)),
                Elementary("revolute", coordinate_of(self.coordinates[1], what), axis)]


@dataclass(frozen=True)
class Planar(Joint):
    """Motion in the joint frame's x-y plane: translations by `coordinates[0]`, `coordinates[1]` (m) along x and y,
    then a rotation by `coordinates[2]` (rad) about z."""

    coordinates: tuple

    def elementary(self) -> list[Elementary]:
        what = f"Planar{tuple(self.coordinates)}"
        _pairs(self.coordinates, ("x", "y", "z"), 3, what)
        x, y, z = (unit_axis(a, what) for a in "xyz")
        return [Elementary("prismatic", coordinate_of(self.coordinates[0], what), x, **self._placement(what)),
                Elementary("prismatic", coordinate_of(self.coordinates[1], what), y),
                Elementary("revolute", coordinate_of(self.coordinates[2], what), z)]


@dataclass(frozen=True)
class Spherical(Joint):
    """A ball joint (3 rotational DOF): the link's frame turned by the rotation whose modified Rodrigues parameters
    (MRPs) are the three `coordinates`, σ = n tan(θ/4) for the angle θ about the unit axis n of the joint frame
    (`lagcomp.multibody.mrp`; docs/multibody.md says why MRPs).

    The coordinates jump to the shadow set σ → −σ/|σ|² (the same orientation, |σ| back below 1) whenever |σ| passes
    1 (a half turn): an event with a reset named ``<link>_shadow``, so the adaptive methods with events integrate
    it.  Initial values: ``mrp_from_rotation``, ``mrp_from_axis_angle`` and ``mrp_rate`` (from the body-frame
    angular velocity) of `lagcomp.multibody.mrp`.

    Parameters
    ----------
    coordinates : 3 names or functions of t
        σ_x, σ_y, σ_z (dimensionless), along the joint frame's axes.
    damping : expression, optional
        A viscous moment −damping·ω on the link (N m s), ω its angular velocity relative to the parent.
    torque : 3 expressions, optional
        A moment on the link from its parent (N m), components along the link's own axes; it may depend on t, the
        coordinates, their velocities and parameters.
    origin, rotation : keyword-only
        The joint frame in the parent link's frame (module docstring).
    """

    coordinates: tuple
    damping: object = 0
    torque: tuple = (0, 0, 0)

    def elementary(self) -> list[Elementary]:
        what = f"Spherical{_shown(self.coordinates)}"
        _pairs(self.coordinates, "xyz", 3, what)
        if isinstance(self.torque, str) or len(tuple(self.torque)) != 3:
            raise ModelError(f"{what}: `torque` must be three expressions (body axes), got {self.torque!r}.")
        steps = spherical_steps(self.coordinates, what, self._placement(what))
        return [replace(step, damping=sp.sympify(self.damping), torque=sp.sympify(moment))
                for step, moment in zip(steps, self.torque)]


@dataclass(frozen=True)
class Free(Joint):
    """A floating base (6 DOF): the link's frame translated by `coordinates[0:3]` (m, along the joint frame's x, y,
    z: the position of the link's origin in the joint frame), then turned by the MRPs `coordinates[3:6]` as a
    `Spherical` joint (its shadow switch included).  Its velocities are these coordinates' rates: the origin's
    velocity in the joint frame and σ̇ (`lagcomp.multibody.mrp.mrp_rate` of the body-frame angular velocity)."""

    coordinates: tuple

    def elementary(self) -> list[Elementary]:
        what = f"Free{_shown(self.coordinates)}"
        _pairs(self.coordinates, "xyzxyz", 6, what)
        x, y, z = (unit_axis(a, what) for a in "xyz")
        translations = [Elementary("prismatic", coordinate_of(self.coordinates[0], what), x, **self._placement(what)),
                        Elementary("prismatic", coordinate_of(self.coordinates[1], what), y),
                        Elementary("prismatic", coordinate_of(self.coordinates[2], what), z)]
        return translations + spherical_steps(self.coordinates[3:], what, {})


def spherical_steps(coordinates, what: str, placement: dict) -> list[Elementary]:
    """The three nodes of a spherical joint: kind "spherical", σ_k along e_k; the first carries the placement (the
    recursions read the three together: `lagcomp.multibody.kinematics`)."""
    axes = [unit_axis(a, what) for a in "xyz"]
    steps = [Elementary("spherical", coordinate_of(c, what), axis) for c, axis in zip(coordinates, axes)]
    return [replace(steps[0], **placement), *steps[1:]]


def _shown(coordinates) -> str:
    return repr(coordinates) if isinstance(coordinates, str) else str(tuple(coordinates))


def _pairs(coordinates, axes, count: int, what: str) -> None:
    if isinstance(coordinates, str) or len(tuple(coordinates)) != count:
        raise ModelError(f"{what}: needs {count} coordinates, one per degree of freedom; got {coordinates!r}.")
    if len(tuple(axes)) != count:
        raise ModelError(f"{what}: needs {count} axes, one per coordinate; got {axes!r}.")
