r"""Bundled examples with constraints, enforced by Lagrange multipliers.

Conventions: SI units, angles in radians, dots are time derivatives, gravity
along −z unless stated.  Every constraint is declared, not eliminated, and is
named: its multiplier is reported under that name.  lagcomp's normal form
(`lagcomp.mechanics.lagrange`) is

    M q̈ = F + Λᵀ λ,    constraint k:  Λ_k·q̇ + b_k = 0
    (holonomic Φ_k = 0: Λ_k = ∂Φ_k/∂q, b_k = ∂Φ_k/∂t),

so λ_k is the generalized force of the constraint along its row Λ_k.  Each
docstring says what the multiplier is physically, with its sign; that
meaning depends on how the constraint is scaled (``x − Rθ`` and ``Rθ − x``
give opposite λ).  The default initial conditions satisfy every constraint
exactly, at position and velocity level.

Several examples "release" a constraint (Lagrange's way of computing a
reaction): a coordinate that the constraint would eliminate is kept, and the
constraint is declared, so its multiplier is the reaction force.
"""

from __future__ import annotations

import math

import numpy as np
import sympy as sp

from lagcomp.model import Holonomic, Nonholonomic, System, coordinates, t

__all__ = [
    "hoop_bead_reaction", "unbalanced_cylinder_reactions", "free_axle", "free_axle_closed_form",
    "rolling_disc", "chaplygin_sleigh", "spherical_pendulum_cartesian", "spherical_pendulum",
    "spherical_to_cartesian", "four_bar_linkage", "four_bar_closure", "CONSTRAINED_EXAMPLES",
]


def _params(names: str) -> tuple[sp.Symbol, ...]:
    """Positive real parameters, always as a tuple."""
    return tuple(sp.symbols(names, positive=True, seq=True))


def _speed2(*xyz: sp.Expr) -> sp.Expr:
    """Squared speed of a point with Cartesian coordinates xyz(t)."""
    return sum((c.diff(t) ** 2 for c in xyz), sp.S.Zero)


# -- released constraints: reactions of the unconstrained examples ---------------------------


def hoop_bead_reaction() -> System:
    """The bead on the turning hoop of `hoop_bead`, with the hoop's angle φ released.

    Bead of mass m on a frictionless hoop of radius R, gravity g, z up.  The
    hoop is turned about its vertical diameter by the imposed angle
    φ(t) = Ω t + ε sin 2t.  Coordinates θ (angle of the bead from the UPWARD
    vertical through the centre, θ = π at the bottom) and φ (the hoop's angle);
    bead at R (sin θ cos φ, sin θ sin φ, cos θ).
        T = ½ m R² (θ̇² + φ̇² sin² θ),   V = m g R cos θ.
    Constraint ``drive``: Φ = φ − (Ω t + ε sin 2t) = 0, so Λ = (0, 1).
    Equations:
        θ̈ = sin θ (g/R + φ̇² cos θ)                  (as in `hoop_bead`),
        d/dt (m R² sin² θ φ̇) = λ,   φ̇ = Ω + 2ε cos 2t,  φ̈ = −4ε sin 2t.
    The multiplier is the torque about the axis that the hoop exerts to keep
    the bead turning with it: λ = R sin θ · f with
        f = m R (2 φ̇ θ̇ cos θ + φ̈ sin θ),
    the hoop's push on the bead normal to the hoop's plane, positive in the
    direction of increasing φ (Coriolis plus azimuthal-acceleration terms).
    Defaults as in `hoop_bead`, so θ(t) can be compared with it;
    q0 = (2.5, φ(0) = 0), q̇0 = (0, φ̇(0) = Ω + 2ε).
    """
    theta, phi = coordinates("theta phi")
    m, R, g, Omega, eps = _params("m R g Omega epsilon")
    imposed = Omega * t + eps * sp.sin(2 * t)
    defaults = {"m": 0.1, "R": 0.5, "g": 9.81, "Omega": 6.0, "epsilon": 0.2}
    return System(
        coordinates=(theta, phi),
        T=m * R**2 * (theta.diff(t) ** 2 + phi.diff(t) ** 2 * sp.sin(theta) ** 2) / 2,
        V=m * g * R * sp.cos(theta),
        constraints=(Holonomic("drive", phi - imposed),),
        parameters=(m, R, g, Omega, eps),
        name="hoop_bead_reaction",
        description="Bead on a turning hoop, hoop angle released: the hoop's push as a reaction.",
        defaults=defaults,
        q0=(2.5, 0.0), qd0=(0.0, defaults["Omega"] + 2 * defaults["epsilon"]), t_end=10.0,
    )


