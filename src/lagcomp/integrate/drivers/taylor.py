"""The Taylor-series method: its driver `taylor_run` and per-trajectory sweep `sweep_taylor`.

The model gives the method its ``taylor_coefficients`` kernel (`lagcomp.codegen.taylor` emits it,
the recurrences written out as loops, for unconstrained systems whose equations use only
functions with a Taylor recurrence), and two pieces of data: ``TAYLOR_PERIODIC``, the
coordinates its equations see only through sin and cos, and ``TAYLOR_WORK``, the rows of the
kernel's work array.  Each step:

1. Order and step (Jorba & Zou, "A software package for the numerical
   integration of ODEs by means of high-order Taylor methods", Experiment.
   Math. 14 (2005) 99-117, sec. 3.2; the rule heyoka uses): the order is
   fixed for the run, ``p = ceil(−½ ln ε + 1)`` with ε = min(rtol, a),
   a = min_i atol_i (20 at ε = 2.2e-16).  At each step the series of the
   solution to order p is computed, and with ``‖x‖ = max_i |x_i| a/atol_i``
   the max norm over the state weighted by the per-component ``atol`` (each
   component in units of its own atol; the plain max norm where atol is one
   number), ``ρ_j = (s / ‖y[j]‖)^(1/j)`` for j = p − 1 and p, s = ‖y‖
   (relative control) or 1 when ``rtol ‖y‖ ≤ a`` (absolute control).  The
   order still compares rtol with an absolute a (the order does not follow
   a change of units; deriving it from rtol alone would change every Taylor
   run's steps); the step is
   ``h = min(ρ_{p−1}, ρ_p) · exp(−0.7/(p − 1)) / e²``, clamped to
   ``max_step`` and to the end of the span.  Then the truncation term is
   about ``s e^(−2p) ≤ ε s``: no step is ever rejected, and ``nrejected``
   stays 0.  When both coefficients vanish (a polynomial solution) the step
   is only limited by ``max_step`` and the span.  The series is computed
   at y, except that each periodic coordinate enters reduced to [−π, π]
   with the carry of step 2 folded in (`lagcomp.kernel_support.angles`):
   an angle that has wound to θ ≈ 500 is stored to ulp(500) = 5.7e-14, and
   the rhs evaluated there took in that rounding at every step (the double
   pendulum's relative energy error at t = 10⁴, rms over 16 starts 1 ulp
   apart, is 2.0e-11 without, 5.4e-13 with it: ``python -m
   bench.taylor_error_sources``).  The norms of the step rule stay those of
   y (with the reduced state: 2.4e-13, for 21% more steps).
2. The new state is the series at h, summed by Horner's rule from the top
   order down, and its increment added to y with compensated (Kahan)
   summation (that energy error is 3.3e-11 with a plain sum, the same
   bench); the carry is an argument, so that a run resumed chunk by chunk
   is bitwise the same as one call (simulate keeps it; sweeps pass an empty
   array and the carry restarts with each call).
3. Dense output is the series itself: ``t_eval`` points and events inside
   the step are evaluated on it exactly (`events.dense_state` of kind
   ``DENSE_SERIES``), events located by Brent's method on it as for DOP853.

``nfev`` counts evaluations of ``taylor_coefficients`` (one per step).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types

from lagcomp.integrate.drivers.events import (
    ACTION_RESET,
    DENSE_SERIES,
    copy_rows,
    dense_state,
    event_crossings,
    record_events_between,
    reset_state,
    resetting_event,
    restart_brackets,
    step_brackets,
)
from lagcomp.integrate.drivers.kernel_types import (
    ENERGY,
    EVENT_RESET,
    EVENTS,
    FLOAT,
    INDICES,
    INT,
    MATRIX,
    OUTCOME,
    TAYLOR,
    VECTOR,
)
from lagcomp.integrate.drivers.run_state import (
    COUNTER_SLOTS,
    EVENT_ROWS,
    NEXT_EVAL,
    NFEV,
    NSTEPS,
    SINCE_SAVE,
    STEP,
    TIME,
)
from lagcomp.integrate.drivers.sweep_rows import (
    NO_PAUSE,
    SWEEP_ROWS,
    fold_events,
    fold_rows,
    record_end,
)
from lagcomp.integrate.status import Status
from lagcomp.kernel_support.angles import reduced_angle


@njit(cache=True, error_model="numpy", nogil=True)
def multiplier_radius(W, rows, order, rtol, atol):
    """The step rule's ρ for the series of the held rows' multipliers λ in rows 0..rows−1 of W (orders 0..order−1:
    ``taylor_coefficients`` returned −rows), from their last two coefficients as for the state.  A body held at rest
    has a state series that vanishes beyond order 0 while λ varies (a pull growing past its weight): without this
    the step would span the lift-off, λ positive at both its ends (`lagcomp.codegen.taylor.ModePrograms`)."""
    norm = 0.0
    norm_last = 0.0
    norm_before = 0.0
    for r in range(rows):
        norm = max(norm, abs(W[r, 0]))
        norm_last = max(norm_last, abs(W[r, order - 1]))
        norm_before = max(norm_before, abs(W[r, order - 2]))
    scale = 1.0 if rtol * norm <= atol else norm
    return min((scale / norm_last) ** (1.0 / (order - 1)), (scale / norm_before) ** (1.0 / (order - 2)))


#: taylor_run(taylor_coefficients, event_values, event_reset, periodic, work_rows, y, clock, counters, p, projecting,
#: residual_max, t_end, rtol, atol, max_step, max_steps, pause_at, save_every, t_eval, ts, ys, directions,
#: actions, ev_t, ev_y, ev_i, ev_y_after, at_zero, carry)
SIGNATURE = OUTCOME(TAYLOR, EVENTS, EVENT_RESET, INDICES, INT, VECTOR, VECTOR, INDICES, VECTOR, INT, VECTOR, FLOAT,
                    FLOAT, VECTOR, FLOAT, INT, INT, INT, VECTOR, VECTOR, MATRIX, INDICES, INDICES, VECTOR, MATRIX,
                    INDICES, MATRIX, INDICES, VECTOR)


def taylor_order(rtol: float, atol) -> int:
    """The order `taylor_run` uses for these tolerances: ceil(−½ ln min(rtol, min atol) + 1), at least 2 (`atol` a
    number or the per-component array)."""
    return max(2, int(math.ceil(-0.5 * math.log(min(rtol, float(np.min(atol)))) + 1.0)))


@njit(SIGNATURE, cache=True, error_model="numpy", nogil=True)
def taylor_run(taylor_coefficients, event_values, event_reset, periodic, work_rows, y, clock, counters, p, projecting,
               residual_max, t_end, rtol, atol, max_step, max_steps, pause_at, save_every, t_eval, ts, ys,
               directions, actions, ev_t, ev_y, ev_i, ev_y_after, at_zero, carry):
    """Adaptive Taylor method of order p = ceil(−½ ln min(rtol, min atol) + 1); see the module docstring.

    ``taylor_coefficients``, ``event_values`` and ``event_reset`` are the model's kernels, ``periodic`` (int64, the
    state indices reduced to [−π, π]) and ``work_rows`` its ``TAYLOR_PERIODIC`` and ``TAYLOR_WORK``.
    The other arguments, statuses and resuming are those of the embedded Runge-Kutta driver
    (`lagcomp.integrate.drivers`: the protocol); ``projecting`` and ``residual_max`` are unused (the
    method takes unconstrained systems only).  ``carry`` float64[n] is the carry of the compensated
    summation, kept across calls by the caller (start with zeros); with an empty array the carry
    restarts at each call (sweeps).  ``clock[1]`` holds the last step taken.
    """
    n = y.shape[0]
    cap = ts.shape[0]
    n_eval = t_eval.shape[0]
    use_t_eval = n_eval > 0
    weights = np.empty(n)               # the max norms' weights: component i in units of atol_i / atol_min
    atol_min = np.inf
    for i in range(n):
        atol_min = min(atol_min, atol[i])
    for i in range(n):
        weights[i] = atol_min / atol[i]  # (1.0 exactly where atol is one number: the unweighted norms' bits)
    order = max(2, int(math.ceil(-0.5 * math.log(min(rtol, atol_min)) + 1.0)))
    rho_factor = math.exp(-0.7 / (order - 1)) / (math.e * math.e)

    # Work arrays, allocated once per call.
    X = np.empty((n, order + 1))
    W = np.empty((work_rows, order + 1))
    y_new = np.empty(n)
    y_series = np.empty(n)              # where the series is computed: y, periodic coordinates reduced
    compensation = carry if carry.shape[0] == n else np.zeros(n)   # no carry kept by the caller: one for this call
    n_events = directions.shape[0]
    g_old = np.empty(n_events)
    g_new = np.empty(n_events)
    g_work = np.empty(n_events)
    y_work = np.empty(n)
    crossed = np.zeros(n_events, dtype=np.bool_)
    crossing_times = np.empty(n_events)
    starts = np.empty(n_events)         # each event's bracket in the step (`restart_brackets`)
    g_start = np.empty(n_events)
    ends = np.empty(n_events)
    g_end = np.empty(n_events)
    side = np.empty(n_events)
    rows_at_event = 1                   # output rows an event's step may add: 2 with a reset (before, after)
    for e in range(n_events):
        if actions[e] >= ACTION_RESET:
            rows_at_event = 2

    n_saved = 0
    t = clock[TIME]
    if t >= t_end:
        return Status.DONE, n_saved
    while counters[NEXT_EVAL] < n_eval and t_eval[counters[NEXT_EVAL]] <= t:
        counters[NEXT_EVAL] += 1
    h_limit = np.inf                    # the step just after a reset: at most the one cut at the event
    if n_events > 0:
        event_values(t, y, p, g_old)
        for e in range(n_events):
            if at_zero[e] != 0:         # just after its reset (a call before this one): at its zero
                g_old[e] = 0.0
                h_limit = clock[STEP]

    while True:
        if t >= t_end:
            return Status.DONE, n_saved
        if counters[NSTEPS] >= max_steps:
            return Status.MAX_STEPS, n_saved
        if counters[NSTEPS] >= pause_at:
            return Status.PAUSED, n_saved

        # The series at (t, y), and the step from its last two coefficients.
        for i in range(n):
            y_series[i] = y[i]
        for i in periodic:
            y_series[i] = reduced_angle(y[i], compensation[i])
        status = taylor_coefficients(t, y_series, p, X, W)
        counters[NFEV] += 1
        if status > 0:
            return Status.RHS_FAILED, n_saved
        for i in periodic:
            X[i, 0] = y[i]                      # the dense output's constant term: y itself
        # Non-finite coefficients: an infinite one among the last two would make the step 0 (-3, "too
        # small"), so those are tested here; any other reaches y_new through the Horner sum, tested there.
        norm_y = 0.0
        norm_last = 0.0
        norm_before = 0.0
        for i in range(n):
            norm_y = max(norm_y, abs(y[i]) * weights[i])
            norm_last = max(norm_last, abs(X[i, order]) * weights[i])
            norm_before = max(norm_before, abs(X[i, order - 1]) * weights[i])
        if not (norm_last < np.inf and norm_before < np.inf):      # (also false for NaN)
            return Status.NONFINITE, n_saved
        scale = 1.0 if rtol * norm_y <= atol_min else norm_y
        rho = min((scale / norm_last) ** (1.0 / order), (scale / norm_before) ** (1.0 / (order - 1)))
        if status < 0 and order > 2:
            rho = min(rho, multiplier_radius(W, -status, order, rtol, atol_min))
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        # inf when both coefficients vanish; after a reset at most the step cut at it, and at least min_step (the
        # event may have been at the very start of that step)
        h = min(rho * rho_factor, max_step, max(h_limit, min_step))
        h_limit = np.inf
        if not h >= min_step:                   # (true for NaN)
            return Status.STEP_TOO_SMALL if h < min_step else Status.NONFINITE, n_saved
        t_new = t + h
        if t_new > t_end:
            t_new = t_end
        h = t_new - t

        # Stop before a step whose outputs would not fit (as the embedded Runge-Kutta driver does).
        room = cap - n_saved
        need = 0
        if use_t_eval:
            j = counters[NEXT_EVAL]
            while j < n_eval and t_eval[j] <= t_new and need <= room:
                need += 1
                j += 1
        elif counters[SINCE_SAVE] + 1 >= save_every or t_new >= t_end:
            need = 1
        if need > room and (n_saved > 0 or not use_t_eval):
            return Status.BUFFER_FULL, n_saved
        if counters[EVENT_ROWS] + n_events > ev_t.shape[0]:
            return Status.BUFFER_FULL, n_saved
        if n_events > 0 and not use_t_eval and n_saved + rows_at_event > cap:
            return Status.BUFFER_FULL, n_saved    # a terminal event saves its row, a reset two

        # The new state: the series at h (Horner), its increment added with compensation.
        for i in range(n):
            acc = 0.0
            for kk in range(order, 0, -1):
                acc = (acc + X[i, kk]) * h
            increment = acc - compensation[i]
            y_new[i] = y[i] + increment
            compensation[i] = (y_new[i] - y[i]) - increment
            if not np.isfinite(y_new[i]):
                return Status.NONFINITE, n_saved

        stop = False
        accumulated = False  # an event with a reset fired again less than the smallest step after its last reset
        reset = -1          # the event whose reset ends the step, if one does
        first_row = counters[EVENT_ROWS]
        if n_events > 0:
            event_values(t_new, y_new, p, g_new)
            n_crossed = event_crossings(g_old, g_new, directions, actions, crossed)
            restarting = False          # some event starts the step at its zero, after its reset
            for e in range(n_events):
                if at_zero[e] != 0:
                    restarting = True
            if n_crossed > 0 or restarting:
                step_brackets(t, h, g_old, g_new, starts, g_start, ends, g_end)
            if restarting:
                n_crossed += restart_brackets(event_values, DENSE_SERIES, X, y, t, h, p, at_zero, g_new, directions,
                                              actions, crossed, starts, g_start, ends, g_end, side, y_work, g_work)
            if n_crossed > 0:
                n_recorded, t_stop = record_events_between(event_values, DENSE_SERIES, X, y, t, h, p, starts, g_start,
                                                           ends, g_end, crossed, actions, crossing_times, ev_t, ev_y,
                                                           ev_i, first_row, y_work, g_work)
                counters[EVENT_ROWS] = n_recorded
                copy_rows(ev_y, ev_y_after, first_row, n_recorded)
                if t_stop < np.inf:
                    reset = resetting_event(ev_t, ev_i, actions, first_row, n_recorded, t_stop)
                    if reset >= 0 and at_zero[reset] != 0 and t_stop - t < min_step:
                        accumulated = True
                        reset = -1
                    stop = reset < 0
                    t_new = t_stop
                    dense_state(DENSE_SERIES, X, y, t, h, t_stop, y_new)
                    for i in range(n):
                        compensation[i] = 0.0

        # Outputs of the step t -> t_new: t_eval points on the series, or every save_every-th step.
        if use_t_eval:
            j = counters[NEXT_EVAL]
            while j < n_eval and t_eval[j] <= t_new and n_saved < cap:
                te = t_eval[j]
                ts[n_saved] = te
                if te == t_new:
                    for i in range(n):
                        ys[n_saved, i] = y_new[i]
                else:
                    u = te - t
                    for i in range(n):
                        acc = 0.0
                        for kk in range(order, 0, -1):
                            acc = (acc + X[i, kk]) * u
                        ys[n_saved, i] = y[i] + acc
                n_saved += 1
                j += 1
            counters[NEXT_EVAL] = j
            if j < n_eval and t_eval[j] <= t_new:
                return Status.BUFFER_FULL, n_saved    # more points in one step than a whole buffer
        else:
            counters[SINCE_SAVE] += 1
            if counters[SINCE_SAVE] >= save_every or t_new >= t_end or stop or reset >= 0:
                ts[n_saved] = t_new
                for i in range(n):
                    ys[n_saved, i] = y_new[i]
                n_saved += 1
                counters[SINCE_SAVE] = 0

        # A reset (as in the embedded Runge-Kutta driver): the state jumps at the event's time, where the step
        # ended; without t_eval the state after it is a second row at that time.
        failed = False
        if reset >= 0:
            failed = reset_state(event_reset, event_values, t_new, y_new, p, reset, y_work, g_old, g_work, ev_t,
                                 ev_i, ev_y_after, first_row, counters[EVENT_ROWS], at_zero) != 0
            if not (failed or use_t_eval):
                ts[n_saved] = t_new
                for i in range(n):
                    ys[n_saved, i] = y_new[i]
                n_saved += 1
            h = t_new - t               # the next step at most this one (the embedded driver says why)
            h_limit = h

        # Commit the step.
        for i in range(n):
            y[i] = y_new[i]
        t = t_new
        clock[TIME] = t
        clock[STEP] = h
        counters[NSTEPS] += 1
        if reset < 0:
            for e in range(n_events):
                at_zero[e] = 0
        if stop:
            return (Status.EVENTS_ACCUMULATED if accumulated else Status.TERMINATED), n_saved
        if failed:
            return Status.RESET_FAILED, n_saved    # at the event, with the state just before it
        if reset < 0:
            for ev in range(n_events):
                g_old[ev] = g_new[ev]


#: sweep_taylor(taylor_coefficients, event_values, event_reset, periodic, work_rows, energy, Y0, P, projecting, t0,
#: t_end, rtol, atol, max_step, max_steps, save_every, t_eval, save_initial, directions, actions, final, t_final,
#: status, counts, dense, energy_stats, event_count, event_t, event_y, carry)
SWEEP_SIGNATURE = types.none(TAYLOR, EVENTS, EVENT_RESET, INDICES, INT, ENERGY, MATRIX, MATRIX, INT, FLOAT, FLOAT,
                             FLOAT, VECTOR, FLOAT, INT, INT, VECTOR, types.boolean, INDICES, INDICES, MATRIX, VECTOR,
                             INDICES, types.int64[:, ::1], types.float64[:, :, ::1], MATRIX, types.int64[:, ::1],
                             types.float64[:, :, ::1], types.float64[:, :, :, ::1], VECTOR)


@njit(SWEEP_SIGNATURE, cache=True, error_model="numpy", nogil=True)
def sweep_taylor(taylor_coefficients, event_values, event_reset, periodic, work_rows, energy, Y0, P, projecting, t0,
                 t_end, rtol, atol, max_step, max_steps, save_every, t_eval, save_initial, directions, actions, final,
                 t_final, status, counts, dense, energy_stats, event_count, event_t, event_y, carry):
    """Trajectory k from (t0, Y0[k]) with parameters P[k] to t_end by `taylor_run`, for every k.

    The outputs of a sweep (`lagcomp.integrate.sweep`): ``final`` (N, 2n), ``t_final``, ``status``,
    ``counts`` (N, 3) = [nfev, nsteps, nrejected]; ``dense`` (N, m, 2n) the ``t_eval`` rows (after t0;
    ``save_initial`` says whether t0 is one too); ``energy_stats`` (N, 2) the initial energy and the
    largest |E − E₀| over the saved rows; ``event_count`` (N, E) and the first occurrences in ``event_t``
    (N, E, cap) and ``event_y`` (N, E, cap, 2n; or 4n: then the states after the events too, `fold_events`).
    ``carry`` is the carry `taylor_run` takes (empty: it restarts with each call).  Each trajectory runs with a
    copy of its row of ``P`` (a contact's event_reset writes the mode slots of its p).  The trajectories release
    the GIL: the caller runs disjoint row ranges on several threads.
    """
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    n_events = directions.shape[0]
    for k in range(n_traj):
        y = Y0[k].copy()
        p = P[k].copy()
        clock = np.zeros(2)
        clock[TIME] = t0
        counters = np.zeros(COUNTER_SLOTS, dtype=np.int64)
        residual = np.zeros(1)
        ts = np.empty(SWEEP_ROWS)
        ys = np.empty((SWEEP_ROWS, n2))
        rows_e = max(n_events, 1)
        ev_t = np.empty(rows_e)
        ev_y = np.empty((rows_e, n2))
        ev_i = np.empty(rows_e, dtype=np.int64)
        ev_y_after = np.empty((rows_e, n2))
        at_zero = np.zeros(n_events, dtype=np.int64)
        e0 = energy(t0, y, p)
        deviation = 0.0
        row = 0
        if dense.shape[1] > 0 and save_initial:
            for c in range(n2):
                dense[k, 0, c] = y[c]
            row = 1
        for e in range(n_events):
            event_count[k, e] = 0
        while True:
            counters[EVENT_ROWS] = 0
            code, n_saved = taylor_run(taylor_coefficients, event_values, event_reset, periodic, work_rows, y, clock,
                                       counters, p,
                                       projecting, residual, t_end, rtol, atol, max_step, max_steps, NO_PAUSE,
                                       save_every, t_eval, ts, ys, directions, actions, ev_t, ev_y, ev_i,
                                       ev_y_after, at_zero, carry)
            deviation, row = fold_rows(energy, ts, ys, n_saved, p, e0, deviation, dense, k, row)
            fold_events(counters[EVENT_ROWS], ev_t, ev_y, ev_y_after, ev_i, event_count, event_t, event_y, k)
            if code != Status.BUFFER_FULL:
                break
        record_end(k, y, clock, counters, code, e0, deviation, final, t_final, status, counts, energy_stats)
