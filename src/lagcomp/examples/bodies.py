r"""Bundled examples built from bodies, loads and moving frames instead of a hand-written T.

Each system is described the way the mechanism is drawn: rigid bodies with
their principal moments, frames reached by elementary rotations
(`lagcomp.rotated`, sympy.physics.vector underneath), torques and gravity as
loads, and — for the gyroscopes and the driven pendulum — a frame that moves
relative to a Galilean one (`lagcomp.MovingFrame`), whose inertial terms
lagcomp adds.  The docstrings state the kinetic energy this produces and the
equations of motion, derived by hand; the tests check both.
"""

from __future__ import annotations

import sympy as sp
from sympy.physics.vector import ReferenceFrame

from lagcomp.model import Force, Gravity, MovingFrame, Particle, RigidBody, System, Torque, coordinates, rotated, t

__all__ = [
    "turn_indicator", "compton_disc", "driven_pendulum_support", "symmetric_top", "wheel_jack", "BODIES_EXAMPLES",
]


def _params(names: str) -> tuple[sp.Symbol, ...]:
    """Positive real parameters, always as a tuple."""
    return tuple(sp.symbols(names, positive=True, seq=True))


def turn_indicator() -> System:
    r"""Turn indicator: a gyroscope in a gimbal, inside an aircraft turning at ω about the vertical.

    Frames.  A turns with the aircraft at the imposed rate ω about the true
    vertical z (a MovingFrame with ω_e = ω z); its axis X is the fuselage axis,
    horizontal, pointing aft, and Y = z × X points to the right wing.  The
    aircraft is banked by the constant α about X (apparent vertical z′ = wing
    normal; a left turn, ω > 0, banks the right wing up: α = arctan(ωV/g) > 0
    at speed V).  The gimbal turns about X by θ from z′ (the coordinate; the
    needle); the flywheel, a body of revolution about the gimbal's Y axis with
    moments I about it and I_X about any diameter, is spun by a motor at the
    imposed rate Ω relative to the gimbal.  Its centre is on the axis and fixed.
    A spiral spring and a dashpot act between aircraft and gimbal: the torque
    −(k θ + c θ̇) about X on the (massless) gimbal.

    With β = θ + α the flywheel's absolute angular velocity in gimbal axes is
    (θ̇, Ω + ω sin β, ω cos β), so (mass irrelevant: the centre does not move)
        T = ½ I_X (θ̇² + ω² cos² β) + ½ I (Ω + ω sin β)²,
        I_X θ̈ + ½ (I_X − I) ω² sin 2β − I ω Ω cos β = −k θ − c θ̇.
    Steady tilt θ*: k θ* = I ω Ω cos(θ* + α) + ½ (I − I_X) ω² sin 2(θ* + α), to
    first order in ω/Ω the pilot's reading ω ≈ k θ*/(I Ω cos(θ* + α)).
    Defaults: a small gyro (I = 2·10⁻⁴ kg m², Ω = 2000 rad/s), a standard-rate
    turn ω = 0.05 rad/s banked α = 0.47 rad (V ≈ 100 m/s), k = 0.1 N m/rad,
    light damping (ζ ≈ 0.14): θ* ≈ 0.161 rad, settled to 10⁻¹⁰ within 10 s.
    """
    (theta,) = coordinates("theta")
    I_X, I, Omega, omega, alpha, k, c = _params("I_X I Omega omega alpha k c")
    A = ReferenceFrame("A")  # aircraft, not banked: X aft, z true vertical
    gimbal = rotated(A, (alpha, "x"), (theta, "x"), name="G")
    flywheel = rotated(gimbal, (Omega * t, "y"), name="F")
    wheel = RigidBody(1, (0, 0, 0), (I_X, I, I_X), flywheel, axes=gimbal, name="flywheel")
    spring_and_dashpot = Torque(-(k * theta + c * theta.diff(t)) * gimbal.x, gimbal, name="spring_dashpot")
    return System(
        coordinates=(theta,),
        bodies=(wheel,),
        loads=(spring_and_dashpot,),
        frame=MovingFrame(axes=A, angular_velocity=omega * A.z),
        parameters=(I_X, I, Omega, omega, alpha, k, c),
        name="turn_indicator",
        description="Gyroscope in a gimbal of a banked, turning aircraft: the needle's tilt measures the turn rate.",
        defaults={"I_X": 1.2e-4, "I": 2e-4, "Omega": 2000.0, "omega": 0.05, "alpha": 0.47, "k": 0.1, "c": 1e-3},
        q0=(0.0,), qd0=(0.0,), t_end=10.0,
    )


