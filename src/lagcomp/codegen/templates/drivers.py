"""Integration drivers: a *template*, appended verbatim to every generated module.

This file is not imported as part of lagcomp.  Its text is appended to each
generated kernel module, after the kernels.  The module it is appended to
provides these names:

* ``np`` and ``njit`` (``import numpy as np`` / ``from numba import njit`` in
  the generated header; they are imported again below so that this file is
  also valid on its own, and the duplicate imports are harmless);
* ``rhs(t, y, p, out) -> int``: the right-hand-side kernel, which writes
  ``y' = f(t, y)`` into ``out`` and returns 0, or ``k > 0`` when the mass
  matrix was singular at pivot ``k``;
* ``project(t, y, p) -> int``: moves ``y`` onto the system's constraints in
  place (0, or ``k > 0`` when that is impossible), and
  ``constraint_residual(t, y, p) -> float``: the largest constraint residual.
  Unconstrained modules define them as no-ops that numba folds away;
* ``event_values(t, y, p, out)``: the values of the system's event
  functions (nothing when it has none).

Why a template rather than generic drivers taking ``rhs`` as an argument:
numba's on-disk cache misses for a cached function that receives a jitted
function as an argument, so each module gets its own copy of the drivers,
calling ``rhs`` as a module-level global.  Every function here is
``@njit(cache=True, error_model="numpy")``; the step loops run entirely in
compiled code and do not allocate (work arrays are allocated once at the start
of each driver call).

Public drivers (the calling convention is shared by all three, and by the
library's fixed-step drivers, `lagcomp.integrate.drivers.fixed_step`: RK4 and
the symplectic compositions):

* ``dopri5_run(y, clock, counters, p, projecting, residual_max, t_end, rtol,
  atol, max_step, max_steps, pause_at, save_every, t_eval, ts, ys,
  directions, actions, ev_t, ev_y, ev_i, A, B, C, E, P)``
* ``dop853_run(...)``: the same arguments as ``dopri5_run``, then
  ``A, B, C, E3, E5, D, A_EXTRA, C_EXTRA``;
* ``collocation_run(y, clock, counters, p, projecting, residual_max, t0, dt,
  n_steps, pause_at, t_end, save_every, ts, ys, A, B, C, E, max_iter,
  newton)``: implicit Gauss-Legendre collocation on the canonical equations
  in (q, p), for any unconstrained Lagrangian (also in ``symplectic.py``),
  its stage equations solved by fixed-point iteration (``newton`` None) or
  simplified Newton (True); it needs the kernels ``velocities``,
  ``momentum_rate`` and ``canonical_jacobian`` and returns -5 when the stage
  equations do not converge.

The trailing tableau arrays are ``lagcomp.integrate.tableaux.driver_arguments``
of the corresponding tableau.  State is kept in the in/out arrays so that a
run can be resumed, chunk by chunk, when the output buffer fills:

* ``y``        float64[N], current state (last accepted state on return);
* ``clock``    float64[2] = [t, h]: current time and next step size to try
  (adaptive drivers; h == 0 selects the initial step automatically);
* ``counters`` int64[6] = [nfev, nsteps, nrejected, i_eval, since_save,
  n_events]: the last is the number of event rows written to ``ev_*`` by
  this call (the caller resets it with each fresh event buffer);
* ``pause_at`` int: return status 11 before step number ``pause_at`` (counted
  from the start of the run, ``counters[1]``); the caller resumes with a
  later ``pause_at``.  This bounds the time of one call, so Python can show
  progress and honour Ctrl-C between calls;
* ``ts``, ``ys`` float64[cap], float64[cap, N]: output rows written from 0;
  the initial point is never written (the caller does that);
* ``projecting`` int: 1 projects every accepted state onto the constraints
  (RK4: before it is saved; adaptive: after the step's outputs, re-evaluating
  the FSAL derivative at the projected state); ``residual_max`` float64[1]
  or [2]: the running maximum of ``constraint_residual`` over accepted
  states, and optionally a bound: the step whose residual exceeds
  ``residual_max[1]`` is committed (and saved if due), then the driver
  returns -6 (RK4, DOP853, DOPRI5);
* events (adaptive drivers): ``directions`` int64[E] (+1, -1, 0),
  ``actions`` int64[E] (0 ignore, 1 record, 2 record and stop), and the
  output rows ``ev_t`` float64[cap_e], ``ev_y`` float64[cap_e, N],
  ``ev_i`` int64[cap_e] (time, state, event index); a step starts only when
  ``cap_e`` has room for one row per event.  After each accepted step the
  events are evaluated at its end; each sign change in an event's direction
  is located on the dense output by Brent's method (``_event_root``) and
  recorded in time order.  A terminal event ends the step, and the run, at
  its time: the event's state is the last saved row and ``y``, status 1.

Every driver returns ``(status, n_saved)``: status 0 = reached ``t_end``;
10 = output buffer full (call again with a fresh buffer; the continuation is
identical to an uninterrupted run except for one extra ``f`` evaluation per
call of the adaptive drivers; with ``t_eval`` the buffer may hold fewer than
``cap`` rows, see "Output buffer" below); 11 = paused at ``pause_at`` (call
again; the continuation is identical in the same way); 1 = a terminal event
stopped the run; -1 = non-finite state, derivative or step size; -2 =
``rhs`` returned a non-zero status; -3 = step size too small; -4 = maximum
number of steps reached; -5 = implicit stage equations not solved; -6 = the
constraint residual of the last (committed) step exceeded ``residual_max[1]``.
On failure ``y`` and ``clock[0]`` hold the last good state and its time (for
-6, the committed state whose residual is too large).

No floating-point trouble raises
--------------------------------

The kernels and the drivers are compiled with numba's
``error_model="numpy"``: a division by zero gives inf or NaN, as in numpy,
instead of raising ``ZeroDivisionError`` (numba's default "python" model),
which would abort the run with a Python exception and lose the partial
solution.  The drivers then detect the non-finite values themselves: every
derivative and every new state is tested, a trial step whose error estimate
is NaN/inf is rejected (``err < 1`` is false for NaN), and the step-size
tests are written so that a NaN step size ends the run (``not h >= min_step``
is true for NaN) instead of looping forever.  The divisions that can meet a
zero norm are guarded as in scipy: ``0.01 d0 / d1`` only when both norms are
at least 1e-5, ``(0.01 / max(d1, d2))`` only when one of them exceeds 1e-15,
``err ** (-1/(q+1))`` only for ``err > 0``, and DOP853's error norm is 0
when both embedded estimates vanish.  A zero component of the error scale
(``atol == 0`` and a component that is exactly 0) makes a norm inf or NaN,
which the step control treats like any other non-finite estimate.  Array
operations that could raise (slice assignment with a shape check) are
written as explicit loops.

Adaptive step-size control
--------------------------

The adaptive drivers implement the standard explicit Runge-Kutta step-size
control of Hairer, Norsett & Wanner, *Solving Ordinary Differential
Equations I* (2nd ed., Springer 1993), sec. II.4 (automatic step size
control, initial step selection) and II.6 (dense output), with the same
constants as scipy's ``solve_ivp`` explicit RK solvers, so that at equal
tolerances they take the same steps:

* DOPRI5: Dormand & Prince, "A family of embedded Runge-Kutta formulae",
  J. Comput. Appl. Math. 6 (1980) 19-26; quartic dense output (HNW II.6).
* DOP853: Hairer's DOP853 (HNW II.5 and II.6; Fortran code ``dop853.f``):
  8th-order method, error estimate combining 5th- and 3rd-order embedded
  formulas, 7th-order dense output from three extra stages.

Both use the FSAL layout (``K[0] = f(t, y)`` on entry to a step; its last
stage ``K[s] = f(t + h, y_new)`` becomes the next ``K[0]``) and proceed as
follows (q is the error order: 4 for DOPRI5, 7 for DOP853):

1. Initial step, when ``clock[1] <= 0`` (HNW sec. II.4, "Starting Step
   Size"): with ``scale = atol + |y0| rtol`` and the RMS norm,
   ``d0 = ||y0||``, ``d1 = ||f0||``; a probe step ``h0 = 0.01 d0/d1`` (1e-6
   if either is tiny, and at most the interval length); an explicit Euler
   step gives ``f1 = f(t0 + h0, y0 + h0 f0)`` and
   ``d2 = ||f1 - f0|| / h0``; then ``h1 = (0.01 / max(d1, d2)) ** (1/(q+1))``
   (or ``max(1e-6, 1e-3 h0)`` when both are negligible) and the step is
   ``min(100 h0, h1, t_end - t0, max_step)``.  A non-finite probe derivative
   gives ``min(h0, max_step)`` and leaves the trouble to the step rejection.
2. Trial steps: the step is clamped to ``max_step`` (or raised to the
   minimum step ``10 ulp(t)``) and clipped to land on ``t_end``.  It is
   accepted when the scaled error norm ``err < 1`` (error scale
   ``atol + max(|y|, |y_new|) rtol`` per component), and the next step is
   ``h * min(MAX_FACTOR, SAFETY err^(-1/(q+1)))`` (capped at ``h`` if this
   step had a rejection); otherwise ``h`` is multiplied by
   ``max(MIN_FACTOR, SAFETY err^(-1/(q+1)))`` and the step retried.  A trial
   with NaN/inf stages or error is rejected with ``h *= MIN_FACTOR``; if
   ``h`` then falls below the minimum step the run stops with -1 (last
   trouble non-finite) or -3.
3. Outputs of the accepted step (see below), then the commit: ``y = y_new``,
   ``K[0] = K[s]``.

Output buffer: before each step the number of rows it may write is bounded
(from the trial step, which rejections only shorten); if they do not fit,
status 10 is returned before the step.  With ``t_eval`` this can happen while
the buffer still has free rows (``n_saved < cap``): the rows written are
always ``ts[:n_saved]``.  Only if a single step holds more ``t_eval`` points
than an empty buffer, the points that fit are written and the step is *not*
committed; the next call redoes the same (deterministic) step and continues
with the remaining points, so the trajectory is unchanged but that step's
f evaluations and rejections are counted twice.

Why each driver is one long function
------------------------------------

Compile time decides the layout.  Every model compiles its drivers once per
cache, so their numba compile time is paid by every bundled example and by
every model in CI.  The earlier layout -- a dozen small helpers, one per step
of the algorithm, nested up to five deep around a core shared by DOPRI5 and
DOP853 -- took twice as long to compile as this one (numba 0.68, first call
with a fresh cache, double pendulum: DOP853 5.5 s -> 3.0 s, DOPRI5
5.5 s -> 2.2 s, RK4 1.1 s -> 0.7 s; 5-link chain the same), while the step
loops of this one are as fast or faster (0-10%).  Where the time went:

* numba links the LLVM module of every callee into its caller and optimises
  the *whole* linked module again, so a chain ``driver -> core -> step ->
  stages -> rhs`` optimises the inner loops (and a small kernel) once per
  level; a public driver that only forwards to a shared core costs about as
  much again as the core's own LLVM optimisation (+1 s for DOP853);
* every ``@njit`` function has a fixed cost (typing, lowering, wrappers, its
  own cache entry) of about 0.1 s even when it is tiny, and an integer
  literal argument (``_f(..., 0, 1, ...)``) compiles a separate
  ``Literal[int]`` specialisation of the callee;
* numba's own IR inlining (``inline="always"``) is slower still: it re-runs
  type inference over the inlined bodies (8.4 s for DOP853);
* what remains is roughly proportional to the number of operations numba
  types and lowers, counting every copy of repeated code, and a ``return``
  costs about twice an ordinary statement (it releases every live array):
  hence one ``rhs`` call site for all the stages of a step (the FSAL stage
  included) and few exits.

Moving the arithmetic into leaf helpers that never call ``rhs`` (stage
sums, error norm, interpolant) compiles in about the same time but slows the
step loop down by 15-35%, so the hot loops stay inline as well.  So each
public driver is a single ``@njit`` function whose only callee is ``rhs``,
and the parts that ``dopri5_run`` and ``dop853_run`` share (initial step,
output bound, trial loop, outputs, commit) are deliberately written twice,
with the same names and in the same order so that the two read side by side:
a change to one must be made to the other (``tests/test_drivers.py`` runs
every test on both).  Only the work arrays, the error norm and the dense
output differ.  ``rhs`` is called from three places in ``dopri5_run`` and
four in ``dop853_run``; LLVM inlines a small kernel at each and calls a large
one.
"""

