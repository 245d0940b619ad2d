"""The canonical (Hamiltonian) form of an unconstrained model, built from its kernels.

The canonical state is x = (q, p), shape (2n,), p the conjugate momenta
P(q, q̇, t) = ∂L/∂q̇ = M(q, t) q̇ + b(q, t).  Nothing here inverts M symbolically: q̇ = v(q, p, t)
solves M v = p − b numerically (the model's ``velocities`` kernel), and the Hamiltonian, the
canonical vector field and its Jacobian are evaluated from kernels at (q, v).  Constrained models
have no such form (their momenta do not determine their velocities) and no ``velocities`` kernel.

`hamiltonian` and `canonical_jacobian` are what `Model.hamiltonian` and
`Model.canonical_jacobian` return; the collocation and Lyapunov drivers call them, and
`canonical_field`, with the kernels they were given.  `jacobian_at_velocities` and
`field_at_velocities` are the same at a state whose velocities are solved already.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

from lagcomp.integrate.drivers.kernel_types import (
    CANONICAL_PARTIALS,
    ENERGY_FUNCTION,
    FLOAT,
    MATRIX,
    MOMENTUM_RATE,
    VECTOR,
    VELOCITIES,
)
from lagcomp.kernel_support.linear_solvers import ldlt_solve_matrix


@njit(types.float64(VELOCITIES, ENERGY_FUNCTION, FLOAT, VECTOR, VECTOR), cache=True, error_model="numpy",
      nogil=True)
def hamiltonian(velocities, energy_function, t, x, p):
    """H(q, p, t) at x = (q, p), shape (2n,): the energy function at (q, v(q, p, t)).

    The Legendre transform H = p·v − L(q, v, t) is the value of the energy function
    h = Σ q̇_i ∂L/∂q̇_i − L at q̇ = v.  Returns NaN where M is not positive definite (v undefined).
    """
    n = x.shape[0] // 2
    v = np.empty(n)
    if velocities(t, x, p, v):
        return np.nan
    y = np.empty(2 * n)
    for i in range(n):
        y[i] = x[i]
        y[n + i] = v[i]
    return energy_function(t, y, p)


@njit(cache=True, error_model="numpy", nogil=True)
def jacobian_at_velocities(canonical_partials, t, x, v, p, J):
    """`canonical_jacobian` at x = (q, p) whose velocities v = q̇ (n,) are known (``velocities`` solved them).

    For a caller that also needs f(t, x) there (the Lyapunov loops): one solve for v serves both.
    Returns 0, or k > 0 when M is not positive definite at pivot k (``J`` is then invalid).
    """
    n = x.shape[0] // 2
    y = np.empty(2 * n)
    for i in range(n):
        y[i] = x[i]
        y[n + i] = v[i]
    blocks = np.empty((4, n, n))
    canonical_partials(t, y, p, blocks)
    for i in range(n):
        for j in range(n):
            J[i, j] = -blocks[1, i, j]
            J[i, n + j] = 1.0 if i == j else 0.0
    status = ldlt_solve_matrix(blocks[0], J[:n])
    if status:
        return status
    for i in range(n):
        for j in range(2 * n):
            s = blocks[2, i, j] if j < n else 0.0
            for k in range(n):
                s += blocks[3, i, k] * J[k, j]
            J[n + i, j] = s
    return 0


@njit(types.int64(VELOCITIES, CANONICAL_PARTIALS, FLOAT, VECTOR, VECTOR, MATRIX), cache=True,
      error_model="numpy", nogil=True)
def canonical_jacobian(velocities, canonical_partials, t, x, p, J):
    """Jacobian ∂f/∂x, shape (2n, 2n) into ``J``, of the canonical equations at x = (q, p).

    f(x) = (q̇, ṗ) = (v, r(q, v, t)) with v = M⁻¹ (p − b) and r the momentum rate
    ∂L/∂q + Q − ∂D/∂q̇ (Hamilton's −∂H/∂q plus the forces).  With the partials at fixed q̇ of
    ``canonical_partials``, P_q = ∂P/∂q, R_q = ∂r/∂q, R_v = ∂r/∂q̇: differentiating P(q, v) = p
    gives P_q dq + M dv = dp, so dv = M⁻¹ (dp − P_q dq), and dṗ = R_q dq + R_v dv:

        J = [[−M⁻¹ P_q,          M⁻¹    ],
             [R_q − R_v M⁻¹ P_q, R_v M⁻¹]].

    The top block row W = M⁻¹ [−P_q | I] is solved with one LDLᵀ factorization of M; the bottom
    one is [R_q | 0] + R_v W.  Returns 0, or k > 0 when M is not positive definite at pivot k
    (``J`` is then invalid).
    """
    v = np.empty(x.shape[0] // 2)
    status = velocities(t, x, p, v)
    if status:
        return status
    return jacobian_at_velocities(canonical_partials, t, x, v, p, J)


@njit(cache=True, error_model="numpy", nogil=True)
def field_at_velocities(momentum_rate, t, x, v, p, y, out):
    """f(t, x) = (v, ṗ) into ``out`` (2n,) at x = (q, p) whose velocities v (n,) are known; ``y`` (2n,) work space."""
    n = x.shape[0] // 2
    r = np.empty(n)
    for i in range(n):
        y[i] = x[i]
        y[n + i] = v[i]
    momentum_rate(t, y, p, r)
    for i in range(n):
        out[i] = v[i]
        out[n + i] = r[i]


@njit(types.int64(VELOCITIES, MOMENTUM_RATE, FLOAT, VECTOR, VECTOR, VECTOR, VECTOR), cache=True,
      error_model="numpy", nogil=True)
def canonical_field(velocities, momentum_rate, t, x, p, y, out):
    """f(t, x) = (q̇, ṗ) into ``out`` (2n,) at x = (q, p); ``y`` (2n,) is work space for (q, q̇).

    Returns 0, or k > 0 when M is not positive definite at pivot k (``out`` is then invalid).

    The body of `field_at_velocities` is written out here: calling it cost the two-trajectory loop,
    which does little besides this, about 20% of its speed (double pendulum, median of 25 runs).
    """
    n = x.shape[0] // 2
    v = np.empty(n)
    status = velocities(t, x, p, v)
    if status:
        return status
    r = np.empty(n)
    for i in range(n):
        y[i] = x[i]
        y[n + i] = v[i]
    momentum_rate(t, y, p, r)
    for i in range(n):
        out[i] = v[i]
        out[n + i] = r[i]
    return 0
