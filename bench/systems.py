"""The benchmark's systems: lagcomp descriptions, hand-written numba baselines and the peers' versions.

Double pendulum (lagcomp example ``double_pendulum``; parameters m1 m2 l1 l2 g):
with δ = θ1 − θ2,

    M = [[(m1 + m2) l1²,  m2 l1 l2 cos δ], [m2 l1 l2 cos δ,  m2 l2²]]
    F = [−m2 l1 l2 θ̇2² sin δ − (m1 + m2) g l1 sin θ1,  m2 l1 l2 θ̇1² sin δ − m2 g l2 sin θ2]

and q̈ = M⁻¹ F by Cramer's rule: that is `double_pendulum_rhs`, what a user
writes by hand.  The N-link chain (``n_link_pendulum(n)``, parameters
m1..mn l1..ln g) in closed form, with μ_k = Σ_{i≥k} m_i:

    M_jk = μ_max(j,k) l_j l_k cos(θj − θk),
    F_j  = −Σ_k μ_max(j,k) l_j l_k sin(θj − θk) θ̇k² − μ_j g l_j sin θj,

solved by an in-place Cholesky factorization: `chain_rhs` (a sine and a cosine per pair of links, the
accuracy section's hand-written form).  `chain_rhs_fast_ws` is the fastest closed form a careful user
writes: sin θ_j and cos θ_j once per link, the pairs' by the angle-difference identities (as lagcomp's
derivation of the chain has them), M's lower triangle only, LDLᵀ with one reciprocal per pivot, scratch
from the caller: the kernel section's baseline for the chain.

The hand-written kernels compile as a careful user compiles them: ``error_model="numpy"`` (no
division-by-zero checks, as lagcomp's kernels), libm's sin and cos (``math``), no fastmath.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import sympy as sp

import lagcomp as lc
from lagcomp.kernel_support import trig


@numba.njit(cache=True, error_model="numpy", fastmath=False)
def double_pendulum_rhs(t, y, p, out):
    """Hand-written double pendulum, state y = (θ1, θ2, θ̇1, θ̇2), p = (m1, m2, l1, l2, g)."""
    m1, m2, l1, l2, g = p[0], p[1], p[2], p[3], p[4]
    d = y[0] - y[1]
    s, c = math.sin(d), math.cos(d)
    a11 = (m1 + m2) * l1 * l1
    a12 = m2 * l1 * l2 * c
    a22 = m2 * l2 * l2
    f1 = -m2 * l1 * l2 * y[3] * y[3] * s - (m1 + m2) * g * l1 * math.sin(y[0])
    f2 = m2 * l1 * l2 * y[2] * y[2] * s - m2 * g * l2 * math.sin(y[1])
    det = a11 * a22 - a12 * a12
    out[0] = y[2]
    out[1] = y[3]
    out[2] = (a22 * f1 - a12 * f2) / det
    out[3] = (a11 * f2 - a12 * f1) / det
    return 0


@numba.njit(cache=True, error_model="numpy", fastmath=False)
def double_pendulum_rhs_polynomial_trig(t, y, p, out):
    """`double_pendulum_rhs` with lagcomp's sin and cos (`lagcomp.kernel_support.trig`, the polynomials its
    kernels call) instead of libm's: the kernel section's row that separates their cost from the rest."""
    m1, m2, l1, l2, g = p[0], p[1], p[2], p[3], p[4]
    d = y[0] - y[1]
    s, c = trig.sin(d), trig.cos(d)
    a11 = (m1 + m2) * l1 * l1
    a12 = m2 * l1 * l2 * c
    a22 = m2 * l2 * l2
    f1 = -m2 * l1 * l2 * y[3] * y[3] * s - (m1 + m2) * g * l1 * trig.sin(y[0])
    f2 = m2 * l1 * l2 * y[2] * y[2] * s - m2 * g * l2 * trig.sin(y[1])
    det = a11 * a22 - a12 * a12
    out[0] = y[2]
    out[1] = y[3]
    out[2] = (a22 * f1 - a12 * f2) / det
    out[3] = (a11 * f2 - a12 * f1) / det
    return 0


@numba.njit(cache=True, error_model="numpy")
def chain_rhs(t, y, p, out):
    """Closed-form N-link chain (n = len(y) // 2), p = (m1..mn, l1..ln, g), allocating its scratch."""
    n = y.shape[0] // 2
    return chain_rhs_ws(t, y, p, out, np.empty((n, n)), np.empty(n), np.empty(n))


@numba.njit(cache=True, error_model="numpy")
def chain_rhs_ws(t, y, p, out, a, f, mu):
    """`chain_rhs` with caller-provided scratch a (n, n), f (n,), mu (n,): no allocation, Cholesky solve."""
    n = y.shape[0] // 2
    g = p[2 * n]
    acc = 0.0
    for k in range(n - 1, -1, -1):
        acc += p[k]
        mu[k] = acc
    for j in range(n):
        lj = p[n + j]
        fj = -mu[j] * g * lj * math.sin(y[j])
        for k in range(n):
            d = y[j] - y[k]
            w = mu[max(j, k)] * lj * p[n + k]
            a[j, k] = w * math.cos(d)
            fj -= w * math.sin(d) * y[n + k] * y[n + k]
        f[j] = fj
    for j in range(n):  # Cholesky a = L Lᵀ, L in the lower triangle
        s = a[j, j]
        for k in range(j):
            s -= a[j, k] * a[j, k]
        a[j, j] = math.sqrt(s)
        for i in range(j + 1, n):
            s = a[i, j]
            for k in range(j):
                s -= a[i, k] * a[j, k]
            a[i, j] = s / a[j, j]
    for i in range(n):
        s = f[i]
        for k in range(i):
            s -= a[i, k] * f[k]
        f[i] = s / a[i, i]
    for i in range(n - 1, -1, -1):
        s = f[i]
        for k in range(i + 1, n):
            s -= a[k, i] * f[k]
        f[i] = s / a[i, i]
    for i in range(n):
        out[i] = y[n + i]
        out[n + i] = f[i]
    return 0


@numba.njit(cache=True, error_model="numpy")
def chain_rhs_fast_ws(t, y, p, out, s, c, mu, a, f):
    """The N-link chain's fastest closed form (module docstring), scratch s, c, mu, f (n,) and a (n, n) given."""
    n = y.shape[0] // 2
    g = p[2 * n]
    acc = 0.0
    for k in range(n - 1, -1, -1):
        acc += p[k]
        mu[k] = acc
        s[k] = math.sin(y[k])
        c[k] = math.cos(y[k])
    for j in range(n):
        f[j] = -mu[j] * g * p[n + j] * s[j]
    for j in range(n):
        lj = p[n + j]
        for k in range(j + 1):
            w = mu[j] * lj * p[n + k]       # μ_max(j,k) = μ_j for k ≤ j
            a[j, k] = w * (c[j] * c[k] + s[j] * s[k])
            if k < j:
                w_sin = w * (s[j] * c[k] - c[j] * s[k])     # M-weighted sin(θj − θk)
                f[j] -= w_sin * y[n + k] * y[n + k]
                f[k] += w_sin * y[n + j] * y[n + j]
    for j in range(n):  # LDLᵀ: D on the diagonal, L below it, 1/D in mu (no longer needed)
        d = a[j, j]
        for k in range(j):
            d -= a[j, k] * a[j, k] * a[k, k]
        a[j, j] = d
        mu[j] = 1.0 / d
        for i in range(j + 1, n):
            v = a[i, j]
            for k in range(j):
                v -= a[i, k] * a[j, k] * a[k, k]
            a[i, j] = v * mu[j]
    for i in range(n):
        v = f[i]
        for k in range(i):
            v -= a[i, k] * f[k]
        f[i] = v
    for i in range(n - 1, -1, -1):
        v = f[i] * mu[i]
        for k in range(i + 1, n):
            v -= a[k, i] * f[k]
        f[i] = v
    for i in range(n):
        out[i] = y[n + i]
        out[n + i] = f[i]
    return 0


@numba.njit(error_model="numpy")
def chain_fast_loop(y, p, out, calls):
    """`calls` calls of `chain_rhs_fast_ws` with scratch allocated once: the kernel section's chain baseline."""
    n = y.shape[0] // 2
    s, c, mu, a, f = np.empty(n), np.empty(n), np.empty(n), np.empty((n, n)), np.empty(n)
    acc = 0.0
    for _ in range(calls):
        y[0] += 1e-12
        chain_rhs_fast_ws(0.0, y, p, out, s, c, mu, a, f)
        acc += out[out.shape[0] - 1]
    return acc


def kepler() -> lc.System:
    """Kepler problem in Cartesian coordinates, μ = 1: T = ½ m (ẋ² + ẏ²), V = −m μ / r; eccentricity 0.5, period 2π.

    Separable (M constant, F free of q̇), so the explicit symplectic methods apply.
    """
    x, y = lc.coordinates("x y")
    m, mu = sp.symbols("m mu", positive=True)
    e = 0.5
    return lc.System(
        [x, y], T=m * (x.diff(lc.t) ** 2 + y.diff(lc.t) ** 2) / 2, V=-m * mu / sp.sqrt(x**2 + y**2),
        parameters=(m, mu), name="bench_kepler", description="Kepler orbit, e = 0.5, period 2π.",
        defaults={"m": 1.0, "mu": 1.0}, q0=(1 - e, 0.0), qd0=(0.0, math.sqrt((1 + e) / (1 - e))),
        t_end=2 * math.pi,
    )


@numba.njit(cache=True, error_model="numpy")
def kepler_rhs(t, y, p, out):
    """Hand-written Kepler, y = (x, y, ẋ, ẏ), p = (m, μ)."""
    r2 = y[0] * y[0] + y[1] * y[1]
    k = -p[1] / (r2 * math.sqrt(r2))
    out[0] = y[2]
    out[1] = y[3]
    out[2] = k * y[0]
    out[3] = k * y[1]
    return 0


@numba.njit(error_model="numpy")
def chain_loop(y, p, out, calls):
    """`calls` calls of `chain_rhs_ws` with scratch allocated once: the closed-form baseline's compiled loop."""
    n = y.shape[0] // 2
    a, f, mu = np.empty((n, n)), np.empty(n), np.empty(n)
    acc = 0.0
    for _ in range(calls):
        y[0] += 1e-12
        chain_rhs_ws(0.0, y, p, out, a, f, mu)
        acc += out[out.shape[0] - 1]
    return acc


def rk4_driver(rhs):
    """A hand-written numba RK4 loop over `rhs`: the baseline of the fixed-step throughput."""
    @numba.njit(error_model="numpy")
    def run(y, p, dt, n):
        k1, k2, k3, k4, tmp = np.empty(y.size), np.empty(y.size), np.empty(y.size), np.empty(y.size), np.empty(y.size)
        t = 0.0
        for _ in range(n):
            rhs(t, y, p, k1)
            for i in range(y.size):
                tmp[i] = y[i] + 0.5 * dt * k1[i]
            rhs(t + 0.5 * dt, tmp, p, k2)
            for i in range(y.size):
                tmp[i] = y[i] + 0.5 * dt * k2[i]
            rhs(t + 0.5 * dt, tmp, p, k3)
            for i in range(y.size):
                tmp[i] = y[i] + dt * k3[i]
            rhs(t + dt, tmp, p, k4)
            for i in range(y.size):
                y[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            t += dt
        return y

    return run


# -- symbolic forms the peers take ----------------------------------------------------------


def double_pendulum_reduced(sin, cos, th1, th2, w1, w2, m1, m2, l1, l2, g):
    """(θ̈1, θ̈2) of the double pendulum as expressions of whatever symbolic library supplies sin/cos."""
    d = th1 - th2
    a11, a12, a22 = (m1 + m2) * l1**2, m2 * l1 * l2 * cos(d), m2 * l2**2
    f1 = -m2 * l1 * l2 * w2**2 * sin(d) - (m1 + m2) * g * l1 * sin(th1)
    f2 = m2 * l1 * l2 * w1**2 * sin(d) - m2 * g * l2 * sin(th2)
    det = a11 * a22 - a12**2
    return (a22 * f1 - a12 * f2) / det, (a11 * f2 - a12 * f1) / det


def kane_chain(n: int):
    """PyDy's way: the N-link chain with sympy.physics.mechanics.KanesMethod, u_i = θ̇_i.

    Returns (KanesMethod, coordinates, speeds, constants) with constants in
    lagcomp's parameter order (m1..mn, l1..ln, g).
    """
    import sympy.physics.mechanics as me

    th = me.dynamicsymbols(f"theta1:{n + 1}")
    u = me.dynamicsymbols(f"u1:{n + 1}")
    ms = sp.symbols(f"m1:{n + 1}", positive=True)
    ls = sp.symbols(f"l1:{n + 1}", positive=True)
    g = sp.Symbol("g", positive=True)
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    prev, particles, loads = O, [], []
    for i in range(n):
        P = prev.locatenew(f"P{i + 1}", ls[i] * (sp.sin(th[i]) * N.x - sp.cos(th[i]) * N.y))
        P.set_vel(N, prev.vel(N) + ls[i] * u[i] * (sp.cos(th[i]) * N.x + sp.sin(th[i]) * N.y))
        particles.append(me.Particle(f"bob{i + 1}", P, ms[i]))
        loads.append((P, -ms[i] * g * N.y))
        prev = P
    km = me.KanesMethod(N, q_ind=th, u_ind=u, kd_eqs=[a.diff(me.dynamicsymbols._t) - b for a, b in zip(th, u)])
    km.kanes_equations(particles, loads)
    return km, th, u, ms + ls + (g,)
