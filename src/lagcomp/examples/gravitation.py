"""Bundled gravitational examples: point masses with close approaches.

They are written the way a physicist writes them, distances as
√((xᵢ − xⱼ)² + (yᵢ − yⱼ)²), and serve as the accuracy cases of the compiler
(`lagcomp.accuracy`): when two bodies pass close, a kernel that multiplied the
squared distances out (xᵢ² + xⱼ² − 2xᵢxⱼ + …) would lose digits to
cancellation; a kernel that keeps the differences stays at the rounding floor.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.model import System, coordinates, t

__all__ = ["pythagorean_three_body", "restricted_three_body", "GRAVITATION_EXAMPLES"]


def _params(names: str) -> tuple[sp.Symbol, ...]:
    """Positive real parameters, always as a tuple."""
    return tuple(sp.symbols(names, positive=True, seq=True))


def _distance(a: tuple, b: tuple) -> sp.Expr:
    """√((a_x − b_x)² + (a_y − b_y)²), as written."""
    return sp.sqrt((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2)


def pythagorean_three_body() -> System:
    """Burrau's Pythagorean three-body problem: masses 3, 4, 5 released at rest in a plane.

    Coordinates x_i, y_i (i = 1, 2, 3) of three point masses m_i under their
    mutual gravitation (constant G); m1 = 3, m2 = 4, m3 = 5 start at rest at
    (1, 3), (−2, −1), (1, −1), the corners of a 3-4-5 right triangle opposite
    the sides of their mass.
    T = ½ Σ m_i (ẋ_i² + ẏ_i²),  V = −Σ_{i<j} G m_i m_j / r_ij,  r_ij = √((x_i − x_j)² + (y_i − y_j)²).
    Equations: m_i r̈_i = Σ_{j≠i} G m_i m_j (r_j − r_i)/r_ij³.  Energy (−769/60 for the
    defaults: V = −(12/5 + 15/2 + 20/3)), linear and angular momentum (zero) are conserved.
    The motion has a sequence of close approaches, the closest r23 ≈ 4.1e-4 at t ≈ 15.83
    (others ≈ 1e-2 at t ≈ 1.9 and 8.8, 2.8e-3 at t ≈ 29.8; lagcomp's dop853 at tol 1e-13),
    before the 4- and 5-mass bodies form a tight binary (r23 down to 6e-3 every 0.84)
    and the 3-mass body escapes (Szebehely & Peters 1967, Astron. J. 72, 876).
    """
    xs = coordinates("x1 y1 x2 y2 x3 y3")
    points = [(xs[2 * i], xs[2 * i + 1]) for i in range(3)]
    G, *ms = _params("G m1 m2 m3")
    T = sum((m * (x.diff(t) ** 2 + y.diff(t) ** 2) for m, (x, y) in zip(ms, points)), sp.S.Zero) / 2
    V = -sum((G * ms[i] * ms[j] / _distance(points[i], points[j]) for i in range(3) for j in range(i + 1, 3)),
             sp.S.Zero)
    return System(
        coordinates=xs,
        T=T,
        V=V,
        parameters=(G, *ms),
        name="pythagorean_three_body",
        description="Burrau's three bodies (masses 3, 4, 5) falling from rest: close approaches.",
        defaults={"G": 1.0, "m1": 3.0, "m2": 4.0, "m3": 5.0},
        q0=(1.0, 3.0, -2.0, -1.0, 1.0, -1.0), qd0=(0.0,) * 6, t_end=70.0,
    )


def restricted_three_body() -> System:
    """Planar circular restricted three-body problem in the frame rotating with the primaries.

    Units: the primaries' distance, their total mass and their angular rate are 1.
    The primaries of mass 1 − μ and μ sit at (−μ, 0) and (1 − μ, 0); the
    coordinates x, y are the massless body's position in the rotating frame, so
    its inertial velocity is (ẋ − y, ẏ + x):
    T = ½ ((ẋ − y)² + (ẏ + x)²),  V = −(1 − μ)/r1 − μ/r2,
    r1 = √((x + μ)² + y²),  r2 = √((x − 1 + μ)² + y²).
    Equations: ẍ − 2ẏ − x = −(1 − μ)(x + μ)/r1³ − μ(x − 1 + μ)/r2³,
               ÿ + 2ẋ − y = −(1 − μ) y/r1³ − μ y/r2³.
    The Jacobi integral h = ½(ẋ² + ẏ²) − ½(x² + y²) + V is conserved.  The defaults are the
    Arenstorf orbit of Hairer, Nørsett & Wanner (Solving ODEs I, §II.0): μ = 0.012277471,
    (x, y, ẋ, ẏ) = (0.994, 0, 0, −2.00158510637908252240537862224), periodic with period
    T = 17.0652165601579625588917206249, passing close to the small primary.
    """
    x, y = coordinates("x y")
    (mu,) = _params("mu")
    return System(
        coordinates=(x, y),
        T=((x.diff(t) - y) ** 2 + (y.diff(t) + x) ** 2) / 2,
        V=-(1 - mu) / _distance((x, y), (-mu, 0)) - mu / _distance((x, y), (1 - mu, 0)),
        parameters=(mu,),
        name="restricted_three_body",
        description="Circular restricted three-body problem, rotating frame: the Arenstorf orbit.",
        defaults={"mu": 0.012277471},
        q0=(0.994, 0.0), qd0=(0.0, -2.00158510637908252240537862224), t_end=17.0652165601579625588917206249,
    )


#: The gravitational examples by name, merged into `lagcomp.examples.EXAMPLES`.
GRAVITATION_EXAMPLES = {f.__name__: f for f in (pythagorean_three_body, restricted_three_body)}
