"""Bundled examples without constraints (or with the constraints eliminated by hand).

Conventions: SI units, gravity g along −z (or −y in planar examples), angles in
radians, dots are time derivatives.  Imposed motions are explicit functions of
`lagcomp.model.t`.  Each docstring states the Lagrangian L = T − V, the
equation of motion it yields and any closed-form solution.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.errors import ModelError
from lagcomp.model import Event, System, coordinates, t

__all__ = [
    "simple_pendulum", "double_pendulum", "n_link_pendulum", "sling", "rope", "rope_friction",
    "hoop_bead", "huygens", "tray_cylinder", "unbalanced_cylinder", "driven_pendulum", "henon_heiles",
    "stiff_spring_pendulum",
]


def _params(names: str) -> tuple[sp.Symbol, ...]:
    """Positive real parameters, always as a tuple."""
    return tuple(sp.symbols(names, positive=True, seq=True))


def _speed2(*xyz: sp.Expr) -> sp.Expr:
    """Squared speed of a point with Cartesian coordinates xyz(t)."""
    return sum((c.diff(t) ** 2 for c in xyz), sp.S.Zero)


def simple_pendulum() -> System:
    """Point mass m on a massless rod of length l, in gravity g.

    Coordinate θ: angle of the rod from the downward vertical (counter-clockwise).
    T = ½ m l² θ̇²,  V = −m g l cos θ.
    Equation: θ̈ = −(g/l) sin θ.  Energy ½ m l² θ̇² − m g l cos θ is conserved;
    for small angles θ = θ0 cos(t √(g/l)) from rest.
    """
    (theta,) = coordinates("theta")
    m, l, g = _params("m l g")
    return System(
        coordinates=(theta,),
        T=m * l**2 * theta.diff(t) ** 2 / 2,
        V=-m * g * l * sp.cos(theta),
        parameters=(m, l, g),
        name="simple_pendulum",
        description="Point mass on a massless rod swinging in gravity.",
        defaults={"m": 1.0, "l": 1.0, "g": 9.81},
        q0=(1.0,), qd0=(0.0,), t_end=10.0,
    )


def double_pendulum() -> System:
    """Two point masses m1, m2 on massless rods l1, l2 (the second hangs from the first).

    Coordinates θ1, θ2: absolute angles of the rods from the downward vertical.
    x1 = l1 sin θ1, y1 = −l1 cos θ1, x2 = x1 + l2 sin θ2, y2 = y1 − l2 cos θ2 (y up);
    T = ½ m1 (ẋ1² + ẏ1²) + ½ m2 (ẋ2² + ẏ2²),  V = g (m1 y1 + m2 y2).
    With δ = θ1 − θ2 the equations are
        (m1 + m2) l1 θ̈1 + m2 l2 (θ̈2 cos δ + θ̇2² sin δ) + (m1 + m2) g sin θ1 = 0,
        l2 θ̈2 + l1 (θ̈1 cos δ − θ̇1² sin δ) + g sin θ2 = 0.
    No closed form (chaotic at large energy); T + V is conserved.
    """
    th1, th2 = coordinates("theta1 theta2")
    m1, m2, l1, l2, g = _params("m1 m2 l1 l2 g")
    x1, y1 = l1 * sp.sin(th1), -l1 * sp.cos(th1)
    x2, y2 = x1 + l2 * sp.sin(th2), y1 - l2 * sp.cos(th2)
    return System(
        coordinates=(th1, th2),
        T=m1 * _speed2(x1, y1) / 2 + m2 * _speed2(x2, y2) / 2,
        V=g * (m1 * y1 + m2 * y2),
        parameters=(m1, m2, l1, l2, g),
        name="double_pendulum",
        description="Planar double pendulum: two point masses on massless rods.",
        defaults={"m1": 1.0, "m2": 1.0, "l1": 1.0, "l2": 1.0, "g": 9.81},
        q0=(2.0, 1.0), qd0=(0.0, 0.0), t_end=20.0,
    )


def n_link_pendulum(n: int = 3) -> System:
    """Planar chain of n point masses m_i on massless rods l_i (i = 1..n), hung from a fixed pivot.

    Coordinates θ1..θn: absolute angles of the rods from the downward vertical.
    Mass i sits at (Σ_{k≤i} l_k sin θ_k, −Σ_{k≤i} l_k cos θ_k).  With the mass
    carried below rod k, μ_k = Σ_{i≥k} m_i,
        T = ½ Σ_{j,k} μ_max(j,k) l_j l_k cos(θj − θk) θ̇j θ̇k,   V = −g Σ_k μ_k l_k cos θk,
    and the equation for θj is
        Σ_k μ_max(j,k) l_j l_k [cos(θj − θk) θ̈k + sin(θj − θk) θ̇k²] + μ_j g l_j sin θj = 0.
    n = 1 is the simple pendulum, n = 2 the double pendulum.  Parameters:
    m1..mn, l1..ln, g (2n + 1 in all).  The System is named ``n_link_pendulum_<n>``.
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ModelError(f"n_link_pendulum needs a whole number of links n >= 1, got n={n!r}.")
    thetas = coordinates(" ".join(f"theta{i}" for i in range(1, n + 1)))
    ms = _params(" ".join(f"m{i}" for i in range(1, n + 1)))
    ls = _params(" ".join(f"l{i}" for i in range(1, n + 1)))
    (g,) = _params("g")
    x = y = sp.S.Zero
    T = V = sp.S.Zero
    for th, m, l in zip(thetas, ms, ls):
        x, y = x + l * sp.sin(th), y - l * sp.cos(th)
        T += m * _speed2(x, y) / 2
        V += m * g * y
    defaults = {s.name: 1.0 for s in ms + ls} | {"g": 9.81}
    return System(
        coordinates=thetas,
        T=T,
        V=V,
        parameters=ms + ls + (g,),
        name=f"n_link_pendulum_{n}",
        description=f"Planar chain of {n} point masses on massless rods.",
        defaults=defaults,
        q0=tuple(1.0 / k for k in range(1, n + 1)), qd0=(0.0,) * n, t_end=10.0,
    )