# ruff: noqa: F821  (rhs, project, velocities, ... are defined by the module this text is appended to)

import numpy as np
from numba import njit

# Step-size controller constants (HNW I, sec. II.4, eqs. (4.12)-(4.13); the
# same values as scipy's explicit Runge-Kutta solvers).
_ODE_SAFETY = 0.9       # safety factor "fac" applied to the optimal step
_ODE_MIN_FACTOR = 0.2   # never shrink the step by more than this factor
_ODE_MAX_FACTOR = 10.0  # never grow the step by more than this factor

# Status codes returned by the drivers: the values of lagcomp.integrate.status.Status.
# Inside a driver, ``status`` holds the outcome of a group of rhs calls: 0, the
# rhs status (> 0), or -1 when a derivative or state was not finite.
_ODE_DONE = 0
_ODE_EVENT = 1            # a terminal event stopped the run (Status.TERMINATED)
_ODE_NONFINITE = -1
_ODE_RHS_FAILED = -2
_ODE_STEP_TOO_SMALL = -3
_ODE_MAX_STEPS = -4
_ODE_NOT_CONVERGED = -5   # implicit stage equations not solved (step too large)
_ODE_RESIDUAL = -6        # constraint residual above the bound residual_max[1]
_ODE_BUFFER_FULL = 10     # the output buffer is full: call again with a fresh one
_ODE_PAUSED = 11          # the call's step budget (``pause_at``) is used up: call again