def unbalanced_cylinder_reactions() -> System:
    """The badly balanced cylinder of `unbalanced_cylinder`, with both rolling constraints released.

    Cylinder of mass M, radius R, centre of mass G at distance a from the axis,
    moment of inertia I about the line through G parallel to the axis, on
    horizontal ground, gravity g.  Axes: x along the ground, z up.
    Coordinates x, z (position of the axis C) and θ (rotation, clockwise, so
    that rolling toward +x increases θ; θ = 0 has G straight below C):
        G = (x − a sin θ, z − a cos θ),
        T = ½ M (ẋ_G² + ż_G²) + ½ I θ̇²,   V = M g z_G.
    Constraints: ``normal`` Φ = z − R (Λ = (0, 1, 0)) and ``friction``
    Φ = x − R θ (Λ = (1, 0, −R)).
    Reactions.  Let the ground push on the cylinder with (F_h, F_v) at the
    contact point P = C − (0, R).  A virtual displacement moves the body's
    material point at P by (δx − R δθ, δz), so the contact force has the
    generalized components (F_h, F_v, −R F_h) = F_v Λ_normal + F_h Λ_friction:
        λ_normal = F_v   (vertical reaction, positive upward),
        λ_friction = F_h (horizontal friction on the cylinder, positive toward +x),
    exactly, in newtons.  The x and z equations are Newton's for G:
        M ẍ_G = λ_friction,   M z̈_G = λ_normal − M g,
    so F_v = M (g + z̈_G) and F_h = M ẍ_G.  On the constraints (x = R θ, z = R)
    θ obeys the equation of `unbalanced_cylinder`.  The cylinder takes off where
    F_v would turn negative and slips where |F_h| > μ F_v.
    Defaults as in `unbalanced_cylinder`; q0 = (R θ0, R, θ0) with θ0 = 1.5, at rest.
    """
    x, z, theta = coordinates("x z theta")
    M, R, a, I, g = _params("M R a I g")
    xG, zG = x - a * sp.sin(theta), z - a * sp.cos(theta)
    defaults = {"M": 1.0, "R": 0.1, "a": 0.03, "I": 0.004, "g": 9.81}
    theta0 = 1.5
    return System(
        coordinates=(x, z, theta),
        T=M * _speed2(xG, zG) / 2 + I * theta.diff(t) ** 2 / 2,
        V=M * g * zG,
        constraints=(Holonomic("normal", z - R), Holonomic("friction", x - R * theta)),
        parameters=(M, R, a, I, g),
        name="unbalanced_cylinder_reactions",
        description="Off-balance rolling cylinder with its contact reactions (normal force and friction).",
        defaults=defaults,
        q0=(defaults["R"] * theta0, defaults["R"], theta0), qd0=(0.0, 0.0, 0.0), t_end=10.0,
    )


# -- free axle on an inclined plane ----------------------------------------------------------


