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

Public drivers (sharing one calling convention):

* ``rk4_run(y, clock, counters, p, projecting, residual_max, t0, dt, n_steps,
  pause_at, t_end, save_every, ts, ys)``
* the adaptive embedded pairs (DOPRI5, DOP853, ...) are library code now:
  ``lagcomp.integrate.drivers.embedded.embedded_run``, with the same
  arguments after the kernels (its docstring holds the step control);
* ``composition_run(y, clock, counters, p, projecting, residual_max, t0, dt,
  n_steps, pause_at, t_end, save_every, ts, ys, weights)``: symplectic compositions of
  Störmer-Verlet for separable systems (in ``symplectic.py``, appended after
  this file);
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

The adaptive step-size control (HNW II.4, scipy's constants), the output
buffer rules and the event location of the embedded pairs are described in
``lagcomp.integrate.drivers.embedded``; ``taylor_run`` follows them.

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
public driver is a single ``@njit`` function whose only callee is ``rhs``.
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
