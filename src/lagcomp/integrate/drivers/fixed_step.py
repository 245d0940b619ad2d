"""The explicit fixed-step drivers: Runge-Kutta from its tableau (RK4), and compositions of Störmer-Verlet.

Both follow the driver protocol of `lagcomp.integrate.drivers` and share its fixed-step part:

* step k (0-based, ``k = counters[1]``) goes from ``t0 + k dt`` to ``min(t0 + (k+1) dt, t_end)``,
  the last one (``k = n_steps - 1``) ending exactly at ``t_end``.  Times are computed from k, not
  accumulated, so there is no drift;
* a row is saved after a step when ``counters[4]`` (steps since the last save) reaches
  ``save_every``, and after the last step; the driver returns ``BUFFER_FULL`` *before* a step
  whose row would not fit into ``ts``/``ys``, and ``PAUSED`` before step number ``pause_at``.
  Either way ``y``, ``clock`` and ``counters`` hold the run's state and the next call continues
  it exactly as one uninterrupted call would have (no stage is carried over between steps except
  the compositions' acceleration, which a call recomputes at its start: one extra evaluation per
  call);
* a non-finite new state stops the run with ``NONFINITE`` and a non-zero ``rhs`` status with
  ``RHS_FAILED``, ``y`` and ``clock[0]`` keeping the last good state and its time.

``counters`` = [nfev, nsteps, nrejected (always 0 here), _, since_save, _]; ``clock`` = [t, _].
The work arrays are allocated once per call; the step loops do not allocate.  Each driver is one
function whose only callees are the kernels (see "Why one long function" in
`lagcomp.integrate.drivers.embedded`: a chain of small helpers costs compile time and, in the
hot loop, speed).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from lagcomp.integrate.drivers.kernel_types import (
    FLOAT,
    INDICES,
    INT,
    MATRIX,
    OUTCOME,
    PROJECT,
    RESIDUAL,
    RHS,
    VECTOR,
)
from lagcomp.integrate.drivers.run_state import NFEV, NSTEPS, SINCE_SAVE, TIME
from lagcomp.integrate.status import Status

#: The arguments every fixed-step driver takes after its kernels and before its coefficients.
FIXED_STEP_RUN = (VECTOR, VECTOR, INDICES, VECTOR, INT, VECTOR,   # y, clock, counters, p, projecting, residual_max
                  FLOAT, FLOAT, INT, INT, FLOAT, INT,             # t0, dt, n_steps, pause_at, t_end, save_every
                  VECTOR, MATRIX)                                 # ts, ys
#: ``runge_kutta_run(rhs, project, constraint_residual, <FIXED_STEP_RUN>, A, C, weights, denominator)``.
RUNGE_KUTTA_RUN = OUTCOME(RHS, PROJECT, RESIDUAL, *FIXED_STEP_RUN, MATRIX, VECTOR, VECTOR, FLOAT)
#: ``composition_run(rhs, <FIXED_STEP_RUN>, weights)``.
COMPOSITION_RUN = OUTCOME(RHS, *FIXED_STEP_RUN, VECTOR)


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def fixed_step_window(step, n_steps, pause_at, since_save, save_every, n_saved, cap, t0, dt, t_end):
    """Whether a fixed-step driver stops before step number `step`, and with which status, else the step's interval.

    Returns (stop, status, t_a, t_b): stop with DONE after the last step, PAUSED at the step budget `pause_at`, or
    BUFFER_FULL when the step would save a row (every `save_every`-th, and the last) into a full buffer of `cap`
    rows; otherwise the step runs over [t_a, t_b] = [t0 + step dt, t0 + (step + 1) dt], clipped to t_end, the
    last one ending at t_end exactly.  Inlined (numba's ``inline="always"``) into each fixed-step driver.
    """
    if step >= n_steps:
        return True, Status.DONE, 0.0, 0.0
    if step >= pause_at:
        return True, Status.PAUSED, 0.0, 0.0
    last = step == n_steps - 1
    if (last or since_save + 1 >= save_every) and n_saved >= cap:
        return True, Status.BUFFER_FULL, 0.0, 0.0
    t_a = min(t0 + step * dt, t_end)
    if last:
        t_b = t_end
    else:
        t_b = min(t0 + (step + 1) * dt, t_end)
    return False, Status.DONE, t_a, t_b


@njit(RUNGE_KUTTA_RUN, cache=True, error_model="numpy", nogil=True)
def runge_kutta_run(rhs, project, constraint_residual, y, clock, counters, p, projecting, residual_max, t0, dt,
                    n_steps, pause_at, t_end, save_every, ts, ys, A, C, weights, denominator):
    """Integrate with the explicit Runge-Kutta method (A, C, weights / denominator) and a fixed step; resumable.

    The method is its Butcher tableau (`lagcomp.integrate.tableaux.driver_arguments`; RK4: HNW I,
    table II.1.2): with s stages, a step of size h from (t, y) computes

        K[m] = f(t + C[m] h, y + sum_{j<m} (A[m, j] h) K[j]),   m = 0 .. s-1,
        y_new = y + (h / denominator) sum_j weights[j] K[j],

    each sum accumulated from j = 0 up, the stage sums over the non-zero A[m, j] only (RK4's
    stages use one earlier stage each).  The weights B of the tableau come as integers over
    their least common denominator when they are simple fractions
    (`tableaux.over_common_denominator`: RK4's are 1, 2, 2, 1 over 6): integer weights multiply
    exactly, so the new state rounds as the textbook ``y + h/6 (K1 + 2 K2 + 2 K3 + K4)`` does.
    A stage costs one ``rhs`` call, from one call site, with the stage state in a work array,
    writing its derivative into its row of K; the weighted sum is formed after the last stage,
    from j = 0 up.  Written so, the loop runs 4% faster on the double pendulum than with the
    derivative written into a work vector and copied into K and the sum as the stages came (the
    same operations in the same order: the same bits; `bench/bench_tiers.py`); a sum over all
    j < m, zeros included, cost 5% of the steps/s.

    ``projecting`` 1 moves every new state onto the constraints (``project``) before it is saved;
    ``residual_max[0]`` keeps the largest ``constraint_residual`` of the accepted states and, when
    ``residual_max`` has a second entry, a step whose residual exceeds it is committed (and saved
    if due) and the run stops with ``RESIDUAL_EXCEEDED``.  Returns ``(status, n_saved)``.
    """
    n = y.shape[0]
    cap = ts.shape[0]
    stages = C.shape[0]
    K = np.empty((stages, n))
    ytmp = np.empty(n)
    y_new = np.empty(n)
    total = np.empty(n)
    n_saved = 0
    residual_bound = residual_max[1] if residual_max.shape[0] > 1 else np.inf
    while True:
        k = counters[NSTEPS]
        stop, why, t_a, t_b = fixed_step_window(k, n_steps, pause_at, counters[SINCE_SAVE], save_every,
                                                n_saved, cap, t0, dt, t_end)
        if stop:
            return why, n_saved
        last = k == n_steps - 1

        h = t_b - t_a
        for s in range(stages):
            for i in range(n):
                ytmp[i] = y[i]
            for j in range(s):
                if A[s, j] != 0.0:
                    a = A[s, j] * h
                    for i in range(n):
                        ytmp[i] += a * K[j, i]
            status = rhs(t_a + C[s] * h, ytmp, p, K[s])
            counters[NFEV] += 1
            if status != 0:
                return Status.RHS_FAILED, n_saved
        for i in range(n):
            total[i] = weights[0] * K[0, i]
        for s in range(1, stages):
            w = weights[s]
            for i in range(n):
                total[i] += w * K[s, i]
        step = h / denominator
        status = 0
        for i in range(n):
            y_new[i] = y[i] + step * total[i]
            if not np.isfinite(y_new[i]):
                status = -1
        if status != 0:
            return Status.NONFINITE, n_saved
        if projecting and project(t_b, y_new, p) != 0:
            return Status.RHS_FAILED, n_saved
        residual = constraint_residual(t_b, y_new, p)
        if residual > residual_max[0]:
            residual_max[0] = residual

        for i in range(n):
            y[i] = y_new[i]
        clock[TIME] = t_b
        counters[NSTEPS] = k + 1
        counters[SINCE_SAVE] += 1
        if last or counters[SINCE_SAVE] >= save_every:
            ts[n_saved] = t_b
            for i in range(n):
                ys[n_saved, i] = y[i]
            n_saved += 1
            counters[SINCE_SAVE] = 0
        if residual > residual_bound:
            return Status.RESIDUAL_EXCEEDED, n_saved


@njit(COMPOSITION_RUN, cache=True, error_model="numpy", nogil=True)
def composition_run(rhs, y, clock, counters, p, projecting, residual_max, t0, dt, n_steps, pause_at, t_end,
                    save_every, ts, ys, weights):
    """Symmetric composition of Störmer-Verlet substeps (`lagcomp.integrate.compositions`); fixed step; resumable.

    For separable systems only (constant mass matrix M, accelerations independent of the
    velocities; `lagcomp.integrate.options.check_method` checks): then p = M q̇ is a constant
    linear change of variables, and kick-drift-kick on y = (q, q̇),

        q̇ ← q̇ + ½ w h q̈(q, t),   q ← q + w h q̇,   q̇ ← q̇ + ½ w h q̈(q, t + w h),

    is the Störmer-Verlet step of H = ½ pᵀ M⁻¹ p + V(q) (HLW, *Geometric Numerical Integration*,
    sec. I.3).  A step of size h runs one substep per weight w; substep j ends at the time
    ``t + (w_0 + ... + w_j) h``, the last one exactly at the step's end.  The acceleration q̈ is
    the second half of ``rhs``'s output, and the one at the end of a substep starts the next, so a
    substep costs one ``rhs`` call (plus one per driver call, at its start).

    Projection is not offered: a constrained system is not separable in this sense, so
    ``projecting`` and ``residual_max`` are accepted for the common calling convention and
    ignored.  Returns ``(status, n_saved)``.
    """
    n2 = y.shape[0]
    n = n2 // 2
    cap = ts.shape[0]
    acc = np.empty(n2)
    acc_new = np.empty(n2)
    y_new = np.empty(n2)
    n_saved = 0
    if counters[NSTEPS] < n_steps:
        status = rhs(clock[TIME], y, p, acc)
        counters[NFEV] += 1
        if status != 0:
            return Status.RHS_FAILED, n_saved
    while True:
        k = counters[NSTEPS]
        stop, why, t_a, t_b = fixed_step_window(k, n_steps, pause_at, counters[SINCE_SAVE], save_every,
                                                n_saved, cap, t0, dt, t_end)
        if stop:
            return why, n_saved
        last = k == n_steps - 1
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
            counters[NFEV] += 1
            if status != 0:
                break
            for i in range(n):
                y_new[n + i] += 0.5 * hw * acc_new[n + i]
        if status != 0:
            return Status.RHS_FAILED, n_saved
        for i in range(n2):
            if not np.isfinite(y_new[i]):
                status = -1
        if status != 0:
            return Status.NONFINITE, n_saved

        for i in range(n2):
            y[i] = y_new[i]
            acc[i] = acc_new[i]
        clock[TIME] = t_b
        counters[NSTEPS] = k + 1
        counters[SINCE_SAVE] += 1
        if last or counters[SINCE_SAVE] >= save_every:
            ts[n_saved] = t_b
            for i in range(n2):
                ys[n_saved, i] = y[i]
            n_saved += 1
            counters[SINCE_SAVE] = 0