# >>> events
# ---------------------------------------------------------------------------
# Events on the dense output (shared by DOPRI5 and DOP853)
# ---------------------------------------------------------------------------

@njit(cache=True, error_model="numpy")
def _dense_state(kind, F, y, t, h, tau, out):
    """State at time ``tau`` inside the step (t, t + h) from its dense output, into ``out``.

    ``kind`` 5: DOPRI5, ``F`` holds Q with ``y(t + x h) = y + h sum_m Q[m] x^(m+1)``;
    ``kind`` 8: DOP853, ``F`` holds the rows of ``contd8`` (see ``dop853_run``);
    ``kind`` 0: the Taylor method, ``F`` holds the series, ``y(t + u) = sum_m F[i, m] u^m``
    (``taylor_run`` in taylor.py).
    """
    n = y.shape[0]
    rows = F.shape[0]
    x = (tau - t) / h
    if kind == 0:
        u = tau - t
        for i in range(n):
            acc = 0.0
            for m in range(F.shape[1] - 1, -1, -1):
                acc = acc * u + F[i, m]
            out[i] = acc
    elif kind == 5:
        for i in range(n):
            acc = 0.0
            for m in range(rows - 1, -1, -1):
                acc = (acc + F[m, i]) * x
            out[i] = y[i] + h * acc
    else:
        one_minus_x = 1.0 - x
        for i in range(n):
            acc = 0.0
            for r in range(rows - 1, -1, -1):
                acc += F[r, i]
                if r % 2 == 0:
                    acc *= x
                else:
                    acc *= one_minus_x
            out[i] = y[i] + acc


@njit(cache=True, error_model="numpy")
def _event_crossings(g_old, g_new, directions, actions, crossed):
    """Flag in ``crossed`` the active events whose sign change over the step matches their direction.

    Up: g_old < 0 <= g_new; down: g_old > 0 >= g_new (a zero at the step's
    start does not count: it was the previous step's end).  Returns the count.
    """
    count = 0
    for e in range(g_old.shape[0]):
        up = g_old[e] < 0.0 and g_new[e] >= 0.0
        down = g_old[e] > 0.0 and g_new[e] <= 0.0
        hit = actions[e] > 0 and ((up and directions[e] >= 0) or (down and directions[e] <= 0))
        crossed[e] = hit
        if hit:
            count += 1
    return count


