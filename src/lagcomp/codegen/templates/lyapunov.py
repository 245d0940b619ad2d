"""Lyapunov exponents: a *template*, appended to unconstrained modules after ``hamiltonian.py``.

Like the other templates this text is not imported as part of lagcomp; it
uses the module's kernels ``velocities``, ``momentum_rate`` and
``canonical_jacobian`` as globals, so numba caches it with the module.

Both loops integrate the canonical equations ẋ = f(t, x), x = (q, p), by
RK4 with the fixed step ``dt`` (step j ends at t0 + (j + 1) dt, computed from
the step count, so long runs do not accumulate rounding in t).  Lyapunov
exponents do not depend on the coordinates, and (q, p) is where the compiled
Jacobian lives.

* ``lyapunov_run``: the variational equations Ẇ = J(t, x) W for k tangent
  vectors (the columns of W), integrated with x by the same RK4 stages.  Every
  ``renorm_every`` steps, and at the end of each call, W is replaced by the
  Q of its QR factorization (Gram-Schmidt, applied twice for orthogonality)
  and log R_jj is added to ``sums[j]``: sums / (elapsed time) are the
  estimates of the k largest exponents (Benettin, Galgani, Giorgilli and
  Strelcyn 1980; Shimada and Nagashima 1979).
* ``divergence_run``: the two-trajectory estimate.  A shadow state xs starts
  at distance d0 from x; both are advanced, and every ``renorm_every`` steps
  (and at the end of each call) log(d/d0) is added to ``sums[0]`` and xs is
  pulled back to distance d0 along xs − x.

Both are resumable: the state lives in the in/out arrays ``x``, ``W`` (or
``xs``), ``steps`` (int64[1], steps taken since t0) and ``sums``, so the
caller runs them in chunks (progress, Ctrl-C) with the same result as one
call.  They return 0, −1 when the state became non-finite, or −2 when M was
singular (the statuses of ``lagcomp.integrate.solution.MESSAGES``).
"""

# ruff: noqa: F821  (velocities, momentum_rate, canonical_jacobian: module globals)

import math

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def _canonical_field(t, x, p, y, out):
    """f(t, x) = (q̇, ṗ) into ``out`` (2n,); ``y`` (2n,) is work space for (q, q̇). Returns 0 or −2."""
    n = x.shape[0] // 2
    v = np.empty(n)
    if velocities(t, x, p, v):
        return -2
    r = np.empty(n)
    for i in range(n):
        y[i] = x[i]
        y[n + i] = v[i]
    momentum_rate(t, y, p, r)
    for i in range(n):
        out[i] = v[i]
        out[n + i] = r[i]
    return 0


