r"""Modified Rodrigues parameters (MRPs): the coordinates of a spherical joint's (and a free joint's) rotation.

A rotation by the angle θ about the unit axis n has the MRP vector σ = n tan(θ/4).  With s = σ·σ:

* the rotation matrix (x_parent = R x_body) is R(σ) = 1 + (8 [σ]×² + 4 (1 − s) [σ]×) / (1 + s)²: rational, no
  trigonometric function, no division by a small number (1 + s ≥ 1);
* the body-frame angular velocity is ω = J(σ) σ̇ with J = 4 Bᵀ / (1 + s)², B = (1 − s) 1 + 2 [σ]× + 2 σ σᵀ;
  BᵀB = (1 + s)² 1, so σ̇ = B ω / 4 (Schaub & Junkins, *Analytical Mechanics of Space Systems*, 4th ed., §3.7);
* σ is singular only at θ = ±2π (|σ| → ∞).  The *shadow* set σˢ = −σ / s describes the same rotation (the angle
  θ − 2π about the same axis) and |σˢ| = 1/|σ|: switching to it when |σ| passes 1 (θ = π) keeps |σ| ≤ 1, a half
  turn from the singularity, for any motion.  Its rates follow by the chain rule, σ̇ˢ = −σ̇ / s + 2 σ (σ·σ̇) / s²,
  so the orientation and the angular velocity do not change across the switch.

The functions take and return plain sequences and use only +, −, ×, /, so the same code builds the sympy
expressions the recursions bind (`lagcomp.multibody.kinematics`) and evaluates numbers (numpy floats) for initial
conditions and checks: `mrp_from_axis_angle`, `mrp_from_rotation`, `mrp_rate` give a user's ``q0`` and ``qd0``.
"""

from __future__ import annotations

import math

import numpy as np


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a, b) -> list:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def rotation(sigma, s=None, k=None) -> list:
    """R(σ), rows (3×3): the body's axes in the parent's, x_parent = R x_body (`s` = σ·σ and `k` = 1 / (1 + s)²
    given when they are bound already)."""
    s = _dot(sigma, sigma) if s is None else s
    k = 1 / (1 + s) ** 2 if k is None else k
    skew = [[0, -sigma[2], sigma[1]], [sigma[2], 0, -sigma[0]], [-sigma[1], sigma[0], 0]]
    square = [[sigma[i] * sigma[j] - (s if i == j else 0) for j in range(3)] for i in range(3)]   # [σ]×² = σσᵀ − s1
    return [[(1 if i == j else 0) + k * (8 * square[i][j] + 4 * (1 - s) * skew[i][j]) for j in range(3)]
            for i in range(3)]


def b_matrix(sigma, s=None) -> list:
    """B(σ) = (1 − s) 1 + 2 [σ]× + 2 σ σᵀ (rows), s = σ·σ (given, when bound already): J = 4 Bᵀ / (1 + s)², J⁻¹ =
    B / 4."""
    s = _dot(sigma, sigma) if s is None else s
    skew = [[0, -sigma[2], sigma[1]], [sigma[2], 0, -sigma[0]], [-sigma[1], sigma[0], 0]]
    return [[(1 - s if i == j else 0) + 2 * skew[i][j] + 2 * sigma[i] * sigma[j] for j in range(3)] for i in range(3)]


def angular_velocity(sigma, sigma_dot) -> list:
    """ω = J(σ) σ̇ = 4 ((1 − s) σ̇ − 2 σ × σ̇ + 2 σ (σ·σ̇)) / (1 + s)²: the body's angular velocity, body axes."""
    return jacobian_times(sigma, sigma_dot)


def jacobian_times(sigma, x) -> list:
    """J(σ) x = 4 Bᵀ x / (1 + s)²."""
    s = _dot(sigma, sigma)
    k = 4 / (1 + s) ** 2
    c, d = _cross(sigma, x), _dot(sigma, x)
    return [k * ((1 - s) * x[i] - 2 * c[i] + 2 * sigma[i] * d) for i in range(3)]


def jacobian_transpose_times(sigma, x) -> list:
    """J(σ)ᵀ x = 4 B x / (1 + s)²: a body-frame moment (or row of a matrix) as generalized forces on σ."""
    s = _dot(sigma, sigma)
    k = 4 / (1 + s) ** 2
    c, d = _cross(sigma, x), _dot(sigma, x)
    return [k * ((1 - s) * x[i] + 2 * c[i] + 2 * sigma[i] * d) for i in range(3)]