@njit(cache=True, error_model="numpy")
def _event_root(kind, F, y, t, h, p, e, a, fa, b, fb, ywork, gwork):
    """Zero of event ``e`` on the dense output between times a and b (fa, fb of opposite signs).

    Brent's method (R. P. Brent, *Algorithms for Minimization without
    Derivatives*, 1973, ch. 4: inverse quadratic interpolation and secant
    steps, safeguarded by bisection), to 2 eps |tau| + 2 eps in time:
    a few units of rounding.
    """
    eps = 2.220446049250313e-16
    c = a
    fc = fa
    d = b - a
    step = d
    for _ in range(200):
        if (fb > 0.0) == (fc > 0.0):
            c = a
            fc = fa
            d = b - a
            step = d
        if abs(fc) < abs(fb):
            a = b
            b = c
            c = a
            fa = fb
            fb = fc
            fc = fa
        tol = 2.0 * eps * abs(b) + 2.0 * eps
        half = 0.5 * (c - b)
        if abs(half) <= tol or fb == 0.0:
            break
        if abs(step) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:                           # secant
                num = 2.0 * half * s
                den = 1.0 - s
            else:                                # inverse quadratic
                qa = fa / fc
                r = fb / fc
                num = s * (2.0 * half * qa * (qa - r) - (b - a) * (r - 1.0))
                den = (qa - 1.0) * (r - 1.0) * (s - 1.0)
            if num > 0.0:
                den = -den
            else:
                num = -num
            if 2.0 * num < min(3.0 * half * den - abs(tol * den), abs(step * den)):
                step = d
                d = num / den
            else:
                d = half
                step = d
        else:
            d = half
            step = d
        a = b
        fa = fb
        if abs(d) > tol:
            b += d
        elif half > 0.0:
            b += tol
        else:
            b -= tol
        _dense_state(kind, F, y, t, h, b, ywork)
        event_values(b, ywork, p, gwork)
        fb = gwork[e]
    return b


@njit(cache=True, error_model="numpy")
def _record_events(kind, F, y, t, h, p, g_old, g_new, crossed, actions, times,
                   te, ye, ie, n_recorded, ywork, gwork):
    """Locate the flagged crossings of the step (t, t + h) and record them in time order.

    Writes times, states and event indices to ``te``/``ye``/``ie`` from row
    ``n_recorded`` (the caller made room for one row per event).  Events
    after the first terminal one are dropped.  Returns the new row count and
    the time of the terminal event (inf when none fired).
    """
    n_events = g_old.shape[0]
    for e in range(n_events):
        times[e] = np.inf
        if crossed[e]:
            times[e] = _event_root(kind, F, y, t, h, p, e, t, g_old[e], t + h, g_new[e], ywork, gwork)
    t_stop = np.inf
    while True:
        first = -1
        for e in range(n_events):
            if times[e] < np.inf and (first < 0 or times[e] < times[first]):
                first = e
        if first < 0 or times[first] > t_stop:
            break
        te[n_recorded] = times[first]
        _dense_state(kind, F, y, t, h, times[first], ye[n_recorded])
        ie[n_recorded] = first
        n_recorded += 1
        if actions[first] == 2:
            t_stop = times[first]
        times[first] = np.inf
    return n_recorded, t_stop

# <<< events

# ---------------------------------------------------------------------------
# Adaptive embedded Runge-Kutta: DOPRI5 and DOP853 (two parallel bodies; see
# "Why each driver is one long function" above)
# ---------------------------------------------------------------------------