@njit(cache=True, error_model="numpy")
def _rk4_state(t, x, p, dt, y, k1, k2, k3, k4, xt):
    """One RK4 step of the canonical equations, x updated in place. Returns 0, −1 or −2."""
    m = x.shape[0]
    if _canonical_field(t, x, p, y, k1):
        return -2
    for i in range(m):
        xt[i] = x[i] + 0.5 * dt * k1[i]
    if _canonical_field(t + 0.5 * dt, xt, p, y, k2):
        return -2
    for i in range(m):
        xt[i] = x[i] + 0.5 * dt * k2[i]
    if _canonical_field(t + 0.5 * dt, xt, p, y, k3):
        return -2
    for i in range(m):
        xt[i] = x[i] + dt * k3[i]
    if _canonical_field(t + dt, xt, p, y, k4):
        return -2
    for i in range(m):
        x[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        if not math.isfinite(x[i]):
            return -1
    return 0


@njit(cache=True, error_model="numpy")
def _tangent(t, x, p, W, J, out):
    """out = J(t, x) W, shape (2n, k); J (2n, 2n) work space. Returns 0 or −2."""
    if canonical_jacobian(t, x, p, J):
        return -2
    m, k = W.shape
    for i in range(m):
        for c in range(k):
            s = 0.0
            for j in range(m):
                s += J[i, j] * W[j, c]
            out[i, c] = s
    return 0


@njit(cache=True, error_model="numpy")
def _orthonormalize(W, sums):
    """W ← Q of W = QR (Gram-Schmidt twice), sums[j] += log R_jj. Returns 0, or −1 if a column vanished."""
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
            return -1
        sums[c] += math.log(norm)
        for i in range(m):
            W[i, c] /= norm
    return 0


@njit(cache=True, error_model="numpy")
def lyapunov_run(x, W, steps, sums, p, t0, dt, n_steps, renorm_every):
    """Advance x (2n,) and the tangent vectors W (2n, k) by ``n_steps`` RK4 steps (see the module docstring).

    ``steps[0]`` counts the steps since t0 (in/out); ``sums`` (k,) accumulates
    log R_jj at each orthonormalization, the last one at the end of the call.
    """
    m, k = W.shape
    y, xt = np.empty(m), np.empty(m)
    k1, k2, k3, k4 = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    J = np.empty((m, m))
    Wt = np.empty((m, k))
    K1, K2, K3, K4 = np.empty((m, k)), np.empty((m, k)), np.empty((m, k)), np.empty((m, k))
    for step in range(n_steps):
        t = t0 + steps[0] * dt
        # stages of the variational equations, on the stages of the state
        if _tangent(t, x, p, W, J, K1):
            return -2
        if _canonical_field(t, x, p, y, k1):
            return -2
        for i in range(m):
            xt[i] = x[i] + 0.5 * dt * k1[i]
            for c in range(k):
                Wt[i, c] = W[i, c] + 0.5 * dt * K1[i, c]
        if _tangent(t + 0.5 * dt, xt, p, Wt, J, K2):
            return -2
        if _canonical_field(t + 0.5 * dt, xt, p, y, k2):
            return -2
        for i in range(m):
            xt[i] = x[i] + 0.5 * dt * k2[i]
            for c in range(k):
                Wt[i, c] = W[i, c] + 0.5 * dt * K2[i, c]
        if _tangent(t + 0.5 * dt, xt, p, Wt, J, K3):
            return -2
        if _canonical_field(t + 0.5 * dt, xt, p, y, k3):
            return -2
        for i in range(m):
            xt[i] = x[i] + dt * k3[i]
            for c in range(k):
                Wt[i, c] = W[i, c] + dt * K3[i, c]
        if _tangent(t + dt, xt, p, Wt, J, K4):
            return -2
        if _canonical_field(t + dt, xt, p, y, k4):
            return -2
        for i in range(m):
            x[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            if not math.isfinite(x[i]):
                return -1
            for c in range(k):
                W[i, c] += dt / 6.0 * (K1[i, c] + 2.0 * K2[i, c] + 2.0 * K3[i, c] + K4[i, c])
        steps[0] += 1
        if (step + 1) % renorm_every == 0 or step == n_steps - 1:
            if _orthonormalize(W, sums):
                return -1
    return 0


@njit(cache=True, error_model="numpy")
def divergence_run(x, xs, steps, sums, p, t0, dt, n_steps, renorm_every, d0):
    """Advance x and its shadow xs by ``n_steps`` RK4 steps, renormalizing their distance to d0 (module docstring)."""
    m = x.shape[0]
    y, xt = np.empty(m), np.empty(m)
    k1, k2, k3, k4 = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    for step in range(n_steps):
        t = t0 + steps[0] * dt
        status = _rk4_state(t, x, p, dt, y, k1, k2, k3, k4, xt)
        if status:
            return status
        status = _rk4_state(t, xs, p, dt, y, k1, k2, k3, k4, xt)
        if status:
            return status
        steps[0] += 1
        if (step + 1) % renorm_every == 0 or step == n_steps - 1:
            d = 0.0
            for i in range(m):
                d += (xs[i] - x[i]) ** 2
            d = math.sqrt(d)
            if not (d > 0.0 and math.isfinite(d)):
                return -1
            sums[0] += math.log(d / d0)
            for i in range(m):
                xs[i] = x[i] + (xs[i] - x[i]) * (d0 / d)
    return 0