def compton_disc() -> System:
    r"""Compton's disc: a wheel on a turning carousel (or the Earth) whose axis is swung over.

    Frames.  The carousel C turns at ω relative to a Galilean frame; at a place
    of latitude λ on the Earth (the carousel), with axes X south, Y east, z up,
    its rotation vector is ω_e = −ω cos λ X + ω sin λ z (λ = π/2: the pole).
    The disc's axis, held at the fixed centre, is swung in the plane (Y, z) by
    the imposed angle θ(t) from the vertical — the pivot frame P is C turned by
    θ + π/2 about X, so its axis Y_P = cos θ z − sin θ Y — here
    θ(t) = π (1 − cos νt)/2: from up (t = 0) to down (t = π/ν) and back.  The
    disc (moments I about a diameter, I_Y about its axis) turns freely by the
    coordinate φ about Y_P.

    Absolute angular velocity in P axes: (θ̇ − ω cos λ, φ̇ + ω sin λ cos θ, −ω sin λ sin θ),
        T = ½ I [(θ̇ − ω cos λ)² + ω² sin² λ sin² θ] + ½ I_Y (φ̇ + ω sin λ cos θ)².
    φ is cyclic: p_φ = I_Y (φ̇ + ω sin λ cos θ) is conserved, so from rest on the
    carousel with the axis up, φ̇(t) = ω sin λ (1 − cos θ(t)): 2 ω sin λ once
    the axis is reversed, nothing at the equator.
    """
    (phi,) = coordinates("phi")
    I, I_Y, omega, lam, nu = _params("I I_Y omega lambda nu")
    theta = sp.pi * (1 - sp.cos(nu * t)) / 2
    C = ReferenceFrame("C")  # X south, Y east, z up
    pivot = rotated(C, (theta + sp.pi / 2, "x"), name="P")
    disc = rotated(pivot, (phi, "y"), name="D")
    carousel = MovingFrame(axes=C, angular_velocity=-omega * sp.cos(lam) * C.x + omega * sp.sin(lam) * C.z)
    return System(
        coordinates=(phi,),
        bodies=(RigidBody(1, (0, 0, 0), (I, I_Y, I), disc, axes=pivot, name="disc"),),
        frame=carousel,
        parameters=(I, I_Y, omega, lam, nu),
        name="compton_disc",
        description="Disc on a turning carousel whose axis is swung over: it spins up by 2 ω sin λ.",
        defaults={"I": 0.05, "I_Y": 0.1, "omega": 1.0, "lambda": 0.7, "nu": 0.5},
        q0=(0.0,), qd0=(0.0,), t_end=12.0,
    )


def driven_pendulum_support() -> System:
    r"""The pendulum of `driven_pendulum` written in the frame of its vibrating support.

    The support is at height h(t) = A cos(Ω t) in a Galilean frame; in the
    support's frame (a MovingFrame translating with a_e = ḧ e_y, y up) the bob
    is a Particle at (l sin θ, −l cos θ, 0), gravity (0, −g, 0).  lagcomp adds
    the driving force −m a_e as the potential m ḧ y, so
        T = ½ m l² θ̇²,   V = −m (g + ḧ) l cos θ,
        θ̈ + (g + ḧ)/l sin θ = 0,   ḧ = −A Ω² cos(Ω t):
    the same equation as `driven_pendulum` (inertial frame), same parameters and defaults.
    """
    (theta,) = coordinates("theta")
    m, l, g, A, Omega = _params("m l g A Omega")
    h = A * sp.cos(Omega * t)
    bob = Particle(m, (l * sp.sin(theta), -l * sp.cos(theta), 0), name="bob")
    return System(
        coordinates=(theta,),
        bodies=(bob,),
        loads=(Gravity((0, -g, 0)),),
        frame=MovingFrame(acceleration=(0, h.diff(t, 2), 0)),
        parameters=(m, l, g, A, Omega),
        name="driven_pendulum_support",
        description="Kapitza's pendulum in the frame of its support, with the driving inertial force.",
        defaults={"m": 1.0, "l": 1.0, "g": 9.81, "A": 0.05, "Omega": 200.0},
        q0=(2.9,), qd0=(0.0,), t_end=10.0,
    )