@njit(cache=True, error_model="numpy")
def dopri5_run(y, clock, counters, p, projecting, residual_max, t_end, rtol,
               atol, max_step, max_steps, pause_at, save_every, t_eval, ts, ys,
               directions, actions, ev_t, ev_y, ev_i, A, B, C, E, P):
    """Dormand-Prince 5(4) with step control and quartic dense output.

    ``A`` (s, s) strictly lower triangular, ``B``/``C`` (s,), ``E`` (s+1,)
    error weights including the FSAL stage, ``P`` (s+1, 4) dense-output
    matrix.  Error order q = 4.

    * Error norm: RMS norm of ``h * sum_j E_j K[j] / scale`` (the difference
      of the 5th- and 4th-order solutions), HNW sec. II.4.
    * Dense output: ``Q[m] = sum_j P[j, m] K[j]`` over all stages including
      the FSAL row, and ``y(t + x h) = y + h * sum_m Q[m] x^(m+1)`` (Dormand
      & Prince 1980; HNW II.6), evaluated in Horner form.

    See the module docstring for the arguments, the return value and the
    algorithm.
    """
    n = y.shape[0]
    cap = ts.shape[0]
    n_eval = t_eval.shape[0]
    use_t_eval = n_eval > 0
    n_stages = B.shape[0]
    n_k = E.shape[0]            # stages + FSAL row
    n_power = P.shape[1]
    exponent = -1.0 / 5.0       # -1 / (q + 1)

    # Work arrays, allocated once per call.
    K = np.empty((n_k, n))
    y_new = np.empty(n)
    ytmp = np.empty(n)
    f_stage = np.empty(n)
    Q = np.empty((n_power, n))  # dense-output coefficients; Q[0] is also
                                # the error scale of the initial step
    # >>> events
    n_events = directions.shape[0]
    g_old = np.empty(n_events)
    g_new = np.empty(n_events)
    g_work = np.empty(n_events)
    crossed = np.zeros(n_events, dtype=np.bool_)
    crossing_times = np.empty(n_events)
    # <<< events

    n_saved = 0
    residual_bound = residual_max[1] if residual_max.shape[0] > 1 else np.inf
    t = clock[0]
    if t >= t_end:
        return _ODE_DONE, n_saved
    # Output points at or before the current time are never emitted here.
    while counters[3] < n_eval and t_eval[counters[3]] <= t:
        counters[3] += 1

    # First stage of the first step (FSAL thereafter); events at the start.
    status = rhs(t, y, p, K[0])
    counters[0] += 1
    # >>> events
    if n_events > 0:
        event_values(t, y, p, g_old)
    # <<< events
    if status == 0:
        for i in range(n):
            if not (np.isfinite(y[i]) and np.isfinite(K[0, i])):
                status = -1

    h_abs = clock[1]
    if status == 0 and h_abs <= 0.0:
        # Initial step (step 1 of the module docstring): probe state in
        # ytmp, probe derivative in y_new, error scale in Q[0].
        interval = t_end - t
        if n == 0:
            h_abs = min(interval, max_step)
        else:
            d0 = 0.0
            d1 = 0.0
            for i in range(n):
                sc = atol + abs(y[i]) * rtol
                Q[0, i] = sc
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
            counters[0] += 1
            finite = True
            d2 = 0.0
            for i in range(n):
                finite = finite and np.isfinite(y_new[i])
                r = (y_new[i] - K[0, i]) / Q[0, i]
                d2 += r * r
            if not finite:
                h_abs = min(h0, max_step)
            else:
                d2 = np.sqrt(d2 / n) / h0
                if d1 <= 1e-15 and d2 <= 1e-15:
                    h1 = max(1e-6, h0 * 1e-3)
                else:
                    h1 = (0.01 / max(d1, d2)) ** (-exponent)
                h_abs = min(100.0 * h0, h1, interval, max_step)
        if status == 0:                     # (not after a failed probe)
            clock[1] = h_abs
    if status != 0:
        return (_ODE_RHS_FAILED if status > 0 else _ODE_NONFINITE), n_saved

    while True:
        if t >= t_end:
            return _ODE_DONE, n_saved
        if counters[1] >= max_steps:
            return _ODE_MAX_STEPS, n_saved
        if counters[1] >= pause_at:
            return _ODE_PAUSED, n_saved

        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step

        # Stop before a step whose outputs would not fit (never lose one).
        # The bound: the t_eval points in (t, t_reach] not yet emitted
        # (counted up to room + 1), else 1 if the step is saved by
        # decimation or may end at t_end.  Rejections only shorten the step.
        room = cap - n_saved
        t_reach = min(t + h_abs, t_end)
        need = 0
        if use_t_eval:
            j = counters[3]
            while j < n_eval and t_eval[j] <= t_reach and need <= room:
                need += 1
                j += 1
        elif counters[4] + 1 >= save_every or t_reach >= t_end:
            need = 1
        if need > room and (n_saved > 0 or not use_t_eval):
            return _ODE_BUFFER_FULL, n_saved
        # >>> events
        if counters[5] + n_events > ev_t.shape[0]:
            return _ODE_BUFFER_FULL, n_saved
        if n_events > 0 and not use_t_eval and n_saved >= cap:
            return _ODE_BUFFER_FULL, n_saved    # a terminal event saves its row
        # <<< events

        # Trial loop: shrink until the error estimate is acceptable.
        step_rejected = False
        nonfinite = False
        while True:
            t_new = t + h_abs
            if t_new > t_end:
                t_new = t_end
            # Too small, or NaN, or infinite (possible only with t_end = inf).
            if not (h_abs >= min_step and t_new < np.inf):
                if h_abs < min_step and not nonfinite:
                    return _ODE_STEP_TOO_SMALL, n_saved
                return _ODE_NONFINITE, n_saved
            h = t_new - t
            h_abs = abs(h)

            # Stages K[1 .. s]: K[s] = f(t + c h, y + h sum_{j<s} a_j K[j])
            # with (a, c) = (A[s], C[s]), and for s = n_stages (B, 1): the
            # stage argument is then y_new and the stage the FSAL derivative.
            # Zero coefficients are skipped (the tableaux are sparse).  No
            # array views in this loop (A[s], K[s]): numba builds and
            # reference-counts each one per stage; rhs writes into f_stage,
            # which is copied into K[s].
            status = 0
            for s in range(1, n_stages + 1):
                last = s == n_stages
                c = 1.0 if last else C[s]
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
                counters[0] += 1
                for i in range(n):
                    K[s, i] = f_stage[i]
                    if status == 0 and not np.isfinite(f_stage[i]):
                        status = -1
                if status != 0:
                    break
            if status > 0:
                return _ODE_RHS_FAILED, n_saved

            # Error norm (DOPRI5), infinite when a value was not finite.
            err = np.inf
            if status == 0:
                acc = 0.0
                for i in range(n):
                    sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
                    e = 0.0
                    for j in range(n_k):
                        e += E[j] * K[j, i]
                    e = h * e / sc
                    acc += e * e
                err = np.sqrt(acc / n) if n > 0 else 0.0

            # Step-size control.
            if err < 1.0:                           # (false for NaN)
                if err == 0.0:
                    factor = _ODE_MAX_FACTOR
                else:
                    factor = min(_ODE_MAX_FACTOR, _ODE_SAFETY * err ** exponent)
                if step_rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            if np.isfinite(err):
                h_abs *= max(_ODE_MIN_FACTOR, _ODE_SAFETY * err ** exponent)
                nonfinite = False
            else:
                h_abs *= _ODE_MIN_FACTOR
                nonfinite = True
            step_rejected = True
            counters[2] += 1

        # Events of the accepted step; the interpolant when an event or a
        # t_eval point lies inside it; a terminal event cuts the step short.
        n_crossed = 0
        # >>> events
        if n_events > 0:
            event_values(t_new, y_new, p, g_new)
            n_crossed = _event_crossings(g_old, g_new, directions, actions, crossed)
        # <<< events
        j = counters[3]
        if n_crossed > 0 or (use_t_eval and j < n_eval and t_eval[j] < t_new):
            for m in range(n_power):
                for i in range(n):
                    Q[m, i] = 0.0
                for jj in range(n_k):
                    w = P[jj, m]
                    if w != 0.0:
                        for i in range(n):
                            Q[m, i] += w * K[jj, i]
        stop = False
        # >>> events
        if n_crossed > 0:
            n_recorded, t_stop = _record_events(5, Q, y, t, h, p, g_old, g_new, crossed, actions,
                                                crossing_times, ev_t, ev_y, ev_i, counters[5], ytmp, g_work)
            counters[5] = n_recorded
            if t_stop < np.inf:
                stop = True
                t_new = t_stop
                _dense_state(5, Q, y, t, h, t_stop, y_new)
        # <<< events

        # Outputs of the accepted step t -> t_new.
        if use_t_eval:
            while j < n_eval and t_eval[j] <= t_new and n_saved < cap:
                te = t_eval[j]
                ts[n_saved] = te
                if te == t_new:
                    for i in range(n):
                        ys[n_saved, i] = y_new[i]
                else:
                    x = (te - t) / h
                    for i in range(n):
                        acc = 0.0
                        for m in range(n_power - 1, -1, -1):
                            acc = (acc + Q[m, i]) * x
                        ys[n_saved, i] = y[i] + h * acc
                n_saved += 1
                j += 1
            counters[3] = j
            if j < n_eval and t_eval[j] <= t_new:
                # Only when one step holds more points than a whole buffer:
                # do not commit; the next call redoes this (deterministic)
                # step and emits the remaining points.
                return _ODE_BUFFER_FULL, n_saved
        else:
            counters[4] += 1
            if counters[4] >= save_every or t_new >= t_end or stop:
                ts[n_saved] = t_new
                for i in range(n):
                    ys[n_saved, i] = y_new[i]
                n_saved += 1
                counters[4] = 0

        # Projection onto the constraints, after the outputs (the dense
        # output interpolates the step as computed); the FSAL stage is then
        # re-evaluated at the projected state.
        if projecting:
            status = project(t_new, y_new, p)
            if status == 0:
                status = rhs(t_new, y_new, p, K[n_stages])
                counters[0] += 1
            if status != 0:
                return _ODE_RHS_FAILED, n_saved
        residual = constraint_residual(t_new, y_new, p)
        if residual > residual_max[0]:
            residual_max[0] = residual

        # Commit the step; the FSAL stage becomes the next first stage.
        for i in range(n):
            y[i] = y_new[i]
            K[0, i] = K[n_stages, i]
        t = t_new
        clock[0] = t
        clock[1] = h_abs
        counters[1] += 1
        if residual > residual_bound:
            return _ODE_RESIDUAL, n_saved
        if stop:
            return _ODE_EVENT, n_saved
        # >>> events
        if n_events > 0:
            if projecting:
                event_values(t, y, p, g_old)
            else:
                for ev in range(n_events):
                    g_old[ev] = g_new[ev]
        # <<< events


