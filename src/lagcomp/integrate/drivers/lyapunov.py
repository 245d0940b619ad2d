"""The Lyapunov loops of `lagcomp.analysis.lyapunov`: the variational and the two-trajectory estimate.

Both integrate the canonical equations ẋ = f(t, x), x = (q, p), of an unconstrained model
(`lagcomp.integrate.drivers.canonical`) by the classic Runge-Kutta method with the fixed step
``dt`` (step j ends at t0 + (j + 1) dt, computed from the step count, so long runs do not
accumulate rounding in t).  Lyapunov exponents do not depend on the coordinates, and (q, p) is
where the Jacobian J = ∂f/∂x is compiled.

* `lyapunov_run`: the variational equations Ẇ = J(t, x) W for k tangent vectors (the columns of
  W), integrated with x by the same RK4 stages.  Every ``renorm_every`` steps, and at the end of
  each call, W is replaced by the Q of its QR factorization (Gram-Schmidt, applied twice for
  orthogonality) and log R_jj is added to ``sums[j]``: sums / (elapsed time) are the estimates of
  the k largest exponents (Benettin, Galgani, Giorgilli and Strelcyn 1980; Shimada and Nagashima
  1979).
* `divergence_run`: the two-trajectory estimate.  A shadow state xs starts at distance d0 from x (in the
  norm weighted by a scale per component: q and p have different units);
  both are advanced, and every ``renorm_every`` steps (and at the end of each call) log(d/d0) is
  added to ``sums[0]`` and xs is pulled back to distance d0 along xs − x.

Chart switches.  A ball joint's MRPs σ (three of the coordinates, their momenta π three of p) switch to the shadow
σ' = −σ/s, s = σ·σ, at the end of the first step past |σ| = 1 (`lagcomp.multibody.shadow`; the rows of ``charts``
name each joint's three coordinates), as the Gauss driver switches (`lagcomp.integrate.drivers.collocation`).  In
(q, p) the switch is the cotangent lift of σ → σ', a symplectic map in closed form: Dσ'/Dσ = −(I − 2σσᵀ/s)/s, its
inverse −s I + 2σσᵀ, symmetric, so π' = −s π + 2σ (σ·π) (`_shadow_state`).  The tangent vectors are pushed through
its derivative at the state before the switch (`_shadow_tangents`):

    δσ' = −δσ/s + 2σ (σ·δσ)/s²,
    δπ' = −s δπ + 2σ (σ·δπ) − 2π (σ·δσ) + 2(σ·π) δσ + 2σ (π·δσ).

The two-trajectory run switches the shadow state with the trajectory's, so that both are in one chart.

Both are resumable: the state lives in the in/out arrays ``x``, ``W`` (or ``xs``), ``steps``
(int64[1], steps taken since t0) and ``sums``, so the caller runs them in chunks (progress,
Ctrl-C) with the same result as one call.  They return `Status` DONE, NONFINITE when the state
(or a tangent vector) became non-finite, or RHS_FAILED when M was singular.

The RK4 coefficients are `lagcomp.integrate.tableaux.RK4`'s, read by numba when it compiles the
loops (module constants: a change of the tableau needs numba's cache of this module cleared).
Its weights B = (1, 2, 2, 1)/6 are applied as integers over their common denominator,
x + dt/6 (k1 + 2 k2 + 2 k3 + k4), the rounding of the loops these replace; the floats 1/6 and 1/3
would round differently.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types

from lagcomp.integrate.drivers.canonical import (
    canonical_field,
    field_at_velocities,
    jacobian_at_velocities,
)
from lagcomp.integrate.drivers.kernel_types import (
    CANONICAL_PARTIALS,
    FLOAT,
    INDICES,
    INT,
    MATRIX,
    MOMENTUM_RATE,
    VECTOR,
    VELOCITIES,
)
from lagcomp.integrate.status import Status
from lagcomp.integrate.tableaux import RK4, over_common_denominator

#: RK4's nodes c, its stage coefficients a[s, s-1] (the only nonzero ones), and its weights as
#: numerators over their common denominator (`tableaux.over_common_denominator`: 1, 2, 2, 1 over 6).
_C = RK4.C
_A = np.diag(RK4.A, -1).copy()
_WEIGHTS, _DENOMINATOR = over_common_denominator(RK4.B)


@njit(cache=True, error_model="numpy", nogil=True)
def _rk4_state(velocities, momentum_rate, t, x, p, dt, y, k1, k2, k3, k4, xt):
    """One RK4 step of the canonical equations, x updated in place. Returns a `Status`."""
    m = x.shape[0]
    if canonical_field(velocities, momentum_rate, t, x, p, y, k1):
        return Status.RHS_FAILED
    for i in range(m):
        xt[i] = x[i] + _A[0] * dt * k1[i]
    if canonical_field(velocities, momentum_rate, t + _C[1] * dt, xt, p, y, k2):
        return Status.RHS_FAILED
    for i in range(m):
        xt[i] = x[i] + _A[1] * dt * k2[i]
    if canonical_field(velocities, momentum_rate, t + _C[2] * dt, xt, p, y, k3):
        return Status.RHS_FAILED
    for i in range(m):
        xt[i] = x[i] + _A[2] * dt * k3[i]
    if canonical_field(velocities, momentum_rate, t + _C[3] * dt, xt, p, y, k4):
        return Status.RHS_FAILED
    for i in range(m):
        x[i] += dt / _DENOMINATOR * (_WEIGHTS[0] * k1[i] + _WEIGHTS[1] * k2[i] + _WEIGHTS[2] * k3[i]
                                     + _WEIGHTS[3] * k4[i])
        if not math.isfinite(x[i]):
            return Status.NONFINITE
    return Status.DONE


@njit(cache=True, error_model="numpy", nogil=True)
def _stage(velocities, momentum_rate, canonical_partials, t, x, p, W, J, y, v, k, K):
    """One RK4 stage of the state and the tangent vectors: k = f(t, x) (2n,) and K = J(t, x) W (2n, k).

    One solve for the velocities v (n,) serves both; J (2n, 2n) and y (2n,) are work space.
    Returns a `Status`.
    """
    if velocities(t, x, p, v):
        return Status.RHS_FAILED
    if jacobian_at_velocities(canonical_partials, t, x, v, p, J):
        return Status.RHS_FAILED
    m, columns = W.shape
    for i in range(m):
        for c in range(columns):
            s = 0.0
            for j in range(m):
                s += J[i, j] * W[j, c]
            K[i, c] = s
    field_at_velocities(momentum_rate, t, x, v, p, y, k)
    return Status.DONE


@njit(cache=True, error_model="numpy", nogil=True)
def _orthonormalize(W, sums):
    """W ← Q of W = QR (Gram-Schmidt twice), sums[j] += log R_jj. Returns a `Status` (NONFINITE: a column vanished)."""
    m, k = W.shape
    for c in range(k):
        for _ in range(2):  # "twice is enough" (Giraud et al. 2005)
            for b in range(c):
                s = 0.0
                for i in range(m):
                    s += W[i, b] * W[i, c]
                for i in range(m):
                    W[i, c] -= s * W[i, b]
        norm = 0.0
        for i in range(m):
            norm += W[i, c] * W[i, c]
        norm = math.sqrt(norm)
        if not (norm > 0.0 and math.isfinite(norm)):
            return Status.NONFINITE
        sums[c] += math.log(norm)
        for i in range(m):
            W[i, c] /= norm
    return Status.DONE


@njit(cache=True, error_model="numpy", nogil=True)
def _shadow_state(x, a):
    """The shadow switch of the ball joint whose σ are x[a[0]], x[a[1]], x[a[2]] (their momenta π at n + a), in place:
    σ' = −σ/s, π' = −s π + 2σ (σ·π) (module docstring)."""
    n = x.shape[0] // 2
    s = x[a[0]] * x[a[0]] + x[a[1]] * x[a[1]] + x[a[2]] * x[a[2]]
    sp = x[a[0]] * x[n + a[0]] + x[a[1]] * x[n + a[1]] + x[a[2]] * x[n + a[2]]
    for i in range(3):
        sigma = x[a[i]]
        x[n + a[i]] = -s * x[n + a[i]] + 2.0 * sigma * sp
        x[a[i]] = -sigma / s


@njit(cache=True, error_model="numpy", nogil=True)
def _shadow_tangents(x, W, a):
    """The tangent vectors W (2n, k) through the derivative of `_shadow_state` at x (before the switch), in place
    (module docstring)."""
    n = x.shape[0] // 2
    s = x[a[0]] * x[a[0]] + x[a[1]] * x[a[1]] + x[a[2]] * x[a[2]]
    sp = x[a[0]] * x[n + a[0]] + x[a[1]] * x[n + a[1]] + x[a[2]] * x[n + a[2]]
    for c in range(W.shape[1]):
        s_ds, s_dp, p_ds = 0.0, 0.0, 0.0
        for i in range(3):
            s_ds += x[a[i]] * W[a[i], c]
            s_dp += x[a[i]] * W[n + a[i], c]
            p_ds += x[n + a[i]] * W[a[i], c]
        for i in range(3):
            sigma, pi, ds, dp = x[a[i]], x[n + a[i]], W[a[i], c], W[n + a[i], c]
            W[a[i], c] = -ds / s + 2.0 * sigma * s_ds / (s * s)
            W[n + a[i], c] = -s * dp + 2.0 * sigma * s_dp - 2.0 * pi * s_ds + 2.0 * sp * ds + 2.0 * sigma * p_ds


@njit(cache=True, error_model="numpy", nogil=True)
def _switch_charts(x, W, xs, charts):
    """After a step: each ball joint (a row of ``charts``) whose |σ| passed 1 switches to the shadow, x in place, the
    tangent vectors W (2n, k) with it (k = 0: none), and the shadow trajectory xs (size 0: none) in the same chart."""
    for j in range(charts.shape[0]):
        a = charts[j]
        if x[a[0]] * x[a[0]] + x[a[1]] * x[a[1]] + x[a[2]] * x[a[2]] > 1.0:
            _shadow_tangents(x, W, a)
            _shadow_state(x, a)
            if xs.shape[0] > 0:
                _shadow_state(xs, a)

#: Each ball joint's three coordinates (rows; none: shape (0, 3)): its chart switches (module docstring).
CHARTS = types.int64[:, ::1]

_LYAPUNOV = types.int64(VELOCITIES, MOMENTUM_RATE, CANONICAL_PARTIALS, VECTOR, MATRIX, INDICES, VECTOR, VECTOR, FLOAT,
                        FLOAT, INT, INT, CHARTS)


@njit(_LYAPUNOV, cache=True, error_model="numpy", nogil=True)
def lyapunov_run(velocities, momentum_rate, canonical_partials, x, W, steps, sums, p, t0, dt, n_steps, renorm_every,
                 charts):
    """Advance x (2n,) and the tangent vectors W (2n, k) by ``n_steps`` RK4 steps (see the module docstring).

    ``steps[0]`` counts the steps since t0 (in/out); ``sums`` (k,) accumulates log R_jj at each
    orthonormalization, the last one at the end of the call; ``charts``: the ball joints' chart switches.
    """
    m, k = W.shape
    y, xt, v = np.empty(m), np.empty(m), np.empty(m // 2)
    k1, k2, k3, k4 = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    J = np.empty((m, m))
    Wt = np.empty((m, k))
    K1, K2, K3, K4 = np.empty((m, k)), np.empty((m, k)), np.empty((m, k)), np.empty((m, k))
    for step in range(n_steps):
        t = t0 + steps[0] * dt
        # stages of the variational equations, on the stages of the state
        if _stage(velocities, momentum_rate, canonical_partials, t, x, p, W, J, y, v,
                  k1, K1) != Status.DONE:
            return Status.RHS_FAILED
        for i in range(m):
            xt[i] = x[i] + _A[0] * dt * k1[i]
            for c in range(k):
                Wt[i, c] = W[i, c] + _A[0] * dt * K1[i, c]
        if _stage(velocities, momentum_rate, canonical_partials, t + _C[1] * dt, xt, p, Wt, J, y, v,
                  k2, K2) != Status.DONE:
            return Status.RHS_FAILED
        for i in range(m):
            xt[i] = x[i] + _A[1] * dt * k2[i]
            for c in range(k):
                Wt[i, c] = W[i, c] + _A[1] * dt * K2[i, c]
        if _stage(velocities, momentum_rate, canonical_partials, t + _C[2] * dt, xt, p, Wt, J, y, v,
                  k3, K3) != Status.DONE:
            return Status.RHS_FAILED
        for i in range(m):
            xt[i] = x[i] + _A[2] * dt * k3[i]
            for c in range(k):
                Wt[i, c] = W[i, c] + _A[2] * dt * K3[i, c]
        if _stage(velocities, momentum_rate, canonical_partials, t + _C[3] * dt, xt, p, Wt, J, y, v,
                  k4, K4) != Status.DONE:
            return Status.RHS_FAILED
        for i in range(m):
            x[i] += dt / _DENOMINATOR * (_WEIGHTS[0] * k1[i] + _WEIGHTS[1] * k2[i] + _WEIGHTS[2] * k3[i]
                                         + _WEIGHTS[3] * k4[i])
            if not math.isfinite(x[i]):
                return Status.NONFINITE
            for c in range(k):
                W[i, c] += dt / _DENOMINATOR * (_WEIGHTS[0] * K1[i, c] + _WEIGHTS[1] * K2[i, c]
                                                + _WEIGHTS[2] * K3[i, c] + _WEIGHTS[3] * K4[i, c])
        if charts.shape[0] > 0:
            _switch_charts(x, W, x[:0], charts)
        steps[0] += 1
        renormalize = (step + 1) % renorm_every == 0 or step == n_steps - 1
        if renormalize and _orthonormalize(W, sums) != Status.DONE:
            return Status.NONFINITE
    return Status.DONE


_DIVERGENCE = types.int64(VELOCITIES, MOMENTUM_RATE, VECTOR, VECTOR, INDICES, VECTOR, VECTOR, FLOAT, FLOAT, INT, INT,
                          FLOAT, VECTOR, CHARTS)


@njit(_DIVERGENCE, cache=True, error_model="numpy", nogil=True)
def divergence_run(velocities, momentum_rate, x, xs, steps, sums, p, t0, dt, n_steps, renorm_every, d0, scale,
                   charts):
    """Advance x and its shadow xs by ``n_steps`` RK4 steps, renormalizing their distance to d0 (module docstring).

    The distance is sqrt(Σ ((xs_i − x_i)/scale_i)²): each component in units of its own ``scale_i`` (ones: the plain
    Euclidean distance, to the bit), so that d0 means the same in any units when the scales follow them.  ``charts``:
    the ball joints' chart switches, xs switched with x."""
    m = x.shape[0]
    y, xt = np.empty(m), np.empty(m)
    no_tangents = np.empty((m, 0))
    k1, k2, k3, k4 = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    for step in range(n_steps):
        t = t0 + steps[0] * dt
        status = _rk4_state(velocities, momentum_rate, t, x, p, dt, y, k1, k2, k3, k4, xt)
        if status != Status.DONE:
            return status
        status = _rk4_state(velocities, momentum_rate, t, xs, p, dt, y, k1, k2, k3, k4, xt)
        if status != Status.DONE:
            return status
        if charts.shape[0] > 0:
            _switch_charts(x, no_tangents, xs, charts)
        steps[0] += 1
        if (step + 1) % renorm_every == 0 or step == n_steps - 1:
            d = 0.0
            for i in range(m):
                d += ((xs[i] - x[i]) / scale[i]) ** 2
            d = math.sqrt(d)
            if not (d > 0.0 and math.isfinite(d)):
                return Status.NONFINITE
            sums[0] += math.log(d / d0)
            for i in range(m):
                xs[i] = x[i] + (xs[i] - x[i]) * (d0 / d)
    return Status.DONE
