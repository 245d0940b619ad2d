r"""The frame a system is described in, and the inertial terms of a moving one.

Bodies and loads are written in one frame R: positions are components along
R's axes, measured from R's origin O, and velocities are rates of change of
those components (velocities relative to R).  R may be Galilean, or move
relative to a Galilean frame G with an imposed motion:

* its origin has the acceleration a_e(t) relative to G (components along R's axes);
* its axes turn with the angular velocity ω_e(t) relative to G (components along R's axes).

Both are explicit functions of t and the parameters (imposed motions), never of q.

How lagcomp accounts for the motion of R
----------------------------------------
For a point of mass m at r (in R) with relative velocity v = ṙ, Newton's law
in R reads m a = F − m a_e − m ω̇_e × r − m ω_e × (ω_e × r) − 2 m ω_e × v
(driving, Euler, centrifugal and Coriolis forces).  Rather than adding the
virtual work of each inertial force, lagcomp writes the Lagrangian with the
absolute velocity, whose components along R's axes are v_O + ω_e × r + v
(v_O: velocity of O relative to G).  Expanding ½ m |v_O + ω_e × r + v|²,

    ½ m |ω_e × r + v|²  +  m v_O·(ω_e × r + v)  +  ½ m |v_O|²,

the last term depends on t only, and ω_e × r + v is the rate of change of the
vector r seen from G, so the middle term is d/dt(m v_O·r) − m a_e·r.  Dropping
the total derivative (it does not change Lagrange's equations) leaves

    T_R = ½ m |v + ω_e × r|²          (kinetic energy, absolute velocity up to v_O)
    V_R = m a_e · r                   (potential of the driving force −m a_e)

whose Lagrange equations are exactly those of T = ½ m v² with the four
inertial forces above as generalized forces Q_i = Σ f·∂r/∂q_i (the tests check
this symbolically).  The translation enters through a_e, so v_O = ∫ a_e dt is
never needed.  For a rigid body (Koenig's theorem in G) the centre of mass
is treated as a point of mass M, and the rotational energy uses the absolute
angular velocity ω + ω_e, with ω_e expressed in the body's axes:

    T_R = ½ M |v_G + ω_e × r_G|² + ½ (ω + ω_e)ᵀ I (ω + ω_e),    V_R = M a_e · r_G.

Why this form and not the forces: the result is a Lagrangian.  The momenta
lagcomp reports are the absolute ones (Compton's disc: p_φ = I_Y (φ̇ + ω_e·axis),
conserved because φ is cyclic), the Jacobi integral h is conserved in a
uniformly turning frame (it contains the centrifugal potential −½ m |ω_e × r|²),
and the gyroscopic and Euler couples on rigid bodies come out of the same
expression with no separate derivation.  The price is that a body in a
turning frame must say how its axes are oriented in R (to express ω_e in
them): give its angular velocity as a sympy ReferenceFrame, or its `axes`.

Sign conventions: a_e and ω_e are the motion of R relative to G (not of G
relative to R); the driving force on a mass m is −m a_e.  A support
accelerated upwards (a_e = +ḧ e_up) therefore acts like extra gravity.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp
from sympy.physics.vector import Point, ReferenceFrame, Vector

from lagcomp.errors import ModelError
from lagcomp.model.inputs import is_input

__all__ = ["MovingFrame", "as_frame", "column"]


def column(value, axes: ReferenceFrame | None, what: str) -> sp.Matrix:
    """A 3-vector as a 3×1 Matrix of components along `axes`.

    `value` is a sympy.physics.vector Vector (expressed in `axes`, which must
    then be given), a sequence or Matrix of three expressions, or 0.
    """
    if isinstance(value, Vector):
        if axes is None:
            raise ModelError(
                f"{what} is a sympy.physics.vector Vector, but no ReferenceFrame says which axes to express it in: "
                "give the System `frame=` (a ReferenceFrame or MovingFrame(axes=...))."
            )
        try:
            return value.to_matrix(axes)
        except ValueError as err:  # sympy: no orientation path between the frames
            raise ModelError(f"{what} cannot be expressed in {axes}: {err}") from err
    if isinstance(value, (int, float, sp.Expr)) and value == 0:
        return sp.zeros(3, 1)
    try:
        entries = list(value)
    except TypeError:
        raise ModelError(f"{what} must be a 3-vector (sequence, Matrix or sympy Vector), got {value!r}.") from None
    if isinstance(value, sp.MatrixBase) and value.shape not in ((3, 1), (1, 3)) or len(entries) != 3:
        raise ModelError(f"{what} must have 3 components, got {value!r}.")
    try:
        return sp.Matrix([sp.sympify(e) for e in entries])
    except (sp.SympifyError, TypeError) as err:
        raise ModelError(f"{what}: components must be sympy expressions, got {value!r}.") from err


def _check_imposed(vec: sp.Matrix, what: str) -> None:
    for e in vec:  # inputs (lagcomp.Input) are imposed too: signals of t
        bad = {f for f in e.atoms(sp.core.function.AppliedUndef) if not is_input(f)}
        bad |= {d for d in e.atoms(sp.Derivative) if not is_input(d.expr)}
        if bad:
            raise ModelError(
                f"{what} contains {sorted(map(str, bad))[0]}: the motion of a frame is imposed, an explicit "
                "function of t and parameters. A frame whose motion is unknown is a body: give it coordinates."
            )


@dataclass(frozen=True, eq=False)
class MovingFrame:
    """The frame R that positions and velocities are written in (see the module docstring).

    Parameters
    ----------
    axes : sympy.physics.vector.ReferenceFrame, optional
        R's axes, needed when bodies, forces or the frame's own motion are
        given as sympy.physics.vector objects.
    origin : sympy.physics.vector.Point, optional
        R's origin, needed when positions are sympy Points.
    acceleration : 3-vector, optional
        a_e(t): acceleration of R's origin relative to a Galilean frame,
        components along R's axes (or a Vector).
    angular_velocity : 3-vector, optional
        ω_e(t): angular velocity of R relative to a Galilean frame, components
        along R's axes (or a Vector, e.g. ``R.ang_vel_in(N)``).

    ``MovingFrame()`` or ``MovingFrame(axes=N)`` is a Galilean frame.
    """

    axes: ReferenceFrame | None = None
    origin: Point | None = None
    acceleration: object = 0
    angular_velocity: object = 0

    def __post_init__(self):
        if self.axes is not None and not isinstance(self.axes, ReferenceFrame):
            raise ModelError(f"MovingFrame `axes` must be a sympy ReferenceFrame, got {self.axes!r}.")
        if self.origin is not None and not isinstance(self.origin, Point):
            raise ModelError(f"MovingFrame `origin` must be a sympy Point, got {self.origin!r}.")
        a = column(self.acceleration, self.axes, "MovingFrame acceleration")
        w = column(self.angular_velocity, self.axes, "MovingFrame angular_velocity")
        _check_imposed(a, "MovingFrame acceleration")
        _check_imposed(w, "MovingFrame angular_velocity")
        object.__setattr__(self, "acceleration", a)
        object.__setattr__(self, "angular_velocity", w)

    @property
    def translating(self) -> bool:
        return any(e != 0 for e in self.acceleration)

    @property
    def rotating(self) -> bool:
        return any(e != 0 for e in self.angular_velocity)

    @property
    def galilean(self) -> bool:
        return not (self.translating or self.rotating)

    def describe(self) -> str:
        """Canonical text of the frame's motion (for fingerprints and messages)."""
        return f"a_e={sp.srepr(self.acceleration)} w_e={sp.srepr(self.angular_velocity)}"

    # -- the inertial terms (module docstring) ---------------------------------------

    def kinetic_energy(self, kin) -> sp.Expr:
        """T_R of one body's `Kinematics`: absolute velocities composed in R's axes."""
        return sum(self.kinetic_energy_parts(kin), sp.S.Zero)

    def kinetic_energy_parts(self, kin) -> tuple[sp.Expr, sp.Expr]:
        """(½ M |v_G + ω_e × r_G|², ½ (ω + ω_e)ᵀ I (ω + ω_e)) of one body (module docstring)."""
        v, w = kin.velocity, kin.angular_velocity
        if self.rotating:
            if kin.position is None:
                raise ModelError(
                    f"{kin.name}: in a turning frame lagcomp needs the body's position, not only its velocity; "
                    "give the frame an `origin` Point (MovingFrame(axes=..., origin=...))."
                )
            v = v + self.angular_velocity.cross(kin.position)
            if w is not None:
                if kin.to_body is None:
                    raise ModelError(
                        f"{kin.name}: in a turning frame the frame's rotation must be expressed in the body's axes; "
                        "give the body's angular velocity as a sympy ReferenceFrame, or its `axes` "
                        "(a ReferenceFrame or a rotation matrix)."
                    )
                w = w + kin.to_body(self.angular_velocity)
        rotation = sp.S.Zero if w is None else (w.T * kin.inertia * w)[0, 0] / 2
        return kin.mass * v.dot(v) / 2, rotation

    def driving_potential(self, kin) -> sp.Expr:
        """V_R = m a_e·r: potential of the driving force −m a_e on one body."""
        if not self.translating:
            return sp.S.Zero
        if kin.position is None:
            raise ModelError(
                f"{kin.name}: in an accelerated frame lagcomp needs the body's position; give the frame an "
                "`origin` Point (MovingFrame(axes=..., origin=...))."
            )
        return kin.mass * self.acceleration.dot(kin.position)


def as_frame(frame) -> MovingFrame:
    """`System(frame=...)` normalized: None (Galilean, plain components), a ReferenceFrame, or a MovingFrame."""
    if frame is None:
        return MovingFrame()
    if isinstance(frame, MovingFrame):
        return frame
    if isinstance(frame, ReferenceFrame):
        return MovingFrame(axes=frame)
    raise ModelError(
        f"`frame` must be a sympy ReferenceFrame (a Galilean frame) or a lagcomp MovingFrame, got {frame!r}."
    )
