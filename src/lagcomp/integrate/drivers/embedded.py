"""One adaptive driver for every embedded explicit Runge-Kutta pair: DOPRI5, DOP853, Tsit5, BS3, ...

`embedded_run` integrates y' = f(t, y) with step-size control and dense output; what differs between
the pairs is data (`lagcomp.integrate.tableaux.driver_arguments`), in the spirit of scipy's
``rk.py``, where DOP853 overrides only its error norm and its interpolant:

* the stages: ``A`` (s, s) strictly lower triangular, weights ``B`` (s,), nodes ``C`` (s,); stage
  s + 1 is the FSAL stage ``f(t + h, y_new)``, which starts the next step;
* the error estimate: ``error_weights`` (rows, s + 1), each row a difference of two weight vectors
  over the stages and the FSAL stage, and ``error_norm``: `ERROR_RMS` (one row E: the RMS norm of
  ``h E·K / scale``, HNW II.4; DOPRI5, Tsit5, BS3) or `ERROR_DOP853` (rows E5, E3: Hairer's combined
  estimate ``|h| e5 / sqrt(n (e5 + 0.01 e3))`` with e5, e3 the squared 2-norms of the scaled 5th- and
  3rd-order estimates, ``dop853.f``; HNW II.5); ``error_exponent`` = -1/(q + 1) for the estimate's
  order q (`Tableau.error_order`);
* the dense output (HNW II.6), built only for steps that hold a ``t_eval`` point or an event:
  ``dense_kind`` `DENSE_POWERS` (DOPRI5, Tsit5, BS3: ``dense_weights`` is Pᵀ (m, s + 1), and
  ``Q[r] = dense_weights[r] @ K`` gives ``y(t + x h) = y + h sum_r Q[r] x^(r+1)``, evaluated in
  Horner form) or `DENSE_CONTD8` (DOP853's ``contd8``: ``extra_A`` (3, s + 4) and ``extra_C`` (3,)
  give three more stages, and the rows ``F0 = dy = y_new - y``, ``F1 = h f_old - dy``,
  ``F2 = 2 dy - h (f_new + f_old)``, ``F3.. = h dense_weights @ K`` give
  ``y(t + x h) = y + x (F0 + (1-x) (F1 + x (F2 + (1-x) (F3 + ...))))``).  Pairs without extra
  stages pass ``extra_A`` (0, s + 1) and ``extra_C`` (0,);
* the stiffness test (below): ``stiffness_bound``, 0 for none.

`lagcomp.integrate.drivers.embedded_sweep.sweep_embedded` runs it over many trajectories (`lagcomp.integrate.sweep`).

Arguments, after the kernels (`kernel_types`) and before the tableau: the driver protocol of
`lagcomp.integrate.drivers`, with

* ``atol`` (N,): the absolute tolerance of each component of ``y``, in its own units (`simulate` fills it with
  one number where the user gives one: then the same bits as a scalar would give);
* ``y`` (N,): the state, the last accepted one on return; ``clock`` = [t, h, t_stiff]: its time and
  the next step to try (h <= 0 selects the initial step); ``counters`` int64[11] = [nfev, nsteps,
  nrejected, i_eval, since_save, n_events, -, -, stiffness test..], n_events the event rows this call
  wrote (the caller resets it with each fresh event buffer); the slots are those of
  `lagcomp.integrate.drivers.run_state`;
* ``projecting`` 1 projects each accepted state onto the constraints (after the step's dense output,
  and the FSAL stage is then evaluated again at the projected state): the rows saved are the projected
  states, and the rows of ``t_eval`` points inside a step the interpolated states, projected;
  ``residual_max`` [running maximum of ``constraint_residual`` over accepted states] or [.., bound]: the
  step whose residual exceeds the bound is committed (and saved if due), then the driver returns
  RESIDUAL_EXCEEDED;
* ``pause_at``: return PAUSED before step number ``pause_at`` (counted from the run's start,
  ``counters[1]``), so that Python can show progress and honour Ctrl-C between calls;
* ``t_eval`` (points after the start; empty: save every ``save_every``-th step and the last one),
  ``ts`` (cap,), ``ys`` (cap, N): output rows from 0 (the caller writes the initial point);
* events: ``directions`` int64[E] (+1, -1, 0), ``actions`` int64[E] (0 ignore, 1 record, 2 record
  and stop) and the rows ``ev_t`` (cap_e,), ``ev_y`` (cap_e, N), ``ev_i`` int64[cap_e]; a step starts
  only when they have room for one row per event.  After each accepted step the events are evaluated
  at its end and each sign change in an event's direction is located on the dense output
  (`lagcomp.integrate.drivers.events`); a terminal event ends the step, and the run, at its time:
  its state is the last saved row and ``y``, status TERMINATED.  ``actions`` 3: an event with a reset, which
  ends the step at its time too; the ``event_reset`` kernel then moves the state, and the run goes on from
  there: the FSAL stage is evaluated again, the step size kept, and without ``t_eval`` the states before and
  after are both saved rows at that time.  ``ev_y_after`` (cap_e, N) gets each event row's state after the
  event (the reset's, or the row's own); a reset whose state is not finite ends the run at the event,
  RESET_FAILED, with the state before it.  ``at_zero`` int64[E], kept by the caller across its calls (zeros
  at the start), marks the events that start the next step at their zero, just after their reset
  (`lagcomp.integrate.drivers.events.reset_state`): that step is at most the one cut at the event, and
  samples them densely (`restart_brackets`); one of them firing again within the smallest step ends the
  run there, EVENTS_ACCUMULATED (a Zeno point);

It returns ``(status, n_saved)``, status a `Status`: DONE at ``t_end``; BUFFER_FULL or PAUSED: call
again (with a fresh output buffer, a later ``pause_at``), and the continuation is identical to an
uninterrupted run except for one more f evaluation per call; TERMINATED; NONFINITE, RHS_FAILED,
STEP_TOO_SMALL, MAX_STEPS, RESIDUAL_EXCEEDED, with ``y`` and ``clock[0]`` the last good state (for
RESIDUAL_EXCEEDED the committed one whose residual is too large).

Step-size control
-----------------

The standard control of explicit Runge-Kutta pairs, Hairer, Norsett & Wanner, *Solving Ordinary
Differential Equations I* (2nd ed., 1993), sec. II.4 (automatic step size control, starting step)
and II.6 (dense output), with scipy's constants (``solve_ivp``), so that at equal tolerances a pair
takes scipy's steps (tests/test_drivers.py checks DOPRI5, DOP853 and BS3 against RK45, DOP853, RK23):

1. Initial step, when ``clock[1] <= 0``: with ``scale = atol + |y0| rtol`` and the RMS norm,
   ``d0 = ||y0||``, ``d1 = ||f0||``; a probe ``h0 = 0.01 d0/d1`` (1e-6 if either is tiny; at most the
   interval); an Euler step gives ``f1 = f(t0 + h0, y0 + h0 f0)`` and ``d2 = ||f1 - f0|| / h0``; then
   ``h1 = (0.01 / max(d1, d2)) ** (1/(q+1))`` (or ``max(1e-6, 1e-3 h0)`` when both are negligible)
   and the step is ``min(100 h0, h1, t_end - t0, max_step)``.  A non-finite probe derivative gives
   ``min(h0, max_step)`` and leaves the trouble to the step rejection.
2. Trial steps: the step is clamped to ``max_step`` (or raised to the minimum ``10 ulp(t)``) and
   clipped to land on ``t_end``.  It is accepted when the error norm ``err < 1`` (scale
   ``atol + max(|y|, |y_new|) rtol`` per component), and the next step is
   ``h min(MAX_FACTOR, SAFETY err^(-1/(q+1)))`` (at most h after a rejection in this step); otherwise
   h is multiplied by ``max(MIN_FACTOR, SAFETY err^(-1/(q+1)))`` and the step tried again.  A trial with
   non-finite stages or error is rejected with ``h *= MIN_FACTOR``; if h then falls below the minimum
   step the run stops with NONFINITE (last trouble non-finite) or STEP_TOO_SMALL.
3. The outputs of the accepted step (below), the projection, then the commit:
   ``y = y_new``, ``K[0] = K[s]``.

No floating-point trouble raises: the driver and the kernels use numba's ``error_model="numpy"``
(a division by zero gives inf or NaN, as in numpy, instead of raising ZeroDivisionError out of the
compiled loop and losing the partial solution).  Every derivative and new state is tested; a trial
whose error is NaN or inf is rejected (``err < 1`` is false for NaN); the step-size tests are written
so that a NaN step ends the run (``not h >= min_step``) instead of looping forever.  The divisions
that can meet a zero norm are guarded as in scipy (``0.01 d0 / d1`` only when both are at least
1e-5, ``0.01 / max(d1, d2)`` only when one exceeds 1e-15, ``err ** exponent`` only for err > 0, and
DOP853's norm is 0 when both estimates vanish).  A zero component of the error scale (atol = 0 and
a component exactly 0) makes a norm inf or NaN, which the control treats like any other non-finite
estimate.  Array operations that could raise (slice assignment) are explicit loops.

Stiffness detection
-------------------

Hairer's test (HNW II, sec. IV.2; ``dopri5.f``, ``dop853.f``), which tells when the steps are set
by the method's stability rather than by its accuracy: the last stage and the FSAL stage are both at
t + h, at the arguments g and y_new, so that ``h |λ| ≈ h ||f(t + h, y_new) - f(t + h, g)|| /
||y_new - g||`` estimates h times the dominant eigenvalue of the Jacobian, with ``y_new - g =
h sum_j (B_j - A[s-1, j]) K_j`` (from the stages: g is not kept).  A test finds the step at the
stability limit when that exceeds ``stiffness_bound`` (a little inside the method's stability interval
on the negative real axis: 3.25 for DOPRI5 and 6.1 for DOP853, as Hairer's codes; `Tableau`).  It runs
after every `STIFFNESS_TEST_EVERY`-th accepted step and, once a test found the limit, after every
step: `STIFF_TESTS_TO_DECLARE` such tests declare the run stiff (the step number and time go to
``counters`` and ``clock``, and the tests stop), `CALM_TESTS_TO_RESET` others in a row start the
count again.  The counts live in ``counters``, so that a run cut into calls decides as an
uninterrupted one (the estimate is formed with the step, the counts move at its commit: a step
redone after BUFFER_FULL counts once).  The test costs about (s + 3) N flops; between tests, two
integer tests per step.  It changes no step: the trajectories stay those of the tableau alone.

Hairer tests every 1000th step; every 100th here, since a single test below the bound waits for the
next chance, and the estimate is noisy (the stiff spring pendulum at rtol = atol = 1e-6 with DOP853:
5-95% of the steps' estimates between 4.6 and 8.0 about a median of 6.45).  Over t in [0, 10] at
rtol = atol = 1e-4, 1e-6 it was declared stiff by every 1000th step at steps 1014, 1015 (DOP853),
never (3045 steps), 2015 (DOPRI5), 2027, 1018 (Tsit5); by every 100th at 114, 219; 229, 114; 128,
226.  The cost of a test is a few hundred flops, not worth saving on.

What it sees, measured.  At tight tolerances (rtol 1e-8) an explicit pair's step on a stiff problem is
set by the accuracy of the fast mode's forced response, well inside the stability interval (h|λ| about
1.9 for DOP853, 0.8 for DOPRI5 and 1.0 for Tsit5 on that pendulum, against 6.4, 3.3 and 3.5 at its
boundary): the test does not see that regime (DOP853 sometimes does, through the estimate's noise),
and a lower bound that did would also flag non-stiff problems at loose tolerances (Hénon-Heiles at
rtol 1e-3 gives DOPRI5 estimates about 1.36).  At loose tolerances an oscillating non-stiff system's
steps can reach the limit too: of the double pendulum, Hénon-Heiles, the restricted and Pythagorean
three-body problems, the 5-link chain and the symmetric top with the three pairs at rtol = atol from
1e-2 to 1e-10, only Hénon-Heiles with Tsit5 at 1e-3 and the top with DOPRI5 at 1e-2 and Tsit5 at 1e-2
and 1e-3 were declared stiff.

Output buffer: before each step the rows it may write are bounded (from the trial step, which
rejections only shorten); if they do not fit, BUFFER_FULL is returned before the step.  With
``t_eval`` this can happen while the buffer still has free rows: the rows written are always
``ts[:n_saved]``.  Only if a single step holds more ``t_eval`` points than an empty buffer, the points
that fit are written and the step is *not* committed; the next call redoes the same (deterministic)
step and goes on with the remaining points.

Why one long function
---------------------

The step loop is one function whose hot loops (stage sums, error norm, dense rows) are written
inline: moving that arithmetic into small helpers slowed the step loop by 15-35% (measured on the
template drivers this one replaces), and so did array views inside the stage loop (numba builds and
reference-counts each one: ``rhs`` writes into ``f_stage``, copied into ``K[s]``).  It calls ``rhs``
from three places (first stage, initial-step probe, stages; four with DOP853's extra stages).  Its
compile time, which decided that layout when every model compiled its own copy, is now paid once
per installation: numba caches this function for every model, since its signature names the
kernels' types, not the kernels.

Register blocks
---------------

A stage sum or an error estimate of one component is a chain of additions, each waiting for the
one before.  For the smallest systems (stage sums, `COMPONENTWISE_MAX`) and for the error estimates
of every system, four components are summed together, each in its own register: four independent
chains that the processor overlaps, with the operations of each component in the same order (the
same bits).  DOP853 on the double pendulum then takes 0.83 times the time of one chain per component
(0.93-0.96 times numbalsoda's dop853, which was 1.13-1.16 times; the 10-link chain 0.95-0.97 times:
``bench/bench_dop853.py``).  The model's ``rhs`` is then about two thirds of the run's time (perf).

Not done, measured: a copy of this function per tableau with the tableau's arrays as compile-time
constants (a closure, whose arrays numba freezes) took 0.96 times the time of this function with one
register per component, and 1.07 times with the register blocks: LLVM does not unroll the stage loops
(their length depends on the stage), so the coefficients stay loads and only the sizes are constants.
Sums over tables of the nonzero terms (no test per coefficient) took 1.01 and 1.03 times.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from lagcomp.integrate.drivers.events import (
    ACTION_RESET,
    DENSE_CONTD8,
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
    EVENT_RESET,
    EVENTS,
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
from lagcomp.integrate.drivers.run_state import (
    CLOCK_SLOTS,
    COUNTER_SLOTS,
    EVENT_ROWS,
    NEXT_EVAL,
    NFEV,
    NONSTIFF_TESTS,
    NREJECTED,
    NSTEPS,
    SINCE_SAVE,
    STEP,
    STIFF_AT_STEP,
    STIFF_AT_TIME,
    STIFF_TESTS,
    TIME,
)
from lagcomp.integrate.status import Status
from lagcomp.integrate.tableaux import ERROR_RMS

#: Step-size controller constants (HNW I, sec. II.4, eqs. (4.12)-(4.13); scipy's values): the safety
#: factor on the optimal step, and the bounds of the factor by which one step may change the next.
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0

#: Largest state whose stage sums accumulate in registers (a one- or two-degree-of-freedom system),
#: four components at a time and the rest one by one: DOP853 on the double pendulum (4 components)
#: took 1.20 times the steps/s of the row-by-row sums with one register, which vectorize and win from
#: 10 components on (0.81 times at 10, 0.74 at 20; 1.02 at 6); with four registers the 10-link chain
#: takes the same time either way (1.01).  Both give the same bits.
COMPONENTWISE_MAX = 4

#: The stiffness test (see "Stiffness detection" in the module docstring): tested steps, tests at the
#: stability limit that declare the run stiff, and tests in a row below it that restart the count.
STIFFNESS_TEST_EVERY, STIFF_TESTS_TO_DECLARE, CALM_TESTS_TO_RESET = 100, 15, 6

#: The tableau's arguments, after the run's: A, B, C, error_weights, error_norm, error_exponent,
#: dense_kind, dense_weights, extra_A, extra_C, stiffness_bound.
TABLEAU = (MATRIX, VECTOR, VECTOR, MATRIX, INT, FLOAT, INT, MATRIX, MATRIX, VECTOR, FLOAT)

SIGNATURE = OUTCOME(RHS, PROJECT, RESIDUAL, EVENTS, EVENT_RESET,
                    VECTOR, VECTOR, INDICES, VECTOR, INT, VECTOR, FLOAT, FLOAT, VECTOR, FLOAT, INT, INT, INT,
                    VECTOR, VECTOR, MATRIX, INDICES, INDICES, VECTOR, MATRIX, INDICES, MATRIX, INDICES,
                    *TABLEAU)


@njit(SIGNATURE, cache=True, error_model="numpy", nogil=True)
def embedded_run(rhs, project, constraint_residual, event_values, event_reset,
                 y, clock, counters, p, projecting, residual_max, t_end, rtol, atol, max_step, max_steps, pause_at,
                 save_every, t_eval, ts, ys, directions, actions, ev_t, ev_y, ev_i, ev_y_after, at_zero,
                 A, B, C, error_weights, error_norm, error_exponent, dense_kind, dense_weights, extra_A, extra_C,
                 stiffness_bound):
    """Integrate from (clock[0], y) towards t_end with the embedded pair given by the tableau arguments.

    See the module docstring for the arguments, the return value and the algorithm.
    """
    n = y.shape[0]
    cap = ts.shape[0]
    n_eval = t_eval.shape[0]
    use_t_eval = n_eval > 0
    n_stages = B.shape[0]
    n_k = n_stages + 1                  # stages and the FSAL stage
    n_all = n_k + extra_C.shape[0]      # ... and the dense output's extra stages
    contd8 = dense_kind == DENSE_CONTD8
    n_special = 3 if contd8 else 0      # contd8's rows F0, F1, F2 from y, y_new, f_old, f_new
    n_rows = n_special + dense_weights.shape[0]

    # Work arrays, allocated once per call.
    K = np.empty((n_all, n))
    y_new = np.empty(n)
    ytmp = np.empty(n)
    f_stage = np.empty(n)
    F = np.empty((n_rows, n))   # dense-output rows; F[0] is also the initial step's error scale
    n_events = directions.shape[0]
    g_old = np.empty(n_events)
    g_new = np.empty(n_events)
    g_work = np.empty(n_events)
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

    # The stiffness test, until the run is declared stiff; never with state arrays of another layout
    # (callers from before its slots existed), whose slots it would write past.
    detecting = (stiffness_bound > 0.0 and counters.shape[0] >= COUNTER_SLOTS and clock.shape[0] >= CLOCK_SLOTS
                 and counters[STIFF_AT_STEP] == 0)
    last_stage = n_stages - 1

    n_saved = 0
    residual_bound = residual_max[1] if residual_max.shape[0] > 1 else np.inf
    t = clock[TIME]
    if t >= t_end:
        return Status.DONE, n_saved
    # Output points at or before the current time are never emitted here.
    while counters[NEXT_EVAL] < n_eval and t_eval[counters[NEXT_EVAL]] <= t:
        counters[NEXT_EVAL] += 1

    # First stage of the first step (FSAL thereafter); events at the start.  ``status`` holds the
    # outcome of a group of rhs calls: 0, the rhs status (> 0), or -1 for a non-finite value.
    status = rhs(t, y, p, K[0])
    counters[NFEV] += 1
    if n_events > 0:
        event_values(t, y, p, g_old)
        for e in range(n_events):
            if at_zero[e] != 0:         # just after its reset (a call before this one): at its zero
                g_old[e] = 0.0
    if status == 0:
        for i in range(n):
            if not (np.isfinite(y[i]) and np.isfinite(K[0, i])):
                status = -1

    h_abs = clock[STEP]
    if status == 0 and h_abs <= 0.0:
        # Initial step (step 1 of the module docstring): probe state in ytmp, probe derivative in
        # y_new, error scale in F[0].
        interval = t_end - t
        if n == 0:
            h_abs = min(interval, max_step)
        else:
            d0 = 0.0
            d1 = 0.0
            for i in range(n):
                sc = atol[i] + abs(y[i]) * rtol
                F[0, i] = sc
                r = y[i] / sc
                d0 += r * r
                r = K[0, i] / sc
                d1 += r * r
            d0 = np.sqrt(d0 / n)
            d1 = np.sqrt(d1 / n)
            if d0 >= 1e-5 and d1 >= 1e-5:   # (false for NaN)
                h0 = 0.01 * d0 / d1
            else:
                h0 = 1e-6
            h0 = min(h0, interval)
            for i in range(n):
                ytmp[i] = y[i] + h0 * K[0, i]
            status = rhs(t + h0, ytmp, p, y_new)
            counters[NFEV] += 1
            finite = True
            d2 = 0.0
            for i in range(n):
                finite = finite and np.isfinite(y_new[i])
                r = (y_new[i] - K[0, i]) / F[0, i]
                d2 += r * r
            if not finite:
                h_abs = min(h0, max_step)
            else:
                d2 = np.sqrt(d2 / n) / h0
                if d1 <= 1e-15 and d2 <= 1e-15:
                    h1 = max(1e-6, h0 * 1e-3)
                else:
                    h1 = (0.01 / max(d1, d2)) ** (-error_exponent)
                h_abs = min(100.0 * h0, h1, interval, max_step)
        if status == 0:                     # (not after a failed probe)
            clock[STEP] = h_abs
    if status != 0:
        return (Status.RHS_FAILED if status > 0 else Status.NONFINITE), n_saved

    while True:
        if t >= t_end:
            return Status.DONE, n_saved
        if counters[NSTEPS] >= max_steps:
            return Status.MAX_STEPS, n_saved
        if counters[NSTEPS] >= pause_at:
            return Status.PAUSED, n_saved

        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step

        # Stop before a step whose outputs would not fit (never lose one).  The bound: the t_eval
        # points in (t, t_reach] not yet emitted (counted up to room + 1), else 1 if the step is saved
        # by decimation or may end at t_end.  Rejections only shorten the step.
        room = cap - n_saved
        t_reach = min(t + h_abs, t_end)
        need = 0
        if use_t_eval:
            j = counters[NEXT_EVAL]
            while j < n_eval and t_eval[j] <= t_reach and need <= room:
                need += 1
                j += 1
        elif counters[SINCE_SAVE] + 1 >= save_every or t_reach >= t_end:
            need = 1
        if need > room and (n_saved > 0 or not use_t_eval):
            return Status.BUFFER_FULL, n_saved
        if counters[EVENT_ROWS] + n_events > ev_t.shape[0]:
            return Status.BUFFER_FULL, n_saved
        if n_events > 0 and not use_t_eval and n_saved + rows_at_event > cap:
            return Status.BUFFER_FULL, n_saved    # a terminal event saves its row, a reset two

        # Trial loop: shrink until the error estimate is acceptable.
        step_rejected = False
        nonfinite = False
        while True:
            t_new = t + h_abs
            if t_new > t_end:  # noqa: PLR1730 (a NaN t_new stays NaN: the test below ends the run)
                t_new = t_end
            # Too small, or NaN, or infinite (possible only with t_end = inf).
            if not (h_abs >= min_step and t_new < np.inf):
                if h_abs < min_step and not nonfinite:
                    return Status.STEP_TOO_SMALL, n_saved
                return Status.NONFINITE, n_saved
            h = t_new - t
            h_abs = abs(h)

            # Stages K[1 .. s]: K[s] = f(t + c h, y + h sum_{j<s} a_j K[j]) with (a, c) = (A[s], C[s]),
            # and for s = n_stages (B, 1): the stage argument is then y_new and the stage the FSAL
            # derivative.  Zero coefficients are skipped (the tableaux are sparse).  The sum runs
            # stage by stage over whole rows of K (which vectorizes), or for the smallest systems in
            # registers, four components at a time (see "Register blocks" in the module docstring):
            # the same operations in the same order.
            status = 0
            for s in range(1, n_stages + 1):
                last = s == n_stages
                c = 1.0 if last else C[s]
                if n <= COMPONENTWISE_MAX:
                    i0 = 0
                    while i0 + 4 <= n:
                        acc0 = acc1 = acc2 = acc3 = 0.0
                        for j in range(s):
                            a = B[j] if last else A[s, j]
                            if a != 0.0:
                                acc0 += a * K[j, i0]
                                acc1 += a * K[j, i0 + 1]
                                acc2 += a * K[j, i0 + 2]
                                acc3 += a * K[j, i0 + 3]
                        ytmp[i0] = y[i0] + h * acc0
                        ytmp[i0 + 1] = y[i0 + 1] + h * acc1
                        ytmp[i0 + 2] = y[i0 + 2] + h * acc2
                        ytmp[i0 + 3] = y[i0 + 3] + h * acc3
                        i0 += 4
                    for i in range(i0, n):
                        acc = 0.0
                        for j in range(s):
                            a = B[j] if last else A[s, j]
                            if a != 0.0:
                                acc += a * K[j, i]
                        ytmp[i] = y[i] + h * acc
                else:
                    for i in range(n):
                        ytmp[i] = 0.0
                    for j in range(s):
                        a = B[j] if last else A[s, j]
                        if a != 0.0:
                            for i in range(n):
                                ytmp[i] += a * K[j, i]
                    for i in range(n):
                        ytmp[i] = y[i] + h * ytmp[i]
                if last:
                    for i in range(n):
                        y_new[i] = ytmp[i]
                        if not np.isfinite(ytmp[i]):
                            status = -1
                    if status != 0:
                        break
                status = rhs(t + c * h, ytmp, p, f_stage)
                counters[NFEV] += 1
                for i in range(n):
                    K[s, i] = f_stage[i]
                    if status == 0 and not np.isfinite(f_stage[i]):
                        status = -1
                if status != 0:
                    break
            if status > 0:
                return Status.RHS_FAILED, n_saved

            # Error norm, infinite when a value was not finite.
            err = np.inf
            if status == 0:
                if error_norm == ERROR_RMS:
                    acc = 0.0
                    i0 = 0
                    while i0 + 4 <= n:
                        e_0 = e_1 = e_2 = e_3 = 0.0
                        for j in range(n_k):
                            w = error_weights[0, j]
                            e_0 += w * K[j, i0]
                            e_1 += w * K[j, i0 + 1]
                            e_2 += w * K[j, i0 + 2]
                            e_3 += w * K[j, i0 + 3]
                        for e, i in ((e_0, i0), (e_1, i0 + 1), (e_2, i0 + 2), (e_3, i0 + 3)):
                            e = h * e / (atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol)
                            acc += e * e
                        i0 += 4
                    for i in range(i0, n):
                        sc = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
                        e = 0.0
                        for j in range(n_k):
                            e += error_weights[0, j] * K[j, i]
                        e = h * e / sc
                        acc += e * e
                    err = np.sqrt(acc / n) if n > 0 else 0.0
                else:
                    sum5 = 0.0
                    sum3 = 0.0
                    i0 = 0
                    while i0 + 4 <= n:
                        e5_0 = e5_1 = e5_2 = e5_3 = 0.0
                        e3_0 = e3_1 = e3_2 = e3_3 = 0.0
                        for j in range(n_k):
                            w5 = error_weights[0, j]
                            w3 = error_weights[1, j]
                            e5_0 += w5 * K[j, i0]
                            e5_1 += w5 * K[j, i0 + 1]
                            e5_2 += w5 * K[j, i0 + 2]
                            e5_3 += w5 * K[j, i0 + 3]
                            e3_0 += w3 * K[j, i0]
                            e3_1 += w3 * K[j, i0 + 1]
                            e3_2 += w3 * K[j, i0 + 2]
                            e3_3 += w3 * K[j, i0 + 3]
                        for e5, e3, i in ((e5_0, e3_0, i0), (e5_1, e3_1, i0 + 1), (e5_2, e3_2, i0 + 2),
                                          (e5_3, e3_3, i0 + 3)):
                            sc = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
                            e5 /= sc
                            e3 /= sc
                            sum5 += e5 * e5
                            sum3 += e3 * e3
                        i0 += 4
                    for i in range(i0, n):
                        sc = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
                        e5 = 0.0
                        e3 = 0.0
                        for j in range(n_k):
                            e5 += error_weights[0, j] * K[j, i]
                            e3 += error_weights[1, j] * K[j, i]
                        e5 /= sc
                        e3 /= sc
                        sum5 += e5 * e5
                        sum3 += e3 * e3
                    if sum5 == 0.0 and sum3 == 0.0:      # (also for n = 0)
                        err = 0.0
                    else:
                        err = abs(h) * sum5 / np.sqrt((sum5 + 0.01 * sum3) * n)

            # Step-size control.
            if err < 1.0:                           # (false for NaN)
                if err == 0.0:
                    factor = MAX_FACTOR
                else:
                    factor = min(MAX_FACTOR, SAFETY * err ** error_exponent)
                if step_rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            if np.isfinite(err):
                h_abs *= max(MIN_FACTOR, SAFETY * err ** error_exponent)
                nonfinite = False
            else:
                h_abs *= MIN_FACTOR
                nonfinite = True
            step_rejected = True
            counters[NREJECTED] += 1

        # Stiffness estimate h |λ| of the accepted step (-1: not tested); counted at its commit.
        h_lambda = -1.0
        if detecting and (counters[STIFF_TESTS] > 0 or (counters[NSTEPS] + 1) % STIFFNESS_TEST_EVERY == 0):
            df2 = 0.0
            dy2 = 0.0
            for i in range(n):
                dy = 0.0
                for j in range(n_stages):
                    dy += (B[j] - A[last_stage, j]) * K[j, i]
                dy *= h
                df = K[n_stages, i] - K[last_stage, i]
                dy2 += dy * dy
                df2 += df * df
            h_lambda = h * np.sqrt(df2 / dy2) if dy2 > 0.0 else 0.0

        # Events of the accepted step; the dense output when an event or a t_eval point lies inside
        # it (first the extra stages K[n_k ..] (jj: stage index; j is the t_eval index), then the
        # rows F); a terminal event cuts the step short.
        n_crossed = 0
        restarting = False              # some event starts the step at its zero, after its reset
        if n_events > 0:
            event_values(t_new, y_new, p, g_new)
            n_crossed = event_crossings(g_old, g_new, directions, actions, crossed)
            for e in range(n_events):
                if at_zero[e] != 0:
                    restarting = True
        j = counters[NEXT_EVAL]
        if n_crossed > 0 or restarting or (use_t_eval and j < n_eval and t_eval[j] < t_new):
            for s in range(n_k, n_all):
                row = s - n_k
                for i in range(n):
                    ytmp[i] = 0.0
                for jj in range(s):
                    a = extra_A[row, jj]
                    if a != 0.0:
                        for i in range(n):
                            ytmp[i] += a * K[jj, i]
                for i in range(n):
                    ytmp[i] = y[i] + h * ytmp[i]
                status = rhs(t + extra_C[row] * h, ytmp, p, K[s])
                counters[NFEV] += 1
                if status == 0:
                    for i in range(n):
                        if not np.isfinite(K[s, i]):
                            status = -1
                if status != 0:
                    return (Status.RHS_FAILED if status > 0 else Status.NONFINITE), n_saved
            if contd8:
                for i in range(n):
                    dy = y_new[i] - y[i]
                    F[0, i] = dy
                    F[1, i] = h * K[0, i] - dy
                    F[2, i] = 2.0 * dy - h * (K[n_stages, i] + K[0, i])
            for r in range(n_special, n_rows):
                for i in range(n):
                    F[r, i] = 0.0
                for jj in range(n_all):
                    w = dense_weights[r - n_special, jj]
                    if w != 0.0:
                        for i in range(n):
                            F[r, i] += w * K[jj, i]
                if contd8:
                    for i in range(n):
                        F[r, i] *= h
        stop = False
        accumulated = False  # an event with a reset fired again less than the smallest step after its last reset
        reset = -1          # the event whose reset ends the step, if one does
        first_row = counters[EVENT_ROWS]
        if n_crossed > 0 or restarting:
            step_brackets(t, h, g_old, g_new, starts, g_start, ends, g_end)
        if restarting:
            n_crossed += restart_brackets(event_values, dense_kind, F, y, t, h, p, at_zero, g_new, directions, actions,
                                          crossed, starts, g_start, ends, g_end, side, ytmp, g_work)
        if n_crossed > 0:
            n_recorded, t_stop = record_events_between(event_values, dense_kind, F, y, t, h, p, starts, g_start, ends,
                                                       g_end, crossed, actions, crossing_times, ev_t, ev_y, ev_i,
                                                       first_row, ytmp, g_work)
            counters[EVENT_ROWS] = n_recorded
            copy_rows(ev_y, ev_y_after, first_row, n_recorded)
            if t_stop < np.inf:
                reset = resetting_event(ev_t, ev_i, actions, first_row, n_recorded, t_stop)
                if reset >= 0 and at_zero[reset] != 0 and t_stop - t < min_step:
                    accumulated = True
                    reset = -1
                stop = reset < 0
                t_new = t_stop
                dense_state(dense_kind, F, y, t, h, t_stop, y_new)

        # Outputs of the accepted step t -> t_new.  Projecting, the row of the state the run continues from
        # (`continued`) gets it after its projection below, and the rows between steps are projected here.
        continued = -1
        if use_t_eval:
            while j < n_eval and t_eval[j] <= t_new and n_saved < cap:
                te = t_eval[j]
                ts[n_saved] = te
                if te == t_new:
                    for i in range(n):
                        ys[n_saved, i] = y_new[i]
                    continued = n_saved
                else:
                    dense_state(dense_kind, F, y, t, h, te, ys[n_saved])
                    if projecting:  # (a row the projection cannot move stays as interpolated)
                        project(te, ys[n_saved], p)
                n_saved += 1
                j += 1
            counters[NEXT_EVAL] = j
            if j < n_eval and t_eval[j] <= t_new:
                # Only when one step holds more points than a whole buffer: do not commit; the next
                # call redoes this (deterministic) step and emits the remaining points.
                return Status.BUFFER_FULL, n_saved
        else:
            counters[SINCE_SAVE] += 1
            if counters[SINCE_SAVE] >= save_every or t_new >= t_end or stop or reset >= 0:
                ts[n_saved] = t_new
                for i in range(n):
                    ys[n_saved, i] = y_new[i]
                continued = n_saved
                n_saved += 1
                counters[SINCE_SAVE] = 0

        # A reset: the state jumps at t_new (the event's time, where the step ended); the state after it is a
        # second row at that time.  The FSAL stage no longer holds: evaluated again (below, or after the
        # projection), and the events' values are those after the reset (`reset_state`).
        if reset >= 0:
            status = reset_state(event_reset, event_values, t_new, y_new, p, reset, ytmp, g_old, g_work, ev_t, ev_i,
                                 ev_y_after, first_row, counters[EVENT_ROWS], at_zero)
            if status != 0:         # the run ends at the event, with the state just before it
                for i in range(n):
                    y[i] = y_new[i]
                clock[TIME] = t_new
                counters[NSTEPS] += 1
                return Status.RESET_FAILED, n_saved
            continued = -1      # the row before the reset is not the state the run continues from
            if not use_t_eval:
                ts[n_saved] = t_new
                for i in range(n):
                    ys[n_saved, i] = y_new[i]
                continued = n_saved
                n_saved += 1
            if not projecting:
                status = rhs(t_new, y_new, p, K[n_stages])
                counters[NFEV] += 1
                if status != 0:
                    return Status.RHS_FAILED, n_saved
            # The next step at most the one cut at the event: the motion after a reset has nothing to do with
            # the step the controller proposed from the motion before (a bounce's next flight is e times the
            # last one, which this step covered at most); `restart_brackets` then samples it.
            h_abs = min(h_abs, t_new - t)

        # Projection onto the constraints, after the dense output (it interpolates the step as computed); the
        # FSAL stage is then evaluated again at the projected state, which its saved row gets.
        if projecting:
            status = project(t_new, y_new, p)
            if status == 0:
                status = rhs(t_new, y_new, p, K[n_stages])
                counters[NFEV] += 1
            if status != 0:
                return Status.RHS_FAILED, n_saved
            if continued >= 0:
                for i in range(n):
                    ys[continued, i] = y_new[i]
        residual = constraint_residual(t_new, y_new, p)
        if residual > residual_max[0]:  # noqa: PLR1730 (a NaN residual leaves the maximum as it was)
            residual_max[0] = residual

        # Commit the step; the FSAL stage becomes the next first stage.
        for i in range(n):
            y[i] = y_new[i]
            K[0, i] = K[n_stages, i]
        t = t_new
        clock[TIME] = t
        clock[STEP] = h_abs
        counters[NSTEPS] += 1
        if reset < 0:
            for e in range(n_events):
                at_zero[e] = 0
        if h_lambda > stiffness_bound:          # (false for NaN)
            counters[NONSTIFF_TESTS] = 0
            counters[STIFF_TESTS] += 1
            if counters[STIFF_TESTS] == STIFF_TESTS_TO_DECLARE:
                counters[STIFF_AT_STEP] = counters[NSTEPS]
                clock[STIFF_AT_TIME] = t
                detecting = False
        elif h_lambda >= 0.0:
            counters[NONSTIFF_TESTS] += 1
            if counters[NONSTIFF_TESTS] == CALM_TESTS_TO_RESET:
                counters[STIFF_TESTS] = 0
        if residual > residual_bound:
            return Status.RESIDUAL_EXCEEDED, n_saved
        if stop:
            return (Status.EVENTS_ACCUMULATED if accumulated else Status.TERMINATED), n_saved
        if n_events > 0 and reset < 0:
            if projecting:
                event_values(t, y, p, g_old)
            else:
                for ev in range(n_events):
                    g_old[ev] = g_new[ev]
