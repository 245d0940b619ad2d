"""Hand-written DAE kernels for the Radau driver's DAE tests (tests/test_radau_dae.py).

The planar pendulum in Cartesian coordinates q = (x, y) (y up), mass m on a massless rod of length L,
gravity g: M = m I, F = (0, −m g), one holonomic constraint Φ = (x² + y² − L²)/2, Λ = ∂Φ/∂q = (x, y),
b = 0, m q̈ = F + Λᵀ λ.  Written as the stabilised index-2 DAE of the Radau driver's DAE form
(`lagcomp.integrate.drivers.radau`, "DAEs"): z = (x, y, vx, vy, wx, wy, λ, μ), differential = 4, and

    G = (vx + x μ, vy + y μ, wx, wy, m wx − x λ, m wy + m g − y λ, x vx + y vy, (x² + y² − L²)/2).

``rhs(t, z, p, out)`` gives G, ``rhs_jacobian(t, z, p, out)`` ∂G/∂z (every entry written), as the kernel
types of `lagcomp.integrate.drivers.kernel_types`; p = (kind, event time, m, g, L) (p[1]: the time of
tests/driver_kernels.py's event g1 = t − p[1]).  Kinds, selected by p[0]:

0. the pendulum (N = 8);
1. the pendulum with its constraint stated twice (k = 2 rows Λ_c = (x, y), both holonomic): z = (x, y,
   vx, vy, wx, wy, λ1, λ2, μ1, μ2), N = 10; its constraint Jacobian has rank 1, so the iteration
   matrices are singular at every step size;
2. a linear one, for forced-step orders (G linear in z, so the simplified Newton iteration with the exact
   J solves the stages to round-off whatever the tolerance): the mass on the line a·q = 0 through the
   origin, a = (−sin α, cos α) with α = p[4], held by an anisotropic spring F = −K q − (0, m g), K =
   [[p[5], p[6]], [p[6], p[7]]] (N = 8, the pendulum's z; Λ = a constant, Φ = a·q).
"""

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def rhs(t, z, p, out):
    if p[0] == 2.0:
        return _line_rhs(z, p, out)
    k = 1 + int(p[0])
    m, g, length = p[2], p[3], p[4]
    x, y, vx, vy, wx, wy = z[0], z[1], z[2], z[3], z[4], z[5]
    lam = 0.0
    mu = 0.0
    for c in range(k):
        lam += z[6 + c]
        mu += z[6 + k + c]
    out[0] = vx + x * mu
    out[1] = vy + y * mu
    out[2] = wx
    out[3] = wy
    out[4] = m * wx - x * lam
    out[5] = m * wy + m * g - y * lam
    for c in range(k):
        out[6 + c] = x * vx + y * vy
        out[6 + k + c] = (x * x + y * y - length * length) / 2
    return 0


@njit(cache=True, error_model="numpy")
def rhs_jacobian(t, z, p, out):
    if p[0] == 2.0:
        return _line_jacobian(p, out)
    k = 1 + int(p[0])
    m = p[2]
    x, y, vx, vy = z[0], z[1], z[2], z[3]
    lam = 0.0
    mu = 0.0
    for c in range(k):
        lam += z[6 + c]
        mu += z[6 + k + c]
    out[:, :] = 0.0
    out[0, 0] = mu
    out[0, 2] = 1.0
    out[1, 1] = mu
    out[1, 3] = 1.0
    out[2, 4] = 1.0
    out[3, 5] = 1.0
    out[4, 0] = -lam
    out[4, 4] = m
    out[5, 1] = -lam
    out[5, 5] = m
    for c in range(k):
        out[0, 6 + k + c] = x
        out[1, 6 + k + c] = y
        out[4, 6 + c] = -x
        out[5, 6 + c] = -y
        out[6 + c, 0] = vx
        out[6 + c, 1] = vy
        out[6 + c, 2] = x
        out[6 + c, 3] = y
        out[6 + k + c, 0] = x
        out[6 + k + c, 1] = y
    return 0