def free_axle(V0: float = 1.0, omega: float = 1.0) -> System:
    r"""An axle with two independently turning wheels rolling without slipping on an inclined plane.

    Bodies.  A massless axle carries at its ends two identical wheels of radius
    R and mass m each, centres C and C′ a distance L apart (L = CC′, the whole
    length), each with moment of inertia I3 about the axle and I1 about a
    diameter.  The plane is inclined at angle α to the horizontal; gravity g.

    Axes in the plane: Y down the line of steepest slope, X horizontal, to the
    right of someone facing downhill, so that K = e_X × e_Y is the upward
    normal to the plane.  Coordinates:
      X, Y      position of the axle's midpoint O (at height R above the plane);
      θ         heading: angle from e_X to u = OC/|OC|, counter-clockwise about K;
      φ, φ′     rotation angles of wheel C and of wheel C′ about +u (the same
                axis for both wheels).
    With v = K × u = (−sin θ, cos θ): C = O + (L/2) u, C′ = O − (L/2) u, and
    wheel C turns with ω_C = θ̇ K + φ̇ u (ω_C′ = θ̇ K + φ̇′ u).
        T = m (Ẋ² + Ẏ²) + (I1 + m L²/4) θ̇² + ½ I3 (φ̇² + φ̇′²),
        V = −2 m g sin α · Y      (the normal component of gravity does no work).
    Rolling.  The material point at the contact H = C − R K moves with
    V_O + (L θ̇/2 + R φ̇) v, and at H′ with V_O + (−L θ̇/2 + R φ̇′) v.  Both vanish
    when V_O·u = 0, V_O·v = −R (φ̇ + φ̇′)/2 and L θ̇ + R (φ̇ − φ̇′) = 0; equivalently
        ``roll_X`` (nonholonomic)  2 Ẋ − R (φ̇ + φ̇′) sin θ = 0,  Λ1 = (2, 0, 0, −R sin θ, −R sin θ),
        ``roll_Y`` (nonholonomic)  2 Ẏ + R (φ̇ + φ̇′) cos θ = 0,  Λ2 = (0, 2, 0, R cos θ, R cos θ),
        ``steer``  (holonomic)     Φ = L θ + R (φ − φ′) = 0,      Λ3 = (0, 0, L, R, −R).
    Equations (M q̈ = F + Λᵀ λ):
        m Ẍ = λ1,   m Ÿ = m g sin α + λ2,   2 (I1 + m L²/4) θ̈ = L λ3,
        I3 φ̈  = −R sin θ λ1 + R cos θ λ2 + R λ3,
        I3 φ̈′ = −R sin θ λ1 + R cos θ λ2 − R λ3.
    Multipliers.  With in-plane contact forces F, F′ on wheels C, C′, virtual
    work gives the generalized force (F_X + F′_X, F_Y + F′_Y, (L/2)(F − F′)·v,
    R F·v, R F′·v), which equals Λᵀ λ with
        λ1 = (F_X + F′_X)/2,  λ2 = (F_Y + F′_Y)/2  (mean friction force per wheel
        along X and along Y, down the slope),  λ3 = (F − F′)·v / 2.
    Only the sum of the components along the axle is determined (the problem
    is hyperstatic there, like a four-legged table).

    Solution.  With σ = (φ + φ′)/2 and δ = φ − φ′: the difference of the wheel
    equations and θ̈ = −R δ̈/L give λ3 = −I3 L θ̈/(2 R²), and then
    [2 I1 + m L²/2 + I3 L²/(2R²)] θ̈ = 0: the heading turns uniformly,
    θ = θ0 + ω t, λ3 = 0 and δ = δ0 − L ω t/R, for every initial condition.
    Rolling gives V_O = s v with s = −R σ̇, and the sum of the wheel equations
    with λ1, λ2 from Newton's equations gives
        (I3 + m R²) σ̈ = −m g R sin α cos θ,   i.e.  ṡ = A cos θ,  A = m g R² sin α / (I3 + m R²)
    (A = 4Γ of the reference text; gravity's pull along v, reduced by the wheels' inertia).
    Launch (the defaults): O at the origin, axle horizontal (θ(0) = 0, u = e_X,
    v = e_Y), moving DOWN the slope with speed V0 (s(0) = V0), spin θ̇(0) = ω,
    φ(0) = φ′(0) = 0.  Then s = V0 + (A/ω) sin ωt and
        θ = ω t,   λ3 = 0,
        X(t) = (V0/ω)(cos ωt − 1) − (A/(4ω²)) (2ωt − sin 2ωt),
        Y(t) = (V0/ω) sin ωt + (A/(4ω²)) (1 − cos 2ωt),
        φ, φ′ = −V0 t/R − (A/(R ω²))(1 − cos ωt) ∓ L ω t/(2R),
        λ1(t) = −m (V0 ω cos ωt + A sin 2ωt),
        λ2(t) = −m (V0 ω sin ωt − A cos 2ωt + g sin α).
    The midpoint drifts along −X at mean speed A/(2ω) while looping with period
    2π/ω.  `free_axle_closed_form` evaluates these.  (The reference text's X, Y
    and λ are for a launch up its upward Y axis; its σ equation has cos α for
    sin α.)  For ω = 0 the axle rolls straight down: Y = V0 t + A t²/2.

    Parameters V0, omega set the default initial conditions only.
    """
    X, Y, theta, phi, phi_p = coordinates("X Y theta phi phi_prime")
    m, R, L, I1, I3, g, alpha = _params("m R L I1 I3 g alpha")
    Xd, Yd, phid, phipd = X.diff(t), Y.diff(t), phi.diff(t), phi_p.diff(t)
    T = m * (Xd**2 + Yd**2) + (I1 + m * L**2 / 4) * theta.diff(t) ** 2 + I3 * (phid**2 + phipd**2) / 2
    constraints = (
        Nonholonomic("roll_X", 2 * Xd - R * (phid + phipd) * sp.sin(theta)),
        Nonholonomic("roll_Y", 2 * Yd + R * (phid + phipd) * sp.cos(theta)),
        Holonomic("steer", L * theta + R * (phi - phi_p)),
    )
    defaults = {"m": 1.0, "R": 0.25, "L": 1.0, "I1": 0.015625, "I3": 0.03125, "g": 9.81, "alpha": 0.3}
    q0, qd0 = _free_axle_initial(defaults, V0, omega)
    return System(
        coordinates=(X, Y, theta, phi, phi_p),
        T=T,
        V=-2 * m * g * sp.sin(alpha) * Y,
        constraints=constraints,
        parameters=(m, R, L, I1, I3, g, alpha),
        name="free_axle",
        description="Axle with two independent wheels rolling without slipping on an inclined plane.",
        defaults=defaults,
        q0=q0, qd0=qd0, t_end=20.0,
    )


def _free_axle_initial(params, V0, omega):
    """Launch of `free_axle`: origin, axle along X, speed V0 down the slope, spin ω, wheel angles 0."""
    R, L = params["R"], params["L"]
    spin = -V0 / R  # σ̇(0) = −s(0)/R
    half = L * omega / (2 * R)  # δ̇/2 = −L ω/(2R)
    return (0.0, 0.0, 0.0, 0.0, 0.0), (0.0, float(V0), float(omega), spin - half, spin + half)


