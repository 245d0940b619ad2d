"""Symplectic driver: a *template*, appended verbatim to every generated module after ``drivers.py``.

Like ``drivers.py`` (read its docstring first: the calling convention, the
status codes, the chunked and resumable state in ``y``, ``clock`` and
``counters``, and why each driver is one long function are shared), this
text is not imported as part of lagcomp; it uses the module's kernels and
the status constants of ``drivers.py`` as globals.

``composition_run``: symmetric compositions of Störmer-Verlet (explicit,
separable systems only); fixed-step: step k goes from ``t0 + k dt`` to
``t0 + (k+1) dt``, the last step landing exactly on ``t_end``, as in
``rk4_run``.  (The implicit Gauss-Legendre methods are library code:
`lagcomp.integrate.drivers.collocation`.)
"""

# ruff: noqa: F821  (rhs and _ODE_* are defined by the module this text is appended to)

import numpy as np
from numba import njit


# ---------------------------------------------------------------------------
# Explicit symplectic compositions for separable systems
# ---------------------------------------------------------------------------

@njit(cache=True, error_model="numpy")
def composition_run(y, clock, counters, p, projecting, residual_max, t0, dt,
                    n_steps, pause_at, t_end, save_every, ts, ys, weights):
    """Symmetric composition of Störmer-Verlet substeps; fixed step ``dt``; resumable.

    For separable systems only (constant mass matrix M, accelerations
    independent of the velocities; the caller checks): then p = M q̇ is a
    constant linear change of variables, and kick-drift-kick on (q, q̇),

        q̇ ← q̇ + ½ w h q̈(q, t),   q ← q + w h q̇,   q̇ ← q̇ + ½ w h q̈(q, t + w h),

    is the Störmer-Verlet step of H = ½ pᵀ M⁻¹ p + V(q) (HLW, *Geometric
    Numerical Integration*, sec. I.3).  A step of size h runs one substep per
    weight w (``lagcomp.integrate.compositions``).  The acceleration at the
    end of a substep is the start of the next one, so a substep costs one
    ``rhs`` call.  Step times, saving, chunking and failure statuses follow
    ``rk4_run``.  Projection is not offered: constrained systems are not
    separable in this sense.
    """
    n2 = y.shape[0]
    n = n2 // 2
    cap = ts.shape[0]
    acc = np.empty(n2)
    acc_new = np.empty(n2)
    y_new = np.empty(n2)
    n_saved = 0
    if counters[1] < n_steps:
        status = rhs(clock[0], y, p, acc)
        counters[0] += 1
        if status != 0:
            return _ODE_RHS_FAILED, n_saved
    while True:
        k = counters[1]
        if k >= n_steps:
            return _ODE_DONE, n_saved
        if k >= pause_at:
            return _ODE_PAUSED, n_saved
        last = k == n_steps - 1
        if last or counters[4] + 1 >= save_every:
            if n_saved >= cap:
                return _ODE_BUFFER_FULL, n_saved
        t_a = min(t0 + k * dt, t_end)
        if last:
            t_b = t_end
        else:
            t_b = min(t0 + (k + 1) * dt, t_end)
        h = t_b - t_a

        for i in range(n2):
            y_new[i] = y[i]
            acc_new[i] = acc[i]
        elapsed = 0.0
        status = 0
        for j in range(weights.shape[0]):
            hw = weights[j] * h
            for i in range(n):
                y_new[n + i] += 0.5 * hw * acc_new[n + i]
                y_new[i] += hw * y_new[n + i]
            elapsed += weights[j]
            t_sub = t_b if j == weights.shape[0] - 1 else t_a + elapsed * h
            status = rhs(t_sub, y_new, p, acc_new)
            counters[0] += 1
            if status != 0:
                break
            for i in range(n):
                y_new[n + i] += 0.5 * hw * acc_new[n + i]
        if status != 0:
            return _ODE_RHS_FAILED, n_saved
        for i in range(n2):
            if not np.isfinite(y_new[i]):
                status = -1
        if status != 0:
            return _ODE_NONFINITE, n_saved

        for i in range(n2):
            y[i] = y_new[i]
            acc[i] = acc_new[i]
        clock[0] = t_b
        counters[1] = k + 1
        counters[4] += 1
        if last or counters[4] >= save_every:
            ts[n_saved] = t_b
            for i in range(n2):
                ys[n_saved, i] = y[i]
            n_saved += 1
            counters[4] = 0