def symmetric_top() -> System:
    r"""Heavy symmetric top with a fixed point O, in Euler angles (z–x–z).

    Fixed axes N, z up.  Coordinates ψ (precession about z), θ (nutation: the
    axis's angle from z), φ (spin about the axis).  The top has mass M, centre
    of mass G on its axis at distance l from O, central moments I1 (about any
    diameter through G) and I3 (about the axis).  Rigid body with com l e_3,
    inertia in the non-spinning axes reached by (ψ about z, θ about x); gravity (0, 0, −g).
    With I1′ = I1 + M l² (moment about O),
        T = ½ I1′ (θ̇² + ψ̇² sin² θ) + ½ I3 (φ̇ + ψ̇ cos θ)²,   V = M g l cos θ.
    ψ and φ are cyclic: p_φ = I3 (φ̇ + ψ̇ cos θ) and p_ψ = I1′ ψ̇ sin² θ + p_φ cos θ
    are conserved with E = T + V.  With u = cos θ and E′ = E − p_φ²/(2 I3),
        u̇² = f(u) = (2/I1′)(E′ − M g l u)(1 − u²) − (p_ψ − p_φ u)²/I1′²,
    a cubic; θ nutates between the arccosines of its two roots in [−1, 1].
    Defaults: a fast top (spin 100 rad/s) released with θ̇ = ψ̇ = 0 at θ = 0.5:
    cusped nutation, period ≈ 0.14 s, slow precession ≈ 3 rad/s.
    """
    psi, theta, phi = coordinates("psi theta phi")
    M, l, g, I1, I3 = _params("M l g I1 I3")
    N = ReferenceFrame("N")
    tilted = rotated(N, (psi, "z"), (theta, "x"), name="K")  # axis K.z, not spinning
    top = rotated(tilted, (phi, "z"), name="B")
    body = RigidBody(M, l * top.z, (I1, I1, I3), top, axes=tilted, name="top")
    return System(
        coordinates=(psi, theta, phi),
        bodies=(body,),
        loads=(Gravity(-g * N.z),),
        frame=N,
        parameters=(M, l, g, I1, I3),
        name="symmetric_top",
        description="Heavy symmetric top on a fixed point: precession and nutation in Euler angles.",
        defaults={"M": 0.5, "l": 0.05, "g": 9.81, "I1": 5e-4, "I3": 8e-4},
        q0=(0.0, 0.5, 0.0), qd0=(0.0, 0.0, 100.0), t_end=5.0,
    )


def wheel_jack() -> System:
    r"""Wheel jack: a crank turns a screw that closes a lozenge, lifting a load (a statics problem).

    Geometry (plane x horizontal, y up).  The lozenge ABCD has side l; C rests
    on the ground at the origin, the load sits on A = (0, 2 l sin θ), and B, D
    = (±l cos θ, l sin θ) are joined by the threaded stem, horizontal, of
    length DB = 2 l cos θ.  Coordinate θ: the angle between a side and the
    stem.  The crank (arm a) turns the stem about its axis by α; a screw of
    pitch h shortens DB by h per turn, so up to a constant
        α(θ) = −4π l cos θ / h,     α′(θ) = 4π l sin θ / h.
    Loads: the weight P on A, Force (0, −P) at A; the effort F pushing the
    crank handle, the Torque F a about the stem axis on the crank.

    Virtual work for δθ: δW = F a δα − P δy_A = (4π a l F sin θ / h − 2 l P cos θ) δθ,
    so the generalized force is Q_θ = 2 l (2π a F sin θ / h − P cos θ), and the
    jack holds the load (d'Alembert: Q_θ = 0) when
        P / F = 2π a tan θ / h
    (a = 20 cm, h = 2 mm, θ = 30°: P/F ≈ 363).  The balance is unstable:
    ∂Q_θ/∂θ > 0, a frictionless jack lifts under any excess effort and runs
    down under any deficit.  The only inertia is the crank and screw's moment J
    about the stem (x), T = ½ J α̇² = ½ J (4π l sin θ / h)² θ̇², which gives the
    mechanism a motion and plays no part in the balance.  Defaults: a 4 kN load,
    12 N of effort (above the 11.0 N that balance at 30°): the jack lifts slowly.
    """
    (theta,) = coordinates("theta")
    l, h, a, P, F, J = _params("l h a P F J")
    N = ReferenceFrame("N")
    alpha = -4 * sp.pi * l * sp.cos(theta) / h
    crank = rotated(N, (alpha, N.x), name="K")
    screw = RigidBody(0, (0, 0, 0), (J, J / 2, J / 2), crank, name="crank_and_screw")  # a disc-like crank
    return System(
        coordinates=(theta,),
        bodies=(screw,),
        loads=(Force((0, -P, 0), (0, 2 * l * sp.sin(theta), 0), name="load"),
               Torque((F * a, 0, 0), crank, name="effort")),
        frame=N,
        parameters=(l, h, a, P, F, J),
        name="wheel_jack",
        description="Wheel jack: a crank and screw close a lozenge under a load (statics by virtual work).",
        defaults={"l": 0.2, "h": 0.002, "a": 0.2, "P": 4000.0, "F": 12.0, "J": 1e-3},
        q0=(float(sp.pi / 6),), qd0=(0.0,), t_end=1.0,
    )


BODIES_EXAMPLES = {
    f.__name__: f for f in (turn_indicator, compton_disc, driven_pendulum_support, symmetric_top, wheel_jack)
}