def free_axle_closed_form(t, params: dict, V0: float, omega: float) -> dict:
    r"""The motion and reactions of `free_axle` after the downhill launch, evaluated with numpy.

    Parameters
    ----------
    t : float or ndarray
        Times.
    params : dict
        Parameter values by name (m, R, L, g, alpha and I3; I1 is not needed).
    V0 : float
        Initial speed of the axle's midpoint, down the slope (+Y).
    omega : float
        Initial (and constant) turning rate θ̇ of the axle.

    Returns
    -------
    dict of ndarray
        The coordinates by name (``X, Y, theta, phi, phi_prime``), their rates
        (``X_dot`` …) and accelerations (``X_ddot`` …), and the multipliers by
        constraint name (``roll_X, roll_Y, steer``).

    Notes
    -----
    Derivation (see `free_axle` for the axes, T, V and the constraint rows):

    1. Equations of motion M q̈ = F + Λᵀ λ:
       m Ẍ = λ1, m Ÿ = m g sin α + λ2, 2(I1 + mL²/4) θ̈ = L λ3,
       I3 φ̈ = R(−sin θ λ1 + cos θ λ2 + λ3), I3 φ̈′ = R(−sin θ λ1 + cos θ λ2 − λ3).
    2. Substitute σ = (φ + φ′)/2, δ = φ − φ′.  The difference of the wheel
       equations is I3 δ̈ = 2 R λ3; the holonomic constraint, differentiated
       twice, is L θ̈ = −R δ̈.  So λ3 = −I3 L θ̈/(2R²), and the θ equation
       becomes [2 I1 + m L²/2 + I3 L²/(2R²)] θ̈ = 0: θ̈ = 0, θ = ω t, λ3 = 0,
       δ = −(L ω/R) t.
    3. The rolling constraints say V_O = s v, v = (−sin θ, cos θ), s = −R σ̇.
       Differentiating, (Ẍ, Ÿ)·v = ṡ.  The sum of the wheel equations is
       I3 σ̈ = R (λ1, λ2)·v = R [m ṡ − m g sin α cos θ]; with σ̈ = −ṡ/R this is
       (m + I3/R²) ṡ = m g sin α cos θ, i.e. ṡ = A cos ωt, A = m g R² sin α/(I3 + m R²).
    4. Integrate with s(0) = V0: s = V0 + (A/ω) sin ωt.  Then
       Ẋ = −s sin ωt = −V0 sin ωt − (A/ω) sin² ωt,
       Ẏ = s cos ωt = V0 cos ωt + (A/(2ω)) sin 2ωt,
       and with X(0) = Y(0) = 0:
       X = (V0/ω)(cos ωt − 1) − (A/(4ω²))(2ωt − sin 2ωt),
       Y = (V0/ω) sin ωt + (A/(4ω²))(1 − cos 2ωt),
       σ = −(1/R) ∫ s = −V0 t/R − (A/(Rω²))(1 − cos ωt),  φ = σ + δ/2, φ′ = σ − δ/2.
    5. Back in step 1: λ1 = m Ẍ = −m (V0 ω cos ωt + A sin 2ωt),
       λ2 = m Ÿ − m g sin α = −m (V0 ω sin ωt − A cos 2ωt + g sin α).
    For ω = 0 the limits are X = 0, Y = V0 t + A t²/2, φ = φ′ = −(V0 t + A t²/2)/R.
    """
    t = np.asarray(t, dtype=float)
    m, R, L, I3, g, alpha = (float(params[k]) for k in ("m", "R", "L", "I3", "g", "alpha"))
    A = m * g * R**2 * math.sin(alpha) / (I3 + m * R**2)
    w = float(omega)
    th, thd = w * t, np.full_like(t, w)
    c, s_, c2, s2 = np.cos(th), np.sin(th), np.cos(2 * th), np.sin(2 * th)
    if w != 0.0:
        X = V0 / w * (c - 1) - A / (4 * w**2) * (2 * th - s2)
        Y = V0 / w * s_ + A / (4 * w**2) * (1 - c2)
        sigma = -V0 * t / R - A / (R * w**2) * (1 - c)
        speed = V0 + A / w * s_
    else:
        X, Y = np.zeros_like(t), V0 * t + A * t**2 / 2
        sigma, speed = -(V0 * t + A * t**2 / 2) / R, V0 + A * t
    accel = A * c  # ṡ
    Xd, Yd = -speed * s_, speed * c
    Xdd, Ydd = -accel * s_ - speed * w * c, accel * c - speed * w * s_
    half_delta = -L * th / (2 * R)
    sigma_d, sigma_dd = -speed / R, -accel / R
    zero = np.zeros_like(t)
    return {
        "X": X, "Y": Y, "theta": th, "phi": sigma + half_delta, "phi_prime": sigma - half_delta,
        "X_dot": Xd, "Y_dot": Yd, "theta_dot": thd,
        "phi_dot": sigma_d - L * w / (2 * R), "phi_prime_dot": sigma_d + L * w / (2 * R),
        "X_ddot": Xdd, "Y_ddot": Ydd, "theta_ddot": zero, "phi_ddot": sigma_dd, "phi_prime_ddot": sigma_dd,
        "roll_X": m * Xdd, "roll_Y": m * Ydd - m * g * math.sin(alpha), "steer": zero,
    }


# -- rolling without slipping ------------------------------------------------------------------