def jacobian_inverse_times(sigma, x) -> list:
    """J(σ)⁻¹ x = B x / 4: the MRP rates of the body-frame angular velocity x."""
    s = _dot(sigma, sigma)
    c, d = _cross(sigma, x), _dot(sigma, x)
    return [((1 - s) * x[i] + 2 * c[i] + 2 * sigma[i] * d) / 4 for i in range(3)]


def rate_product(sigma, sigma_dot) -> list:
    """J̇ σ̇ = −4 (σ·σ̇) ω / (1 + s) + 8 |σ̇|² σ / (1 + s)², ω = J σ̇: what ω̇ holds besides J σ̈ (the time
    derivative of ω = J(σ) σ̇ at σ̈ = 0; derived in docs/multibody.md)."""
    s = _dot(sigma, sigma)
    w = jacobian_times(sigma, sigma_dot)
    a = -4 * _dot(sigma, sigma_dot) / (1 + s)
    b = 8 * _dot(sigma_dot, sigma_dot) / (1 + s) ** 2
    return [a * w[i] + b * sigma[i] for i in range(3)]


def shadow(sigma, sigma_dot) -> tuple[list, list]:
    """The shadow set (σˢ, σ̇ˢ) = (−σ / s, −σ̇ / s + 2 σ (σ·σ̇) / s²): the same orientation and angular velocity."""
    s = _dot(sigma, sigma)
    d = _dot(sigma, sigma_dot)
    return [-x / s for x in sigma], [-sigma_dot[i] / s + 2 * sigma[i] * d / s ** 2 for i in range(3)]


# -- numbers: initial conditions and checks ------------------------------------------------------------------------


def mrp_from_axis_angle(axis, angle: float) -> np.ndarray:
    """σ = n tan(θ/4) of the rotation by `angle` (rad) about `axis` (three numbers, normalised), with θ reduced to
    (−π, π] first (the set with |σ| ≤ 1)."""
    n = np.asarray(axis, dtype=float)
    norm = np.linalg.norm(n)
    if n.shape != (3,) or not norm > 0:
        raise ValueError(f"the axis must be three numbers, not all zero; got {axis!r}")
    theta = math.remainder(float(angle), 2 * math.pi)
    return n / norm * math.tan(theta / 4)


def mrp_from_rotation(R) -> np.ndarray:
    """σ with |σ| ≤ 1 of the rotation matrix `R` (3×3, x_parent = R x_body), from its unit quaternion."""
    R = np.asarray(R, dtype=float)
    if R.shape != (3, 3) or np.max(np.abs(R.T @ R - np.eye(3))) > 1e-9 or np.linalg.det(R) < 0:
        raise ValueError(f"not a rotation matrix (RᵀR = 1, det R = +1): {R.tolist()}")
    # Shepperd's method: the largest of the four squared quaternion components decides the formula
    trace = np.trace(R)
    squares = [1 + trace, 1 + 2 * R[0, 0] - trace, 1 + 2 * R[1, 1] - trace, 1 + 2 * R[2, 2] - trace]
    k = int(np.argmax(squares))
    r = math.sqrt(squares[k])
    if k == 0:
        quaternion = [r / 2, (R[2, 1] - R[1, 2]) / (2 * r), (R[0, 2] - R[2, 0]) / (2 * r), (R[1, 0] - R[0, 1]) / (2 * r)]
    else:
        i, j, m = k - 1, k % 3, (k + 1) % 3
        v = [0.0, 0.0, 0.0]
        v[i], v[j], v[m] = r / 2, (R[j, i] + R[i, j]) / (2 * r), (R[m, i] + R[i, m]) / (2 * r)
        quaternion = [(R[m, j] - R[j, m]) / (2 * r), *v]
    w, x = quaternion[0], np.array(quaternion[1:])
    if w < 0:   # the quaternion of the two with w ≥ 0: |σ| = |x| / (1 + w) ≤ 1
        w, x = -w, -x
    return x / (1 + w)


def mrp_rate(sigma, omega) -> np.ndarray:
    """σ̇ = B(σ) ω / 4 of the body-frame angular velocity `omega` (rad/s, body axes) at `sigma`: a ``qd0``."""
    return np.array(jacobian_inverse_times([float(x) for x in sigma], [float(x) for x in omega]))