def sling() -> System:
    """Bead of mass m sliding without friction on a rod turning at constant rate ω in a horizontal plane.

    Coordinate ρ: distance of the bead from the rod's fixed end.  The rod's angle
    ωt is imposed, so T = ½ m (ρ̇² + ω² ρ²), V = 0.
    Equation: ρ̈ − ω² ρ = 0.  From ρ(0) = a (the default q0), ρ̇(0) = 0:
    ρ(t) = a cosh(ω t).
    """
    (rho,) = coordinates("rho")
    m, omega = _params("m omega")
    return System(
        coordinates=(rho,),
        T=m * (rho.diff(t) ** 2 + omega**2 * rho**2) / 2,
        parameters=(m, omega),
        name="sling",
        description="Bead flung outward along a rod turning at a constant rate.",
        defaults={"m": 0.1, "omega": 2.0},
        q0=(0.1,), qd0=(0.0,), t_end=2.0,
    )


def _rope(friction: bool) -> System:
    (x,) = coordinates("x")
    M, L, g = _params("M L g")
    mu = M / L  # linear density
    params, defaults, forces = (M, L, g), {"M": 1.0, "L": 1.0, "g": 9.81}, ()
    name, description = "rope", "Rope slipping off the edge of a frictionless table."
    x0, t_end = 0.2, 0.6
    if friction:
        (f,) = _params("f")
        xd = x.diff(t)
        s = sp.Piecewise((sp.sign(xd), sp.Ne(xd, 0)), (1, True))
        forces = (-f * mu * g * (L - x) * s,)
        params, defaults = params + (f,), defaults | {"f": 0.3}
        name, description = "rope_friction", "Rope slipping off a table edge against Coulomb friction."
        x0, t_end = 0.4, 0.55
    return System(
        coordinates=(x,),
        T=M * x.diff(t) ** 2 / 2,
        V=-mu * g * x**2 / 2,
        forces=forces,
        parameters=params,
        name=name,
        description=description,
        defaults=defaults,
        q0=(x0,), qd0=(0.0,), t_end=t_end,
    )


def rope() -> System:
    """Rope of mass M, length L slipping off the edge of a frictionless table, in gravity g.

    Coordinate x: length hanging vertically below the edge (0 ≤ x ≤ L).  Every
    element moves at speed ẋ; linear density μ = M/L; the hanging part has its
    centre of mass x/2 below the table top.
    T = ½ M ẋ²,  V = −μ g x²/2.
    Equation: ẍ = (g/L) x.  From rest at x0: x(t) = x0 cosh(t √(g/L)), valid
    until x = L (the default t_end stops before that).
    """
    return _rope(friction=False)