def rolling_disc() -> System:
    r"""Thin disc rolling without slipping on a horizontal plane, in gravity.

    Disc of mass m, radius r, moments of inertia I1 about a diameter and I3
    about its axis (thin uniform disc: I1 = m r²/4, I3 = m r²/2, the defaults
    for m = 1, r = 0.1).  Fixed axes x, y horizontal, z up.  Frames: A is
    turned by ψ about z; B is A leaned by θ about A_x; the disc is B turned by φ
    about B_y (its axis).  Coordinates:
      x, y   the contact point P on the plane (a geometric point, not a material one);
      ψ      heading: the direction of rolling is A_x = (cos ψ, sin ψ, 0);
      θ      lean from the vertical (θ = 0 upright; θ > 0 tilts the top toward −A_y);
      φ      spin about the disc's axis B_y = (−sin ψ cos θ, cos ψ cos θ, sin θ).
    The centre is G = P + r B_z, B_z = (sin ψ sin θ, −cos ψ sin θ, cos θ).
    Angular velocity ω = ψ̇ z + θ̇ A_x + φ̇ B_y, in B: (θ̇, φ̇ + ψ̇ sin θ, ψ̇ cos θ).
        T = ½ m |Ġ|² + ½ [I1 (θ̇² + ψ̇² cos² θ) + I3 (φ̇ + ψ̇ sin θ)²],
        V = m g r cos θ.
    Rolling: the disc's material point at P has velocity Ġ + ω × (−r B_z) =
    (ẋ, ẏ, 0) − r φ̇ A_x, so (the vertical component vanishes identically)
        ``roll_x``: ẋ − r φ̇ cos ψ = 0,   ``roll_y``: ẏ − r φ̇ sin ψ = 0.
    Multipliers: a virtual displacement moves that material point by
    (δx − r δφ cos ψ, δy − r δφ sin ψ, 0), so λ_roll_x and λ_roll_y are exactly
    the x and y components of the friction force of the plane on the disc (the
    normal force does no virtual work in these coordinates).
    Steady turning: θ = θ0, ψ̇ = Ω, φ̇ = p constant (the contact point on a
    circle of radius r p/|Ω|) solves the equations when
        m g r sin θ0 + (I3 + m r²) p Ω cos θ0 + (I3 + m r² − I1) Ω² sin θ0 cos θ0 = 0
    (θ̈ = 0 in the constrained equations at that state; ψ̈ = φ̈ = 0 there
    identically).  Leaning toward −A_y (θ0 > 0) while rolling forward (p > 0)
    turns toward −A_y (Ω < 0).  The defaults start on such a turn: lean
    θ0 = 0.2 rad, spin p = 15 rad/s (1.5 m/s), Ω the root of smaller magnitude
    (≈ −0.89 rad/s).  On it, from the origin with ψ(0) = 0, the contact point
    runs round the circle x = (r p/Ω) sin Ωt, y = (r p/Ω)(1 − cos Ωt) (radius
    about 1.7 m, period about 7 s), and the turn is stable: a kick to the lean
    rate only makes the disc wobble about it.
    """
    x, y, psi, theta, phi = coordinates("x y psi theta phi")
    m, r, I1, I3, g = _params("m r I1 I3 g")
    G = (
        x + r * sp.sin(psi) * sp.sin(theta),
        y - r * sp.cos(psi) * sp.sin(theta),
        r * sp.cos(theta),
    )
    psid, thetad, phid = psi.diff(t), theta.diff(t), phi.diff(t)
    T = m * _speed2(*G) / 2 + (I1 * (thetad**2 + psid**2 * sp.cos(theta) ** 2)
                               + I3 * (phid + psid * sp.sin(theta)) ** 2) / 2
    constraints = (
        Nonholonomic("roll_x", x.diff(t) - r * phid * sp.cos(psi)),
        Nonholonomic("roll_y", y.diff(t) - r * phid * sp.sin(psi)),
    )
    defaults = {"m": 1.0, "r": 0.1, "I1": 0.0025, "I3": 0.005, "g": 9.81}
    theta0, spin = 0.2, 15.0
    Omega = _disc_steady_turn_rate(defaults, theta0, spin)
    return System(
        coordinates=(x, y, psi, theta, phi),
        T=T,
        V=m * g * r * sp.cos(theta),
        constraints=constraints,
        parameters=(m, r, I1, I3, g),
        name="rolling_disc",
        description="Thin disc rolling without slipping on a horizontal plane (two nonholonomic constraints).",
        defaults=defaults,
        q0=(0.0, 0.0, 0.0, theta0, 0.0),
        qd0=(defaults["r"] * spin, 0.0, Omega, 0.0, spin),
        t_end=8.0,
    )


def _disc_steady_turn_rate(params, theta0, spin):
    """Heading rate Ω of steady turning at lean θ0 and spin p (the root of smaller magnitude; see `rolling_disc`)."""
    m, r, I1, I3, g = (params[k] for k in ("m", "r", "I1", "I3", "g"))
    s, c = math.sin(theta0), math.cos(theta0)
    qa = (I3 + m * r**2 - I1) * s * c  # coefficients of qa Ω² + qb Ω + qc = 0
    qb = (I3 + m * r**2) * spin * c
    qc = m * g * r * s
    disc = qb * qb - 4 * qa * qc
    if disc < 0:
        raise ValueError(f"No steady turn at lean {theta0} with spin {spin}.")
    return -2 * qc / (qb + math.copysign(math.sqrt(disc), qb))