def consistent_state(theta, omega, p):
    """z at angle θ from the downward vertical and angular velocity ω: (x, y) = L (sin θ, −cos θ),
    v = L ω (cos θ, sin θ), λ = m (g y − |v|²)/L² (tests/test_radau_dae.py derives it), w = (F + Λᵀλ)/m, μ = 0;
    with k rows the reaction λ is split equally between them."""
    k = 1 + int(p[0])
    m, g, length = p[2], p[3], p[4]
    x, y = length * np.sin(theta), -length * np.cos(theta)
    vx, vy = length * omega * np.cos(theta), length * omega * np.sin(theta)
    lam = m * (g * y - (vx * vx + vy * vy)) / length**2
    z = np.zeros(6 + 2 * k)
    z[:6] = x, y, vx, vy, lam * x / m, -g + lam * y / m
    z[6:6 + k] = lam / k
    return z


@njit(cache=True, error_model="numpy")
def _line_rhs(z, p, out):
    m, g, alpha, k11, k12, k22 = p[2], p[3], p[4], p[5], p[6], p[7]
    ax, ay = -np.sin(alpha), np.cos(alpha)
    x, y, vx, vy, wx, wy, lam, mu = z[0], z[1], z[2], z[3], z[4], z[5], z[6], z[7]
    out[0] = vx + ax * mu
    out[1] = vy + ay * mu
    out[2] = wx
    out[3] = wy
    out[4] = m * wx + k11 * x + k12 * y - ax * lam
    out[5] = m * wy + k12 * x + k22 * y + m * g - ay * lam
    out[6] = ax * vx + ay * vy
    out[7] = ax * x + ay * y
    return 0


@njit(cache=True, error_model="numpy")
def _line_jacobian(p, out):
    m, alpha, k11, k12, k22 = p[2], p[4], p[5], p[6], p[7]
    ax, ay = -np.sin(alpha), np.cos(alpha)
    out[:, :] = 0.0
    out[0, 2] = 1.0
    out[0, 7] = ax
    out[1, 3] = 1.0
    out[1, 7] = ay
    out[2, 4] = 1.0
    out[3, 5] = 1.0
    out[4, 0] = k11
    out[4, 1] = k12
    out[4, 4] = m
    out[4, 6] = -ax
    out[5, 0] = k12
    out[5, 1] = k22
    out[5, 5] = m
    out[5, 6] = -ay
    out[6, 2] = ax
    out[6, 3] = ay
    out[7, 0] = ax
    out[7, 1] = ay
    return 0


def line_solution(t, s0, sdot0, p):
    """The exact z(t) of kind 2 from arc length s0 and speed ṡ0 along u = (cos α, sin α): with ω² = uᵀKu/m
    and s* = −g sin α/ω², s = s* + (s0 − s*) cos ωt + ṡ0/ω sin ωt, q = s u, v = ṡ u, w = s̈ u; the
    normal balance a·(F + a λ) = 0 gives λ = aᵀK u s + m g cos α; μ = 0.  Shape (len(t), 8)."""
    m, g, alpha, k11, k12, k22 = p[2], p[3], p[4], p[5], p[6], p[7]
    u, a = np.array([np.cos(alpha), np.sin(alpha)]), np.array([-np.sin(alpha), np.cos(alpha)])
    stiffness = np.array([[k11, k12], [k12, k22]])
    omega = np.sqrt(u @ stiffness @ u / m)
    rest = -g * np.sin(alpha) / omega**2
    t = np.asarray(t, dtype=float)
    s = rest + (s0 - rest) * np.cos(omega * t) + sdot0 / omega * np.sin(omega * t)
    sdot = -(s0 - rest) * omega * np.sin(omega * t) + sdot0 * np.cos(omega * t)
    sddot = -omega**2 * (s - rest)
    z = np.zeros((t.size, 8))
    z[:, 0:2], z[:, 2:4], z[:, 4:6] = np.outer(s, u), np.outer(sdot, u), np.outer(sddot, u)
    z[:, 6] = a @ stiffness @ u * s + m * g * np.cos(alpha)
    return z