def rope_friction() -> System:
    """The rope of `rope` with Coulomb friction, coefficient f, on the part lying on the table.

    Coordinate x, T and V as in `rope` (μ = M/L).  The table part, of length
    L − x, presses with μ g (L − x); friction opposes its motion, giving the
    generalized force
        Q = −f μ g (L − x) s,  s = sign(ẋ) if ẋ ≠ 0, s = 1 at rest.
    The choice s = 1 at rest is limiting static friction for a rope about to
    slide toward +x: the weight μ g x beats f μ g (L − x) above the critical
    length l0 = f L/(1 + f), and below l0 a real rope would stay put (the model
    is meant for x0 > l0, where the rope moves toward +x throughout).
    Equation while sliding (ẋ > 0): ẍ = (g(1 + f)/L) (x − l0).  From rest at
    x0 > l0: x(t) = l0 + (x0 − l0) cosh(t √(g(1 + f)/L)) while x ≤ L.
    """
    return _rope(friction=True)


def hoop_bead() -> System:
    """Bead of mass m on a frictionless hoop of radius R turned about its vertical diameter.

    The hoop's angle is imposed: φ(t) = Ω t + ε sin 2t (Ω, ε parameters; the
    wobble's frequency is 2 rad/s).  Coordinate θ: angle of the bead from the
    UPWARD vertical through the hoop's centre (θ = π is the bottom); position
    R (sin θ cos φ, sin θ sin φ, cos θ), z up.
    T = ½ m R² (θ̇² + φ̇² sin² θ),  V = m g R cos θ.
    Equation: θ̈ = sin θ (g/R + φ̇² cos θ), φ̇ = Ω + 2ε cos 2t.
    For ε = 0 and Ω² > g/R the bottom is unstable and the bead settles around
    cos θ* = −g/(R Ω²).
    """
    (theta,) = coordinates("theta")
    m, R, g, Omega, eps = _params("m R g Omega epsilon")
    phi = Omega * t + eps * sp.sin(2 * t)
    return System(
        coordinates=(theta,),
        T=m * R**2 * (theta.diff(t) ** 2 + phi.diff(t) ** 2 * sp.sin(theta) ** 2) / 2,
        V=m * g * R * sp.cos(theta),
        parameters=(m, R, g, Omega, eps),
        name="hoop_bead",
        description="Bead on a hoop spun about its vertical diameter by an imposed angle.",
        defaults={"m": 0.1, "R": 0.5, "g": 9.81, "Omega": 6.0, "epsilon": 0.2},
        q0=(2.5,), qd0=(0.0,), t_end=10.0,
    )


def huygens() -> System:
    """Huygens' isochronous pendulum: a bead of mass m sliding without friction on a cycloid.

    Coordinate θ (the rolling-circle angle): x = R(θ + sin θ), z = R(1 − cos θ),
    z up, bottom at θ = 0, cusps at θ = ±π.
    T = 2 m R² cos²(θ/2) θ̇²,  V = m g R (1 − cos θ).
    Lagrange's equation is 2 m R² cos(θ/2) × [2 cos(θ/2) θ̈ − sin(θ/2) θ̇² + (g/R) sin(θ/2)] = 0.
    The arc length from the bottom, s = 4R sin(θ/2), gives T = ½ m ṡ², V = ½ m ω² s²
    with ω² = g/(4R): s̈ + ω² s = 0.  From rest at θ0 (|θ0| < π):
    sin(θ/2) = sin(θ0/2) cos(ω t); the period 4π √(R/g) does not depend on θ0.
    """
    (theta,) = coordinates("theta")
    m, R, g = _params("m R g")
    return System(
        coordinates=(theta,),
        T=2 * m * R**2 * sp.cos(theta / 2) ** 2 * theta.diff(t) ** 2,
        V=m * g * R * (1 - sp.cos(theta)),
        parameters=(m, R, g),
        name="huygens",
        description="Bead on a cycloid: Huygens' isochronous pendulum.",
        defaults={"m": 1.0, "R": 0.25, "g": 9.81},
        q0=(2.5,), qd0=(0.0,), t_end=10.0,
    )