def chaplygin_sleigh() -> System:
    r"""Chaplygin's sleigh: a rigid body on a horizontal plane, held by a knife edge that cannot slide sideways.

    Body of mass m and moment of inertia I about its centre of mass G; the
    knife edge is at K = G + a e1 on the body axis e1 = (cos θ, sin θ), and
    e2 = (−sin θ, cos θ).  Coordinates x, y (of G) and θ (heading of e1).
        T = ½ m (ẋ² + ẏ²) + ½ I θ̇²,   V = 0.
    Constraint ``knife``: v_K · e2 = −ẋ sin θ + ẏ cos θ + a θ̇ = 0,
    Λ = (−sin θ, cos θ, a).  A virtual displacement moves K by δG + a δθ e2,
    so the multiplier is exactly the sideways force F of the plane on the
    blade, along e2, in newtons.
    With the body-frame velocity of G, v = v_G·e1 and v_G·e2 = −a ω (ω = θ̇):
        m v̇ = −m a ω²,   J ω̇ = m a v ω,   J = I + m a²,   F = m (v ω − a ω̇).
    The energy E = ½ m v² + ½ J ω² is conserved and, with V = √(2E/m),
    k = a m V/J:
        v(t) = −V tanh(k (t − t0)),   ω(t) = ±√(2E/J) sech(k (t − t0)),
    t0 = atanh(v(0)/V)/k, the sign of ω that of ω(0).  Whatever the start, the
    sleigh ends up gliding straight along −e1, blade trailing; the heading
    turns by θ(t) − θ(0) = ±(1/a)√(J/m) · [gd(k(t − t0)) + gd(k t0)],
    gd(u) = 2 atan(tanh(u/2)), in all at most π√(J/m)/a.
    Defaults start blade first (v(0) = 1 m/s along +e1, ω(0) = 1 rad/s), so the
    sleigh turns around.
    """
    x, y, theta = coordinates("x y theta")
    m, I, a = _params("m I a")
    xd, yd, thetad = x.diff(t), y.diff(t), theta.diff(t)
    defaults = {"m": 1.0, "I": 0.1, "a": 0.2}
    v0, w0 = 1.0, 1.0
    return System(
        coordinates=(x, y, theta),
        T=m * (xd**2 + yd**2) / 2 + I * thetad**2 / 2,
        constraints=(Nonholonomic("knife", -xd * sp.sin(theta) + yd * sp.cos(theta) + a * thetad),),
        parameters=(m, I, a),
        name="chaplygin_sleigh",
        description="Chaplygin's sleigh: a body on a knife edge that cannot slide sideways.",
        defaults=defaults,
        q0=(0.0, 0.0, 0.0), qd0=(v0, -defaults["a"] * w0, w0), t_end=20.0,
    )


# -- spherical pendulum, Cartesian and angular -----------------------------------------------


def spherical_pendulum_cartesian() -> System:
    r"""Spherical pendulum in Cartesian coordinates, the rod as a holonomic constraint.

    Bob of mass m at r = (x, y, z), z up, on a massless rod of length l
    pivoted at the origin; gravity g.
        T = ½ m (ẋ² + ẏ² + ż²),   V = m g z.
    Constraint ``rod``: Φ = x² + y² + z² − l² = 0, so Λ = 2 (x, y, z), and the
    rod's force on the bob is Λᵀ λ = 2 λ r.  The tension N (positive when the
    rod pulls the bob toward the pivot) is therefore
        N = −2 λ l,
    and Newton's law along r̂ = r/l (r̂·r̈ = −|v|²/l on the sphere) gives
        N = m (|v|²/l − g z/l)      (m v²/l + m g hanging straight down).
    Equations: m r̈ = −m g e_z + 2 λ r, with 2 λ l² = m (g z − |v|²).
    The same motion in angles: `spherical_pendulum`; `spherical_to_cartesian`
    converts initial conditions.  The defaults start at θ = 1 rad from the
    downward vertical, φ = 0, with θ̇ = 0 and φ̇ = 2 rad/s.
    """
    x, y, z = coordinates("x y z")
    m, l, g = _params("m l g")
    defaults = {"m": 1.0, "l": 1.0, "g": 9.81}
    q0, qd0 = spherical_to_cartesian(*_SPHERICAL_START, defaults["l"])
    return System(
        coordinates=(x, y, z),
        T=m * (x.diff(t) ** 2 + y.diff(t) ** 2 + z.diff(t) ** 2) / 2,
        V=m * g * z,
        constraints=(Holonomic("rod", x**2 + y**2 + z**2 - l**2),),
        parameters=(m, l, g),
        name="spherical_pendulum_cartesian",
        description="Spherical pendulum in Cartesian coordinates; the rod's tension is the reaction.",
        defaults=defaults,
        q0=q0, qd0=qd0, t_end=10.0,
    )


#: (θ, φ, θ̇, φ̇) at t = 0 for both spherical pendulum examples.
_SPHERICAL_START = (1.0, 0.0, 0.0, 2.0)