@njit(cache=True, error_model="numpy")
def dop853_run(y, clock, counters, p, projecting, residual_max, t_end, rtol,
               atol, max_step, max_steps, pause_at, save_every, t_eval, ts, ys,
               directions, actions, ev_t, ev_y, ev_i, A, B, C, E3, E5, D, A_EXTRA,
               C_EXTRA):
    """Hairer's DOP853: order 8 with the combined 5th/3rd-order error
    estimate (error order q = 7) and 7th-order dense output.

    ``A`` (s, s), ``B``/``C`` (s,), ``E3``/``E5`` (s+1,), ``D`` (4, s+4),
    ``A_EXTRA`` (3, s+4), ``C_EXTRA`` (3,).

    * Error norm: Hairer's combined estimate
      ``|h| e5 / sqrt(n (e5 + 0.01 e3))`` with ``e5``/``e3`` the squared
      2-norms of the scaled 5th- and 3rd-order estimates
      ``sum_j E5_j K[j] / scale`` and ``sum_j E3_j K[j] / scale``
      (``dop853.f``; HNW sec. II.5, the 8(5,3) pair): it behaves like an
      estimate of order 7 while staying robust when the 5th-order estimate
      happens to be small.
    * Dense output (``dop853.f`` routine ``contd8``; HNW sec. II.6), built
      only for steps that hold a ``t_eval`` point: three extra stages
      ``K[s+1 .. s+3]`` (``A_EXTRA``, ``C_EXTRA``) and the rows
      ``F0 = dy = y_new - y``, ``F1 = h f_old - dy``,
      ``F2 = 2 dy - h (f_new + f_old)``, ``F3..F6 = h * D @ K``; then
      ``y(t + x h) = y + x (F0 + (1-x) (F1 + x (F2 + (1-x) (F3 + ...))))``.

    See the module docstring for the arguments, the return value and the
    algorithm.
    """
    n = y.shape[0]
    cap = ts.shape[0]
    n_eval = t_eval.shape[0]
    use_t_eval = n_eval > 0
    n_stages = B.shape[0]
    n_k = E5.shape[0]           # stages + FSAL row
    n_all = A_EXTRA.shape[1]    # ... + extra dense-output stages
    n_rows = 3 + D.shape[0]     # rows of the interpolant
    exponent = -1.0 / 8.0       # -1 / (q + 1)

    # Work arrays, allocated once per call.
    K = np.empty((n_all, n))
    y_new = np.empty(n)
    ytmp = np.empty(n)
    f_stage = np.empty(n)
    F = np.empty((n_rows, n))   # dense-output coefficients; F[0] is also
                                # the error scale of the initial step
    # >>> events
    n_events = directions.shape[0]
    g_old = np.empty(n_events)
    g_new = np.empty(n_events)
    g_work = np.empty(n_events)
    crossed = np.zeros(n_events, dtype=np.bool_)
    crossing_times = np.empty(n_events)
    # <<< events

    n_saved = 0
    residual_bound = residual_max[1] if residual_max.shape[0] > 1 else np.inf
    t = clock[0]
    if t >= t_end:
        return _ODE_DONE, n_saved
    # Output points at or before the current time are never emitted here.
    while counters[3] < n_eval and t_eval[counters[3]] <= t:
        counters[3] += 1

    # First stage of the first step (FSAL thereafter); events at the start.
    status = rhs(t, y, p, K[0])
    counters[0] += 1
    # >>> events
    if n_events > 0:
        event_values(t, y, p, g_old)
    # <<< events
    if status == 0:
        for i in range(n):
            if not (np.isfinite(y[i]) and np.isfinite(K[0, i])):
                status = -1

    h_abs = clock[1]
    if status == 0 and h_abs <= 0.0:
        # Initial step (step 1 of the module docstring): probe state in
        # ytmp, probe derivative in y_new, error scale in F[0].
        interval = t_end - t
        if n == 0:
            h_abs = min(interval, max_step)
        else:
            d0 = 0.0
            d1 = 0.0
            for i in range(n):
                sc = atol + abs(y[i]) * rtol
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
            counters[0] += 1
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
                    h1 = (0.01 / max(d1, d2)) ** (-exponent)
                h_abs = min(100.0 * h0, h1, interval, max_step)
        if status == 0:                     # (not after a failed probe)
            clock[1] = h_abs
    if status != 0:
        return (_ODE_RHS_FAILED if status > 0 else _ODE_NONFINITE), n_saved

    while True:
        if t >= t_end:
            return _ODE_DONE, n_saved
        if counters[1] >= max_steps:
            return _ODE_MAX_STEPS, n_saved
        if counters[1] >= pause_at:
            return _ODE_PAUSED, n_saved

        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step

        # Stop before a step whose outputs would not fit (never lose one).
        # The bound: the t_eval points in (t, t_reach] not yet emitted
        # (counted up to room + 1), else 1 if the step is saved by
        # decimation or may end at t_end.  Rejections only shorten the step.
        room = cap - n_saved
        t_reach = min(t + h_abs, t_end)
        need = 0
        if use_t_eval:
            j = counters[3]
            while j < n_eval and t_eval[j] <= t_reach and need <= room:
                need += 1
                j += 1
        elif counters[4] + 1 >= save_every or t_reach >= t_end:
            need = 1
        if need > room and (n_saved > 0 or not use_t_eval):
            return _ODE_BUFFER_FULL, n_saved
        # >>> events
        if counters[5] + n_events > ev_t.shape[0]:
            return _ODE_BUFFER_FULL, n_saved
        if n_events > 0 and not use_t_eval and n_saved >= cap:
            return _ODE_BUFFER_FULL, n_saved    # a terminal event saves its row
        # <<< events

        # Trial loop: shrink until the error estimate is acceptable.
        step_rejected = False
        nonfinite = False
        while True:
            t_new = t + h_abs
            if t_new > t_end:
                t_new = t_end
            # Too small, or NaN, or infinite (possible only with t_end = inf).
            if not (h_abs >= min_step and t_new < np.inf):
                if h_abs < min_step and not nonfinite:
                    return _ODE_STEP_TOO_SMALL, n_saved
                return _ODE_NONFINITE, n_saved
            h = t_new - t
            h_abs = abs(h)

            # Stages K[1 .. s]: K[s] = f(t + c h, y + h sum_{j<s} a_j K[j])
            # with (a, c) = (A[s], C[s]), and for s = n_stages (B, 1): the
            # stage argument is then y_new and the stage the FSAL derivative.
            # Zero coefficients are skipped (the tableaux are sparse).  No
            # array views in this loop (A[s], K[s]): numba builds and
            # reference-counts each one per stage; rhs writes into f_stage,
            # which is copied into K[s].
            status = 0
            for s in range(1, n_stages + 1):
                last = s == n_stages
                c = 1.0 if last else C[s]
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
                counters[0] += 1
                for i in range(n):
                    K[s, i] = f_stage[i]
                    if status == 0 and not np.isfinite(f_stage[i]):
                        status = -1
                if status != 0:
                    break
            if status > 0:
                return _ODE_RHS_FAILED, n_saved

            # Error norm (DOP853), infinite when a value was not finite.
            err = np.inf
            if status == 0:
                sum5 = 0.0
                sum3 = 0.0
                for i in range(n):
                    sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
                    e5 = 0.0
                    e3 = 0.0
                    for j in range(n_k):
                        e5 += E5[j] * K[j, i]
                        e3 += E3[j] * K[j, i]
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
                    factor = _ODE_MAX_FACTOR
                else:
                    factor = min(_ODE_MAX_FACTOR, _ODE_SAFETY * err ** exponent)
                if step_rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            if np.isfinite(err):
                h_abs *= max(_ODE_MIN_FACTOR, _ODE_SAFETY * err ** exponent)
                nonfinite = False
            else:
                h_abs *= _ODE_MIN_FACTOR
                nonfinite = True
            step_rejected = True
            counters[2] += 1

        # Events of the accepted step; the interpolant when an event or a
        # t_eval point lies inside it (first the extra stages K[s+1 .. s+3]
        # (jj: stage index; j is the t_eval index), then the rows F); a
        # terminal event cuts the step short.
        n_crossed = 0
        # >>> events
        if n_events > 0:
            event_values(t_new, y_new, p, g_new)
            n_crossed = _event_crossings(g_old, g_new, directions, actions, crossed)
        # <<< events
        j = counters[3]
        if n_crossed > 0 or (use_t_eval and j < n_eval and t_eval[j] < t_new):
            for s in range(n_k, n_all):
                row = s - n_k
                for i in range(n):
                    ytmp[i] = 0.0
                for jj in range(s):
                    a = A_EXTRA[row, jj]
                    if a != 0.0:
                        for i in range(n):
                            ytmp[i] += a * K[jj, i]
                for i in range(n):
                    ytmp[i] = y[i] + h * ytmp[i]
                status = rhs(t + C_EXTRA[row] * h, ytmp, p, K[s])
                counters[0] += 1
                if status == 0:
                    for i in range(n):
                        if not np.isfinite(K[s, i]):
                            status = -1
                if status != 0:
                    return ((_ODE_RHS_FAILED if status > 0
                             else _ODE_NONFINITE), n_saved)
            for i in range(n):
                dy = y_new[i] - y[i]
                F[0, i] = dy
                F[1, i] = h * K[0, i] - dy
                F[2, i] = 2.0 * dy - h * (K[n_stages, i] + K[0, i])
            for r in range(3, n_rows):
                for i in range(n):
                    F[r, i] = 0.0
                for jj in range(n_all):
                    w = D[r - 3, jj]
                    if w != 0.0:
                        for i in range(n):
                            F[r, i] += w * K[jj, i]
                for i in range(n):
                    F[r, i] *= h
        stop = False
        # >>> events
        if n_crossed > 0:
            n_recorded, t_stop = _record_events(8, F, y, t, h, p, g_old, g_new, crossed, actions,
                                                crossing_times, ev_t, ev_y, ev_i, counters[5], ytmp, g_work)
            counters[5] = n_recorded
            if t_stop < np.inf:
                stop = True
                t_new = t_stop
                _dense_state(8, F, y, t, h, t_stop, y_new)
        # <<< events

        # Outputs of the accepted step t -> t_new.
        if use_t_eval:
            while j < n_eval and t_eval[j] <= t_new and n_saved < cap:
                te = t_eval[j]
                ts[n_saved] = te
                if te == t_new:
                    for i in range(n):
                        ys[n_saved, i] = y_new[i]
                else:
                    x = (te - t) / h
                    one_minus_x = 1.0 - x
                    for i in range(n):
                        acc = 0.0
                        for r in range(n_rows - 1, -1, -1):
                            acc += F[r, i]
                            if r % 2 == 0:
                                acc *= x
                            else:
                                acc *= one_minus_x
                        ys[n_saved, i] = y[i] + acc
                n_saved += 1
                j += 1
            counters[3] = j
            if j < n_eval and t_eval[j] <= t_new:
                # Only when one step holds more points than a whole buffer:
                # do not commit; the next call redoes this (deterministic)
                # step and emits the remaining points.
                return _ODE_BUFFER_FULL, n_saved
        else:
            counters[4] += 1
            if counters[4] >= save_every or t_new >= t_end or stop:
                ts[n_saved] = t_new
                for i in range(n):
                    ys[n_saved, i] = y_new[i]
                n_saved += 1
                counters[4] = 0

        # Projection onto the constraints, after the outputs (the dense
        # output interpolates the step as computed); the FSAL stage is then
        # re-evaluated at the projected state.
        if projecting:
            status = project(t_new, y_new, p)
            if status == 0:
                status = rhs(t_new, y_new, p, K[n_stages])
                counters[0] += 1
            if status != 0:
                return _ODE_RHS_FAILED, n_saved
        residual = constraint_residual(t_new, y_new, p)
        if residual > residual_max[0]:
            residual_max[0] = residual

        # Commit the step; the FSAL stage becomes the next first stage.
        for i in range(n):
            y[i] = y_new[i]
            K[0, i] = K[n_stages, i]
        t = t_new
        clock[0] = t
        clock[1] = h_abs
        counters[1] += 1
        if residual > residual_bound:
            return _ODE_RESIDUAL, n_saved
        if stop:
            return _ODE_EVENT, n_saved
        # >>> events
        if n_events > 0:
            if projecting:
                event_values(t, y, p, g_old)
            else:
                for ev in range(n_events):
                    g_old[ev] = g_new[ev]
        # <<< events