def tray_cylinder() -> System:
    """Cylinder (mass M, radius R, moment of inertia I about its axis) rolling on a moving tray.

    The tray moves horizontally along the imposed a(t) = A sin(Ω t).  Coordinate
    X: absolute horizontal position of the cylinder's axis.  Rolling without
    slipping fixes the clockwise spin rate at (Ẋ − ȧ)/R, so
    T = ½ M Ẋ² + ½ I (Ẋ − ȧ)²/R²,  V = 0 (the axis stays at height R).
    Equation: (I + M R²) Ẍ = I ä, i.e. Ẍ = I ä/(I + M R²).  With k = I/(I + M R²):
    X(t) = X0 + k (a(t) − a(0)) + (Ẋ0 − k ȧ(0)) t; from rest the cylinder drifts
    at −k A Ω while oscillating with amplitude k A.
    """
    (X,) = coordinates("X")
    M, R, I, A, Omega = _params("M R I A Omega")
    a = A * sp.sin(Omega * t)
    return System(
        coordinates=(X,),
        T=M * X.diff(t) ** 2 / 2 + I * (X.diff(t) - a.diff(t)) ** 2 / (2 * R**2),
        parameters=(M, R, I, A, Omega),
        name="tray_cylinder",
        description="Cylinder rolling without slipping on a tray shaken along a(t).",
        defaults={"M": 1.0, "R": 0.1, "I": 0.005, "A": 0.2, "Omega": 3.0},
        q0=(0.0,), qd0=(0.0,), t_end=10.0,
    )


def unbalanced_cylinder() -> System:
    """Badly balanced cylinder (mass M, radius R) rolling without slipping on horizontal ground.

    Its centre of mass G is at distance a from the axis; I is the moment of
    inertia about the line through G parallel to the axis.  Axes: x along the
    ground, y up.  Coordinate θ: rotation angle, clockwise, so the cylinder rolls
    toward +x as θ grows; θ = 0 has G straight below the axis C.
        C = (R θ, R),  G = (R θ − a sin θ, R − a cos θ).
    T = ½ M |Ġ|² + ½ I θ̇² = ½ [M (R² + a² − 2 a R cos θ) + I] θ̇²,
    V = M g (R − a cos θ).
    Equation: [M (R² + a² − 2 a R cos θ) + I] θ̈ + M a R sin θ θ̇² + M g a sin θ = 0.
    First integral: E = T + V.  The contact force needed (no take-off, no slip)
    follows from M G̈ = (F_h, F_v − M g).
    """
    (theta,) = coordinates("theta")
    M, R, a, I, g = _params("M R a I g")
    J = M * (R**2 + a**2 - 2 * a * R * sp.cos(theta)) + I
    return System(
        coordinates=(theta,),
        T=J * theta.diff(t) ** 2 / 2,
        V=M * g * (R - a * sp.cos(theta)),
        parameters=(M, R, a, I, g),
        name="unbalanced_cylinder",
        description="Rolling cylinder whose centre of mass is off its axis.",
        defaults={"M": 1.0, "R": 0.1, "a": 0.03, "I": 0.004, "g": 9.81},
        q0=(1.5,), qd0=(0.0,), t_end=10.0,
    )


def driven_pendulum() -> System:
    """Pendulum (mass m, length l, gravity g) whose support vibrates vertically: Kapitza's pendulum.

    The support's height is imposed, h(t) = A cos(Ω t).  Coordinate θ: angle
    from the downward vertical.  Support (0, h), bob (l sin θ, h − l cos θ), y up.
    T = ½ m (l² θ̇² + 2 l ḣ sin θ θ̇ + ḣ²),  V = m g (h − l cos θ).
    Equation: l θ̈ = −(g + ḧ) sin θ, ḧ = −A Ω² cos(Ω t).
    Averaging over the fast drive, the inverted position θ = π is stable when
    A² Ω² > 2 g l; the defaults (A²Ω² = 100 m²/s², 2gl ≈ 19.6) are in that regime
    and start the bob 0.24 rad from upright.
    """
    (theta,) = coordinates("theta")
    m, l, g, A, Omega = _params("m l g A Omega")
    h = A * sp.cos(Omega * t)
    x, y = l * sp.sin(theta), h - l * sp.cos(theta)
    return System(
        coordinates=(theta,),
        T=m * _speed2(x, y) / 2,
        V=m * g * y,
        parameters=(m, l, g, A, Omega),
        name="driven_pendulum",
        description="Pendulum on a vertically vibrated support (stable when inverted).",
        defaults={"m": 1.0, "l": 1.0, "g": 9.81, "A": 0.05, "Omega": 200.0},
        q0=(2.9,), qd0=(0.0,), t_end=10.0,
    )