def spherical_pendulum() -> System:
    r"""Spherical pendulum in angles (the same bob, rod and gravity as `spherical_pendulum_cartesian`).

    Coordinates θ (polar angle of the rod from the DOWNWARD vertical) and φ
    (azimuth about the vertical, from the x axis):
        r = l (sin θ cos φ, sin θ sin φ, −cos θ),
        T = ½ m l² (θ̇² + φ̇² sin² θ),   V = −m g l cos θ.
    Equations: θ̈ = φ̇² sin θ cos θ − (g/l) sin θ,  d/dt (sin² θ φ̇) = 0.
    φ is cyclic: p_φ = m l² sin² θ φ̇ (the vertical angular momentum) and the
    energy are conserved.  Conical motion θ = θ0 needs φ̇² = g/(l cos θ0).
    Defaults and initial conditions describe the same motion as the Cartesian
    example's (see `spherical_to_cartesian`).
    """
    theta, phi = coordinates("theta phi")
    m, l, g = _params("m l g")
    th0, ph0, thd0, phd0 = _SPHERICAL_START
    return System(
        coordinates=(theta, phi),
        T=m * l**2 * (theta.diff(t) ** 2 + phi.diff(t) ** 2 * sp.sin(theta) ** 2) / 2,
        V=-m * g * l * sp.cos(theta),
        parameters=(m, l, g),
        name="spherical_pendulum",
        description="Spherical pendulum in polar and azimuthal angles.",
        defaults={"m": 1.0, "l": 1.0, "g": 9.81},
        q0=(th0, ph0), qd0=(thd0, phd0), t_end=10.0,
    )


def spherical_to_cartesian(theta, phi, theta_dot, phi_dot, l):
    """Cartesian (q, q̇) of the bob for angles θ (from the downward vertical), φ and their rates.

    Returns two tuples (x, y, z) and (ẋ, ẏ, ż) with r = l (sin θ cos φ, sin θ sin φ, −cos θ).
    """
    st, ct, sp_, cp = math.sin(theta), math.cos(theta), math.sin(phi), math.cos(phi)
    q = (l * st * cp, l * st * sp_, -l * ct)
    qd = (
        l * (ct * cp * theta_dot - st * sp_ * phi_dot),
        l * (ct * sp_ * theta_dot + st * cp * phi_dot),
        l * st * theta_dot,
    )
    return q, qd


# -- closed kinematic loop -------------------------------------------------------------------


def four_bar_linkage(theta1: float = 0.0, theta1_dot: float = 10.0) -> System:
    r"""Planar four-bar linkage: crank, coupler and rocker closing a loop with the ground, in gravity.

    Ground link between the fixed pivots O = (0, 0) and D = (d, 0); x along OD,
    y up, gravity g along −y.  Three uniform rods, each of mass m_i and moment
    of inertia m_i L_i²/12 about its centre:
      crank   OA, length a, mass m1, angle θ1;
      coupler AB, length b, mass m2, angle θ2;
      rocker  DB, length c, mass m3, angle θ3,
    every angle absolute, from +x, counter-clockwise.  With e_i = (cos θ_i, sin θ_i):
        A = a e1,   B = A + b e2 = D + c e3,
        centres G1 = (a/2) e1,  G2 = A + (b/2) e2,  G3 = D + (c/2) e3,
        T = ½ Σ_i [m_i |Ġ_i|² + (m_i L_i²/12) θ̇_i²]
          = ½ (m1 a²/3) θ̇1² + ½ m2 [a² θ̇1² + a b cos(θ1 − θ2) θ̇1 θ̇2 + b² θ̇2²/3] + ½ (m3 c²/3) θ̇3²,
        V = g Σ_i m_i y_Gi = g [(m1/2 + m2) a sin θ1 + (m2/2) b sin θ2 + (m3/2) c sin θ3].
    The mass matrix depends on θ1 − θ2 (so RATTLE does not apply).
    Loop closure, B reached along the crank and coupler minus B reached along
    the rocker (two holonomic constraints):
        ``loop_x``: Φ_x = a cos θ1 + b cos θ2 − c cos θ3 − d = 0,
        ``loop_y``: Φ_y = a sin θ1 + b sin θ2 − c sin θ3 = 0,
    rows Λ_x = (−a sin θ1, −b sin θ2, c sin θ3), Λ_y = (a cos θ1, b cos θ2, −c cos θ3).
    Multipliers.  Cut the pin at B and let the rocker push the coupler with
    F = (F_x, F_y) at B (the coupler pushes the rocker with −F).  Its virtual
    work is F·δB_coupler − F·δB_rocker = F·δΦ = (Λ_xᵀ F_x + Λ_yᵀ F_y)·δq, so the
    generalized force of the pin is Λᵀ λ with
        λ_loop_x = F_x,   λ_loop_y = F_y:
    the multipliers are exactly the Cartesian force, in newtons, that the
    rocker exerts ON THE COUPLER at the pin B (the opposite acts on the rocker).
    The forces at O, A and D follow from Newton's law for each rod
    (tests/test_four_bar.py solves the three bodies' Newton–Euler equations
    by hand and compares both q̈ and F).
    Proportions (defaults a = 0.2, b = 0.6, c = 0.5, d = 0.6 m): Grashof,
    s + l = 0.2 + 0.6 ≤ p + q = 0.5 + 0.6, with the shortest link the crank:
    a crank-rocker.  |AD| stays in [d − a, d + a] = [0.4, 0.8], strictly inside
    (|b − c|, b + c) = (0.1, 1.1), so the circles about A (radius b) and D
    (radius c) always cross at an angle: Λ has rank 2 at every crank angle and
    the linkage never reaches a singular (folded or stretched) position.
    Initial state: crank angle θ1 (default 0) and rate θ̇1 (default 10 rad/s;
    the crank turns 58 times in the 30 s run, its rate between about 7.5
    and 24 rad/s: the energy carries it over the highest potential, 1.5 J above
    the start, so θ1 increases monotonically; 5 rad/s would not), the assembly with B on
    the left of the ray A → D (B above the ground at θ1 = 0), θ2, θ3 and their
    rates from `four_bar_closure`: exactly on both constraints.
    Parameters theta1, theta1_dot set the default initial conditions only.
    """
    th1, th2, th3 = coordinates("theta1 theta2 theta3")
    a, b, c, d, m1, m2, m3, g = _params("a b c d m1 m2 m3 g")
    A = (a * sp.cos(th1), a * sp.sin(th1))
    G1 = (A[0] / 2, A[1] / 2)
    G2 = (A[0] + b * sp.cos(th2) / 2, A[1] + b * sp.sin(th2) / 2)
    G3 = (d + c * sp.cos(th3) / 2, c * sp.sin(th3) / 2)
    T = sum(
        (m * _speed2(*G) / 2 + m * L**2 * th.diff(t) ** 2 / 24
         for m, G, L, th in ((m1, G1, a, th1), (m2, G2, b, th2), (m3, G3, c, th3))),
        sp.S.Zero,
    )
    defaults = {"a": 0.2, "b": 0.6, "c": 0.5, "d": 0.6, "m1": 0.5, "m2": 1.0, "m3": 0.8, "g": 9.81}
    q0, qd0 = four_bar_closure(defaults, theta1, theta1_dot)
    return System(
        coordinates=(th1, th2, th3),
        T=T,
        V=g * (m1 * G1[1] + m2 * G2[1] + m3 * G3[1]),
        constraints=(
            Holonomic("loop_x", a * sp.cos(th1) + b * sp.cos(th2) - c * sp.cos(th3) - d),
            Holonomic("loop_y", a * sp.sin(th1) + b * sp.sin(th2) - c * sp.sin(th3)),
        ),
        parameters=(a, b, c, d, m1, m2, m3, g),
        name="four_bar_linkage",
        description="Planar four-bar linkage (crank-rocker): a closed loop; λ is the pin force at B.",
        defaults=defaults,
        q0=q0, qd0=qd0, t_end=30.0,
    )


