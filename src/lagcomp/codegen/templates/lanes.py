"""Batched (SIMD) sweeps: a *template*, appended to modules that have the ``rhs_lanes`` kernel.

``rhs_lanes`` evaluates the right-hand side of B trajectories at once, laid
out as structure of arrays (``Y[i, l]``: component i of lane l), in a loop
over lanes that LLVM vectorizes: 4 lanes per AVX2 instruction.  Two things
would keep that loop scalar, and are avoided: an early return (a singular
mass matrix sets ``bad[l]`` instead) and calls into libm, whose ``sin`` and
``cos`` LLVM cannot vectorize.  Those two come from ``_vsin`` and ``_vcos``
(``trig.py``): the polynomials the scalar kernels use too, without their
branch to libm for huge arguments.  On the
double pendulum the kernel costs 18 ns per trajectory against 50 ns for the
scalar ``rhs`` (measured in a compiled loop, AVX2).

``sweep_dop853_lanes`` (at the end) does the same for DOP853, every lane
with its own step-size control.  ``sweep_rk4_lanes`` is the batched
counterpart of ``sweep_rk4_run``
(``sweeps.py``): classic RK4 with the same arithmetic in the same order,
lanes in lock-step (a fixed step makes every lane take the same steps), in
blocks of ``_LANES`` trajectories whose work arrays stay in the L1 cache.
A lane whose mass matrix turns singular (status -2) or whose state turns
non-finite (-1) keeps its last good state and time, like ``rk4_run``.
"""

# ruff: noqa: F821  (rhs_lanes, energy, _ODE_* are defined by the module this text is appended to)

import numpy as np
from numba import njit

_LANES = 32


@njit(cache=True, error_model="numpy", nogil=True)
def sweep_rk4_lanes(Y0, P, t0, dt, n_steps, t_end, save_every, final, t_final, status, counts, dense,
                    energy_stats):
    """RK4 over the trajectories (Y0[k], P[k]) in batches of ``_LANES``; outputs as ``sweep_rk4_run``."""
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    n_p = P.shape[1]
    for a in range(0, n_traj, _LANES):
        lanes = min(_LANES, n_traj - a)
        Y = np.empty((n2, lanes))
        Pl = np.empty((n_p, lanes))
        for l in range(lanes):
            for c in range(n2):
                Y[c, l] = Y0[a + l, c]
            for c in range(n_p):
                Pl[c, l] = P[a + l, c]
        K = np.empty((4, n2, lanes))
        Yt = np.empty((n2, lanes))
        Yn = np.empty((n2, lanes))
        bad = np.zeros(lanes, dtype=np.bool_)
        code = np.zeros(lanes, dtype=np.int64)
        steps = np.zeros(lanes, dtype=np.int64)
        t_last = np.full(lanes, t0)
        T = np.empty(lanes)
        e0 = np.empty(lanes)
        deviation = np.zeros(lanes)
        for l in range(lanes):
            e0[l] = energy(t0, Y0[a + l], P[a + l])
        row = 0
        if dense.shape[1] > 0:
            for l in range(lanes):
                for c in range(n2):
                    dense[a + l, 0, c] = Y[c, l]
            row = 1
        since_save = 0
        y_row = np.empty(n2)
        for k in range(n_steps):
            t_a = min(t0 + k * dt, t_end)
            t_b = t_end if k == n_steps - 1 else min(t0 + (k + 1) * dt, t_end)
            h = t_b - t_a
            for s in range(4):
                if s == 0:
                    cs = 0.0
                elif s == 3:
                    cs = 1.0
                else:
                    cs = 0.5
                if s > 0:
                    for i in range(n2):
                        for l in range(lanes):
                            Yt[i, l] = Y[i, l] + cs * h * K[s - 1, i, l]
                for l in range(lanes):
                    T[l] = t_a + cs * h
                rhs_lanes(T, Y if s == 0 else Yt, Pl, K[s], bad)
                for l in range(lanes):
                    if bad[l] and code[l] == 0:
                        code[l] = _ODE_RHS_FAILED
            sixth = h / 6.0
            for i in range(n2):
                for l in range(lanes):
                    Yn[i, l] = Y[i, l] + sixth * (K[0, i, l] + 2.0 * K[1, i, l] + 2.0 * K[2, i, l] + K[3, i, l])
            running = 0
            for l in range(lanes):
                if code[l] == 0:
                    for i in range(n2):
                        if not np.isfinite(Yn[i, l]):
                            code[l] = _ODE_NONFINITE
                if code[l] == 0:
                    for i in range(n2):
                        Y[i, l] = Yn[i, l]
                    t_last[l] = t_b
                    steps[l] += 1
                    running += 1
            since_save += 1
            if since_save >= save_every or k == n_steps - 1:
                since_save = 0
                for l in range(lanes):
                    if code[l] == 0:
                        for c in range(n2):
                            y_row[c] = Y[c, l]
                        deviation[l] = max(deviation[l], abs(energy(t_b, y_row, P[a + l]) - e0[l]))
                        if row < dense.shape[1]:
                            for c in range(n2):
                                dense[a + l, row, c] = y_row[c]
                row += 1
            if running == 0:
                break
        for l in range(lanes):
            for c in range(n2):
                final[a + l, c] = Y[c, l]
            t_final[a + l] = t_last[l]
            status[a + l] = code[l]
            counts[a + l, 0] = 4 * steps[l]
            counts[a + l, 1] = steps[l]
            counts[a + l, 2] = 0
            energy_stats[a + l, 0] = e0[l]
            energy_stats[a + l, 1] = deviation[l]