def henon_heiles() -> System:
    """Hénon–Heiles: a star in an axisymmetric galaxy's potential, in scaled units.

    Coordinates x, y (unit mass and frequency); coupling λ (1 in the classic
    problem, 0 leaves two uncoupled unit oscillators).
    T = ½ (ẋ² + ẏ²),  V = ½ (x² + y²) + λ (x² y − y³/3).
    Equations: ẍ = −x − 2λ x y,  ÿ = −y − λ (x² − y²).  The energy is the only
    classical integral; below the escape energy 1/6 λ⁻² the motion is bounded,
    mostly regular at E = 1/12 and largely chaotic at E = 1/8.

    Events: ``section``, x = 0 crossed with ẋ > 0 (the usual Poincaré section,
    points (y, ẏ)); ``y_turn``, ẏ = 0 crossed downwards (a maximum of y).
    The default start lies on the section at E = 1/12, y = 0.1, ẏ = 0.
    """
    x, y = coordinates("x y")
    (lam,) = _params("lam")
    energy, y0 = sp.Rational(1, 12), sp.Rational(1, 10)
    xd0 = sp.sqrt(2 * (energy - y0**2 / 2 + y0**3 / 3))  # V(0, y0) = y0²/2 − y0³/3 at λ = 1
    return System(
        coordinates=(x, y),
        T=(x.diff(t) ** 2 + y.diff(t) ** 2) / 2,
        V=(x**2 + y**2) / 2 + lam * (x**2 * y - y**3 / 3),
        parameters=(lam,),
        name="henon_heiles",
        description="Star in a galactic potential: regular and chaotic orbits, Poincaré section x = 0.",
        defaults={"lam": 1.0},
        q0=(0.0, float(y0)), qd0=(float(xd0), 0.0), t_end=200.0,
        events=(Event("section", x, direction=1), Event("y_turn", y.diff(t), direction=-1)),
    )


def stiff_spring_pendulum() -> System:
    """Bob of mass m on a stiff, damped spring (stiffness k, rest length l0, damper c), swinging in gravity g.

    A stiff problem: the spring's fast mode next to the slow swing.  Coordinates r (the spring's
    length) and θ (its angle from the downward vertical); bob at (r sin θ, −r cos θ), y up.
    T = ½ m (ṙ² + r² θ̇²),  V = ½ k (r − l0)² − m g r cos θ,  D = ½ c ṙ² (the damper along the spring).
    Equations:
        m r̈ = m r θ̇² − k (r − l0) + m g cos θ − c ṙ,
        r θ̈ = −2 ṙ θ̇ − g sin θ.
    Linearized about the stretched rest length, the spring's own mode is m x'' + c x' + k x = 0: with the
    defaults k/m = 10⁶ s⁻² and c = 2 √(k m) (critical damping) both its eigenvalues are −c/(2m) = −1000 s⁻¹,
    while the swing has a period near 2π √(l0/g) ≈ 2 s.  An explicit method's step is bounded by that
    eigenvalue (h ≲ 3/1000 s for DOP853) however smooth the motion is; a stiff method's is not.
    The default start is at rest with the spring stretched to balance gravity along it,
    r0 = l0 + m g cos θ0 / k, so that the fast mode is hardly excited: the motion stays on its slow manifold.
    T + V decreases only through D (the power −c ṙ²).
    """
    r, theta = coordinates("r theta")
    m, k, c, l0, g = _params("m k c l0 g")
    defaults = {"m": 1.0, "k": 1.0e6, "c": 2.0e3, "l0": 1.0, "g": 9.81}
    theta0 = 1.0
    r0 = defaults["l0"] + defaults["m"] * defaults["g"] * float(sp.cos(theta0)) / defaults["k"]
    return System(
        coordinates=(r, theta),
        T=m * (r.diff(t) ** 2 + r**2 * theta.diff(t) ** 2) / 2,
        V=k * (r - l0) ** 2 / 2 - m * g * r * sp.cos(theta),
        dissipation=c * r.diff(t) ** 2 / 2,
        parameters=(m, k, c, l0, g),
        name="stiff_spring_pendulum",
        description="Pendulum on a stiff damped spring (k/m = 1e6): a stiff problem for method='radau'.",
        defaults=defaults,
        q0=(r0, theta0), qd0=(0.0, 0.0), t_end=10.0,
    )