def four_bar_closure(params: dict, theta1: float, theta1_dot: float):
    """(θ1, θ2, θ3) and their rates on both loop constraints of `four_bar_linkage`, given the crank's.

    Positions in closed form: B is where the circles of radius b about A and c
    about D cross, on the left of the ray A → D (r = |AD|, B at distance
    p = (b² − c² + r²)/(2r) along it and h = √(b² − p²) to its left).
    Velocities from Λ q̇ = 0 solved for (θ̇2, θ̇3) by Cramer's rule (the 2×2
    determinant is b c sin(θ2 − θ3), nonzero away from singular positions).
    Returns two tuples (θ1, θ2, θ3) and (θ̇1, θ̇2, θ̇3); raises ValueError where
    the linkage cannot be assembled.
    """
    a, b, c, d = (float(params[k]) for k in ("a", "b", "c", "d"))
    ax, ay = a * math.cos(theta1), a * math.sin(theta1)
    vx, vy = d - ax, -ay
    r = math.hypot(vx, vy)
    p = (b * b - c * c + r * r) / (2 * r)
    if r == 0.0 or b * b - p * p <= 0.0:
        raise ValueError(f"The four-bar linkage cannot be assembled at crank angle {theta1}.")
    h = math.sqrt(b * b - p * p)
    ux, uy = vx / r, vy / r
    bx, by = ax + p * ux - h * uy, ay + p * uy + h * ux
    th2, th3 = math.atan2(by - ay, bx - ax), math.atan2(by, bx - d)
    # Λ q̇ = 0: b θ̇2 e2⊥ − c θ̇3 e3⊥ = −a θ̇1 e1⊥, with e⊥ = (−sin θ, cos θ)
    rx, ry = a * theta1_dot * math.sin(theta1), -a * theta1_dot * math.cos(theta1)
    s2, c2, s3, c3 = math.sin(th2), math.cos(th2), math.sin(th3), math.cos(th3)
    det = b * c * (s2 * c3 - s3 * c2)  # b c sin(θ2 − θ3), of [[−b s2, c s3], [b c2, −c c3]]
    th2_dot = (rx * (-c * c3) - c * s3 * ry) / det
    th3_dot = (-b * s2 * ry - b * c2 * rx) / det
    return (float(theta1), th2, th3), (float(theta1_dot), th2_dot, th3_dot)


#: The constrained examples by name, merged into `lagcomp.examples.EXAMPLES`.
CONSTRAINED_EXAMPLES = {
    f.__name__: f
    for f in (
        hoop_bead_reaction, unbalanced_cylinder_reactions, free_axle, rolling_disc, chaplygin_sleigh,
        spherical_pendulum_cartesian, spherical_pendulum, four_bar_linkage,
    )
}
