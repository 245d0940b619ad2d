"""Taylor-series integrator: a *template*, appended to the generated modules that have a Taylor kernel.

Like ``drivers.py``, this text is appended verbatim to a generated module,
after ``drivers.py`` and the module's ``taylor_coefficients`` kernel
(`lagcomp.codegen.taylor` emits it, the recurrences written out as loops,
for unconstrained systems whose
equations use only functions with a Taylor recurrence).  The module provides
``taylor_coefficients(t, y, p, X, W)``, ``TAYLOR_WORK``, ``TAYLOR_PERIODIC``, ``event_values`` and
the helpers and status codes of ``drivers.py`` (``_ODE_*``, and in modules
with events ``_event_crossings``, ``_record_events``, ``_dense_state``).

``taylor_run`` has the calling convention of ``dop853_run`` (the module
docstring of ``drivers.py``: arguments, statuses, output buffer, events,
resuming), without tableau arrays.  Each step:

1. Order and step (Jorba & Zou, "A software package for the numerical
   integration of ODEs by means of high-order Taylor methods", Experiment.
   Math. 14 (2005) 99-117, sec. 3.2; the rule heyoka uses): the order is
   fixed for the run, ``p = ceil(−½ ln ε + 1)`` with ε = min(rtol, atol)
   (20 at ε = 2.2e-16).  At each step the series of the solution to order p
   is computed, and with ``‖·‖`` the max norm over the state,
   ``ρ_j = (s / ‖y[j]‖)^(1/j)`` for j = p − 1 and p, s = ‖y‖ (relative
   control) or 1 when ``rtol ‖y‖ ≤ atol`` (absolute control); the step is
   ``h = min(ρ_{p−1}, ρ_p) · exp(−0.7/(p − 1)) / e²``, clamped to
   ``max_step`` and to the end of the span.  Then the truncation term is
   about ``s e^(−2p) ≤ ε s``: no step is ever rejected, and ``nrejected``
   stays 0.  When both coefficients vanish (a polynomial solution) the step
   is only limited by ``max_step`` and the span.  The series is computed
   at y, except that each coordinate the rhs sees only through sin and cos
   (``TAYLOR_PERIODIC``, `lagcomp.codegen.periodic`) enters reduced to
   [−π, π] with the carry of step 2 folded in (``_taylor_reduced``): an
   angle that has wound to θ ≈ 500 is stored to ulp(500) = 5.7e-14, and the
   rhs evaluated there took in that rounding at every step (the double
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
   the step are evaluated on it exactly (``_dense_state`` kind 0), events
   located by Brent's method on it as for DOP853.

``nfev`` counts evaluations of ``taylor_coefficients`` (one per step).
"""

# ruff: noqa: F821  (taylor_coefficients, TAYLOR_WORK, TAYLOR_PERIODIC, event_values, _ODE_* ... come from the module)

import math

import numpy as np
from numba import njit

# 2π in three parts: the first two of 31 and 32 significant bits, so that m times them is exact for
# |m| < 2²⁰ (fdlibm's π/2 parts pio2_1, pio2_2, pio2_3, times 4); the third leaves 3.4e-31
_TWO_PI_1, _TWO_PI_2, _TWO_PI_3 = 6.2831853069365025, 2.4308402025215864e-10, 8.089064994844666e-21
#: Up to this |y| ``_taylor_reduced`` reduces (|m| < 2²⁰); beyond, y − carry as it is.
_TAYLOR_REDUCE_MAX = 6.5e6


@njit(cache=True, error_model="numpy", inline="always")
def _taylor_reduced(y, carry):
    """y − carry − 2πm with m the nearest integer to y/2π, rounded once (|result| ≤ π + 1 ulp).

    y − m·2π₁ is exact (both factors short, and Sterbenz's lemma: the two
    are within a factor 2 when m ≠ 0); the second part is subtracted with
    its rounding error kept (Knuth's TwoSum), then the third part and the
    carry (y stands for y − carry, ``taylor_run``) join that small term.
    Branch-free apart from the final choice, for the SIMD lanes of
    ``taylor_lanes`` as well.
    """
    m = np.floor(y * 0.15915494309189535 + 0.5)
    r = y - m * _TWO_PI_1
    b = m * _TWO_PI_2
    s = r - b
    bb = s - r
    e = (r - (s - bb)) - (b + bb)
    reduced = s + ((e - m * _TWO_PI_3) - carry)
    return reduced if abs(y) < _TAYLOR_REDUCE_MAX else y - carry


