"""Batched (SIMD) sweeps: RK4 and DOP853 over blocks of trajectories, one lane kernel call per stage.

The model's lane kernel ``rhs_lanes`` (emitted per model, `lagcomp.codegen.lower`) evaluates the
right-hand side of B trajectories at once, laid out as structure of arrays (``Y[i, l]``: component
i of lane l), in a loop over lanes that LLVM vectorizes: 4 lanes per AVX2 instruction.  Two things
would keep that loop scalar, and are avoided there: an early return (a singular mass matrix sets
``bad[l]`` instead) and calls into libm (``sin`` and ``cos`` are the polynomials ``vsin`` and
``vcos``).  On the double pendulum the kernel costs 18 ns per trajectory against 50 ns for the
scalar ``rhs``.  That inlined, vectorized body is what makes the lanes fast, so it stays emitted
per model; the loops around it are this module, compiled once per installation.  One call of the
kernel evaluates a whole block, so calling it through its address, not inlined, costs little: at
most 5% of the template loops' time (RK4 at 32 lanes on Hénon-Heiles, the cheapest kernel), which
the wider blocks below more than make up for.

`sweep_rk4_lanes` is the batched counterpart of the RK4 sweep: the arithmetic of ``rk4_run`` in
the same order, lanes in lock-step (a fixed step makes every lane take the same steps).
`sweep_dop853_lanes` is that of the DOP853 sweep: every lane with its own step-size control.
Trajectories go in blocks of `RK4_LANES` and `DOP853_LANES`.  A lane whose mass
matrix turns singular (`Status.RHS_FAILED`) or whose state turns non-finite (`Status.NONFINITE`)
keeps its last good state and time, as the scalar drivers do.

Outputs, per trajectory k, as the scalar sweep loops write them (`lagcomp.integrate.sweep`):
``final[k]`` (2n,) and ``t_final[k]`` where it stopped, ``status[k]``, ``counts[k]`` = (rhs
evaluations, accepted steps, rejected steps), ``dense[k]`` the saved rows (RK4 only; width 0 for
none) and ``energy_stats[k]`` = (E0, largest |E - E0| over the saved rows).
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

from lagcomp.integrate.drivers.kernel_types import (
    ENERGY,
    FLOAT,
    INT,
    MATRIX,
    RHS_LANES,
    VECTOR,
)
from lagcomp.integrate.status import Status
from lagcomp.integrate.tableaux import DOP853, RK4, over_common_denominator

#: Trajectories per block (the lane kernel's batch width B).  A kernel call and a step cost a fixed time per
#: block besides their time per lane, so wider blocks are faster until their work arrays leave the caches
#: or, for DOP853, until the lanes waiting for the block's slowest one cost more (RK4's lanes all take the
#: same steps).  Against the 32-lane template loops (the loops alone, one thread, 512-1024 trajectories of
#: the double pendulum, Hénon-Heiles, the 10-link chain): RK4 at 128 lanes 1.27x, 1.35x, 0.99x (the chain's
#: kernel dominates), DOP853 at 64 lanes 1.10x, 1.07x, 0.99x (at 128: 0.99x, 0.91x, 0.92x); these loops at
#: 32 lanes: RK4 1.00x, 0.95x, 0.99x, DOP853 1.05x, 1.02x, 1.01x.
RK4_LANES, DOP853_LANES = 128, 64

#: The outputs both loops write (after their settings): final, t_final, status, counts, dense, energy_stats.
_OUTPUTS = (MATRIX, VECTOR, types.int64[::1], types.int64[:, ::1], types.float64[:, :, ::1], MATRIX)


def _rk4_stage_factors() -> tuple[float, ...]:
    """RK4's A[s, s-1] = C[s] per stage (0 for the first): stage s > 0 evaluates f at t + C[s] h,
    y + A[s, s-1] h K[s-1], as ``rk4_run`` does; refuses a tableau whose stages use more than the one before."""
    A = RK4.A
    below = [A[s, s - 1] for s in range(1, A.shape[0])]
    if np.count_nonzero(A) != len(below) or any(a != c for a, c in zip(below, RK4.C[1:])):
        raise ValueError("sweep_rk4_lanes needs a tableau whose stage s uses only stage s - 1, at node A[s, s-1]")
    return (0.0, *map(float, below))


#: RK4 (`tableaux.RK4`): the stages' factors, and the update y + h/denominator * sum_j weight_j K[j]
#: (`tableaux.over_common_denominator`).
_RK4_FACTORS = _rk4_stage_factors()
_RK4_NUMERATORS, _RK4_DENOMINATOR = over_common_denominator(RK4.B)  # 1, 2, 2, 1 over 6: the rounding RK4 always had
_RK4_WEIGHTS = tuple(map(float, _RK4_NUMERATORS))
_RK4_STAGES = len(_RK4_FACTORS)

#: DOP853 (`tableaux.DOP853`): stage matrix, weights, nodes, the 3rd- and 5th-order error weights, and the
#: step-size exponent -1/(q + 1) of its error order q = 7.
_A, _B, _C, _E3, _E5 = (np.ascontiguousarray(getattr(DOP853, name), dtype=np.float64)
                        for name in ("A", "B", "C", "E3", "E5"))
_EXPONENT = -1.0 / (DOP853.error_order + 1)
#: Step-size control of ``dop853_run``: safety factor, and the bounds of the step's change per step.
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0


@njit(types.none(RHS_LANES, ENERGY, MATRIX, MATRIX, FLOAT, FLOAT, INT, FLOAT, INT, *_OUTPUTS),
      cache=True, error_model="numpy", nogil=True)
def sweep_rk4_lanes(rhs_lanes, energy, Y0, P, t0, dt, n_steps, t_end, save_every, final, t_final, status, counts,
                    dense, energy_stats):
    """RK4 over the trajectories (Y0[k], P[k]) in blocks of `RK4_LANES`, ``n_steps`` steps of ``dt`` to ``t_end``.

    Step k goes from ``t0 + k dt`` to ``min(t0 + (k+1) dt, t_end)``, the last one ending at ``t_end``,
    as in ``rk4_run``; a row (dense output, energy) is kept every ``save_every`` steps and after the last.
    """
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    n_p = P.shape[1]
    for a in range(0, n_traj, RK4_LANES):
        lanes = min(RK4_LANES, n_traj - a)
        Y = np.empty((n2, lanes))
        Pl = np.empty((n_p, lanes))
        for l in range(lanes):
            for c in range(n2):
                Y[c, l] = Y0[a + l, c]
            for c in range(n_p):
                Pl[c, l] = P[a + l, c]
        K = np.empty((_RK4_STAGES, n2, lanes))
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
            for s in range(_RK4_STAGES):
                cs = _RK4_FACTORS[s]
                if s > 0:
                    for i in range(n2):
                        for l in range(lanes):
                            Yt[i, l] = Y[i, l] + cs * h * K[s - 1, i, l]
                for l in range(lanes):
                    T[l] = t_a + cs * h
                rhs_lanes(T, Y if s == 0 else Yt, Pl, K[s], bad)
                for l in range(lanes):
                    if bad[l] and code[l] == 0:
                        code[l] = Status.RHS_FAILED
            fraction = h / _RK4_DENOMINATOR
            for i in range(n2):
                for l in range(lanes):
                    combined = _RK4_WEIGHTS[0] * K[0, i, l]
                    for s in range(1, _RK4_STAGES):
                        combined += _RK4_WEIGHTS[s] * K[s, i, l]
                    Yn[i, l] = Y[i, l] + fraction * combined
            running = 0
            for l in range(lanes):
                if code[l] == 0:
                    for i in range(n2):
                        if not np.isfinite(Yn[i, l]):
                            code[l] = Status.NONFINITE
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
            counts[a + l, 0] = _RK4_STAGES * steps[l]
            counts[a + l, 1] = steps[l]
            counts[a + l, 2] = 0
            energy_stats[a + l, 0] = e0[l]
            energy_stats[a + l, 1] = deviation[l]


@njit(types.none(RHS_LANES, ENERGY, MATRIX, MATRIX, FLOAT, FLOAT, FLOAT, VECTOR, FLOAT, INT, INT, *_OUTPUTS),
      cache=True, error_model="numpy", nogil=True)
def sweep_dop853_lanes(rhs_lanes, energy, Y0, P, t0, t_end, rtol, atol, max_step, max_steps, save_every, final,
                       t_final, status, counts, dense, energy_stats):
    """DOP853 over the trajectories (Y0[k], P[k]) in blocks of `DOP853_LANES`, each lane with its own steps.

    The lanes advance in lock-step *trials*: every iteration, each running
    lane tries one step of its own size h from its own t (the stages of all
    lanes in one ``rhs_lanes`` call per stage), then accepts or rejects it
    by its own error norm.  The per-lane arithmetic, step-size control and
    initial step are those of ``dop853_run``, in the same order, so a lane
    takes the steps the scalar driver takes (``atol`` (N,) per state component, as the scalar driver's).  No dense
    rows and no events
    (``dense`` is not written); lanes that finish early idle.
    """
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    n_p = P.shape[1]
    n_stages = _B.shape[0]
    n_k = _E5.shape[0]
    for a in range(0, n_traj, DOP853_LANES):
        lanes = min(DOP853_LANES, n_traj - a)
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
                code[l] = Status.RHS_FAILED
                running[l] = False
            elif not finite:
                code[l] = Status.NONFINITE
                running[l] = False
            d0 = 0.0
            d1 = 0.0
            for i in range(n2):
                sc = atol[i] + abs(Y[i, l]) * rtol
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
                sc = atol[i] + abs(Y[i, l]) * rtol
                r = (Yn[i, l] - K[0, i, l]) / sc
                d2 += r * r
            if bad[l]:
                code[l] = Status.RHS_FAILED
                running[l] = False
            elif not finite:
                h_abs[l] = min(h0[l], max_step)
            else:
                d2 = np.sqrt(d2 / n2) / h0[l]
                if d1s[l] <= 1e-15 and d2 <= 1e-15:
                    h1 = max(1e-6, h0[l] * 1e-3)
                else:
                    h1 = (0.01 / max(d1s[l], d2)) ** (-_EXPONENT)
                h_abs[l] = min(100.0 * h0[l], h1, t_end - t0, max_step)

        while True:
            # Start of a step, then the trial's size, per lane.
            active = 0
            for l in range(lanes):
                if running[l] and starting[l]:
                    if t[l] >= t_end:
                        running[l] = False
                    elif steps[l] >= max_steps:
                        code[l] = Status.MAX_STEPS
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
                    t_new = min(t[l] + h_abs[l], t_end)
                    if not (h_abs[l] >= min_step[l] and t_new < np.inf):
                        code[l] = Status.STEP_TOO_SMALL if h_abs[l] < min_step[l] and not nonfinite[l] \
                            else Status.NONFINITE
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
                    w = _A[s]
                    cs = _C[s]
                    arg = Yt
                else:
                    w = _B
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
                        code[l] = Status.RHS_FAILED
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
                        sc = atol[i] + max(abs(Y[i, l]), abs(Yn[i, l])) * rtol
                        e5 = 0.0
                        e3 = 0.0
                        for j in range(n_k):
                            e5 += _E5[j] * K[j, i, l]
                            e3 += _E3[j] * K[j, i, l]
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
                        factor = _MAX_FACTOR
                    else:
                        factor = min(_MAX_FACTOR, _SAFETY * err ** _EXPONENT)
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
                    h_abs[l] *= max(_MIN_FACTOR, _SAFETY * err ** _EXPONENT)
                    nonfinite[l] = False
                    rejected[l] = True
                    n_rejected[l] += 1
                else:
                    h_abs[l] *= _MIN_FACTOR
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