@njit(cache=True, error_model="numpy", nogil=True)
def sweep_dop853_lanes(Y0, P, t0, t_end, rtol, atol, max_step, max_steps, save_every, final, t_final, status,
                       counts, dense, energy_stats, A, B, C, E3, E5):
    """DOP853 over the trajectories (Y0[k], P[k]) in batches of ``_LANES``, each lane with its own steps.

    The lanes advance in lock-step *trials*: every iteration, each running
    lane tries one step of its own size h from its own t (the stages of all
    lanes in one ``rhs_lanes`` call per stage), then accepts or rejects it
    by its own error norm.  The per-lane arithmetic, step-size control and
    initial step are those of ``dop853_run``, in the same order, so a lane
    takes the steps the scalar driver takes.  Outputs as ``sweep_dop853_run``
    without dense rows and events; lanes that finish early idle.
    """
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    n_p = P.shape[1]
    n_stages = B.shape[0]
    n_k = E5.shape[0]
    exponent = -1.0 / 8.0
    for a in range(0, n_traj, _LANES):
        lanes = min(_LANES, n_traj - a)
        Y = np.empty((n2, lanes))
        Pl = np.empty((n_p, lanes))
        for l in range(lanes):
            for c in range(n2):
                Y[c, l] = Y0[a + l, c]
            for c in range(n_p):
                Pl[c, l] = P[a + l, c]
        K = np.empty((n_k, n2, lanes))
        Yt = np.empty((n2, lanes))
        Yn = np.empty((n2, lanes))
        T = np.empty(lanes)
        t = np.full(lanes, t0)
        t_next = np.full(lanes, t0)
        h = np.zeros(lanes)
        h_abs = np.zeros(lanes)
        min_step = np.zeros(lanes)
        bad = np.zeros(lanes, dtype=np.bool_)
        code = np.zeros(lanes, dtype=np.int64)
        running = np.ones(lanes, dtype=np.bool_)
        starting = np.ones(lanes, dtype=np.bool_)      # the next trial begins a new step
        rejected = np.zeros(lanes, dtype=np.bool_)
        nonfinite = np.zeros(lanes, dtype=np.bool_)
        nfev = np.zeros(lanes, dtype=np.int64)
        steps = np.zeros(lanes, dtype=np.int64)
        n_rejected = np.zeros(lanes, dtype=np.int64)
        since_save = np.zeros(lanes, dtype=np.int64)
        e0 = np.empty(lanes)
        deviation = np.zeros(lanes)
        y_row = np.empty(n2)
        for l in range(lanes):
            e0[l] = energy(t0, Y0[a + l], P[a + l])
            T[l] = t0
            if t0 >= t_end:
                running[l] = False

        # First stage and initial step (dop853_run, step 1), per lane.
        rhs_lanes(T, Y, Pl, K[0], bad)
        h0 = np.zeros(lanes)
        d1s = np.zeros(lanes)
        for l in range(lanes):
            nfev[l] += 1
            finite = not bad[l]
            for i in range(n2):
                if not (np.isfinite(Y[i, l]) and np.isfinite(K[0, i, l])):
                    finite = False
            if bad[l]:
                code[l] = _ODE_RHS_FAILED
                running[l] = False
            elif not finite:
                code[l] = _ODE_NONFINITE
                running[l] = False
            d0 = 0.0
            d1 = 0.0
            for i in range(n2):
                sc = atol + abs(Y[i, l]) * rtol
                r = Y[i, l] / sc
                d0 += r * r
                r = K[0, i, l] / sc
                d1 += r * r
            d0 = np.sqrt(d0 / n2)
            d1 = np.sqrt(d1 / n2)
            d1s[l] = d1
            if d0 >= 1e-5 and d1 >= 1e-5:
                h0[l] = 0.01 * d0 / d1
            else:
                h0[l] = 1e-6
            h0[l] = min(h0[l], t_end - t0)
            for i in range(n2):
                Yt[i, l] = Y[i, l] + h0[l] * K[0, i, l]
            T[l] = t0 + h0[l]
        rhs_lanes(T, Yt, Pl, Yn, bad)
        for l in range(lanes):
            nfev[l] += 1
            if not running[l]:
                continue
            finite = True
            d2 = 0.0
            for i in range(n2):
                finite = finite and np.isfinite(Yn[i, l])
                sc = atol + abs(Y[i, l]) * rtol
                r = (Yn[i, l] - K[0, i, l]) / sc
                d2 += r * r
            if bad[l]:
                code[l] = _ODE_RHS_FAILED
                running[l] = False
            elif not finite:
                h_abs[l] = min(h0[l], max_step)
            else:
                d2 = np.sqrt(d2 / n2) / h0[l]
                if d1s[l] <= 1e-15 and d2 <= 1e-15:
                    h1 = max(1e-6, h0[l] * 1e-3)
                else:
                    h1 = (0.01 / max(d1s[l], d2)) ** (-exponent)
                h_abs[l] = min(100.0 * h0[l], h1, t_end - t0, max_step)

        while True:
            # Start of a step, then the trial's size, per lane.
            active = 0
            for l in range(lanes):
                if running[l] and starting[l]:
                    if t[l] >= t_end:
                        running[l] = False
                    elif steps[l] >= max_steps:
                        code[l] = _ODE_MAX_STEPS
                        running[l] = False
                    else:
                        min_step[l] = 10.0 * abs(np.nextafter(t[l], np.inf) - t[l])
                        if h_abs[l] > max_step:
                            h_abs[l] = max_step
                        elif h_abs[l] < min_step[l]:
                            h_abs[l] = min_step[l]
                        rejected[l] = False
                        nonfinite[l] = False
                        starting[l] = False
                if running[l]:
                    t_new = t[l] + h_abs[l]
                    if t_new > t_end:
                        t_new = t_end
                    if not (h_abs[l] >= min_step[l] and t_new < np.inf):
                        code[l] = _ODE_STEP_TOO_SMALL if h_abs[l] < min_step[l] and not nonfinite[l] \
                            else _ODE_NONFINITE
                        running[l] = False
                    else:
                        t_next[l] = t_new
                        h[l] = t_new - t[l]
                        h_abs[l] = abs(h[l])
                        active += 1
                if not running[l]:
                    h[l] = 0.0      # an idle lane re-evaluates its own state: harmless
            if active == 0:
                break

            # Stages K[1 .. s] of all lanes (dop853_run's sums, in its order).
            for s in range(1, n_stages + 1):
                if s < n_stages:
                    w = A[s]
                    cs = C[s]
                    arg = Yt
                else:
                    w = B
                    cs = 1.0
                    arg = Yn
                for i in range(n2):
                    for l in range(lanes):
                        arg[i, l] = 0.0
                for j in range(s):
                    aj = w[j]
                    if aj != 0.0:
                        for i in range(n2):
                            for l in range(lanes):
                                arg[i, l] += aj * K[j, i, l]
                for i in range(n2):
                    for l in range(lanes):
                        arg[i, l] = Y[i, l] + h[l] * arg[i, l]
                for l in range(lanes):
                    T[l] = t[l] + cs * h[l]
                rhs_lanes(T, arg, Pl, K[s], bad)
                for l in range(lanes):
                    if running[l] and bad[l]:
                        code[l] = _ODE_RHS_FAILED
                        running[l] = False

            # Error norm, step control, commit: per lane.
            for l in range(lanes):
                if not running[l]:
                    continue
                nfev[l] += n_stages
                finite = True
                for s in range(1, n_stages + 1):
                    for i in range(n2):
                        if not np.isfinite(K[s, i, l]):
                            finite = False
                for i in range(n2):
                    if not np.isfinite(Yn[i, l]):
                        finite = False
                err = np.inf
                if finite:
                    sum5 = 0.0
                    sum3 = 0.0
                    for i in range(n2):
                        sc = atol + max(abs(Y[i, l]), abs(Yn[i, l])) * rtol
                        e5 = 0.0
                        e3 = 0.0
                        for j in range(n_k):
                            e5 += E5[j] * K[j, i, l]
                            e3 += E3[j] * K[j, i, l]
                        e5 /= sc
                        e3 /= sc
                        sum5 += e5 * e5
                        sum3 += e3 * e3
                    if sum5 == 0.0 and sum3 == 0.0:
                        err = 0.0
                    else:
                        err = abs(h[l]) * sum5 / np.sqrt((sum5 + 0.01 * sum3) * n2)
                if err < 1.0:
                    if err == 0.0:
                        factor = _ODE_MAX_FACTOR
                    else:
                        factor = min(_ODE_MAX_FACTOR, _ODE_SAFETY * err ** exponent)
                    if rejected[l]:
                        factor = min(1.0, factor)
                    h_abs[l] *= factor
                    t[l] = t_next[l]
                    for i in range(n2):
                        Y[i, l] = Yn[i, l]
                        K[0, i, l] = K[n_stages, i, l]
                    steps[l] += 1
                    starting[l] = True
                    since_save[l] += 1
                    if since_save[l] >= save_every or t[l] >= t_end:
                        since_save[l] = 0
                        for i in range(n2):
                            y_row[i] = Y[i, l]
                        deviation[l] = max(deviation[l], abs(energy(t[l], y_row, P[a + l]) - e0[l]))
                elif np.isfinite(err):
                    h_abs[l] *= max(_ODE_MIN_FACTOR, _ODE_SAFETY * err ** exponent)
                    nonfinite[l] = False
                    rejected[l] = True
                    n_rejected[l] += 1
                else:
                    h_abs[l] *= _ODE_MIN_FACTOR
                    nonfinite[l] = True
                    rejected[l] = True
                    n_rejected[l] += 1
        for l in range(lanes):
            for c in range(n2):
                final[a + l, c] = Y[c, l]
            t_final[a + l] = t[l]
            status[a + l] = code[l]
            counts[a + l, 0] = nfev[l]
            counts[a + l, 1] = steps[l]
            counts[a + l, 2] = n_rejected[l]
            energy_stats[a + l, 0] = e0[l]
            energy_stats[a + l, 1] = deviation[l]