@njit(cache=True, error_model="numpy")
def taylor_run(y, clock, counters, p, projecting, residual_max, t_end, rtol,
               atol, max_step, max_steps, pause_at, save_every, t_eval, ts, ys,
               directions, actions, ev_t, ev_y, ev_i, compensation):
    """Adaptive Taylor method of order p = ceil(−½ ln min(rtol, atol) + 1); see the module docstring.

    The arguments, statuses and resuming are those of ``dop853_run``
    (``drivers.py``), then ``compensation`` float64[n], the carry of the
    compensated summation, kept across calls by the caller (start with
    zeros); with an empty array the carry restarts at each call (sweeps,
    whose trajectories share the argument).  ``clock[1]`` holds the last
    step taken.
    """
    n = y.shape[0]
    cap = ts.shape[0]
    n_eval = t_eval.shape[0]
    use_t_eval = n_eval > 0
    order = max(2, int(math.ceil(-0.5 * math.log(min(rtol, atol)) + 1.0)))
    rho_factor = math.exp(-0.7 / (order - 1)) / (math.e * math.e)

    # Work arrays, allocated once per call.
    X = np.empty((n, order + 1))
    W = np.empty((TAYLOR_WORK, order + 1))
    y_new = np.empty(n)
    y_series = np.empty(n)              # where the series is computed: y, periodic coordinates reduced
    if compensation.shape[0] != n:      # no carry kept by the caller (sweeps): one for this call
        compensation = np.zeros(n)
    # >>> events
    n_events = directions.shape[0]
    g_old = np.empty(n_events)
    g_new = np.empty(n_events)
    g_work = np.empty(n_events)
    y_work = np.empty(n)
    crossed = np.zeros(n_events, dtype=np.bool_)
    crossing_times = np.empty(n_events)
    # <<< events

    n_saved = 0
    t = clock[0]
    if t >= t_end:
        return _ODE_DONE, n_saved
    while counters[3] < n_eval and t_eval[counters[3]] <= t:
        counters[3] += 1
    # >>> events
    if n_events > 0:
        event_values(t, y, p, g_old)
    # <<< events

    while True:
        if t >= t_end:
            return _ODE_DONE, n_saved
        if counters[1] >= max_steps:
            return _ODE_MAX_STEPS, n_saved
        if counters[1] >= pause_at:
            return _ODE_PAUSED, n_saved

        # The series at (t, y), and the step from its last two coefficients.
        for i in range(n):
            y_series[i] = y[i]
        for i in TAYLOR_PERIODIC:
            y_series[i] = _taylor_reduced(y[i], compensation[i])
        status = taylor_coefficients(t, y_series, p, X, W)
        counters[0] += 1
        if status != 0:
            return _ODE_RHS_FAILED, n_saved
        for i in TAYLOR_PERIODIC:
            X[i, 0] = y[i]                      # the dense output's constant term: y itself
        # Non-finite coefficients: an infinite one among the last two would make the step 0 (-3, "too
        # small"), so those are tested here; any other reaches y_new through the Horner sum, tested there.
        norm_y = 0.0
        norm_last = 0.0
        norm_before = 0.0
        for i in range(n):
            norm_y = max(norm_y, abs(y[i]))
            norm_last = max(norm_last, abs(X[i, order]))
            norm_before = max(norm_before, abs(X[i, order - 1]))
        if not (norm_last < np.inf and norm_before < np.inf):      # (also false for NaN)
            return _ODE_NONFINITE, n_saved
        scale = 1.0 if rtol * norm_y <= atol else norm_y
        rho = min((scale / norm_last) ** (1.0 / order), (scale / norm_before) ** (1.0 / (order - 1)))
        h = min(rho * rho_factor, max_step)     # inf when both coefficients vanish
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if not h >= min_step:                   # (true for NaN)
            return _ODE_STEP_TOO_SMALL if h < min_step else _ODE_NONFINITE, n_saved
        t_new = t + h
        if t_new > t_end:
            t_new = t_end
        h = t_new - t

        # Stop before a step whose outputs would not fit (as in dop853_run).
        room = cap - n_saved
        need = 0
        if use_t_eval:
            j = counters[3]
            while j < n_eval and t_eval[j] <= t_new and need <= room:
                need += 1
                j += 1
        elif counters[4] + 1 >= save_every or t_new >= t_end:
            need = 1
        if need > room and (n_saved > 0 or not use_t_eval):
            return _ODE_BUFFER_FULL, n_saved
        # >>> events
        if counters[5] + n_events > ev_t.shape[0]:
            return _ODE_BUFFER_FULL, n_saved
        if n_events > 0 and not use_t_eval and n_saved >= cap:
            return _ODE_BUFFER_FULL, n_saved    # a terminal event saves its row
        # <<< events

        # The new state: the series at h (Horner), its increment added with compensation.
        for i in range(n):
            acc = 0.0
            for kk in range(order, 0, -1):
                acc = (acc + X[i, kk]) * h
            increment = acc - compensation[i]
            y_new[i] = y[i] + increment
            compensation[i] = (y_new[i] - y[i]) - increment
            if not np.isfinite(y_new[i]):
                return _ODE_NONFINITE, n_saved

        stop = False
        # >>> events
        if n_events > 0:
            event_values(t_new, y_new, p, g_new)
            if _event_crossings(g_old, g_new, directions, actions, crossed) > 0:
                n_recorded, t_stop = _record_events(0, X, y, t, h, p, g_old, g_new, crossed, actions,
                                                    crossing_times, ev_t, ev_y, ev_i, counters[5], y_work, g_work)
                counters[5] = n_recorded
                if t_stop < np.inf:
                    stop = True
                    t_new = t_stop
                    _dense_state(0, X, y, t, h, t_stop, y_new)
                    for i in range(n):
                        compensation[i] = 0.0
        # <<< events

        # Outputs of the step t -> t_new: t_eval points on the series, or every save_every-th step.
        if use_t_eval:
            j = counters[3]
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
            counters[3] = j
            if j < n_eval and t_eval[j] <= t_new:
                return _ODE_BUFFER_FULL, n_saved    # more points in one step than a whole buffer
        else:
            counters[4] += 1
            if counters[4] >= save_every or t_new >= t_end or stop:
                ts[n_saved] = t_new
                for i in range(n):
                    ys[n_saved, i] = y_new[i]
                n_saved += 1
                counters[4] = 0

        # Commit the step.
        for i in range(n):
            y[i] = y_new[i]
        t = t_new
        clock[0] = t
        clock[1] = h
        counters[1] += 1
        if stop:
            return _ODE_EVENT, n_saved
        # >>> events
        for ev in range(n_events):
            g_old[ev] = g_new[ev]
        # <<< events
